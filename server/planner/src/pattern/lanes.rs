//! Boustrophedon lanes for one region.
//!
//! Lanes are parallel lines one tool width apart (or a little less, so that the set fits the region exactly),
//! clipped to the region where the robot keeps its clearance, and emitted as straight segments between lane
//! ends. A lane that an obstacle or a narrow passage splits yields several segments — each kept, none
//! dropped; the ordering stage links them.
//!
//! Lane placement: the outermost lanes sit on the region's outermost reachable cells when the region's
//! cover targets (its cells plus the wall band they are responsible for) extend beyond them, and half a tool
//! width inside otherwise (an internal border with a neighbouring region: each side covers up to the border,
//! no double sweep).
//!
//! Direction: each region tries its dominant wall directions (from the clearance gradient along its walls)
//! and 0°, 45°, 90°, 135°, and keeps the one with the smallest estimated sweep cost: lane length, the steps
//! between lanes, and a turn penalty per lane segment (fewest lanes and turns).

use super::{Task, TaskKind};
use crate::geom::{Point2, Vector2, direction};
use crate::space::CoverageSpace;

/// Lane generation knobs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LaneParams {
    /// Cost of one lane segment's pair of turns, in metres of straight driving. `None`: 2 × tool width.
    pub turn_cost_m: Option<f64>,
    /// Fixed sweep direction (radians) instead of choosing one.
    pub fixed_angle_rad: Option<f64>,
    /// Lane placement; `None` lets the pipeline plan with each and keep the shorter plan.
    pub placement: Option<Placement>,
}

/// One region's cells and cover targets.
#[derive(Debug, Clone, Copy)]
pub struct RegionView<'a> {
    /// Region id in `labels`.
    pub id: u32,
    /// Region label per grid cell.
    pub labels: &'a [u32],
    /// Per grid cell, the region responsible for covering it (coverable cells only, else `NO_REGION`).
    pub target_labels: &'a [u32],
    /// The region's cells.
    pub cells: &'a [usize],
    /// Coverable cells this region must cover (its own and the wall band nearest to it).
    pub targets: &'a [usize],
}

/// Lanes of a region along its best direction; returns the angle (radians) and the lane segments in sweep
/// order (by lane, then along the lane).
pub fn plan_lanes(space: &CoverageSpace, region: RegionView<'_>, params: &LaneParams) -> (f64, Vec<Task>) {
    let angle = params
        .fixed_angle_rad
        .unwrap_or_else(|| best_angle(space, region, params));
    (
        angle,
        lanes_at(
            space,
            region,
            angle,
            true,
            params.placement.unwrap_or(Placement::Lattice),
        ),
    )
}

/// Candidate sweep directions for a region, radians in [0, π).
pub fn candidate_angles(space: &CoverageSpace, region: RegionView<'_>) -> Vec<f64> {
    use std::f64::consts::PI;
    let g = space.geometry();
    let (w, h) = (g.width, g.height);
    let near_wall = space.robot.radius_m + 2.0 * g.resolution;
    let mut hist = [0.0f64; 180];
    for &i in region.cells {
        if space.clearance.at(i) > near_wall {
            continue;
        }
        let c = g.cell(i);
        if c.x == 0 || c.y == 0 || c.x + 1 >= w || c.y + 1 >= h {
            continue;
        }
        let gx = space.clearance.at(i + 1) - space.clearance.at(i - 1);
        let gy = space.clearance.at(i + w) - space.clearance.at(i - w);
        let mag = gx.hypot(gy);
        if mag < 1e-9 {
            continue;
        }
        // Wall tangent = gradient + 90°, folded into [0, 180).
        let t = (gy.atan2(gx) + PI / 2.0).rem_euclid(PI);
        hist[(t.to_degrees().round() as usize) % 180] += mag;
    }
    let smooth: Vec<f64> = (0..180)
        .map(|k| (0..7).map(|j| hist[(k + 180 + j - 3) % 180]).sum())
        .collect();
    let mut angles: Vec<f64> = vec![0.0, PI / 4.0, PI / 2.0, 3.0 * PI / 4.0];
    if let Some((k, &v)) = smooth.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))
        && v > 0.0
    {
        let t = (k as f64).to_radians();
        angles.push(t);
        angles.push((t + PI / 2.0).rem_euclid(PI));
    }
    let mut out: Vec<f64> = Vec::new();
    for a in angles {
        if !out.iter().any(|&b| {
            let d = (a - b).rem_euclid(PI);
            d.min(PI - d) < 3f64.to_radians()
        }) {
            out.push(a);
        }
    }
    out
}

