//! Occupancy grids given as JSON, shaped like nav_msgs/OccupancyGrid (DESIGN §5.3):
//! `{"resolution", "origin": [x, y], "width", "height", "cells": [..]}`, row-major from the origin row,
//! values 0 free … 100 occupied, −1 unknown. Optional `free_thresh` / `occupied_thresh` (probabilities,
//! defaults as map_server) decide which percentages count as free or occupied.

use serde::Deserialize;

use super::grid::{CellState, GridGeometry, OccupancyGrid, Thresholds};
use crate::error::{PlannerError, Result, finite};
use crate::geom::Point2;

/// The JSON grid document.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JsonGrid {
    /// Metres per cell.
    pub resolution: f64,
    /// Map-frame position of cell (0, 0)'s outer corner, metres.
    pub origin: [f64; 2],
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major occupancy percentages (−1 unknown).
    pub cells: Vec<i16>,
    /// Free below this probability (default 0.196).
    #[serde(default)]
    pub free_thresh: Option<f64>,
    /// Occupied above this probability (default 0.65).
    #[serde(default)]
    pub occupied_thresh: Option<f64>,
}

impl JsonGrid {
    /// Parses JSON text.
    pub fn parse(text: &str) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| PlannerError::InvalidParam {
            name: "json grid",
            reason: e.to_string(),
        })
    }

    /// Validates and thresholds into an [`OccupancyGrid`].
    pub fn into_grid(self) -> Result<OccupancyGrid> {
        finite("origin x", self.origin[0])?;
        finite("origin y", self.origin[1])?;
        let geometry = GridGeometry::new(
            self.width,
            self.height,
            self.resolution,
            Point2::new(self.origin[0], self.origin[1]),
        )?;
        let defaults = Thresholds::default();
        let t = Thresholds {
            free: self.free_thresh.unwrap_or(defaults.free),
            occupied: self.occupied_thresh.unwrap_or(defaults.occupied),
        };
        t.validate()?;
        if self.cells.len() != geometry.len() {
            return Err(PlannerError::SizeMismatch {
                width: self.width,
                height: self.height,
                expected: geometry.len(),
                got: self.cells.len(),
            });
        }
        let mut cells = Vec::with_capacity(self.cells.len());
        for (i, &v) in self.cells.iter().enumerate() {
            cells.push(match v {
                -1 => CellState::Unknown,
                0..=100 => t.classify(f64::from(v) / 100.0),
                _ => {
                    return Err(PlannerError::InvalidParam {
                        name: "cells",
                        reason: format!("cell {i} has value {v}; expected -1 or 0..=100"),
                    });
                }
            });
        }
        OccupancyGrid::new(geometry, cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_thresholds() {
        let g = JsonGrid::parse(r#"{"resolution":0.1,"origin":[0,0],"width":2,"height":2,"cells":[0,100,-1,50]}"#)
            .expect("parse")
            .into_grid()
            .expect("valid");
        assert_eq!(
            g.cells,
            vec![
                CellState::Free,
                CellState::Occupied,
                CellState::Unknown,
                CellState::Unknown
            ]
        );
    }

    #[test]
    fn rejects_bad_grids() {
        let bad = |s: &str| JsonGrid::parse(s).and_then(JsonGrid::into_grid);
        assert!(matches!(
            bad(r#"{"resolution":0.1,"origin":[0,0],"width":2,"height":2,"cells":[0]}"#),
            Err(PlannerError::SizeMismatch { .. })
        ));
        assert!(matches!(
            bad(r#"{"resolution":0,"origin":[0,0],"width":1,"height":1,"cells":[0]}"#),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            bad(r#"{"resolution":0.1,"origin":[0,0],"width":0,"height":1,"cells":[]}"#),
            Err(PlannerError::EmptyMap { .. })
        ));
        assert!(matches!(
            bad(r#"{"resolution":0.1,"origin":[0,0],"width":1,"height":1,"cells":[101]}"#),
            Err(PlannerError::InvalidParam { .. })
        ));
        assert!(bad(r#"{"resolution":0.1}"#).is_err());
        assert!(bad("not json").is_err());
    }

    #[test]
    fn absurd_sizes_are_refused_before_anything_is_allocated() {
        let bad = |s: &str| JsonGrid::parse(s).and_then(JsonGrid::into_grid);
        // 10^12 cells declared in a few bytes, and a width × height that overflows usize.
        for doc in [
            r#"{"resolution":1,"origin":[0,0],"width":1000000,"height":1000000,"cells":[]}"#,
            r#"{"resolution":1,"origin":[0,0],"width":18446744073709551615,"height":3,"cells":[]}"#,
        ] {
            let e = bad(doc).expect_err(doc);
            assert!(matches!(e, PlannerError::MapTooLarge { .. }), "{e}");
            assert!(e.to_string().contains("width"), "{e}");
        }
    }
}
