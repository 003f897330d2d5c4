//! The time a robot is expected to spend on a cell: what division balances.

use super::FleetRobot;
use crate::map::GridGeometry;
use crate::speed::attribute::AttributeMap;
use crate::speed::dwell::DwellLaw;

/// Expected seconds per coverable cell, per robot: lanes one tool width apart driven at the speed the
/// attribute asks for there (RFICP's law, [`DwellLaw`], over the attribute's range on the fleet's coverable
/// area; full speed without an attribute map), plus the turns at the lanes' ends, times the place's
/// calibration.
///
/// **Turns.** A lane ends in a U-turn: two sharp corners, each slowed to a stop and accelerated back, which
/// costs about 2·v/a seconds over driving on at v (each of the four ramps takes v/a seconds for v²/(2a) of
/// distance, which at v would take v/(2a): each loses v/(2a)). A lane of length L a tool w wide sweeps L·w, so per cell of area A the turns add
/// (2·v/a)·A/(w·L) to the lane's A/(w·v): a factor 1 + 2·v²/(a·L). L is the longer straight run of
/// coverable cells through the cell, along the rows or the columns (lanes follow the longer way; at least a
/// tool width). In an open hall (L of tens of metres) the factor is near 1; between shelves and on a ragged
/// SLAM map, where lanes run a metre or two, it is 2 to 5, which is what plans there take over the area
/// estimate. (Measured with `shiftd eval --robots 2,3,4` on the shared scenes: the worst longest-over-shortest
/// planned duration went from 1.17 to 1.13 with the factor; the rounds of [`crate::pipeline::fleet`] still
/// correct what it misses.)
pub(super) struct Work<'a> {
    /// Per robot: cell area / tool width, m (divide by a speed for seconds).
    per_speed: Vec<f64>,
    /// Per cell: planned over expected time learned there (see [`super::divide`]).
    calibration: Option<&'a [f64]>,
    /// Per robot: its speed law, with the attribute map.
    laws: Vec<DwellLaw>,
    attribute: Option<&'a AttributeMap>,
    v_max: Vec<f64>,
    a_max: Vec<f64>,
    tool_width: Vec<f64>,
    /// Per cell: the longer of its straight runs of coverable cells along the grid's rows and columns, m.
    runs: Vec<f32>,
}

/// Per cell, the longer of the row run and the column run of `mask` cells it lies in, metres (0 off the mask).
fn run_lengths(g: &GridGeometry, mask: &[bool]) -> Vec<f32> {
    let (w, h) = (g.width, g.height);
    let mut runs = vec![0.0_f32; g.len()];
    let mut mark = |cells: &mut dyn Iterator<Item = usize>| {
        let cells: Vec<usize> = cells.collect();
        let mut k = 0;
        while k < cells.len() {
            if !mask[cells[k]] {
                k += 1;
                continue;
            }
            let end = (k..cells.len()).find(|&j| !mask[cells[j]]).unwrap_or(cells.len());
            let len = ((end - k) as f64 * g.resolution) as f32;
            for &i in &cells[k..end] {
                runs[i] = runs[i].max(len);
            }
            k = end;
        }
    };
    for y in 0..h {
        mark(&mut (0..w).map(|x| y * w + x));
    }
    for x in 0..w {
        mark(&mut (0..h).map(|y| y * w + x));
    }
    runs
}

impl<'a> Work<'a> {
    /// `coverable`: the fleet's coverable cells (for the attribute's range).
    pub fn new(
        robots: &[FleetRobot],
        calibration: Option<&'a [f64]>,
        g: &GridGeometry,
        attribute: Option<&'a AttributeMap>,
        coverable: &[bool],
    ) -> Self {
        let cell_area_m2 = g.resolution * g.resolution;
        let (a_lo, a_hi) = attribute.and_then(|a| a.range_over(coverable)).unwrap_or((1.0, 1.0));
        let per_speed = robots.iter().map(|r| cell_area_m2 / r.shape.tool_width_m).collect();
        let laws = robots
            .iter()
            .map(|r| DwellLaw::for_range(a_lo, a_hi, r.shape.tool_width_m, &r.limits))
            .collect();
        Self {
            per_speed,
            calibration,
            laws,
            attribute,
            v_max: robots.iter().map(|r| r.limits.v_max_mps).collect(),
            a_max: robots.iter().map(|r| r.limits.a_max_mps2).collect(),
            tool_width: robots.iter().map(|r| r.shape.tool_width_m).collect(),
            runs: run_lengths(g, coverable),
        }
    }

    /// Robot `r`'s expected seconds on cell `i`.
    pub fn at(&self, r: usize, i: usize) -> f64 {
        let v = match self.attribute {
            Some(a) => self.laws[r].speed(a.at(i)),
            None => self.v_max[r],
        };
        let c = self
            .calibration
            .and_then(|c| c.get(i))
            .copied()
            .filter(|c| c.is_finite() && *c > 0.0)
            .unwrap_or(1.0);
        let run = f64::from(self.runs[i]).max(self.tool_width[r]);
        let turns = 1.0 + 2.0 * v * v / (self.a_max[r] * run);
        c * self.per_speed[r] / v * turns
    }
}

#[cfg(test)]
mod tests {
    use super::run_lengths;
    use crate::geom::Point2;
    use crate::map::GridGeometry;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn run_lengths_match_counting_along_rows_and_columns(w in 1usize..12, h in 1usize..12, bits in proptest::collection::vec(any::<bool>(), 144)) {
            let g = GridGeometry::new(w, h, 0.5, Point2::origin()).expect("geometry");
            let mask: Vec<bool> = (0..g.len()).map(|i| bits[i]).collect();
            let runs = run_lengths(&g, &mask);
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    // Brute force: walk both ways along the row and the column while the mask holds.
                    let count = |dx: i64, dy: i64| {
                        let mut n = 0;
                        let (mut cx, mut cy) = (x as i64 + dx, y as i64 + dy);
                        while cx >= 0 && cy >= 0 && (cx as usize) < w && (cy as usize) < h && mask[cy as usize * w + cx as usize] {
                            n += 1;
                            cx += dx;
                            cy += dy;
                        }
                        n
                    };
                    let want = if mask[i] {
                        0.5 * (1 + count(1, 0) + count(-1, 0)).max(1 + count(0, 1) + count(0, -1)) as f64
                    } else {
                        0.0
                    };
                    prop_assert!((f64::from(runs[i]) - want).abs() < 1e-6, "({x}, {y}): {} vs {want}", runs[i]);
                }
            }
        }
    }
}
