//! A grid-sized set of cells kept as run lengths: how a mission's coverable cells and a measured coverage
//! raster are persisted and recorded (a 4 M-cell site with a few thousand runs is a few kilobytes, where the
//! cells one by one would be megabytes).

use serde::{Deserialize, Serialize};

use crate::error::{EngineError, Result};

/// Cells as alternating run lengths, starting with a run of cells *not* in the set (possibly empty).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct CellMask {
    /// Cells of the grid.
    pub len: usize,
    /// Run lengths: out, in, out, in, … summing to `len`.
    pub runs: Vec<u32>,
}

impl CellMask {
    /// The runs of `cells`.
    pub fn encode(cells: &[bool]) -> Self {
        let mut runs = Vec::new();
        let mut state = false;
        let mut run = 0u32;
        for &c in cells {
            if c != state || run == u32::MAX {
                runs.push(run);
                if c == state {
                    // A run longer than u32 holds: an empty run of the other state continues it.
                    runs.push(0);
                }
                state = c;
                run = 0;
            }
            run += 1;
        }
        runs.push(run);
        Self { len: cells.len(), runs }
    }

    /// The cells, checked: the runs must sum to `len`, which must be `expect_len` (the grid the mask is for).
    pub fn decode(&self, expect_len: usize) -> Result<Vec<bool>> {
        if self.len != expect_len {
            return Err(EngineError::InvalidRequest(format!(
                "cell mask holds {} cells; its grid has {expect_len}",
                self.len
            )));
        }
        let mut cells = Vec::with_capacity(self.len);
        let mut state = false;
        for &run in &self.runs {
            let n = run as usize;
            if cells.len() + n > self.len {
                return Err(EngineError::InvalidRequest("cell mask runs overflow its grid".into()));
            }
            cells.resize(cells.len() + n, state);
            state = !state;
        }
        if cells.len() != self.len {
            return Err(EngineError::InvalidRequest(format!(
                "cell mask runs cover {} of {} cells",
                cells.len(),
                self.len
            )));
        }
        Ok(cells)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #[test]
        fn runs_round_trip(cells in proptest::collection::vec(any::<bool>(), 0..400)) {
            let mask = CellMask::encode(&cells);
            prop_assert_eq!(mask.runs.iter().map(|&r| r as usize).sum::<usize>(), cells.len());
            prop_assert_eq!(mask.decode(cells.len()).expect("decodes"), cells);
        }
    }

    #[test]
    fn a_mask_for_another_grid_or_with_bad_runs_is_refused() {
        let mask = CellMask::encode(&[true, true, false]);
        assert_eq!(mask.runs, vec![0, 2, 1]);
        assert!(mask.decode(4).is_err());
        let bad = CellMask {
            len: 3,
            runs: vec![1, 5],
        };
        assert!(bad.decode(3).is_err());
        let short = CellMask { len: 3, runs: vec![1] };
        assert!(short.decode(3).is_err());
    }
}
