//! The occupancy grid: cells, their states and the map-frame geometry of the raster.
//!
//! Convention: cell `(x, y)` is column `x` and row `y`, row 0 at the map origin (the *bottom* row of a ROS
//! map image). The linear index is `y * width + x`. The centre of cell `(x, y)` is
//! `origin + ((x + 0.5) · resolution, (y + 0.5) · resolution)` in the map frame, metres.

use crate::error::{PlannerError, Result, finite};
use crate::geom::Point2;

/// What a cell is, after the map's thresholds were applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CellState {
    /// Occupancy probability below `free_thresh`.
    Free,
    /// Occupancy probability above `occupied_thresh`.
    Occupied,
    /// Anything else: never free.
    Unknown,
}

/// Cell coordinates (column, row), row 0 at the map origin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Column.
    pub x: usize,
    /// Row (0 at the origin).
    pub y: usize,
}

impl Cell {
    /// Cell at column `x`, row `y`.
    pub const fn new(x: usize, y: usize) -> Self {
        Self { x, y }
    }
}

/// The raster geometry shared by every grid-shaped layer (occupancy, distance, labels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGeometry {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Metres per cell edge.
    pub resolution: f64,
    /// Map-frame position of the outer corner of cell (0, 0), metres.
    pub origin: Point2,
}

impl GridGeometry {
    /// Most cells a grid may have: 64 Mi (8192 × 8192, 410 m square at 5 cm). A plan on it needs a few GiB
    /// (distance fields, masks, labels); a width and height declared beyond it are refused before anything of
    /// that size is allocated.
    pub const MAX_CELLS: usize = 1 << 26;

    /// Validates and builds a geometry: non-empty, at most [`Self::MAX_CELLS`] cells, a positive finite
    /// resolution and a finite origin.
    pub fn new(width: usize, height: usize, resolution: f64, origin: Point2) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(PlannerError::EmptyMap { width, height });
        }
        Self::check_size(width, height)?;
        if !resolution.is_finite() || resolution <= 0.0 {
            return Err(PlannerError::InvalidResolution(resolution));
        }
        finite("origin x", origin.x)?;
        finite("origin y", origin.y)?;
        Ok(Self {
            width,
            height,
            resolution,
            origin,
        })
    }

    /// Refuses a width × height over [`Self::MAX_CELLS`] (or one that overflows).
    pub fn check_size(width: usize, height: usize) -> Result<()> {
        match width.checked_mul(height) {
            Some(n) if n <= Self::MAX_CELLS => Ok(()),
            _ => Err(PlannerError::MapTooLarge {
                width,
                height,
                max_cells: Self::MAX_CELLS,
            }),
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Always false for a validated geometry; present for API symmetry with `len`.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of a cell.
    #[inline]
    pub fn index(&self, c: Cell) -> usize {
        c.y * self.width + c.x
    }

    /// Cell of a linear index.
    #[inline]
    pub fn cell(&self, i: usize) -> Cell {
        Cell::new(i % self.width, i / self.width)
    }

    /// Map-frame centre of a cell, metres.
    #[inline]
    pub fn center(&self, c: Cell) -> Point2 {
        Point2::new(
            self.origin.x + (c.x as f64 + 0.5) * self.resolution,
            self.origin.y + (c.y as f64 + 0.5) * self.resolution,
        )
    }

    /// Map-frame centre of the cell with linear index `i`.
    #[inline]
    pub fn center_of(&self, i: usize) -> Point2 {
        self.center(self.cell(i))
    }

    /// Cell containing map-frame point `p`, or `None` outside the map (or for a non-finite point).
    #[inline]
    pub fn locate(&self, p: Point2) -> Option<Cell> {
        let fx = (p.x - self.origin.x) / self.resolution;
        let fy = (p.y - self.origin.y) / self.resolution;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        // Truncation is the floor for these non-negative values (and saturates for +inf, which fails below);
        // `floor` is a library call on baseline x86-64.
        let (x, y) = (fx as usize, fy as usize);
        (x < self.width && y < self.height).then_some(Cell::new(x, y))
    }

    /// Continuous cell coordinates of `p` (cell centres at half-integers), unclamped.
    #[inline]
    pub fn to_cell_coords(&self, p: Point2) -> (f64, f64) {
        (
            (p.x - self.origin.x) / self.resolution,
            (p.y - self.origin.y) / self.resolution,
        )
    }

    /// The (up to) 8 neighbours of a cell that lie on the grid.
    pub fn neighbors8(&self, c: Cell) -> impl Iterator<Item = Cell> + '_ {
        const D: [(isize, isize); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];
        D.iter().filter_map(move |&(dx, dy)| self.offset(c, dx, dy))
    }

    /// The (up to) 4 edge neighbours of a cell that lie on the grid.
    pub fn neighbors4(&self, c: Cell) -> impl Iterator<Item = Cell> + '_ {
        const D: [(isize, isize); 4] = [(0, -1), (-1, 0), (1, 0), (0, 1)];
        D.iter().filter_map(move |&(dx, dy)| self.offset(c, dx, dy))
    }

    /// `c + (dx, dy)` when that lies on the grid.
    #[inline]
    pub fn offset(&self, c: Cell, dx: isize, dy: isize) -> Option<Cell> {
        let x = c.x.checked_add_signed(dx)?;
        let y = c.y.checked_add_signed(dy)?;
        (x < self.width && y < self.height).then_some(Cell::new(x, y))
    }
}

