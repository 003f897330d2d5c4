//! Direct landmark point planning for drones and sprayers (seed 000 §IV.B).
//!
//! The parameter domain of the smoothed surface is discretised into stations every `station_spacing_m` along
//! the lanes (eq. 12). At each station the vertical section of the surface across the lanes is measured by arc
//! length, and the lanes are placed along it at equal surface spacing: with N lanes and a section of surface
//! width A(t), lane k sits where the arc from the edge is (k + ½)·A(t)/N. N is the smallest count that keeps
//! that spacing within the tool width at every station, N = ⌈max_t A(t) / tool_width⌉, so the spacing ON the
//! surface is the tool width where the section is widest and a little less elsewhere — never more, hence no
//! strip is missed. Lanes on a slope therefore draw closer in plan view: across a 30° ramp they are
//! tool_width · cos 30° apart on the map. Each lane point is mapped onto the surface and lifted by the
//! elevation offset (eq. 13–14): x, y, z = surface + offset, metres in the map frame. The lanes are flown in a
//! boustrophedon order; each turn follows the domain's edge at the same offset over the ground.
//!
//! The lane axis is x or y: the one that needs fewer lanes (fewer turns), and on a tie the longer one.

use super::profile::{LaneAxis, Section};
use super::surface::TerrainSurface;
use crate::error::{PlannerError, Result, finite};
use crate::map::DistanceField;

/// Most waypoints a drone plan may hold (lanes × stations plus turns).
pub const MAX_WAYPOINTS: usize = 1 << 24;

/// Which way the lanes run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LaneChoice {
    /// The axis that needs fewer lanes (on a tie: along the longer side).
    #[default]
    Auto,
    /// Along the given axis.
    Along(LaneAxis),
}

/// What a drone (or sprayer) plan needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DroneParams {
    /// Swath width ON the surface, metres (> 0).
    pub tool_width_m: f64,
    /// Height over the surface to fly at, metres (≥ 0).
    pub altitude_offset_m: f64,
    /// Distance between stations along the lanes, metres; 0 takes the grid's cell size.
    pub station_spacing_m: f64,
    /// Lane axis.
    pub lanes: LaneChoice,
    /// The region to cover: cells whose height was measured or filled at most this far from measured ones,
    /// metres (∞: the whole grid). Lanes are flown from their first to their last station over the region, the
    /// tool off over holes in it; an irregular tile is not flown where it has no data.
    pub region_fill_m: f64,
}

impl Default for DroneParams {
    fn default() -> Self {
        Self {
            tool_width_m: 5.0,
            altitude_offset_m: 3.0,
            station_spacing_m: 0.0,
            lanes: LaneChoice::Auto,
            region_fill_m: f64::INFINITY,
        }
    }
}

impl DroneParams {
    /// Checks the ranges, naming the field that is wrong.
    pub fn validate(&self) -> Result<()> {
        for (name, v, positive) in [
            ("tool_width_m", self.tool_width_m, true),
            ("altitude_offset_m", self.altitude_offset_m, false),
            ("station_spacing_m", self.station_spacing_m, false),
        ] {
            let v = finite(name, v)?;
            if v < 0.0 || (positive && v == 0.0) {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("must be {} metres, got {v}", if positive { "> 0" } else { "≥ 0" }),
                });
            }
        }
        if self.region_fill_m.is_nan() || self.region_fill_m < 0.0 {
            return Err(PlannerError::InvalidParam {
                name: "region_fill_m",
                reason: format!("must be ≥ 0 metres (∞ for the whole grid), got {}", self.region_fill_m),
            });
        }
        Ok(())
    }
}

