//! Escapes: a robot that saw an obstacle late and is already closer than its radius to it.
//!
//! Every patch starts at the start anchor, on the path at or ahead of the robot. When the anchor is itself
//! closer than the radius to live obstacle points (the obstacle was seen when the robot was already beside it,
//! or its voxels quantise it a few millimetres nearer than the laser did), no patch can keep the radius from
//! its first point, and [`super::repair`] used to fail at every check while the robot drove on into the
//! obstacle along its old path. The escape plans as if the robot were as thin as the clearance it has now,
//! then accepts the patch only when it never comes closer than that and has the full radius back within a
//! short way: no further than twice the missing clearance plus two point spacings (the optimiser's heading
//! neighbours), so it leads out of the band instead of squeezing through a gap the robot does not fit. From
//! there on it is checked at the full radius. A robot closer than the radius to the static map is not
//! escaped: plans keep the radius from it, so that is not a late sight but a robot off its plan, and nothing
//! is published for it (the error stands).

use crate::geom::{Point2, point_segment_distance};

use super::params::CorrectParams;
use super::verify::verify;
use super::world::{STATIC_SLACK_M, World};
use super::{Breach, Escape, Repair};

/// The floor stays this far under the anchor's clearance, metres: the chord-sag allowance of the verifier at
/// the anchor itself, and the f32 rounding of live points, fit in it.
const FLOOR_SLACK_M: f64 = 1e-3;
/// The escape stretch is checked at this step, metres.
const STEP_M: f64 = 0.01;

/// A start anchor an escape may start from: the robot is inside the band of live obstacles only.
#[derive(Debug, Clone, Copy)]
pub(super) struct EscapeCase {
    anchor: Point2,
    floor: f64,
    /// The params to repair with: a robot as thin as the clearance it has now, aiming at the same d_safe.
    pub(super) thin: CorrectParams,
}

impl EscapeCase {
    /// The case of a repair whose first start anchor `anchor` is in collision, or `None` when it is not an
    /// escape's (off the map, inside the static band, on a live point, or clear after all).
    pub(super) fn new(world: &World<'_>, p: &CorrectParams, anchor: Point2) -> Option<Self> {
        let r = p.robot_radius_m;
        if !world.inside(anchor) || world.static_clearance_upto(anchor, r) < r - STATIC_SLACK_M {
            return None;
        }
        let floor = world.live_clearance(anchor) - FLOOR_SLACK_M;
        if !(floor > 0.0 && floor < r) {
            return None;
        }
        let thin = CorrectParams {
            robot_radius_m: floor,
            static_radius_m: p.static_radius_m.min(floor),
            margin_m: p.d_safe() - floor,
            ..*p
        };
        Some(Self { anchor, floor, thin })
    }

    /// `rep` (a repair of `breach` on `path` with [`Self::thin`]) as an escape, when it leads out of the band;
    /// `None` otherwise.
    pub(super) fn accept(
        &self,
        mut rep: Repair,
        path: &[Point2],
        breach: &Breach,
        world: &World<'_>,
        p: &CorrectParams,
    ) -> Option<Repair> {
        if !leads_out(&rep.waypoints, world, p, self.floor) {
            return None;
        }
        // Needed only when the path itself does not lead out as an escape would.
        let own = path_from(path, breach.earliest.seg, self.anchor);
        rep.escape = Some(Escape {
            floor_m: self.floor,
            needed: regains(&own, world, p, self.floor).is_none(),
        });
        Some(rep)
    }
}

/// True when `points` keep `floor` from live points (and the radius, less the static slack, from the static
/// map) until they are clear of the full radius, get there within the escape's allowance, and keep the full
/// radius from there on ([`verify`]). A single point (a stop at the anchor) leads nowhere closer.
fn leads_out(points: &[Point2], world: &World<'_>, p: &CorrectParams, floor: f64) -> bool {
    if let [only] = points {
        return world.live_clearance(*only) >= floor;
    }
    let Some((k, q)) = regains(points, world, p, floor) else {
        return false;
    };
    let mut rest = Vec::with_capacity(points.len() - k);
    rest.push(q);
    rest.extend_from_slice(&points[k + 1..]);
    verify(&rest, world, p.robot_radius_m)
}

/// Where the polyline `points` first has the full radius back (segment index and point), when it keeps
/// `floor` from live points and the radius less the static slack from the static map until then and gets
/// there within the escape's allowance; `None` otherwise.
fn regains(points: &[Point2], world: &World<'_>, p: &CorrectParams, floor: f64) -> Option<(usize, Point2)> {
    let r = p.robot_radius_m;
    let allowance = 2.0 * (r - floor) + 2.0 * p.spacing_m;
    let mut driven = 0.0;
    for (k, w) in points.windows(2).enumerate() {
        let len = (w[1] - w[0]).norm();
        let n = (len / STEP_M).ceil().max(1.0) as usize;
        for j in 0..n {
            let f = j as f64 / n as f64;
            let q = w[0] + (w[1] - w[0]) * f;
            if world.clear_of(q, r + FLOOR_SLACK_M) {
                return Some((k, q));
            }
            let keeps_floor = world.inside(q)
                && world.live_clearance(q) >= floor
                && world.static_clearance_upto(q, r) >= r - STATIC_SLACK_M;
            if driven + len * f > allowance || !keeps_floor {
                return None;
            }
        }
        driven += len;
    }
    None
}

