//! What is left to cover of a site once part of it is covered (issue 20, resume and replan): the coverable
//! cells the measured coverage raster does not show swept, cleaned so that the replan never shatters.
//!
//! A measured raster's boundary is a staircase, lanes leave hairline gaps between them, and a robot's
//! wobble leaves speckle; planned as they are, these are hundreds of slivers a robot would drive a pass
//! along for a few new cells each. The cleaning rule, with every threshold derived from the tool:
//!
//! 1. **Uncovered**: coverable cells not marked covered.
//! 2. **Worth a pass** (slivers): a reachable cell `c` is a *seed* when the tool disc centred on it (radius
//!    tool_width / 2: what the tool sweeps with the robot's centre there) finds enough new ground: at least
//!    `φ(min_new_share)` of the coverable cells in the disc are uncovered, where φ(t) = (2/π)(asin t +
//!    t√(1−t²)) is the share of a disc that a centred strip `t` tool widths wide holds. So a pass along a
//!    sliver `s` wide (which sweeps `s / tool_width` new ground) finds seeds only when `s / tool_width`
//!    reaches `min_new_share` (default ½: a pass must sweep at least as much new ground as covered). The
//!    uncovered cells kept are those some seed's disc sweeps: everything a pass worth driving would cover.
//!    A large uncovered piece keeps every cell (every tool disc inside it is all new ground, and its
//!    staircase edge lies within a disc of the seeds just inside it); a sliver beside covered ground, or
//!    a speck, is dropped.
//! 3. **Tiny pieces**: kept pieces of fewer cells than `min_piece_discs` tool discs are joined to a larger
//!    kept piece within a tool width (the robot covers them from there: its work zone, below, reaches
//!    both) and dropped otherwise.
//!
//! Everything dropped is counted (slivers and tiny pieces apart, [`Remainder::dropped_area_m2`]) so the
//! caller can say what the replan leaves out. A piece that holds a whole tool disc of uncovered ground
//! around a reachable cell is never lost (the disc is kept, and its piece holds a disc's cells).
//!
//! The *work zone* is where the replan's patterns may lie: the reachable cells whose tool disc reaches a
//! kept cell. The replan ([`crate::pipeline::remainder`]) decomposes it alone ([`CoverageSpace::work`]),
//! so lanes sit on the remainder and transits cross covered ground.

pub(crate) mod disc;
#[cfg(test)]
pub(crate) mod tests;

use crate::error::{PlannerError, Result};
use crate::parallel::map_indexed;
use crate::space::CoverageSpace;
use disc::{Disc, RowSums, pieces};

/// Knobs of [`remainder`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RemainderParams {
    /// A pass is worth driving when at least this share of the swath it sweeps is new ground (see the
    /// module docs), in [0, 1]; 0 keeps every uncovered cell a reachable centre's tool reaches.
    pub min_new_share: f64,
    /// Kept pieces smaller than this many tool discs are joined to a larger piece within a tool width, or
    /// dropped; 0 keeps them all.
    pub min_piece_discs: f64,
}

impl Default for RemainderParams {
    fn default() -> Self {
        Self {
            min_new_share: 0.5,
            min_piece_discs: 1.0,
        }
    }
}

impl RemainderParams {
    /// Checks both knobs: `min_new_share` in [0, 1], `min_piece_discs` finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.min_new_share) {
            return Err(PlannerError::InvalidParam {
                name: "min_new_share",
                reason: format!("must be a share in [0, 1], got {}", self.min_new_share),
            });
        }
        if !(self.min_piece_discs.is_finite() && self.min_piece_discs >= 0.0) {
            return Err(PlannerError::InvalidParam {
                name: "min_piece_discs",
                reason: format!("must be a non-negative number, got {}", self.min_piece_discs),
            });
        }
        Ok(())
    }
}

/// What is left to cover, cleaned (see the module docs), with its figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Remainder {
    /// Per grid cell: still to cover (coverable, uncovered, kept by the cleaning rule).
    pub keep: Vec<bool>,
    /// Per grid cell: a reachable cell whose tool disc reaches a kept cell (where the replan's patterns lie).
    pub work: Vec<bool>,
    /// Coverable cells not covered, before cleaning.
    pub uncovered_cells: usize,
    /// Uncovered cells no pass worth driving would sweep (slivers and specks along covered ground).
    pub dropped_sliver_cells: usize,
    /// Uncovered cells in tiny pieces with no larger piece within a tool width.
    pub dropped_tiny_cells: usize,
    /// Kept cells.
    pub kept_cells: usize,
    /// 8-connected pieces of the uncovered cells, before cleaning.
    pub pieces_before: usize,
    /// 8-connected pieces of the kept cells, each tiny piece counted with the larger one it was joined to.
    pub pieces_after: usize,
    /// 8-connected pieces of the work zone (places the robot goes; kept pieces within a tool width of each
    /// other share one).
    pub work_pieces: usize,
    /// Area of one cell, m².
    pub cell_area_m2: f64,
}

impl Remainder {
    /// Uncovered coverable area before cleaning, m².
    pub fn uncovered_area_m2(&self) -> f64 {
        self.uncovered_cells as f64 * self.cell_area_m2
    }

