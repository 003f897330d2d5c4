//! Metrics of a drone plan over terrain (issue 23: DESIGN §6 extended to surfaces).
//!
//! - surface coverage: covered surface area / total surface area of the domain. Each cell centre stands for its
//!   share of the surface ([`TerrainSurface::cell_area`]); it is covered when the distance ON the surface —
//!   the arc length along the terrain's vertical section across the lanes through it — to the nearest lane is
//!   at most tool_width / 2. Lanes run the domain's full length, so along them nothing is left out.
//! - lane spacing: the same arc length between neighbouring lanes, on every cell-centre section (not the
//!   planner's stations), sampled at an eighth of a cell (the planner samples at a quarter); p5, p50, p95.
//! - altitude error: along the flown path (straight segments between waypoints, sampled every half cell),
//!   the height over the surface — a vertical ray cast on the parry mesh — minus the offset; p50, p95 and max
//!   of its magnitude.
//! - max path slope: the steepest segment of the path from the horizontal.

use super::drone::DronePlan;
use super::mesh::TerrainMesh;
use super::profile::{LaneAxis, Section};
use super::surface::TerrainSurface;
use crate::map::Cell;

/// Nearest-rank quantiles of a sample, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Quantiles {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest value.
    pub max: f64,
    /// Sample size.
    pub count: usize,
}

impl Quantiles {
    /// Quantiles of `values` (NaN-free); all zero for an empty sample.
    pub fn of(mut values: Vec<f64>) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        values.sort_by(f64::total_cmp);
        let q = |p: f64| values[((values.len() - 1) as f64 * p).round() as usize];
        Self {
            p5: q(0.05),
            p50: q(0.5),
            p95: q(0.95),
            max: values[values.len() - 1],
            count: values.len(),
        }
    }
}

/// Metrics of a drone plan.
#[derive(Debug, Clone, PartialEq)]
pub struct DroneMetrics {
    /// Covered surface area of the region / its total surface area, in [0, 1] (the region: `DronePlan::region`).
    pub surface_coverage: f64,
    /// Covered surface area, m².
    pub covered_area_m2: f64,
    /// Surface area swept more than once, counted once per extra swath, m² (DESIGN §6 overlap on the surface).
    pub overlap_area_m2: f64,
    /// Surface area of the domain, m².
    pub total_area_m2: f64,
    /// |height over the surface − offset| along the path, metres.
    pub altitude_error_m: Quantiles,
    /// Steepest path segment, radians from the horizontal.
    pub max_path_slope_rad: f64,
    /// Arc length on the surface between neighbouring lanes, metres.
    pub lane_spacing_m: Quantiles,
    /// Number of lanes.
    pub lanes: usize,
    /// 3-D length of the path, metres.
    pub path_length_m: f64,
}

/// Lane `k`'s across coordinate at along-lane coordinate `t`, linear between the plan's stations.
fn lane_at(plan: &DronePlan, k: usize, t: f64) -> f64 {
    let st = &plan.stations_t;
    let j = st.partition_point(|&v| v < t).clamp(1, st.len().max(2) - 1);
    if st.len() < 2 {
        return plan.lane_s[k][0];
    }
    let f = ((t - st[j - 1]) / (st[j] - st[j - 1])).clamp(0.0, 1.0);
    plan.lane_s[k][j - 1] + f * (plan.lane_s[k][j] - plan.lane_s[k][j - 1])
}

/// Measures `plan` over `surface` (and its mesh).
pub fn drone_metrics(surface: &TerrainSurface, mesh: &TerrainMesh, plan: &DronePlan) -> DroneMetrics {
    let g = surface.geometry;
    let half = plan.tool_width_m / 2.0 + 1e-9;
    let (mut covered, mut total, mut overlap) = (0.0, 0.0, 0.0);
    let mut spacings = Vec::new();
    // Cell-centre lines along the lanes' axis: along x means rows are the sections' t.
    let (lines, along) = match plan.axis {
        LaneAxis::X => (g.width, g.height),
        LaneAxis::Y => (g.height, g.width),
    };
    for a in 0..lines {
        let cell = |b: usize| match plan.axis {
            LaneAxis::X => Cell::new(a, b),
            LaneAxis::Y => Cell::new(b, a),
        };
        let centre = g.center(cell(0));
        let t = match plan.axis {
            LaneAxis::X => centre.x,
            LaneAxis::Y => centre.y,
        };
        let sec = Section::new(surface, plan.axis, t, g.resolution / 8.0);
        // The lanes flown at this t (each from its first to its last station over the region).
        let flown = |k: &usize| {
            plan.lane_span.get(*k).copied().flatten().is_some_and(|(a, b)| {
                let (lo, hi) = (plan.stations_t[a], plan.stations_t[b]);
                t >= lo.min(hi) - 1e-9 && t <= lo.max(hi) + 1e-9
            })
        };
        let lane_arcs: Vec<f64> = (0..plan.lane_s.len())
            .filter(flown)
            .map(|k| sec.arc_at(lane_at(plan, k, t)))
            .collect();
        spacings.extend(lane_arcs.windows(2).map(|w| w[1] - w[0]));
        for b in 0..along {
            let c = cell(b);
            let p = g.center(c);
            let s = match plan.axis {
                LaneAxis::X => p.y,
                LaneAxis::Y => p.x,
            };
            if !plan.region.get(g.index(c)).copied().unwrap_or(true) {
                continue;
            }
            let arc = sec.arc_at(s);
            let area = surface.cell_area(g.index(c));
            total += area;
            // Lane arcs increase with k: the lanes whose swath holds this point are a run around the insertion
            // point.
            let k = lane_arcs.partition_point(|&v| v < arc);
            let within = |limit: f64| {
                let below = lane_arcs[..k].iter().rev().take_while(|&&v| arc - v <= limit).count();
                let above = lane_arcs[k..].iter().take_while(|&&v| v - arc <= limit).count();
                below + above
            };
            // Covered by a swath's closed band; swept twice only inside two open bands (a point on the seam
            // of two swaths that tile the surface is swept once).
            if within(half) > 0 {
                covered += area;
                overlap += area * within(half - 2e-9).saturating_sub(1) as f64;
            }
        }
    }
    let mut errors = Vec::new();
    let (mut max_slope, mut length) = (0.0f64, 0.0);
    let sample = g.resolution / 2.0;
    for (i, seg) in plan.path.windows(2).enumerate() {
        let (a, b) = (seg[0], seg[1]);
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let flat = d[0].hypot(d[1]);
        length += flat.hypot(d[2]);
        if flat > 1e-9 {
            max_slope = max_slope.max(d[2].abs().atan2(flat));
        }
        let steps = ((flat / sample).ceil() as usize).max(1);
        let first = if i == 0 { 0 } else { 1 };
        for q in first..=steps {
            let f = q as f64 / steps as f64;
            let p = [a[0] + f * d[0], a[1] + f * d[1], a[2] + f * d[2]];
            if let Some(alt) = mesh.altitude(p) {
                errors.push((alt - plan.altitude_offset_m).abs());
            }
        }
    }
    DroneMetrics {
        surface_coverage: if total > 0.0 { covered / total } else { 0.0 },
        covered_area_m2: covered,
        overlap_area_m2: overlap,
        total_area_m2: total,
        altitude_error_m: Quantiles::of(errors),
        max_path_slope_rad: max_slope,
        lane_spacing_m: Quantiles::of(spacings),
        lanes: plan.lane_s.len(),
        path_length_m: length,
    }
}
