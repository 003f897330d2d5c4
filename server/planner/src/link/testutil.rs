//! Random maps for the link tests.

use crate::geom::Point2;
use crate::map::{CellState, GridGeometry, OccupancyGrid};
use crate::space::{CoverageSpace, RobotShape};

/// A tiny deterministic generator (xorshift64*), so tests need no extra dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// A `w × h` map at 0.1 m with `obstacles` random rectangles and disks (half-sizes 0.05–1.2 m); `None`
/// when the robot fits nowhere.
pub fn random_space(seed: u64, w: usize, h: usize, obstacles: usize, radius_m: f64) -> Option<CoverageSpace> {
    let mut rng = Rng::new(seed);
    let g = GridGeometry::new(w, h, 0.1, Point2::new(-1.0, 2.0)).ok()?;
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    let (wm, hm) = (w as f64 * 0.1, h as f64 * 0.1);
    for _ in 0..obstacles {
        let c = Point2::new(-1.0 + rng.range(0.0, wm), 2.0 + rng.range(0.0, hm));
        let disk = rng.unit() < 0.5;
        let (ex, ey) = if disk {
            let r = rng.range(0.05, 0.6);
            (r, r)
        } else {
            (rng.range(0.05, 1.2), rng.range(0.05, 1.2))
        };
        // Paint inside the bounding box only (fast on big maps).
        let (cx, cy) = g.to_cell_coords(c);
        let (x0, x1) = (
            (cx - ex * 10.0 - 1.0).max(0.0) as usize,
            ((cx + ex * 10.0 + 1.0) as usize).min(w - 1),
        );
        let (y0, y1) = (
            (cy - ey * 10.0 - 1.0).max(0.0) as usize,
            ((cy + ey * 10.0 + 1.0) as usize).min(h - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = g.center(crate::map::Cell::new(x, y));
                let inside = if disk {
                    (p - c).norm() <= ex
                } else {
                    (p.x - c.x).abs() <= ex && (p.y - c.y).abs() <= ey
                };
                if inside {
                    grid.cells[y * w + x] = CellState::Occupied;
                }
            }
        }
    }
    let robot = RobotShape {
        radius_m,
        tool_width_m: 0.3,
    };
    let start = Point2::new(-1.0 + rng.range(0.0, wm), 2.0 + rng.range(0.0, hm));
    CoverageSpace::new(grid, robot, start).ok()
}

/// A random valid robot position (not a cell centre) on the reachable set.
pub fn random_point(space: &CoverageSpace, rng: &mut Rng) -> Point2 {
    random_points(space, rng, 1)[0]
}

/// `n` random valid robot positions (not cell centres) on the reachable set.
pub fn random_points(space: &CoverageSpace, rng: &mut Rng, n: usize) -> Vec<Point2> {
    let g = *space.geometry();
    let cells: Vec<usize> = (0..g.len()).filter(|&i| space.reachable[i]).collect();
    (0..n)
        .map(|_| {
            for _ in 0..1000 {
                let c = g.center_of(cells[rng.below(cells.len())]);
                let p = c + crate::geom::Vector2::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05));
                if space.point_ok(p) {
                    return p;
                }
            }
            g.center_of(cells[0])
        })
        .collect()
}
