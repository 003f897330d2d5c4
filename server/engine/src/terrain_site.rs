//! Terrain sites (issue 23, `POST /v1/sites/{site}/terrain`): a ground robot's site made from a point cloud.
//!
//! The daemon reads the cloud and the planner extracts its surface (seed 000 §IV.A); the site keeps that
//! smoothed elevation map (heights as f32, sub-millimetre at any real elevation) and the robot limits, not the
//! cloud: a restart rebuilds the same occupancy from it without the file. Slope, step and roughness over the
//! limits are obstacles; ground interpolated farther from any point than the cloud's own sampling gaps reach
//! ([`shift_planner::terrain::interior_fill_rings`], decided at upload and kept) is unknown.
//! Every plan and correction on the site gets each waypoint's z from the elevation map (ground height, map
//! frame, metres).

use serde::{Deserialize, Serialize};
use shift_planner::geom::Point2;
use shift_planner::map::GridGeometry;
use shift_planner::map::grid::OccupancyGrid;
use shift_planner::terrain::{GroundLimits, TerrainSurface, Traversability};
use shift_proto::{CloudSourceDoc, WaypointDoc};

use crate::error::{EngineError, Result};

/// Records written before the fill reach was measured per cloud used this one.
fn legacy_fill_rings() -> u32 {
    4
}

/// What the store keeps of a terrain site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TerrainSite {
    /// The cloud it was made from (units, conversion, points).
    pub source: CloudSourceDoc,
    /// Grid columns.
    pub width: u64,
    /// Grid rows.
    pub height: u64,
    /// Cell edge, metres.
    pub resolution: f64,
    /// Lower-left corner of the grid, map frame, metres.
    pub origin: [f64; 2],
    /// Smoothed heights, row-major, f32 little-endian, metres.
    #[serde(with = "crate::bytes_as_hex")]
    pub heights_f32le: Vec<u8>,
    /// Per cell: 0 where points fell, k where filled k cells from data (saturating at 255).
    #[serde(with = "crate::bytes_as_hex")]
    pub fill_ring: Vec<u8>,
    /// Steepest slope a robot drives, degrees.
    pub max_slope_deg: f64,
    /// Highest step, metres.
    pub max_step_m: f64,
    /// Roughest patch (RMS over 3 × 3 cells), metres.
    pub max_roughness_m: f64,
    /// Interpolated ground farther than this many fill rings from data is unknown (the reach of the cloud's own
    /// sampling gaps at upload).
    #[serde(default = "legacy_fill_rings")]
    pub fill_rings: u32,
}

impl TerrainSite {
    /// The record of `surface` read from `source` under `limits`; interpolated ground counts as drivable up to
    /// `fill_rings` rings from data.
    pub fn new(surface: &TerrainSurface, source: CloudSourceDoc, limits: &GroundLimits, fill_rings: u32) -> Self {
        let g = surface.geometry;
        Self {
            source,
            width: g.width as u64,
            height: g.height as u64,
            resolution: g.resolution,
            origin: [g.origin.x, g.origin.y],
            heights_f32le: surface.heights.iter().flat_map(|&z| (z as f32).to_le_bytes()).collect(),
            fill_ring: surface.fill_ring.iter().map(|&r| r.min(255) as u8).collect(),
            max_slope_deg: limits.max_slope_rad.to_degrees(),
            max_step_m: limits.max_step_m,
            max_roughness_m: limits.max_roughness_m,
            fill_rings,
        }
    }

    /// The robot limits.
    pub fn limits(&self) -> GroundLimits {
        GroundLimits {
            max_slope_rad: self.max_slope_deg.to_radians(),
            max_step_m: self.max_step_m,
            max_roughness_m: self.max_roughness_m,
        }
    }

    /// The elevation map back, checked (sizes, finite heights).
    pub fn surface(&self) -> Result<TerrainSurface> {
        let bad = |m: String| EngineError::InvalidRequest(format!("terrain site: {m}"));
        let (w, h) = (
            usize::try_from(self.width).map_err(|_| bad("width too large".into()))?,
            usize::try_from(self.height).map_err(|_| bad("height too large".into()))?,
        );
        let geometry = GridGeometry::new(w, h, self.resolution, Point2::new(self.origin[0], self.origin[1]))?;
        let n = geometry.len();
        if self.heights_f32le.len() != 4 * n || self.fill_ring.len() != n {
            return Err(bad(format!(
                "{} height bytes and {} fill rings for {w} × {h} cells",
                self.heights_f32le.len(),
                self.fill_ring.len()
            )));
        }
        let heights: Vec<f64> = self
            .heights_f32le
            .chunks_exact(4)
            .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .collect();
        if let Some(i) = heights.iter().position(|z| !z.is_finite()) {
            return Err(bad(format!("height of cell {i} is not finite")));
        }
        let mut surface = TerrainSurface::from_heights(geometry, heights)?;
        surface.fill_ring = self.fill_ring.iter().map(|&r| u32::from(r)).collect();
        Ok(surface)
    }

