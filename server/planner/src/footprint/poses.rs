//! The poses a robot takes along a polyline, as DESIGN §6 samples them for a footprint: the heading along
//! each segment (the robot drives forward), the segment sampled every `spacing_m`, and at each vertex a turn
//! in place from the incoming to the outgoing heading, the shorter way, sampled every `step_rad`.

use std::f64::consts::PI;
use std::ops::ControlFlow;

use crate::geom::Point2;

/// `a` wrapped to (−π, π], radians.
pub fn wrap_angle(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > PI { w - std::f64::consts::TAU } else { w }
}

/// Heading of the segment `a` → `b`, radians counter-clockwise from +x; `None` for a segment shorter than a
/// nanometre.
pub fn segment_heading(a: Point2, b: Point2) -> Option<f64> {
    let d = b - a;
    (d.norm() > 1e-9).then(|| d.y.atan2(d.x))
}

/// The headings of a turn in place from `yaw0` to `yaw1` the shorter way (a half turn goes
/// counter-clockwise), at most `step_rad` apart: `yaw0` left out, `yaw1` last. Empty when they agree.
pub fn turn_headings(yaw0: f64, yaw1: f64, step_rad: f64) -> impl Iterator<Item = f64> {
    let mut delta = wrap_angle(yaw1 - yaw0);
    if delta <= -PI + 1e-12 {
        delta = PI;
    }
    let n = if delta.abs() <= 1e-12 {
        0
    } else {
        (delta.abs() / step_rad.max(1e-6) - 1e-9).ceil().max(1.0) as usize
    };
    (1..=n).map(move |k| yaw0 + delta * k as f64 / n as f64)
}

/// Visits every pose of `path` (see the module docs) in order until `visit` breaks; true when it never did.
///
/// `start_yaw`: the heading the robot has at the first point (`None`: it starts at the first segment's
/// heading, whose pose is visited; `Some`: the turn from it is visited, not the pose at it). `end_yaw`: a
/// heading to turn to at the last point. A path with no segment longer than a nanometre is its first point:
/// the turn from `start_yaw` to `end_yaw` there, or the pose at heading 0 when neither is known.
pub fn visit_poses(
    path: &[Point2],
    start_yaw: Option<f64>,
    end_yaw: Option<f64>,
    spacing_m: f64,
    step_rad: f64,
    visit: &mut dyn FnMut(Point2, f64) -> ControlFlow<()>,
) -> bool {
    let Some(&first) = path.first() else {
        return true;
    };
    let mut yaw = start_yaw;
    let mut at = first;
    let turn_to =
        |p: Point2, from: Option<f64>, to: f64, visit: &mut dyn FnMut(Point2, f64) -> ControlFlow<()>| match from {
            None => visit(p, to).is_continue(),
            Some(y) => turn_headings(y, to, step_rad).all(|h| visit(p, h).is_continue()),
        };
    for &next in &path[1..] {
        let Some(h) = segment_heading(at, next) else { continue };
        if !turn_to(at, yaw, h, visit) {
            return false;
        }
        let len = (next - at).norm();
        let m = (len / spacing_m.max(1e-9)).ceil().max(1.0) as usize;
        for j in 1..=m {
            if visit(at + (next - at) * (j as f64 / m as f64), h).is_break() {
                return false;
            }
        }
        yaw = Some(h);
        at = next;
    }
    match (yaw, end_yaw) {
        (Some(_), Some(e)) => turn_to(at, yaw, e, visit),
        (Some(_), None) => true,
        // No segment at all.
        (None, Some(e)) => match start_yaw {
            Some(s) => turn_to(at, Some(s), e, visit),
            None => visit(at, e).is_continue(),
        },
        (None, None) => visit(at, 0.0).is_continue(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turns_go_the_shorter_way_in_small_steps() {
        let t: Vec<f64> = turn_headings(0.1, -0.3, 0.1).collect();
        assert_eq!(t.len(), 4);
        assert!((t[3] + 0.3).abs() < 1e-12 && t[0] < 0.1);
        let wrap: Vec<f64> = turn_headings(3.0, -3.0, 0.5).collect();
        assert!(wrap.len() == 1 && (wrap_angle(wrap[0]) + 3.0).abs() < 1e-12, "{wrap:?}");
        assert_eq!(turn_headings(1.0, 1.0 + std::f64::consts::TAU, 0.1).count(), 0);
        let half: Vec<f64> = turn_headings(0.0, PI, 1.0).collect();
        assert!(half.iter().all(|&h| h > 0.0), "a half turn is counter-clockwise");
    }

    #[test]
    fn poses_follow_segments_and_turn_at_vertices() {
        let path = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)];
        let mut seen = Vec::new();
        let done = visit_poses(&path, None, Some(PI), 0.25, 0.5, &mut |p, h| {
            seen.push((p, h));
            ControlFlow::Continue(())
        });
        assert!(done);
        // 1 start + 4 along x + 4 turn steps (π/2 in ≤ 0.5) + 4 along y + 4 turn steps (π/2 again).
        assert_eq!(seen.len(), 1 + 4 + 4 + 4 + 4, "{seen:?}");
        assert_eq!(seen[0], (path[0], 0.0));
        assert!((seen[8].1 - PI / 2.0).abs() < 1e-12 && seen[8].0 == path[1]);
        assert!((wrap_angle(seen.last().expect("poses").1) - PI).abs() < 1e-12);
        let mut n = 0;
        assert!(!visit_poses(&path, Some(0.0), None, 0.25, 0.5, &mut |_, _| {
            n += 1;
            if n == 3 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        }));
        assert_eq!(n, 3);
    }
}
