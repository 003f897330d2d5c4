//! Corner rounding: every corner of the path is replaced by a clamped cubic B-spline (eq. 20) over its two
//! legs, where that keeps clearance and loses no covered cell; otherwise the corner stays sharp.
//!
//! For a corner c with incoming direction u_in, outgoing u_out and leg length d, the control polygon is
//! c − d·u_in, c − ⅔d·u_in, c − ⅓d·u_in, c, c + ⅓d·u_out, c + ⅔d·u_out, c + d·u_out. Three collinear
//! control points at each end make the curvature zero where the curve meets the straight path (G2). The leg
//! d is at most `max_leg_m` and half of each adjacent segment, so neighbouring curves never overlap (a
//! U-turn's two corners meet in the middle of the step between lanes).
//!
//! Coverage is checked exactly: every piece of the path is stamped on a per-cell count raster with the
//! capsule of `metrics::coverage`; a corner's legs are taken out and its curve put in, and the corner is
//! kept sharp if any coverable cell drops to zero. Clearance is checked on the sampled curve with
//! `CoverageSpace::segment_ok` (radius clearance on the reachable set).

use crate::geom::{Point2, Vector2, heading_change};
use crate::metrics::coverage::for_each_cell_in_capsule;
use crate::pipeline::Waypoint;
use crate::space::CoverageSpace;

use super::SmoothParams;
use super::bspline::BSpline;

/// A smoothed path: waypoints with, for each, the curvature of the path there (1/m; `f64::INFINITY` at a
/// corner left sharp, 0 on straight stretches).
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedPath {
    /// The path, map frame, metres.
    pub waypoints: Vec<Waypoint>,
    /// Curvature at each waypoint, 1/m.
    pub curvature: Vec<f64>,
    /// Corners replaced by curves.
    pub rounded: usize,
    /// Corners kept sharp (clearance or coverage would suffer, or a reversal).
    pub kept_sharp: usize,
}

struct Corner {
    at: usize,
    leg: f64,
    u_in: Vector2,
    u_out: Vector2,
}

/// Rounds the corners of `path` on `space` (see the module docs). Consecutive duplicate points are dropped.
pub fn round_corners(space: &CoverageSpace, path: &[Waypoint], params: &SmoothParams) -> SmoothedPath {
    round_corners_where(space, path, params, &|_| true)
}

/// [`round_corners`], keeping a curve only where `also` accepts its samples too (a robot footprint's check,
/// say: the disc's clearance is all the space knows).
pub fn round_corners_where(
    space: &CoverageSpace,
    path: &[Waypoint],
    params: &SmoothParams,
    also: &dyn Fn(&[Point2]) -> bool,
) -> SmoothedPath {
    let pts = distinct(path);
    let n = pts.len();
    let (corners, mut sharp) = find_corners(&pts, params);
    // Pieces of the unsmoothed path, split at every corner's leg ends, stamped on a count raster.
    let g = *space.geometry();
    let half = space.robot.tool_width_m / 2.0 + 1e-9;
    let mut count = vec![0u32; g.len()];
    let stamp = |count: &mut Vec<u32>, a: Point2, b: Point2, add: bool| {
        for_each_cell_in_capsule(&g, a, b, half, |i| {
            if add {
                count[i] += 1;
            } else {
                count[i] = count[i].saturating_sub(1);
            }
        });
    };
    let mut leg_at = vec![0.0; n];
    for c in &corners {
        leg_at[c.at] = c.leg;
    }
    for i in 0..n.saturating_sub(1) {
        let (a, b) = (pts[i].position, pts[i + 1].position);
        let u = (b - a).normalize();
        let (a2, b2) = (a + u * leg_at[i], b - u * leg_at[i + 1]);
        stamp(&mut count, a2, b2, true);
        if leg_at[i] > 0.0 {
            stamp(&mut count, a, a2, true);
        }
        if leg_at[i + 1] > 0.0 {
            stamp(&mut count, b2, b, true);
        }
    }
    let mut curves: Vec<Option<Curve>> = Vec::with_capacity(corners.len());
    let mut rounded = 0;
    for c in &corners {
        let p = pts[c.at].position;
        let (a, b) = (p - c.u_in * c.leg, p + c.u_out * c.leg);
        let curve = fillet(p, c, params.samples_per_rad);
        let clear = curve.0.windows(2).all(|w| space.segment_ok(w[0], w[1])) && also(&curve.0);
        if !clear {
            curves.push(None);
            sharp[c.at] = true;
            continue;
        }
        stamp(&mut count, a, p, false);
        stamp(&mut count, p, b, false);
        for w in curve.0.windows(2) {
            stamp(&mut count, w[0], w[1], true);
        }
        let mut lost = false;
        for (x, y) in [(a, p), (p, b)] {
            for_each_cell_in_capsule(&g, x, y, half, |i| lost |= space.coverable[i] && count[i] == 0);
        }
        if lost {
            for w in curve.0.windows(2) {
                stamp(&mut count, w[0], w[1], false);
            }
            stamp(&mut count, a, p, true);
            stamp(&mut count, p, b, true);
            curves.push(None);
            sharp[c.at] = true;
        } else {
            rounded += 1;
            curves.push(Some(curve));
        }
    }
    assemble(&pts, (&corners, &curves), &sharp, rounded)
}