/// A drone coverage plan over a surface: 3-D waypoints in the map frame, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct DronePlan {
    /// The axis the lanes run along.
    pub axis: LaneAxis,
    /// Along-lane coordinate of each station, increasing, metres.
    pub stations_t: Vec<f64>,
    /// Per lane (in increasing across order), its across coordinate at each station, metres.
    pub lane_s: Vec<Vec<f64>>,
    /// The whole flight: lanes in boustrophedon order joined by turns, each point (x, y, surface + offset).
    pub path: Vec<[f64; 3]>,
    /// Per point of `path`: on a lane over the region (the tool works) rather than on a turn between lanes or
    /// over a hole in the region.
    pub on_lane: Vec<bool>,
    /// Per lane: its first and last station over the region (the part flown); None for a lane not flown.
    pub lane_span: Vec<Option<(usize, usize)>>,
    /// Per surface cell: in the region to cover (within `region_fill_m` of measured ground).
    pub region: Vec<bool>,
    /// Swath width on the surface, metres.
    pub tool_width_m: f64,
    /// Height over the surface, metres.
    pub altitude_offset_m: f64,
}

/// A lane axis with what planning along it takes.
struct Candidate {
    lanes: usize,
    length: f64,
    axis: LaneAxis,
    stations: Vec<f64>,
    secs: Vec<Section>,
}

/// Arc sampling step of the planning sections: a quarter cell.
fn section_step(surface: &TerrainSurface) -> f64 {
    surface.geometry.resolution / 4.0
}

/// Stations along `axis` and each station's section.
fn sections(surface: &TerrainSurface, axis: LaneAxis, spacing: f64) -> (Vec<f64>, Vec<Section>) {
    let ([t0, t1], _) = axis.ranges(surface);
    let m = (((t1 - t0) / spacing).ceil() as usize).max(1);
    let stations: Vec<f64> = (0..=m).map(|j| t0 + (t1 - t0) * j as f64 / m as f64).collect();
    let step = section_step(surface);
    let secs = stations.iter().map(|&t| Section::new(surface, axis, t, step)).collect();
    (stations, secs)
}

/// Lanes needed so that no station's surface spacing exceeds the tool width.
fn lane_count(secs: &[Section], tool_width: f64) -> usize {
    let widest = secs.iter().map(Section::total).fold(0.0, f64::max);
    ((widest / tool_width - 1e-9).ceil() as usize).max(1)
}