    /// The occupancy a ground robot plans on, the elevation map, and a remark for the site's summary.
    pub fn parse(&self) -> Result<(OccupancyGrid, TerrainSurface, String)> {
        let surface = self.surface()?;
        let limits = self.limits();
        let trav = Traversability::new(&surface, &limits)?;
        let grid = trav.occupancy(&surface, &limits, f64::from(self.fill_rings) * self.resolution)?;
        let s = &self.source;
        let remark = format!(
            "terrain from {} ({}, {} of {} points; {}): obstacles over {:.1}° slope, {} m step, {} m roughness; \
             ground interpolated more than {:.2} m from points is unknown",
            s.name,
            s.format,
            s.points_used,
            s.points_read,
            s.conversion,
            self.max_slope_deg,
            self.max_step_m,
            self.max_roughness_m,
            f64::from(self.fill_rings) * self.resolution
        );
        Ok((grid, surface, remark))
    }
}

/// Sets each waypoint's z to the ground height under it. The surface is interpolated between cell centres; a
/// waypoint in the outer half cell takes the height at the nearest point of that domain.
pub fn set_ground_height(surface: &TerrainSurface, waypoints: &mut [WaypointDoc]) {
    for w in waypoints {
        if let Some(z) = surface.height_clamped(w.x, w.y) {
            w.z = z;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn source() -> CloudSourceDoc {
        CloudSourceDoc {
            name: "hill.ply".into(),
            format: "ply".into(),
            crs: None,
            horizontal_unit: "metre".into(),
            vertical_unit: "metre".into(),
            unit_source: "assumed".into(),
            conversion: "none".into(),
            points_read: 10,
            points_used: 10,
            ground_filter: "all points".into(),
        }
    }

    #[test]
    fn a_site_round_trips_through_its_record_and_blocks_the_steep_part() {
        // 20 m × 10 m: flat for x < 10 m, then a 45° ramp.
        let g = GridGeometry::new(40, 20, 0.5, Point2::new(100.0, 200.0)).expect("geometry");
        let surface = TerrainSurface::from_fn(g, |x, _| 5.0 + (x - 110.0).max(0.0)).expect("surface");
        let rec = TerrainSite::new(&surface, source(), &GroundLimits::default(), 4);
        let text = serde_json::to_string(&rec).expect("ser");
        let back: TerrainSite = serde_json::from_str(&text).expect("de");
        assert_eq!(back, rec);
        let (grid, s, remark) = back.parse().expect("parse");
        assert!(remark.contains("hill.ply"), "{remark}");
        assert!(
            s.heights
                .iter()
                .zip(&surface.heights)
                .all(|(a, b)| (a - b).abs() < 1e-4)
        );
        let free_at = |x: f64, y: f64| grid.is_free(g.index(g.locate(Point2::new(x, y)).expect("inside")));
        assert!(free_at(103.0, 205.0), "flat ground is free");
        assert!(!free_at(116.0, 205.0), "the 45° ramp is an obstacle");
        let mut w = [WaypointDoc {
            x: 115.0,
            y: 205.0,
            z: 0.0,
            v: 1.0,
            t: 0.0,
            kind: shift_proto::WaypointKindDoc::Cover,
            region: None,
        }];
        set_ground_height(&s, &mut w);
        assert!((w[0].z - 10.0).abs() < 0.3, "z {}", w[0].z);
    }

    #[test]
    fn a_damaged_record_is_refused_naming_what_is_wrong() {
        let g = GridGeometry::new(4, 4, 1.0, Point2::origin()).expect("geometry");
        let surface = TerrainSurface::from_fn(g, |_, _| 1.0).expect("surface");
        let mut rec = TerrainSite::new(&surface, source(), &GroundLimits::default(), 4);
        rec.heights_f32le.truncate(10);
        let e = rec.parse().expect_err("short heights");
        assert!(e.to_string().contains("height bytes"), "{e}");
        let mut rec = TerrainSite::new(&surface, source(), &GroundLimits::default(), 4);
        rec.heights_f32le[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(rec.parse().expect_err("NaN").to_string().contains("not finite"));
    }
}
