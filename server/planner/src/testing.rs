//! Generated scenes for tests and benches (deterministic, seeded).

use crate::error::Result;
use crate::geom::Point2;
use crate::map::{CellState, GridGeometry, OccupancyGrid};

/// `n` docks spread round the rim of a `side_m` square site, 1 m in from the walls, in equal steps along it
/// ([`cluttered_site`] keeps (1, 1) clear; a fleet's division moves the others onto reachable cells).
pub fn rim_docks(side_m: f64, n: usize) -> Vec<Point2> {
    (0..n)
        .map(|k| {
            let t = k as f64 / n as f64 * 4.0;
            let (s, e) = (side_m - 1.5, t.fract() * (side_m - 2.5) + 1.0);
            match t as usize {
                0 => Point2::new(e, 1.0),
                1 => Point2::new(s, e),
                2 => Point2::new(side_m - e, s),
                _ => Point2::new(1.0, side_m - e),
            }
        })
        .collect()
}

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

/// Two walled rooms side by side with a doorway in the wall between them, the whole geometry turned by an
/// angle: see [`two_rooms`].
#[derive(Debug, Clone)]
pub struct TwoRooms {
    /// The rasterised site (a cell is a wall when its centre is in one; everything round the rooms is wall).
    pub grid: OccupancyGrid,
    /// A start in the near room, 1 m from its corner walls, map frame, metres.
    pub start: Point2,
    /// The doorway's centre, map frame, metres.
    pub door: Point2,
    /// Heading straight through the doorway from the near room to the far one, radians.
    pub through_rad: f64,
    /// Each room's size: along the doorway's axis, across it, metres.
    pub room_m: (f64, f64),
    /// Wall thickness, metres.
    pub wall_m: f64,
    /// Doorway width, metres.
    pub door_m: f64,
    centre: Point2,
    angle_rad: f64,
}

impl TwoRooms {
    /// `p` in the rooms' own frame (x along the doorway's axis, origin at the outer corner of the near room's
    /// wall), metres.
    pub fn local(&self, p: Point2) -> Point2 {
        let (s, c) = self.angle_rad.sin_cos();
        let d = p - self.centre;
        let (lx, ly) = self.local_size();
        Point2::new(c * d.x + s * d.y + lx / 2.0, -s * d.x + c * d.y + ly / 2.0)
    }

    fn local_size(&self) -> (f64, f64) {
        (
            2.0 * self.room_m.0 + 3.0 * self.wall_m,
            self.room_m.1 + 2.0 * self.wall_m,
        )
    }

    /// True when `p` lies in the far room (beyond the dividing wall).
    pub fn in_far_room(&self, p: Point2) -> bool {
        let q = self.local(p);
        let (t, (l, h)) = (self.wall_m, self.room_m);
        q.x > 2.0 * t + l && q.x < 2.0 * t + 2.0 * l && q.y > t && q.y < t + h
    }

    /// True when `p` lies in the near room.
    pub fn in_near_room(&self, p: Point2) -> bool {
        let q = self.local(p);
        let (t, (l, h)) = (self.wall_m, self.room_m);
        q.x > t && q.x < t + l && q.y > t && q.y < t + h
    }

    /// True when `p` lies in the dividing wall's band (in the doorway if it is free).
    pub fn in_wall_band(&self, p: Point2) -> bool {
        let q = self.local(p);
        q.x >= self.wall_m + self.room_m.0 && q.x <= 2.0 * self.wall_m + self.room_m.0
    }
}

/// Two rooms of `room_m` (length along the doorway's axis, width across it) with walls `wall_m` thick, the
/// dividing wall holding a doorway `door_m` wide at its middle, turned by `angle_rad` about the site's
/// centre and rasterised at `resolution`.
pub fn two_rooms(room_m: (f64, f64), wall_m: f64, door_m: f64, angle_rad: f64, resolution: f64) -> Result<TwoRooms> {
    let (lx, ly) = (2.0 * room_m.0 + 3.0 * wall_m, room_m.1 + 2.0 * wall_m);
    let (s, c) = angle_rad.sin_cos();
    // The turned outer box's half extents, plus a cell.
    let (ex, ey) = (
        (c.abs() * lx + s.abs() * ly) / 2.0 + resolution,
        (s.abs() * lx + c.abs() * ly) / 2.0 + resolution,
    );
    let (w, h) = (
        (2.0 * ex / resolution).ceil() as usize,
        (2.0 * ey / resolution).ceil() as usize,
    );
    let g = GridGeometry::new(w, h, resolution, Point2::origin())?;
    let centre = Point2::new(w as f64 * resolution / 2.0, h as f64 * resolution / 2.0);
    let mut rooms = TwoRooms {
        grid: OccupancyGrid::filled(g, CellState::Occupied),
        start: Point2::origin(),
        door: Point2::origin(),
        through_rad: angle_rad,
        room_m,
        wall_m,
        door_m,
        centre,
        angle_rad,
    };
    let to_map = |q: Point2| {
        let d = Point2::new(q.x - lx / 2.0, q.y - ly / 2.0);
        Point2::new(centre.x + c * d.x - s * d.y, centre.y + s * d.x + c * d.y)
    };
    let (t, (l, rh)) = (wall_m, room_m);
    for i in 0..g.len() {
        let q = rooms.local(g.center_of(i));
        let in_y = q.y > t && q.y < t + rh;
        let near = q.x > t && q.x < t + l;
        let far = q.x > 2.0 * t + l && q.x < 2.0 * t + 2.0 * l;
        let doorway = q.x >= t + l && q.x <= 2.0 * t + l && (q.y - (t + rh / 2.0)).abs() < door_m / 2.0;
        if (in_y && (near || far)) || doorway {
            rooms.grid.cells[i] = CellState::Free;
        }
    }
    rooms.start = to_map(Point2::new(t + 1.0, t + 1.0));
    rooms.door = to_map(Point2::new(1.5 * t + l, t + rh / 2.0));
    Ok(rooms)
}
