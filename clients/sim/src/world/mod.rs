//! The hidden world the robots drive in: the site's map, obstacles the daemon does not know, and movers. It
//! answers the laser's rays and says when a robot touches something.

pub mod file;
pub mod movers;
pub mod raycast;
pub mod shapes;

use std::path::Path;

use shift_planner::geom::Point2;
use shift_planner::map::{CellState, OccupancyGrid, load_ros_map};

use self::file::{ObstacleSpec, RobotSpecFile, WorldFile};
use self::movers::Mover;
use self::raycast::cast_grid;
use self::shapes::Solid;
use crate::error::SimError;

/// The world: map, hidden static solids, movers, and the robots' specs.
#[derive(Debug, Clone)]
pub struct World {
    /// The site's map as loaded (what the daemon knows too).
    pub grid: OccupancyGrid,
    /// Non-free cells of the map: walls for the laser and for collisions (DESIGN §6: unknown is not free).
    solid: Vec<bool>,
    /// Hidden static obstacles.
    pub obstacles: Vec<Solid>,
    /// Moving obstacles.
    pub movers: Vec<Mover>,
    /// The robots of the world file.
    pub robots: Vec<RobotSpecFile>,
}

impl World {
    /// Reads a world file and the map it names (relative to the world file's folder).
    pub fn load(path: &Path) -> Result<Self, SimError> {
        let io = |p: &Path, e| SimError::Io {
            path: p.display().to_string(),
            source: e,
        };
        let text = std::fs::read_to_string(path).map_err(|e| io(path, e))?;
        let file = WorldFile::parse(&text)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let yaml_path = dir.join(&file.map);
        let yaml = std::fs::read_to_string(&yaml_path).map_err(|e| io(&yaml_path, e))?;
        let yaml_dir = yaml_path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let map = load_ros_map(&yaml, |image| {
            let p = yaml_dir.join(image);
            std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))
        })
        .map_err(|e| SimError::Map(format!("{}: {e}", yaml_path.display())))?;
        Ok(Self::new(map.grid, file))
    }

    /// A world on `grid` with the file's obstacles, movers and robots.
    pub fn new(grid: OccupancyGrid, file: WorldFile) -> Self {
        let solid = (0..grid.cells.len()).map(|i| !grid.is_free(i)).collect();
        let obstacles = file
            .obstacles
            .iter()
            .map(|o| match *o {
                ObstacleSpec::Box([x0, y0, x1, y1]) => Solid::aabb(x0, y0, x1, y1),
                ObstacleSpec::Disc([x, y, r]) => Solid::disc(Point2::new(x, y), r),
            })
            .collect();
        Self {
            grid,
            solid,
            obstacles,
            movers: file.movers.into_iter().map(Mover::new).collect(),
            robots: file.robots,
        }
    }

    /// Distance along the unit direction `dir` from `origin` to the first thing the laser sees, within
    /// `max_range`.
    pub fn cast(&self, origin: Point2, dir: (f64, f64), max_range: f64) -> Option<f64> {
        let mut best = cast_grid(&self.grid.geometry, &self.solid, origin, dir, max_range);
        let solids = self.obstacles.iter().chain(self.movers.iter().map(|m| &m.solid));
        for s in solids {
            let limit = best.unwrap_or(max_range);
            if let Some(t) = s.cast(origin, dir, limit)
                && t <= limit
            {
                best = Some(t);
            }
        }
        best
    }

    /// True when a disc of radius `r` at `centre` touches the static world: a non-free map cell whose centre is
    /// closer than `r` (DESIGN §6's collision), or a hidden obstacle deeper than half a cell (parry's
    /// intersection test with the disc shrunk by half a cell). Both allow the same reach: a plan keeps the radius
    /// from cell centres, so the body may reach half a cell into a wall, and into a hidden obstacle alike.
    pub fn collides(&self, centre: Point2, r: f64) -> bool {
        let half_cell = self.grid.geometry.resolution / 2.0;
        self.obstacles.iter().any(|o| o.overlaps_disc(centre, r - half_cell)) || self.touches_map(centre, r)
    }

    fn touches_map(&self, centre: Point2, r: f64) -> bool {
        let g = &self.grid.geometry;
        let (fx, fy) = g.to_cell_coords(centre);
        let reach = (r / g.resolution).ceil() + 1.0;
        let x0 = (fx - reach).floor().max(0.0) as usize;
        let y0 = (fy - reach).floor().max(0.0) as usize;
        let x1 = ((fx + reach).ceil().max(0.0) as usize).min(g.width);
        let y1 = ((fy + reach).ceil().max(0.0) as usize).min(g.height);
        (y0..y1).any(|y| {
            (x0..x1).any(|x| {
                let i = y * g.width + x;
                self.solid[i] && (g.center_of(i) - centre).norm() < r
            })
        }) || g.locate(centre).is_none()
    }

    /// True when a disc of radius `r` at `centre` overlaps a mover.
    pub fn touches_mover(&self, centre: Point2, r: f64) -> bool {
        self.movers.iter().any(|m| m.solid.overlaps_disc(centre, r))
    }

    /// Advances the movers by `dt` seconds; they turn back rather than walk into a robot.
    pub fn step_movers(&mut self, dt: f64, robots: &[(Point2, f64)]) {
        for m in &mut self.movers {
            m.step(dt, robots);
        }
    }

    /// The map with the hidden static obstacles burned in (cells whose centre lies inside one are occupied):
    /// what can really be covered.
    pub fn static_grid(&self) -> OccupancyGrid {
        let mut grid = self.grid.clone();
        let g = grid.geometry;
        for i in 0..g.len() {
            if grid.is_free(i) && self.obstacles.iter().any(|o| o.contains(g.center_of(i))) {
                grid.cells[i] = CellState::Occupied;
            }
        }
        grid
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_planner::map::GridGeometry;

    /// A 6 m × 4 m room at 0.1 m with a wall all round.
    pub(crate) fn room() -> OccupancyGrid {
        let g = GridGeometry::new(60, 40, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for i in 0..g.len() {
            let c = g.cell(i);
            if c.x == 0 || c.y == 0 || c.x == 59 || c.y == 39 {
                grid.cells[i] = CellState::Occupied;
            }
        }
        grid
    }

    fn world(obstacles: Vec<ObstacleSpec>) -> World {
        World::new(
            room(),
            WorldFile {
                map: "m.yaml".into(),
                obstacles,
                movers: vec![],
                robots: vec![],
            },
        )
    }

    #[test]
    fn the_laser_sees_walls_and_hidden_boxes() {
        let w = world(vec![ObstacleSpec::Box([3.0, 1.5, 3.5, 2.5])]);
        let t = w.cast(Point2::new(1.0, 2.0), (1.0, 0.0), 10.0).expect("box");
        assert!((t - 2.0).abs() < 1e-5, "{t}");
        let t = w.cast(Point2::new(1.0, 2.0), (-1.0, 0.0), 10.0).expect("wall");
        assert!((t - 0.9).abs() < 1e-9, "{t}");
        assert_eq!(w.cast(Point2::new(1.0, 2.0), (-1.0, 0.0), 0.5), None);
    }

    #[test]
    fn collisions_follow_design_and_parry() {
        let w = world(vec![ObstacleSpec::Disc([3.0, 2.0, 0.5])]);
        assert!(!w.collides(Point2::new(1.0, 2.0), 0.25));
        // The wall's cell centres are at x = 0.05: a 0.25 m disc at x = 0.29 reaches them.
        assert!(w.collides(Point2::new(0.29, 2.0), 0.25));
        assert!(!w.collides(Point2::new(0.31, 2.0), 0.25));
        // The hidden disc's surface is at x = 2.5; the body may reach half a 0.1 m cell into it.
        assert!(w.collides(Point2::new(2.32, 2.0), 0.25));
        assert!(!w.collides(Point2::new(2.28, 2.0), 0.25));
        assert!(w.collides(Point2::new(-1.0, 2.0), 0.25), "off the map");
        let g = w.static_grid();
        let centre = g.geometry.locate(Point2::new(3.0, 2.0)).expect("cell");
        assert_eq!(g.state(centre), CellState::Occupied);
        // π · 0.5² m² at 0.01 m² per cell: about 79 cells fewer are free.
        let lost = w.grid.free_count() - g.free_count();
        assert!((70..=90).contains(&lost), "{lost}");
    }
}