/// The sweep direction of a region: the candidate whose lattice lanes are cheapest to sweep (length, steps
/// and a turn cost per lane). It does not depend on the placement, so strategies that differ only in
/// placement can share it.
pub fn best_angle(space: &CoverageSpace, region: RegionView<'_>, params: &LaneParams) -> f64 {
    let w = space.robot.tool_width_m;
    let turn = params.turn_cost_m.unwrap_or(2.0 * w);
    candidate_angles(space, region)
        .into_iter()
        .map(|a| {
            (
                a,
                sweep_cost(&lanes_at(space, region, a, false, Placement::Lattice), turn),
            )
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.0, |(a, _)| a)
}

/// Estimated cost of sweeping `lanes` in order: their length, the steps between them, and `turn` per lane.
fn sweep_cost(lanes: &[Task], turn: f64) -> f64 {
    let len: f64 = lanes.iter().map(Task::length).sum();
    let steps: f64 = lanes
        .windows(2)
        .map(|p| {
            let (e, s) = (p[0].points[p[0].points.len() - 1], p[1].points[0]);
            (e - s).norm().min((p[0].points[0] - s).norm())
        })
        .sum();
    len + steps + turn * lanes.len() as f64
}

/// Where lanes sit across the sweep direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// On the map-wide lattice of offsets `k · tool_width` (shared with every region of the same direction).
    Lattice,
    /// Fitted to the region alone, evenly spaced.
    Fit,
    /// Fitted and inset for a frame along the walls (`pattern::frame`): on a wall side the outermost lane
    /// sits one tool width inside the region's outermost cells, and lane ends keep half a tool width more
    /// clearance, so the frame covers the wall band and the lanes meet it edge to edge.
    Framed,
}