/// Every corner of `path` rounded, with no check of clearance or coverage: what the path would look like to
/// the speed profile if smoothing kept every corner it may round (reversals above `max_turn_rad` stay
/// sharp). The planner's estimate of a plan's driving time reads it before the path is linked.
pub fn round_every_corner(path: &[Waypoint], params: &SmoothParams) -> SmoothedPath {
    let pts = distinct(path);
    let (corners, sharp) = find_corners(&pts, params);
    let curves: Vec<_> = corners
        .iter()
        .map(|c| Some(fillet(pts[c.at].position, c, params.samples_per_rad)))
        .collect();
    assemble(&pts, (&corners, &curves), &sharp, corners.len())
}

/// `path` without consecutive duplicate points; a dropped duplicate's kind goes to the point it repeats
/// (the later waypoint's kind for the empty segment it ends).
fn distinct(path: &[Waypoint]) -> Vec<Waypoint> {
    let mut pts: Vec<Waypoint> = Vec::with_capacity(path.len());
    for w in path {
        if pts
            .last()
            .is_none_or(|l: &Waypoint| (l.position - w.position).norm() > 1e-9)
        {
            pts.push(*w);
        } else if let Some(l) = pts.last_mut() {
            l.kind = w.kind;
        }
    }
    pts
}

/// The corners of `pts` that may be rounded, and which vertices are sharp (reversals, legs too short).
fn find_corners(pts: &[Waypoint], params: &SmoothParams) -> (Vec<Corner>, Vec<bool>) {
    let n = pts.len();
    let mut corners: Vec<Corner> = Vec::new();
    let mut sharp = vec![false; n];
    for i in 1..n.saturating_sub(1) {
        let (a, c, b) = (pts[i - 1].position, pts[i].position, pts[i + 1].position);
        let (din, dout) = (c - a, b - c);
        let theta = heading_change(din, dout);
        if theta < params.min_turn_rad {
            continue;
        }
        let leg = params.max_leg_m.min(0.5 * din.norm()).min(0.5 * dout.norm());
        if theta > params.max_turn_rad || leg < 1e-6 {
            sharp[i] = true;
            continue;
        }
        corners.push(Corner {
            at: i,
            leg,
            u_in: din / din.norm(),
            u_out: dout / dout.norm(),
        });
    }
    (corners, sharp)
}

type Curve = (Vec<Point2>, Vec<f64>);

/// The smoothed path: every rounded corner's curve (`Some` in `curves`, one per corner) replaces its vertex.
fn assemble(
    pts: &[Waypoint],
    (corners, curves): (&[Corner], &[Option<Curve>]),
    sharp: &[bool],
    rounded: usize,
) -> SmoothedPath {
    let n = pts.len();
    // Assemble: a rounded corner's curve replaces its vertex (its first and last samples are the leg ends).
    let mut waypoints = Vec::with_capacity(n + rounded * 16);
    let mut curvature = Vec::with_capacity(waypoints.capacity());
    let mut next_corner = 0;
    for (i, w) in pts.iter().enumerate() {
        let curve = if next_corner < corners.len() && corners[next_corner].at == i {
            next_corner += 1;
            curves[next_corner - 1].as_ref()
        } else {
            None
        };
        match curve {
            Some((samples, kappa)) => {
                let mid = samples.len() / 2;
                for (j, (q, k)) in samples.iter().zip(kappa).enumerate() {
                    // Samples up to the apex finish the incoming segment; the rest start the outgoing one.
                    let from = if j <= mid { *w } else { pts[i + 1] };
                    waypoints.push(Waypoint {
                        position: *q,
                        kind: from.kind,
                        region: from.region,
                    });
                    curvature.push(*k);
                }
            }
            None => {
                waypoints.push(*w);
                curvature.push(if sharp[i] { f64::INFINITY } else { 0.0 });
            }
        }
    }
    SmoothedPath {
        waypoints,
        curvature,
        rounded,
        kept_sharp: sharp.iter().filter(|&&s| s).count(),
    }
}