/// Plans the lanes and the flight over `surface`.
pub fn plan_lanes(surface: &TerrainSurface, params: &DroneParams) -> Result<DronePlan> {
    params.validate()?;
    let g = surface.geometry.resolution;
    let spacing = if params.station_spacing_m > 0.0 {
        params.station_spacing_m
    } else {
        g
    };
    let w = params.tool_width_m;
    // Refuse what would not fit before sampling anything of that size.
    let (lo, hi) = surface.domain();
    let stations_max = ((hi[0] - lo[0]).max(hi[1] - lo[1]) / spacing).ceil() + 1.0;
    if stations_max > MAX_WAYPOINTS as f64 {
        return Err(PlannerError::TerrainTooLarge {
            field: "stations",
            needed: stations_max.min(usize::MAX as f64) as usize,
            limit: MAX_WAYPOINTS,
        });
    }
    let candidates: Vec<LaneAxis> = match params.lanes {
        LaneChoice::Auto => vec![LaneAxis::X, LaneAxis::Y],
        LaneChoice::Along(a) => vec![a],
    };
    let mut best: Option<Candidate> = None;
    for axis in candidates {
        let (stations, secs) = sections(surface, axis, spacing);
        let lanes = lane_count(&secs, w);
        let ([t0, t1], _) = axis.ranges(surface);
        let length = t1 - t0;
        let better = best
            .as_ref()
            .is_none_or(|b| lanes < b.lanes || (lanes == b.lanes && length > b.length));
        if better {
            best = Some(Candidate {
                lanes,
                length,
                axis,
                stations,
                secs,
            });
        }
    }
    let Some(Candidate {
        lanes: n,
        axis,
        stations,
        secs,
        ..
    }) = best
    else {
        return Err(PlannerError::InvalidParam {
            name: "lanes",
            reason: "no lane axis to plan along".into(),
        });
    };
    let needed = n.saturating_mul(stations.len() + secs.len());
    if needed > MAX_WAYPOINTS {
        return Err(PlannerError::TerrainTooLarge {
            field: "waypoints",
            needed,
            limit: MAX_WAYPOINTS,
        });
    }
    let lane_s: Vec<Vec<f64>> = (0..n)
        .map(|k| {
            secs.iter()
                .map(|sec| sec.s_at((k as f64 + 0.5) * sec.total() / n as f64))
                .collect()
        })
        .collect();
    let lift = |t: f64, s: f64| {
        let (x, y) = axis.point(t, s);
        let z = surface.height_at(x, y).unwrap_or(f64::NAN);
        [x, y, z + params.altitude_offset_m]
    };
    let region = region_mask(surface, params.region_fill_m);
    let g = &surface.geometry;
    let in_region = |t: f64, s: f64| {
        let (x, y) = axis.point(t, s);
        g.locate(crate::geom::Point2::new(x, y))
            .is_some_and(|c| region[g.index(c)])
    };
    // Whether the swath at (t, s) reaches the region: its centre or either edge (half the tool width across in
    // plan, which on a slope reaches a little beyond the swath on the surface).
    let swath_in = |t: f64, s: f64| in_region(t, s) || in_region(t, s - w / 2.0) || in_region(t, s + w / 2.0);
    // Each lane from its first to its last station whose swath reaches the region (None: it never does).
    let lane_span: Vec<Option<(usize, usize)>> = lane_s
        .iter()
        .map(|lane| {
            let inside = |&j: &usize| swath_in(stations[j], lane[j]);
            Some((
                (0..stations.len()).find(inside)?,
                (0..stations.len()).rev().find(inside)?,
            ))
        })
        .collect();
    let mut path = Vec::with_capacity(n * (stations.len() + 4));
    let mut on_lane = Vec::with_capacity(path.capacity());
    // (t, s) of the last point flown.
    let mut last: Option<(f64, f64)> = None;
    let mut forward = true;
    for (lane, span) in lane_s.iter().zip(&lane_span) {
        let Some((a, b)) = *span else { continue };
        let order: Vec<usize> = if forward {
            (a..=b).collect()
        } else {
            (a..=b).rev().collect()
        };
        forward = !forward;
        let (t0, s0) = (stations[order[0]], lane[order[0]]);
        if let Some((pt, ps)) = last {
            // The turn from the previous lane's end, straight in the parameter plane (along the edge station when
            // both lanes reach it), every `spacing` metres, at the same offset over the ground.
            let steps = ((t0 - pt).hypot(s0 - ps) / spacing).ceil() as usize;
            for q in 1..steps {
                let f = q as f64 / steps as f64;
                path.push(lift(pt + (t0 - pt) * f, ps + (s0 - ps) * f));
                on_lane.push(false);
            }
        }
        for &j in &order {
            path.push(lift(stations[j], lane[j]));
            // Over a hole in the region (no data near) the tool is off.
            on_lane.push(swath_in(stations[j], lane[j]));
        }
        let end = order[order.len() - 1];
        last = Some((stations[end], lane[end]));
    }
    if path.is_empty() {
        return Err(PlannerError::InvalidParam {
            name: "region_fill_m",
            reason: "no lane crosses the region (the cells within region_fill_m of measured ground)".into(),
        });
    }
    if let Some(p) = path.iter().find(|p| !p[2].is_finite()) {
        return Err(PlannerError::NonFinite {
            field: "waypoint height",
            value: p[2],
        });
    }
    Ok(DronePlan {
        axis,
        stations_t: stations,
        lane_s,
        path,
        on_lane,
        lane_span,
        region,
        tool_width_m: w,
        altitude_offset_m: params.altitude_offset_m,
    })
}

/// Cells whose centre lies within `fill_m` metres (Euclidean) of a measured cell's centre (all of them for ∞).
pub fn region_mask(surface: &TerrainSurface, fill_m: f64) -> Vec<bool> {
    if fill_m.is_infinite() {
        return vec![true; surface.geometry.len()];
    }
    let measured = DistanceField::compute(surface.geometry, |i| surface.fill_ring[i] == 0, false);
    (0..surface.geometry.len())
        .map(|i| measured.at(i) <= fill_m + 1e-9)
        .collect()
}

#[cfg(test)]
#[path = "drone_tests.rs"]
mod tests;