    /// Area left out by the cleaning (slivers and tiny pieces), m².
    pub fn dropped_area_m2(&self) -> f64 {
        (self.dropped_sliver_cells + self.dropped_tiny_cells) as f64 * self.cell_area_m2
    }

    /// Area still to cover, m².
    pub fn area_m2(&self) -> f64 {
        self.kept_cells as f64 * self.cell_area_m2
    }

    /// A remark for the user when the cleaning left something out.
    pub fn warning(&self) -> Option<String> {
        (self.dropped_sliver_cells + self.dropped_tiny_cells > 0).then(|| {
            format!(
                "the replan leaves out {:.2} m² of the {:.2} m² uncovered: {:.2} m² in slivers along covered ground \
                 and {:.2} m² in tiny pieces, where a pass would sweep mostly covered ground",
                self.dropped_area_m2(),
                self.uncovered_area_m2(),
                self.dropped_sliver_cells as f64 * self.cell_area_m2,
                self.dropped_tiny_cells as f64 * self.cell_area_m2
            )
        })
    }
}

/// Share of a disc's area inside a centred strip `t` diameters wide (φ in the module docs), `t` in [0, 1].
pub fn strip_share(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    2.0 / std::f64::consts::PI * (t.asin() + t * (1.0 - t * t).sqrt())
}

/// The cleaned remainder of `space` given the `covered` flags (one per grid cell, row-major), see the module
/// docs. Errors: `covered` of the wrong length, knobs out of range.
pub fn remainder(space: &CoverageSpace, covered: &[bool], params: &RemainderParams) -> Result<Remainder> {
    params.validate()?;
    let g = *space.geometry();
    if covered.len() != g.len() {
        return Err(PlannerError::InvalidParam {
            name: "covered",
            reason: format!("needs one flag per grid cell ({}), got {}", g.len(), covered.len()),
        });
    }
    let uncovered: Vec<bool> = (0..g.len()).map(|i| space.coverable[i] && !covered[i]).collect();
    let tool = Disc::new(space.robot.tool_width_m / 2.0, g.resolution);
    // 2. Seeds: reachable centres whose tool disc finds enough new ground.
    let share = strip_share(params.min_new_share);
    let seeds = {
        let new = RowSums::new(&g, |i| uncovered[i]);
        let ground = RowSums::new(&g, |i| space.coverable[i]);
        // Rows with no uncovered cell within a disc's reach hold no seed (a covered band is skipped whole).
        let reach = tool.rows();
        let mut near = vec![false; g.height];
        for y in (0..g.height).filter(|&y| uncovered[y * g.width..(y + 1) * g.width].contains(&true)) {
            near[y.saturating_sub(reach)..=(y + reach).min(g.height - 1)].fill(true);
        }
        let seed = map_indexed(g.len(), |i| {
            if !(space.reachable[i] && near[i / g.width]) {
                return false;
            }
            let n = new.count(&tool, i);
            n > 0 && f64::from(n) >= share * f64::from(ground.count(&tool, i)) - 1e-9
        });
        RowSums::new(&g, |i| seed[i])
    };
    let swept = map_indexed(g.len(), |i| uncovered[i] && seeds.any(&tool, i));
    drop(seeds);
    // 3. Tiny pieces: joined to a larger piece within a tool width, or dropped.
    let (id, sizes) = pieces(&g, &swept);
    let small = (params.min_piece_discs * tool.cells as f64).ceil() as usize;
    let is_big = |i: usize| id[i] != u32::MAX && sizes[id[i] as usize] >= small;
    let mut joined = vec![false; sizes.len()];
    if sizes.iter().any(|&s| s < small) {
        let big = RowSums::new(&g, is_big);
        let reach = Disc::new(space.robot.tool_width_m, g.resolution);
        for (i, &k) in id.iter().enumerate() {
            if k != u32::MAX && sizes[k as usize] < small && !joined[k as usize] && big.any(&reach, i) {
                joined[k as usize] = true;
            }
        }
    }
    let keep: Vec<bool> = (0..g.len())
        .map(|i| is_big(i) || (id[i] != u32::MAX && joined[id[i] as usize]))
        .collect();
    let work = {
        let kept = RowSums::new(&g, |i| keep[i]);
        map_indexed(g.len(), |i| space.reachable[i] && kept.any(&tool, i))
    };
    let count = |m: &[bool]| m.iter().filter(|&&b| b).count();
    let (uncovered_cells, swept_cells, kept_cells) = (count(&uncovered), count(&swept), count(&keep));
    Ok(Remainder {
        uncovered_cells,
        dropped_sliver_cells: uncovered_cells - swept_cells,
        dropped_tiny_cells: swept_cells - kept_cells,
        kept_cells,
        pieces_before: pieces(&g, &uncovered).1.len(),
        pieces_after: sizes.iter().filter(|&&s| s >= small).count(),
        work_pieces: pieces(&g, &work).1.len(),
        cell_area_m2: g.resolution * g.resolution,
        keep,
        work,
    })
}