/// Lanes along `angle`. `exact`: sample every half cell with the exact clearance and refine lane ends by
/// bisection; otherwise a cheap cell-centre estimate for choosing the direction.
pub fn lanes_at(
    space: &CoverageSpace,
    region: RegionView<'_>,
    angle: f64,
    exact: bool,
    placement: Placement,
) -> Vec<Task> {
    let g = space.geometry();
    let res = g.resolution;
    let w = space.robot.tool_width_m;
    let d = direction(angle);
    let n = Vector2::new(-d.y, d.x);
    // Offsets are measured from the map frame's origin so that every region sweeping in the same direction
    // shares one lattice of lanes, `w` apart: neighbouring regions continue each other's lanes instead of
    // each rounding its own lane count up at their common border.
    let origin = Point2::origin();
    let uv = |p: Point2| ((p - origin).dot(&d), (p - origin).dot(&n));
    let (mut umin, mut umax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &i in region.cells {
        let (u, v) = uv(g.center_of(i));
        (umin, umax, vmin, vmax) = (umin.min(u), umax.max(u), vmin.min(v), vmax.max(v));
    }
    let (mut tmin, mut tmax) = (vmin, vmax);
    for &i in region.targets {
        let (_, v) = uv(g.center_of(i));
        (tmin, tmax) = (tmin.min(v), tmax.max(v));
    }
    let half = w / 2.0;
    // Lanes keep the clearance r plus the depth of the scallops that a wall of cell centres leaves in the
    // iso-clearance line (≈ res² / 8r, doubled): then lanes along a wall, and the step from one lane end to
    // the next along a wall across them, keep the clearance too.
    let margin = res * res / (4.0 * space.robot.radius_m);
    let (vlo, vhi) = if vmax - vmin > 2.0 * margin {
        (vmin + margin, vmax - margin)
    } else {
        (vmin, vmax)
    };
    // A side where cover targets lie beyond the region's own cells is a wall side: the outermost lane moves
    // onto the outermost cells there. Elsewhere the region owns the lattice lanes in its half-open offset
    // range [vmin - res/2, vmax + res/2), exactly tiling it with its neighbours.
    // A side is a wall side when most of the region's outermost cells on that side touch unreachable space.
    let (mut low, mut low_wall, mut high, mut high_wall) = (0usize, 0usize, 0usize, 0usize);
    for &i in region.cells {
        let (_, v) = uv(g.center_of(i));
        let (is_low, is_high) = (v <= vmin + res, v >= vmax - res);
        if !(is_low || is_high) {
            continue;
        }
        let walled =
            g.neighbors4(g.cell(i)).count() < 4 || g.neighbors4(g.cell(i)).any(|c| !space.reachable[g.index(c)]);
        if is_low {
            low += 1;
            low_wall += usize::from(walled);
        }
        if is_high {
            high += 1;
            high_wall += usize::from(walled);
        }
    }
    let wall_low = tmin < vmin - 0.5 * res && 2 * low_wall >= low;
    let wall_high = tmax > vmax + 0.5 * res && 2 * high_wall >= high;
    let kmin = if wall_low {
        ((tmin - half) / w - 1e-9).ceil()
    } else {
        ((vmin - 0.5 * res) / w - 1e-9).ceil()
    };
    let kmax = if wall_high {
        ((tmax + half) / w + 1e-9).floor()
    } else {
        ((vmax + 0.5 * res) / w - 1e-9).floor()
    };
    let mut lattice: Vec<f64> = Vec::new();
    let mut k = kmin;
    while k <= kmax {
        let v = (k * w).clamp(vlo, vhi);
        if lattice.last().is_none_or(|&last| v - last > 1e-6) {
            lattice.push(v);
        }
        k += 1.0;
    }
    if lattice.is_empty() {
        // A sliver between two lattice lanes: one lane through its middle.
        lattice.push(0.5 * (vmin + vmax));
    }
    // The alternative: lanes fitted to this region alone, evenly spaced at most `w` apart between its
    // outermost needed offsets. Better where the region's neighbours sweep in other directions.
    let framed = placement == Placement::Framed;
    let fit = {
        let (lo, hi) = if framed {
            (
                if wall_low { vmin + w } else { tmin + half },
                if wall_high { vmax - w } else { tmax - half },
            )
        } else {
            (tmin + half, tmax - half)
        };
        let mut v0 = lo.max(vlo).min(vhi);
        let mut v1 = hi.min(vhi).max(vlo);
        if v1 < v0 {
            let m = 0.5 * (v0 + v1);
            (v0, v1) = (m, m);
        }
        let count = if v1 - v0 < 1e-9 {
            1
        } else {
            ((v1 - v0) / w - 1e-9).ceil() as usize + 1
        };
        let spacing = if count > 1 { (v1 - v0) / (count - 1) as f64 } else { 0.0 };
        (0..count).map(|k| v0 + spacing * k as f64).collect::<Vec<f64>>()
    };
    let offsets = match placement {
        Placement::Lattice => lattice,
        Placement::Fit | Placement::Framed => fit,
    };
    let end_clearance = space.robot.radius_m + margin + if framed { half } else { 0.0 };
    let ok = |p: Point2| -> bool {
        match g.locate(p) {
            Some(c) => {
                let i = g.index(c);
                region.labels[i] == region.id && (!exact || space.has_clearance(p, end_clearance))
            }
            None => false,
        }
    };
    let step = if exact { res * 0.5 } else { res };
    let at = |u: f64, v: f64| origin + d * u + n * v;
    let mut tasks = Vec::new();
    for &v in &offsets {
        let mut u = umin - res;
        let mut run_start: Option<f64> = None;
        let mut last_ok = u;
        while u <= umax + res + 1e-12 {
            if ok(at(u, v)) {
                if run_start.is_none() {
                    run_start = Some(if exact { refine(&ok, &at, v, u - step, u) } else { u });
                }
                last_ok = u;
            } else if let Some(s) = run_start.take() {
                let e = if exact {
                    refine(&ok, &at, v, u, last_ok)
                } else {
                    last_ok
                };
                tasks.push(Task {
                    points: vec![at(s, v), at(e, v)],
                    kind: TaskKind::Lane,
                });
            }
            u += step;
        }
        if let Some(s) = run_start {
            tasks.push(Task {
                points: vec![at(s, v), at(last_ok, v)],
                kind: TaskKind::Lane,
            });
        }
    }
    if exact {
        // Sub-step clearance dips between samples: keep only segments whose whole length checks out,
        // shrinking the ends inwards a little where needed.
        tasks.retain_mut(|t| {
            let (a, b) = (t.points[0], t.points[1]);
            if space.segment_ok(a, b) {
                return true;
            }
            let dir = b - a;
            for k in 1..=8 {
                let f = k as f64 * 0.02;
                let (a2, b2) = (a + dir * f, b - dir * f);
                if space.segment_ok(a2, b2) {
                    t.points = vec![a2, b2];
                    return true;
                }
            }
            false
        });
    }
    tasks
}

/// Bisection between a failing `u_bad` and a passing `u_good` on lane `v`; returns a passing u.
fn refine(ok: &dyn Fn(Point2) -> bool, at: &dyn Fn(f64, f64) -> Point2, v: f64, u_bad: f64, u_good: f64) -> f64 {
    let (mut bad, mut good) = (u_bad, u_good);
    for _ in 0..8 {
        let mid = 0.5 * (bad + good);
        if ok(at(mid, v)) {
            good = mid;
        } else {
            bad = mid;
        }
    }
    good
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};

    fn whole(space: &CoverageSpace) -> (Vec<u32>, Vec<u32>, Vec<usize>, Vec<usize>) {
        let g = space.geometry();
        let labels: Vec<u32> = (0..g.len())
            .map(|i| if space.reachable[i] { 0 } else { u32::MAX })
            .collect();
        let target_labels: Vec<u32> = (0..g.len())
            .map(|i| if space.coverable[i] { 0 } else { u32::MAX })
            .collect();
        let cells: Vec<usize> = (0..g.len()).filter(|&i| space.reachable[i]).collect();
        let targets: Vec<usize> = (0..g.len()).filter(|&i| space.coverable[i]).collect();
        (labels, target_labels, cells, targets)
    }

    #[test]
    fn long_room_gets_lanes_along_its_length() {
        let g = GridGeometry::new(80, 20, 0.05, Point2::origin()).expect("valid");
        let space = crate::decompose::tests::small_robot_space(OccupancyGrid::filled(g, CellState::Free));
        let (labels, target_labels, cells, targets) = whole(&space);
        let view = RegionView {
            id: 0,
            labels: &labels,
            target_labels: &target_labels,
            cells: &cells,
            targets: &targets,
        };
        let (angle, lanes) = plan_lanes(&space, view, &LaneParams::default());
        assert!(angle.sin().abs() < 1e-6, "lanes along x, got {angle}");
        // 1 m wide room, reachable y in [0.175, 0.825], walls on both sides: the outermost lanes sit on the
        // outermost reachable rows, the lattice fills between: 4 lanes (3.33 tool widths of cover).
        assert_eq!(lanes.len(), 4, "{lanes:?}");
        for t in &lanes {
            assert!(space.segment_ok(t.points[0], t.points[1]));
            assert_eq!(t.points.len(), 2);
        }
        let mut all = Vec::new();
        for (k, t) in lanes.iter().enumerate() {
            if k % 2 == 0 {
                all.extend(t.points.iter().copied())
            } else {
                all.extend(t.points.iter().rev().copied())
            }
        }
        for s in all.windows(2) {
            assert!(space.segment_ok(s[0], s[1]), "step {s:?} keeps clearance");
        }
        let m = crate::metrics::evaluate(&space, &all);
        assert!(m.coverage_pct > 99.0, "{m:?}");
        assert_eq!(m.collisions, 0);
    }

    #[test]
    fn pillar_splits_lanes_into_segments_not_drops() {
        let g = GridGeometry::new(60, 40, 0.05, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(1.3, 0.8, 1.7, 1.2, CellState::Occupied);
        let space = crate::decompose::tests::small_robot_space(grid);
        let (labels, target_labels, cells, targets) = whole(&space);
        let view = RegionView {
            id: 0,
            labels: &labels,
            target_labels: &target_labels,
            cells: &cells,
            targets: &targets,
        };
        let lanes = lanes_at(&space, view, 0.0, true, Placement::Fit);
        // Lanes at the pillar's height are split into two segments each.
        let split = lanes
            .iter()
            .filter(|t| t.points[0].y > 0.6 && t.points[0].y < 1.4)
            .count();
        let rows: std::collections::BTreeSet<i64> =
            lanes.iter().map(|t| (t.points[0].y * 1000.0).round() as i64).collect();
        assert!(lanes.len() > rows.len(), "some lanes split");
        assert!(split >= 2);
        for t in &lanes {
            assert!(space.segment_ok(t.points[0], t.points[1]));
        }
    }
}
