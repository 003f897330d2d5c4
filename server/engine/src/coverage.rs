//! Measured coverage: the cells a robot's tool really swept, stamped along its odometry while it drives a plan
//! (issue 20). One raster per site (every plan driven there) and one per mission (its plans only, counted
//! against the mission's coverable cells). The raster is the truth a replan of the remainder starts from, so it
//! is committed to the store at intervals and when the daemon stops, and read back at start.

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_planner::geom::Point2;
use shift_planner::map::grid::GridGeometry;
use shift_planner::metrics::coverage::for_each_cell_in_capsule;

use crate::cell_mask::CellMask;
use crate::error::Result;

/// Whose raster a record is.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(tag = "of", content = "id", rename_all = "snake_case")]
pub enum CoverageKey {
    /// Everything driven on a site.
    Site(String),
    /// A mission's plans.
    Mission(String),
}

impl CoverageKey {
    /// The store's key (`site/NAME`, `mission/ID`).
    pub fn store_key(&self) -> String {
        match self {
            Self::Site(s) => format!("site/{s}"),
            Self::Mission(m) => format!("mission/{m}"),
        }
    }
}

/// A raster as the store keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageRecord {
    /// Whose.
    pub key: CoverageKey,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Metres per cell.
    pub resolution: f64,
    /// Map-frame corner of cell (0, 0), metres.
    pub origin: [f64; 2],
    /// Swept cells.
    pub covered: CellMask,
    /// Last stamp, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

/// One measured raster.
#[derive(Debug, Clone)]
pub struct Raster {
    geometry: GridGeometry,
    covered: Vec<bool>,
    /// Only these cells count (a mission's coverable cells); `None`: every cell.
    within: Option<Arc<Vec<bool>>>,
    /// Swept cells that count.
    counted: usize,
    /// Cells that count.
    total: usize,
    /// Stamped since the store last took it.
    pub dirty_store: bool,
    /// Stamped since the read model last took it.
    pub dirty_view: bool,
    /// Last stamp, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

impl Raster {
    /// An empty raster over `geometry`, counting only `within` when given (its length must be the grid's).
    pub fn new(geometry: GridGeometry, within: Option<Arc<Vec<bool>>>) -> Self {
        let n = geometry.len();
        let within = within.filter(|w| w.len() == n);
        let total = within.as_ref().map_or(n, |w| w.iter().filter(|&&c| c).count());
        Self {
            geometry,
            covered: vec![false; n],
            within,
            counted: 0,
            total,
            dirty_store: false,
            dirty_view: false,
            updated_ms: 0,
        }
    }

    /// A raster read back from `record` (which must be over `geometry`).
    pub fn restore(geometry: GridGeometry, within: Option<Arc<Vec<bool>>>, record: &CoverageRecord) -> Result<Self> {
        let mut r = Self::new(geometry, within);
        r.covered = record.covered.decode(geometry.len())?;
        r.counted = (0..r.covered.len()).filter(|&i| r.covered[i] && r.counts(i)).count();
        r.updated_ms = record.updated_ms;
        Ok(r)
    }

    fn counts(&self, i: usize) -> bool {
        self.within.as_ref().is_none_or(|w| w[i])
    }

    /// Marks the cells whose centre is within `half_width_m` of segment `a`–`b`; returns how many that count
    /// were newly swept.
    pub fn stamp(&mut self, a: Point2, b: Point2, half_width_m: f64, now_ms: u64) -> usize {
        let mut fresh = 0;
        let mut touched = false;
        let (covered, within) = (&mut self.covered, &self.within);
        for_each_cell_in_capsule(&self.geometry, a, b, half_width_m, |i| {
            if !covered[i] {
                covered[i] = true;
                touched = true;
                if within.as_ref().is_none_or(|w| w[i]) {
                    fresh += 1;
                }
            }
        });
        self.counted += fresh;
        if touched {
            self.dirty_store = true;
            self.dirty_view = true;
            self.updated_ms = now_ms;
        }
        fresh
    }

    /// Swept share of the cells that count, percent (100 when none count).
    pub fn pct(&self) -> f64 {
        if self.total == 0 {
            100.0
        } else {
            self.counted as f64 / self.total as f64 * 100.0
        }
    }

    /// Every cell, swept or not.
    pub fn covered(&self) -> &[bool] {
        &self.covered
    }

    /// The grid it is over.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Its record for the store.
    pub fn record(&self, key: CoverageKey) -> CoverageRecord {
        let g = &self.geometry;
        CoverageRecord {
            key,
            width: g.width,
            height: g.height,
            resolution: g.resolution,
            origin: [g.origin.x, g.origin.y],
            covered: CellMask::encode(&self.covered),
            updated_ms: self.updated_ms,
        }
    }
}

impl CoverageRecord {
    /// True when the record is over `g`.
    pub fn fits(&self, g: &GridGeometry) -> bool {
        self.width == g.width
            && self.height == g.height
            && self.resolution == g.resolution
            && self.origin == [g.origin.x, g.origin.y]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> GridGeometry {
        GridGeometry::new(20, 10, 0.1, Point2::new(0.0, 0.0)).expect("geometry")
    }

    #[test]
    fn a_stamp_counts_new_cells_inside_the_mask_only_and_survives_the_store() {
        let g = geometry();
        // Only the left half counts.
        let within: Vec<bool> = (0..g.len()).map(|i| i % 20 < 10).collect();
        let mut r = Raster::new(g, Some(Arc::new(within.clone())));
        assert_eq!(r.pct(), 0.0);
        // A 0.24 m wide swath along y = 0.55 across the whole width: 3 rows of 20 cells (centres 0.45–0.65).
        let fresh = r.stamp(Point2::new(0.0, 0.55), Point2::new(2.0, 0.55), 0.12, 7);
        assert_eq!(fresh, 30, "3 rows × 10 counted columns");
        assert!((r.pct() - 30.0).abs() < 1e-9, "{}", r.pct());
        assert_eq!(r.stamp(Point2::new(0.0, 0.55), Point2::new(2.0, 0.55), 0.12, 8), 0);
        assert!(r.dirty_store && r.dirty_view);
        let rec = r.record(CoverageKey::Mission("m-1".into()));
        let back = Raster::restore(g, Some(Arc::new(within)), &rec).expect("restores");
        assert_eq!(back.covered(), r.covered());
        assert_eq!(back.pct(), r.pct());
        assert!(rec.fits(&g));
        let other = GridGeometry::new(21, 10, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        assert!(!rec.fits(&other));
        assert!(Raster::restore(other, None, &rec).is_err());
    }

    #[test]
    fn non_finite_poses_stamp_nothing() {
        let mut r = Raster::new(geometry(), None);
        assert_eq!(r.stamp(Point2::new(f64::NAN, 0.5), Point2::new(1.0, 0.5), 0.15, 1), 0);
        assert!(!r.dirty_store);
    }
}
