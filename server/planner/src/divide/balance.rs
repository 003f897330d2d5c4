//! Step 2 of [`divide`](super::divide): the weights that balance the robots' loads.

use super::work::Work;
use super::{DivideParams, RobotField};

/// Reachable cells (of any robot) above which the first balancing iterations run on a sample of them.
const SAMPLE_CELLS: usize = 100_000;

/// Per reachable cell of any robot, every robot's distance to it and the work it stands for.
pub(super) struct Table {
    /// Grid indices of the cells some robot can reach.
    pub cells: Vec<u32>,
    /// `dist[r][k]`: robot r's grid distance to cell k, metres (infinite where r cannot reach it).
    pub dist: Vec<Vec<f32>>,
    /// `work[r][k]`: seconds robot r spends on the coverable cells nearest to cell k.
    pub work: Vec<Vec<f32>>,
    /// `gap[i][j]`: how much further robot j's start is from robot i than from robot j, metres. Robot j keeps
    /// its start while `w[j] < w[i] + gap[i][j]`.
    pub gap: Vec<Vec<f64>>,
}

impl Table {
    /// `work`: each robot's expected seconds per coverable cell.
    pub fn new(fields: &[RobotField], work: &Work<'_>) -> Self {
        let n = fields[0].space.reachable.len();
        let cells: Vec<u32> = (0..n)
            .filter(|&i| fields.iter().any(|f| f.space.reachable[i]))
            .map(|i| i as u32)
            .collect();
        let mut slot = vec![u32::MAX; n];
        for (k, &i) in cells.iter().enumerate() {
            slot[i as usize] = k as u32;
        }
        let dist = fields
            .iter()
            .map(|f| cells.iter().map(|&i| f.dist[i as usize] as f32).collect())
            .collect();
        let work = fields
            .iter()
            .enumerate()
            .map(|(r, f)| {
                let mut w = vec![0.0_f32; cells.len()];
                for i in (0..n).filter(|&i| f.space.coverable[i]) {
                    let k = f.to_reachable.nearest_site_index(i).map_or(u32::MAX, |j| slot[j]);
                    if let Some(x) = w.get_mut(k as usize) {
                        *x += work.at(r, i) as f32;
                    }
                }
                w
            })
            .collect();
        let gap = fields
            .iter()
            .map(|fi| {
                fields
                    .iter()
                    .map(|fj| {
                        let i = fj.space.geometry().index(fj.start_cell);
                        fi.dist[i] - fj.dist[i]
                    })
                    .collect()
            })
            .collect();
        Self { cells, dist, work, gap }
    }

    /// The robot of cell `k` for `weights`: least distance plus weight, ties to the lower index.
    #[inline]
    pub fn owner(&self, k: usize, weights: &[f64]) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for (r, w) in weights.iter().enumerate() {
            let d = f64::from(self.dist[r][k]);
            if d.is_finite() && best.is_none_or(|(b, _)| d + w < b) {
                best = Some((d + w, r));
            }
        }
        best.map(|(_, r)| r)
    }

    /// Every robot's load (seconds) for `weights`, counting every `stride`-th cell (scaled back up).
    fn loads(&self, weights: &[f64], stride: usize) -> Vec<f64> {
        let mut loads = vec![0.0; weights.len()];
        for k in (0..self.cells.len()).step_by(stride) {
            if let Some(r) = self.owner(k, weights) {
                loads[r] += f64::from(self.work[r][k]);
            }
        }
        loads.iter_mut().for_each(|l| *l *= stride as f64);
        loads
    }

    /// Moves the weights onto the set where every robot keeps its start (`w[j] < w[i] + gap[i][j]` for all
    /// i ≠ j, a margin of a millimetre): each violated pair is projected onto its constraint, the two weights
    /// moving half the excess each (their sum kept), in Gauss–Seidel passes.
    ///
    /// Why both move: a robot whose start lies on the border with a neighbour forms a pair with it whose
    /// border cannot move further, and the pair must move as one, by the sum of both robots' wishes. Lowering
    /// only the robot whose start is threatened let its neighbour's wish alone drag the pair: a neighbour
    /// short of work pulled a robot with too much work along, which then could not shed to its other side.
    fn keep_starts(&self, weights: &mut [f64]) {
        let n = weights.len();
        for _ in 0..4 * n {
            let mut moved = false;
            for j in 0..n {
                for i in (0..n).filter(|&i| i != j) {
                    let excess = weights[j] - (weights[i] + self.gap[i][j] - 1e-3);
                    if excess > 0.0 {
                        weights[j] -= 0.5 * excess;
                        weights[i] += 0.5 * excess;
                        moved = true;
                    }
                }
            }
            if !moved {
                break;
            }
        }
        // Whatever the passes left (a cycle of tight pairs), the plain cap settles: every start is kept.
        for _ in 0..n {
            let mut moved = false;
            for j in 0..n {
                for i in (0..n).filter(|&i| i != j) {
                    let cap = weights[i] + self.gap[i][j] - 1e-3;
                    if weights[j] > cap {
                        weights[j] = cap;
                        moved = true;
                    }
                }
            }
            if !moved {
                break;
            }
        }
    }
}