/// Samples (map frame) and curvatures (1/m) of the B-spline that rounds corner `c` at `p`.
fn fillet(p: Point2, c: &Corner, samples_per_rad: f64) -> (Vec<Point2>, Vec<f64>) {
    let (d, ui, uo) = (c.leg, c.u_in, c.u_out);
    let control = [
        p - ui * d,
        p - ui * (2.0 * d / 3.0),
        p - ui * (d / 3.0),
        p,
        p + uo * (d / 3.0),
        p + uo * (2.0 * d / 3.0),
        p + uo * d,
    ];
    let theta = heading_change(ui, uo);
    let m = ((theta * samples_per_rad).ceil() as usize).clamp(4, 64);
    // Seven points always make a valid cubic.
    let Ok(spline) = BSpline::clamped(&control, 3) else {
        return (vec![p - ui * d, p, p + uo * d], vec![0.0, f64::INFINITY, 0.0]);
    };
    let mut pts = Vec::with_capacity(m + 1);
    let mut kappa = Vec::with_capacity(m + 1);
    for j in 0..=m {
        let u = j as f64 / m as f64;
        pts.push(spline.point(u));
        kappa.push(spline.curvature(u));
    }
    // Exact ends (the clamped spline interpolates them; this removes rounding noise).
    pts[0] = control[0];
    pts[m] = control[6];
    (pts, kappa)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::metrics::evaluate;
    use crate::pipeline::WaypointKind;
    use crate::space::RobotShape;

    fn room() -> CoverageSpace {
        let g = GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        CoverageSpace::new(OccupancyGrid::filled(g, CellState::Free), robot, Point2::new(1.0, 1.0)).expect("space")
    }

    fn wp(x: f64, y: f64) -> Waypoint {
        Waypoint {
            position: Point2::new(x, y),
            kind: WaypointKind::Cover,
            region: Some(0),
        }
    }

    #[test]
    fn rounds_open_corners_and_keeps_coverage() {
        let space = room();
        // A square loop in the open middle of the room, far from walls.
        let path = [wp(1.5, 1.5), wp(4.5, 1.5), wp(4.5, 2.5), wp(1.5, 2.5), wp(1.5, 1.5)];
        let before = evaluate(&space, &path.iter().map(|w| w.position).collect::<Vec<_>>());
        let s = round_corners(&space, &path, &SmoothParams::for_tool(0.4));
        let pts: Vec<Point2> = s.waypoints.iter().map(|w| w.position).collect();
        let after = evaluate(&space, &pts);
        assert_eq!(after.collisions, 0);
        assert!(after.covered_coverable_cells >= before.covered_coverable_cells);
        assert_eq!(s.waypoints.len(), s.curvature.len());
        assert!(s.rounded + s.kept_sharp == 3, "{} {}", s.rounded, s.kept_sharp);
        assert!(s.curvature.iter().all(|k| k.is_finite() || *k == f64::INFINITY));
        assert_eq!(pts.first(), Some(&Point2::new(1.5, 1.5)));
        assert_eq!(pts.last(), Some(&Point2::new(1.5, 1.5)));
    }

    #[test]
    fn corners_at_the_reach_limit_stay_sharp() {
        let space = room();
        // Corners exactly at the robot radius from the walls: any curve would cut a covered wall cell.
        let path = [wp(0.2, 0.2), wp(5.8, 0.2), wp(5.8, 0.6), wp(0.2, 0.6)];
        let s = round_corners(&space, &path, &SmoothParams::for_tool(0.4));
        let pts: Vec<Point2> = s.waypoints.iter().map(|w| w.position).collect();
        assert_eq!(evaluate(&space, &pts).collisions, 0);
        let before = evaluate(&space, &path.iter().map(|w| w.position).collect::<Vec<_>>());
        assert!(evaluate(&space, &pts).covered_coverable_cells >= before.covered_coverable_cells);
    }
}