/// The path from `anchor` on: the anchor, then the waypoints after the first segment from `from_seg` on that
/// holds it.
fn path_from(path: &[Point2], from_seg: usize, anchor: Point2) -> Vec<Point2> {
    let seg = (from_seg..path.len().saturating_sub(1))
        .find(|&k| point_segment_distance(anchor, path[k], path[k + 1]) < 1e-6)
        .unwrap_or(path.len().saturating_sub(1));
    let mut out = Vec::with_capacity(path.len() - seg);
    out.push(anchor);
    out.extend_from_slice(&path[(seg + 1).min(path.len())..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correct::tests::{Site, after_arc, walled};
    use crate::correct::{CorrectError, apply, judge, repair, worth_publishing};

    /// Along y = 5 from x = 1 to 9, every 0.1 m.
    fn lane() -> Vec<Point2> {
        (10..=90).map(|i| Point2::new(f64::from(i) * 0.1, 5.0)).collect()
    }

    /// A row of live points `gap` m beside the lane from x = 2.8 to 4.5 (a shelf seen when the robot was level
    /// with it).
    fn shelf(gap: f64) -> Vec<Point2> {
        (0..=85)
            .map(|i| Point2::new(2.8 + f64::from(i) * 0.02, 5.0 + gap))
            .collect()
    }

    #[test]
    fn a_robot_level_with_a_shelf_it_saw_late_is_led_out_of_the_band_and_then_kept_at_its_radius() {
        let site = Site::new(walled(10.0, 10.0), shelf(0.29));
        let world = site.world();
        let p = CorrectParams::default();
        let r = p.robot_radius_m;
        let path = lane();
        let robot = Point2::new(3.0, 5.0);
        let b = judge(&path, 20, robot, &world, &p);
        assert!(!b.is_empty() && b[0].min_clearance_m < r, "{b:?}");
        let rep = repair(&path, &b[0], &world, &p).expect("an escape");
        let e = rep.escape.expect("an escape, not a patch at the full radius");
        assert!(e.needed, "the lane stays 0.29 m from the shelf for 1.7 m");
        assert!((e.floor_m - (0.29 - FLOOR_SLACK_M)).abs() < 1e-4, "{e:?}");
        assert!(worth_publishing(&b[0], &rep, &world, &p));
        // Never closer than the robot is now; the full radius within the allowance and from there on.
        let allowance = 2.0 * (r - e.floor_m) + 2.0 * p.spacing_m;
        let (clear, on_map) = site.oracle(&rep.waypoints);
        assert!(on_map && clear >= e.floor_m - 1e-6, "{clear}");
        let (clear, _) = site.oracle(&after_arc(&rep.waypoints, allowance + STEP_M));
        assert!(clear >= r - 1e-6, "{clear} after the allowance");
        assert!((rep.waypoints[0] - robot).norm() < 1e-6, "starts where the robot is");

        // Driving it: the next check from the same place finds the escape stretch, and does not publish again.
        let escaped = apply(&path, &rep);
        let b = judge(&escaped, 20, robot, &world, &p);
        if let Some(first) = b.first() {
            match repair(&escaped, first, &world, &p) {
                Ok(again) => assert!(!worth_publishing(first, &again, &world, &p), "{again:?}"),
                Err(e) => panic!("the escaped path cannot be checked: {e}"),
            }
        }
    }

    #[test]
    fn a_robot_on_a_live_point_or_in_the_static_band_is_not_escaped() {
        let p = CorrectParams::default();
        let path = lane();
        // On the shelf itself.
        let site = Site::new(walled(10.0, 10.0), shelf(0.0));
        let world = site.world();
        let b = judge(&path, 20, Point2::new(3.0, 5.0), &world, &p);
        assert!(matches!(
            repair(&path, &b[0], &world, &p),
            Err(CorrectError::AnchorInCollision { .. })
        ));
        // 0.275 m from a wall the map has always had (cell centres from y = 5.275): not a late sight.
        let mut grid = walled(10.0, 10.0);
        grid.fill_rect(2.8, 5.26, 4.5, 5.5, crate::map::CellState::Occupied);
        let site = Site::new(grid, Vec::new());
        let world = site.world();
        let b = judge(&path, 20, Point2::new(3.0, 5.0), &world, &p);
        assert!(!b.is_empty());
        assert!(matches!(
            repair(&path, &b[0], &world, &p),
            Err(CorrectError::AnchorInCollision { .. })
        ));
    }
}