/// Longest over shortest load; infinite when a robot has none.
fn spread(loads: &[f64]) -> f64 {
    let lo = loads.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = loads.iter().copied().fold(0.0, f64::max);
    if lo > 0.0 { hi / lo } else { f64::INFINITY }
}

/// The balancing weights, and whether they reach `params.balance_tol`. Iterates on a sample of the cells
/// first (every `stride`-th, about [`SAMPLE_CELLS`] of them), then on all; each stage keeps the best weights
/// it saw. The step grows while the spread shrinks and halves when it grows (the loads jump when a weight
/// moves a whole room, so plain gradient steps would oscillate), but never falls below a subgradient
/// schedule (a quarter of the distance scale over √(iteration + 1)): where a room toggles between two
/// robots at every step, halving alone froze every weight within a few dozen iterations, while a third
/// robot's steady excess (a neighbour's weight dragged along by the toggling) still needed hundreds of
/// small steps to drain (a corridor site with four docks stuck at an expected-load ratio of 1.19 reached
/// 1.08 with the floor).
pub(super) fn balance(table: &Table, params: &DivideParams) -> (Vec<f64>, bool) {
    let n = table.dist.len();
    let mut weights = vec![0.0; n];
    if n == 1 || table.cells.is_empty() {
        return (weights, true);
    }
    // The distance scale: the mean distance from a cell to its nearest start.
    let (sum, count) = (0..table.cells.len())
        .step_by(table.cells.len().div_ceil(10_000).max(1))
        .map(|k| {
            (0..n)
                .map(|r| f64::from(table.dist[r][k]))
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|d| d.is_finite())
        .fold((0.0, 0usize), |(s, c), d| (s + d, c + 1));
    let near = if count > 0 { sum / count as f64 } else { 1.0 };
    let target = 1.0 + params.balance_tol;
    let sample = table.cells.len().div_ceil(SAMPLE_CELLS);
    let [first, then] = params.iterations;
    let stages = if sample > 1 {
        vec![(sample, first), (1, then)]
    } else {
        vec![(1, first + then)]
    };
    for (stride, iterations) in stages {
        let mut step = near * 0.25;
        let mut best = (f64::INFINITY, weights.clone());
        let mut last = f64::INFINITY;
        for it in 0..iterations.max(1) {
            let loads = table.loads(&weights, stride);
            let s = spread(&loads);
            if s < best.0 {
                best = (s, weights.clone());
            }
            if s <= target {
                break;
            }
            step *= if s < last { 1.2 } else { 0.5 };
            step = step.max(near * 0.25 / (1.0 + it as f64).sqrt());
            last = s;
            let mean = loads.iter().sum::<f64>() / n as f64;
            for (w, l) in weights.iter_mut().zip(&loads) {
                *w += step * ((l - mean) / mean).clamp(-1.0, 1.0);
            }
            table.keep_starts(&mut weights);
        }
        weights = best.1;
    }
    let reached = spread(&table.loads(&weights, 1)) <= target;
    (weights, reached)
}

#[cfg(test)]
mod tests {
    use super::Table;

    fn table(gap: Vec<Vec<f64>>) -> Table {
        Table {
            cells: Vec::new(),
            dist: Vec::new(),
            work: Vec::new(),
            gap,
        }
    }

    #[test]
    fn a_tight_pair_moves_as_one_keeping_the_sum_of_its_weights() {
        // Robot 1's start is 5 m further from robot 0 than from itself; weights 0 and 10 would hand it to
        // robot 0. Both weights move half the excess: the pair keeps the sum of what both robots asked for.
        let t = table(vec![vec![0.0, 5.0], vec![5.0, 0.0]]);
        let mut w = vec![0.0, 10.0];
        t.keep_starts(&mut w);
        assert!((w[0] + w[1] - 10.0).abs() < 1e-9, "{w:?}");
        assert!(w[1] < w[0] + 5.0 && w[1] > w[0] + 4.99, "{w:?}");
    }

    #[test]
    fn every_start_is_kept_after_the_projection() {
        // Three robots in a row (gaps 4 and 6 m) with weights far outside the feasible set.
        let gap = vec![vec![0.0, 4.0, 10.0], vec![4.0, 0.0, 6.0], vec![10.0, 6.0, 0.0]];
        let t = table(gap.clone());
        for start in [[0.0, 20.0, -20.0], [30.0, -5.0, 12.0], [-9.0, 0.0, 40.0]] {
            let mut w = start.to_vec();
            t.keep_starts(&mut w);
            for i in 0..3 {
                for j in (0..3).filter(|&j| j != i) {
                    assert!(
                        w[j] < w[i] + gap[i][j],
                        "{start:?} -> {w:?}: robot {j} loses its start to {i}"
                    );
                }
            }
        }
    }
}
