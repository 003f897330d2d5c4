//! Where a footprinted plan lays its patterns. A robot that turns in place sweeps its circumscribed disc in
//! every turn of 90° or more (a rectangle's diagonal passes every direction), and boustrophedon lanes turn
//! at both ends: lanes whose ends are closer to a wall than the circumscribed radius cannot be driven, and
//! the repair would cut them back or drop them. So patterns go where the circumscribed disc fits, and the
//! footprint earns its keep on the ways between: doorways and aisles it passes lengthwise.
//!
//! - [`LaneSpace::Disc`]: the space of the disc in which the robot turns freely, from the same start: the
//!   circumscribed radius plus half the diagonal of a blocked cell grown by the check's margin (a space
//!   measures clearance between cell centres; the polygon must stay off the cells' squares). Its plan is what
//!   that disc would drive, and every pose of it is clear at any heading. Chosen when that disc reaches
//!   every part of the site where it fits at all.
//! - [`LaneSpace::Turning`]: the inscribed space (transits through every place the inscribed disc reaches)
//!   with patterns confined to its cells where that disc fits, and only what lies within half a tool of
//!   those to cover. Chosen when that disc cannot reach all of them from the start (rooms behind a doorway
//!   only the footprint passes lengthwise).
//! - [`LaneSpace::Inscribed`]: lanes in the inscribed space itself, as close to walls as the inscribed disc
//!   goes, repaired where the body cannot follow (measured lower: lane ends at a wall cannot be turned at).

use std::borrow::Cow;

use crate::footprint::FootprintCheck;
use crate::map::DistanceField;
use crate::space::{CoverageSpace, RobotShape};

/// The choice of pattern space (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LaneSpace {
    /// `Disc` when the circumscribed disc reaches every cell where it fits, else `Turning`.
    #[default]
    Auto,
    /// The circumscribed disc's own space.
    Disc,
    /// The inscribed space, patterns where the circumscribed disc fits.
    Turning,
    /// The inscribed space as it is.
    Inscribed,
}

/// Share of the cells where the circumscribed disc fits that may lie out of its reach (specks) for `Auto`
/// to choose `Disc`.
const UNREACHED_SHARE: f64 = 0.005;

/// The space patterns are laid in on `inscribed` for the footprint `check` decides (see [`LaneSpace`]), and
/// what was chosen.
pub fn lane_space<'s>(
    inscribed: &'s CoverageSpace,
    check: &FootprintCheck<'_>,
    choice: LaneSpace,
) -> (Cow<'s, CoverageSpace>, LaneSpace) {
    let g = *inscribed.geometry();
    // Cells the inscribed disc reaches where the robot turns freely: clearance (centre to centre, as a space
    // counts it) of the circumscribed radius plus half a blocked cell's grown diagonal. A disc space of that
    // radius keeps every point of its paths there, so its lanes turn at their ends by construction.
    let rc = check.turning_clearance_m() + 1e-6;
    let fits: Vec<bool> = (0..g.len())
        .map(|i| inscribed.reachable[i] && inscribed.clearance.at(i) >= rc)
        .collect();
    let turning = |fits: &[bool]| {
        let to_fits = DistanceField::compute(g, |i| fits[i], false);
        let half = inscribed.robot.tool_width_m / 2.0 + 1e-9;
        let keep: Vec<bool> = (0..g.len())
            .map(|i| inscribed.coverable[i] && to_fits.at(i) <= half)
            .collect();
        inscribed.with_work(inscribed.start_cell, inscribed.start, &keep, fits)
    };
    let disc = || {
        let robot = RobotShape {
            radius_m: rc,
            tool_width_m: inscribed.robot.tool_width_m,
        };
        CoverageSpace::new(inscribed.grid.clone(), robot, inscribed.start).ok()
    };
    let n_fits = fits.iter().filter(|&&f| f).count();
    match choice {
        LaneSpace::Inscribed => (Cow::Borrowed(inscribed), LaneSpace::Inscribed),
        LaneSpace::Turning if n_fits > 0 => (Cow::Owned(turning(&fits)), LaneSpace::Turning),
        LaneSpace::Disc => match disc() {
            Some(d) => (Cow::Owned(d), LaneSpace::Disc),
            None => (Cow::Borrowed(inscribed), LaneSpace::Inscribed),
        },
        LaneSpace::Turning => (Cow::Borrowed(inscribed), LaneSpace::Inscribed),
        LaneSpace::Auto => {
            if n_fits == 0 {
                return (Cow::Borrowed(inscribed), LaneSpace::Inscribed);
            }
            if let Some(d) = disc() {
                let unreached = (0..g.len()).filter(|&i| fits[i] && !d.reachable[i]).count();
                if (unreached as f64) <= UNREACHED_SHARE * n_fits as f64 {
                    return (Cow::Owned(d), LaneSpace::Disc);
                }
            }
            (Cow::Owned(turning(&fits)), LaneSpace::Turning)
        }
    }
}