/// An occupancy grid after thresholds: one [`CellState`] per cell.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    /// Raster geometry.
    pub geometry: GridGeometry,
    /// Row-major cell states, row 0 at the origin.
    pub cells: Vec<CellState>,
}

impl OccupancyGrid {
    /// Builds a grid, checking that `cells` has `width × height` entries.
    pub fn new(geometry: GridGeometry, cells: Vec<CellState>) -> Result<Self> {
        let expected = geometry.len();
        if cells.len() != expected {
            return Err(PlannerError::SizeMismatch {
                width: geometry.width,
                height: geometry.height,
                expected,
                got: cells.len(),
            });
        }
        Ok(Self { geometry, cells })
    }

    /// A grid of `width × height` free cells (tests and generated scenes).
    pub fn filled(geometry: GridGeometry, state: CellState) -> Self {
        Self {
            cells: vec![state; geometry.len()],
            geometry,
        }
    }

    /// State of a cell.
    #[inline]
    pub fn state(&self, c: Cell) -> CellState {
        self.cells[self.geometry.index(c)]
    }

    /// True when the cell is free.
    #[inline]
    pub fn is_free(&self, i: usize) -> bool {
        self.cells[i] == CellState::Free
    }

    /// Sets a cell's state.
    pub fn set(&mut self, c: Cell, state: CellState) {
        let i = self.geometry.index(c);
        self.cells[i] = state;
    }

    /// Marks every cell whose centre lies in the axis-aligned rectangle `[x0, x1] × [y0, y1]` (metres).
    pub fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, state: CellState) {
        for i in 0..self.cells.len() {
            let p = self.geometry.center_of(i);
            if p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1 {
                self.cells[i] = state;
            }
        }
    }

    /// Marks every cell whose centre lies within `radius` metres of `centre`.
    pub fn fill_disk(&mut self, centre: Point2, radius: f64, state: CellState) {
        for i in 0..self.cells.len() {
            if (self.geometry.center_of(i) - centre).norm() <= radius {
                self.cells[i] = state;
            }
        }
    }

    /// Number of free cells.
    pub fn free_count(&self) -> usize {
        self.cells.iter().filter(|&&s| s == CellState::Free).count()
    }
}

/// Occupancy thresholds as in ROS map_server: probability `p` is free below `free`, occupied above
/// `occupied`, unknown between.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Below this occupancy probability a cell is free.
    pub free: f64,
    /// Above this occupancy probability a cell is occupied.
    pub occupied: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            free: 0.196,
            occupied: 0.65,
        }
    }
}

impl Thresholds {
    /// Validates `0 ≤ free ≤ occupied ≤ 1`, both finite.
    pub fn validate(&self) -> Result<()> {
        finite("free_thresh", self.free)?;
        finite("occupied_thresh", self.occupied)?;
        if !(0.0..=1.0).contains(&self.free) || !(0.0..=1.0).contains(&self.occupied) || self.free > self.occupied {
            return Err(PlannerError::InvalidParam {
                name: "thresholds",
                reason: format!(
                    "need 0 <= free_thresh ({}) <= occupied_thresh ({}) <= 1",
                    self.free, self.occupied
                ),
            });
        }
        Ok(())
    }

    /// Classifies an occupancy probability in [0, 1].
    #[inline]
    pub fn classify(&self, p: f64) -> CellState {
        if p > self.occupied {
            CellState::Occupied
        } else if p < self.free {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_and_center_round_trip() {
        let g = GridGeometry::new(4, 3, 0.5, Point2::new(-1.0, 2.0)).expect("valid");
        for i in 0..g.len() {
            let c = g.cell(i);
            assert_eq!(g.locate(g.center(c)), Some(c));
            assert_eq!(g.index(c), i);
        }
        assert_eq!(g.locate(Point2::new(-1.01, 2.1)), None);
        assert_eq!(g.locate(Point2::new(1.0, 2.1)), None);
        assert_eq!(g.locate(Point2::new(f64::NAN, 2.1)), None);
    }

    #[test]
    fn geometry_rejects_bad_input() {
        assert!(matches!(
            GridGeometry::new(0, 3, 0.5, Point2::origin()),
            Err(PlannerError::EmptyMap { .. })
        ));
        assert!(matches!(
            GridGeometry::new(3, 3, 0.0, Point2::origin()),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            GridGeometry::new(3, 3, -1.0, Point2::origin()),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            GridGeometry::new(3, 3, f64::NAN, Point2::origin()),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            GridGeometry::new(3, 3, 0.1, Point2::new(f64::INFINITY, 0.0)),
            Err(PlannerError::NonFinite { .. })
        ));
    }

    #[test]
    fn neighbours_stay_on_grid() {
        let g = GridGeometry::new(3, 3, 1.0, Point2::origin()).expect("valid");
        assert_eq!(g.neighbors8(Cell::new(0, 0)).count(), 3);
        assert_eq!(g.neighbors8(Cell::new(1, 1)).count(), 8);
        assert_eq!(g.neighbors4(Cell::new(2, 1)).count(), 3);
    }
}
