//! Generated scenes for tests and benches (deterministic, seeded).

use crate::error::Result;
use crate::geom::Point2;
use crate::map::{CellState, GridGeometry, OccupancyGrid};

/// A `width_m × height_m` walled site at `resolution` with `obstacles` random boxes and disks (seeded), and a
/// few long interior walls with gaps, like a cluttered warehouse or yard. The start is near (1, 1).
pub fn cluttered_site(
    width_m: f64,
    height_m: f64,
    resolution: f64,
    obstacles: usize,
    seed: u64,
) -> Result<OccupancyGrid> {
    let (w, h) = (
        (width_m / resolution).round() as usize,
        (height_m / resolution).round() as usize,
    );
    let g = GridGeometry::new(w, h, resolution, Point2::origin())?;
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    let t = 2.0 * resolution;
    grid.fill_rect(0.0, 0.0, width_m, t, CellState::Occupied);
    grid.fill_rect(0.0, height_m - t, width_m, height_m, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, t, height_m, CellState::Occupied);
    grid.fill_rect(width_m - t, 0.0, width_m, height_m, CellState::Occupied);
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407) | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 1_000_000) as f64 / 1_000_000.0
    };
    // Interior walls with doors every so often.
    let walls = ((width_m / 25.0) as usize).max(1);
    for k in 1..=walls {
        let x = width_m * k as f64 / (walls + 1) as f64;
        let mut y = 0.0;
        while y < height_m {
            let len = 5.0 + next() * 15.0;
            grid.fill_rect(x, y, x + t, (y + len).min(height_m), CellState::Occupied);
            y += len + 1.5 + next() * 2.0;
        }
    }
    // Keep the dock corner clear.
    for _ in 0..obstacles {
        let (x, y) = (next() * width_m, next() * height_m);
        if x < 3.0 && y < 3.0 {
            continue;
        }
        if next() < 0.5 {
            grid.fill_disk(Point2::new(x, y), 0.15 + next() * 0.8, CellState::Occupied);
        } else {
            let (a, b) = (0.3 + next() * 3.0, 0.3 + next() * 1.5);
            grid.fill_rect(x, y, x + a, y + b, CellState::Occupied);
        }
    }
    Ok(grid)
}
