//! Sites: a named map the plans of that site are computed on.
//!
//! A site keeps the bytes it was uploaded as ([`MapSource`]) so the store can persist exactly what the client
//! sent and a restart re-reads it with the same code, plus the parsed grid shared by every plan job.

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_planner::map::DistanceField;
use shift_planner::map::grid::OccupancyGrid;
use shift_planner::map::json_grid::JsonGrid;
use shift_planner::map::ros::{MapYaml, grid_from_image};
use shift_planner::terrain::TerrainSurface;
use shift_proto::{FieldRequest, GeoReference, SiteSummary};

use crate::terrain_site::TerrainSite;

use crate::error::{EngineError, Result};

/// A map as uploaded: map_server YAML + image bytes, or a JSON grid (DESIGN §5.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MapSource {
    /// map_server YAML text and the PGM/PNG bytes it describes (the YAML's `image` name is ignored).
    Ros {
        /// YAML text.
        yaml: String,
        /// Image bytes.
        #[serde(with = "crate::bytes_as_hex")]
        image: Vec<u8>,
    },
    /// nav_msgs/OccupancyGrid-shaped JSON text.
    Json {
        /// JSON text.
        text: String,
    },
    /// A field drawn in GeoJSON (`POST /v1/sites/{site}/field`).
    Field {
        /// The upload as sent.
        request: FieldRequest,
    },
    /// A point cloud's smoothed elevation map and ground-robot limits (`POST /v1/sites/{site}/terrain`).
    Terrain {
        /// The elevation map and limits.
        terrain: Box<TerrainSite>,
    },
}

/// A parsed site map.
#[derive(Debug, Clone)]
pub struct SiteMap {
    /// The thresholded grid, shared with running jobs.
    pub grid: Arc<OccupancyGrid>,
    /// Distance from every cell centre to the nearest non-free cell centre (the map border counts as one),
    /// metres: the static half of the obstacle distance path checks use (the live ikd-tree is the other).
    pub clearance: Arc<DistanceField>,
    /// Remarks from reading it.
    pub warnings: Vec<String>,
    /// Where its frame lies on the earth (fields only).
    pub georef: Option<GeoReference>,
    /// The ground's height (terrain sites only): plans and corrections get their waypoints' z from it.
    pub elevation: Option<Arc<TerrainSurface>>,
}

impl SiteMap {
    /// A parsed map with its clearance field (an exact distance transform: linear in the cells).
    pub fn new(grid: OccupancyGrid, warnings: Vec<String>) -> Self {
        let clearance = DistanceField::compute(grid.geometry, |i| !grid.is_free(i), true);
        Self {
            grid: Arc::new(grid),
            clearance: Arc::new(clearance),
            warnings,
            georef: None,
            elevation: None,
        }
    }
}

impl MapSource {
    /// Parses and validates the map (pure; may take a while on large images, so callers run it off the
    /// async workers).
    pub fn parse(&self) -> Result<SiteMap> {
        match self {
            Self::Ros { yaml, image } => {
                let y = MapYaml::parse(yaml)?;
                let loaded = grid_from_image(&y, image)?;
                Ok(SiteMap::new(loaded.grid, loaded.warnings))
            }
            Self::Json { text } => {
                let grid = JsonGrid::parse(text)?.into_grid()?;
                Ok(SiteMap::new(grid, Vec::new()))
            }
            Self::Field { request } => {
                let field = crate::field::load(request)?;
                let mut map = SiteMap::new(field.grid, field.warnings);
                map.georef = Some(field.georef);
                Ok(map)
            }
            Self::Terrain { terrain } => {
                let (grid, surface, remark) = terrain.parse()?;
                let mut map = SiteMap::new(grid, vec![remark]);
                map.elevation = Some(Arc::new(surface));
                Ok(map)
            }
        }
    }
}

/// What the store keeps per site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteRecord {
    /// Site name.
    pub site: String,
    /// The map as uploaded.
    pub source: MapSource,
    /// Upload time, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

/// A site's record with its parsed map, as events carry it. In a recording it is the record alone: reading
/// one back parses the map again, with the code the daemon uses.
#[derive(Debug, Clone)]
pub struct LoadedSite {
    /// What the store keeps.
    pub record: SiteRecord,
    /// The parsed map.
    pub map: SiteMap,
}

impl LoadedSite {
    /// Parses `record`'s map.
    pub fn parse(record: SiteRecord) -> Result<Self> {
        let map = record.source.parse()?;
        Ok(Self { record, map })
    }
}

impl Serialize for LoadedSite {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.record.serialize(s)
    }
}

impl<'de> Deserialize<'de> for LoadedSite {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let record = SiteRecord::deserialize(d)?;
        Self::parse(record).map_err(serde::de::Error::custom)
    }
}

/// A site held by the engine.
#[derive(Debug, Clone)]
pub(crate) struct Site {
    pub record: SiteRecord,
    pub map: SiteMap,
    /// Last time robots' points reached its live map, milliseconds since the Unix epoch (0 = never).
    pub last_fed_ms: u64,
}

impl From<LoadedSite> for Site {
    fn from(s: LoadedSite) -> Self {
        Self {
            record: s.record,
            map: s.map,
            last_fed_ms: 0,
        }
    }
}

impl Site {
    pub fn summary(&self) -> SiteSummary {
        let g = self.map.grid.geometry;
        SiteSummary {
            site: self.record.site.clone(),
            width: g.width as u64,
            height: g.height as u64,
            resolution: g.resolution,
            origin: [g.origin.x, g.origin.y],
            free_cells: self.map.grid.free_count() as u64,
            points_in_tree: 0,
            updates_per_s: 0.0,
            dropped_clouds: 0,
            updated_ms: self.record.updated_ms,
            warnings: self.map.warnings.clone(),
            crs: self.map.georef.as_ref().map(|g| g.crs.clone()),
            origin_wgs84: self.map.georef.as_ref().map(|g| g.origin_wgs84),
        }
    }
}

/// Checks a site name by the one name rule ([`shift_proto::keys::validate_name`]): it becomes part of URLs and
/// Zenoh keys.
pub fn validate_site_name(name: &str) -> Result<()> {
    validate_name("site", name)
}

/// Checks a name of `what` (`site`, `robot`) by the one name rule ([`shift_proto::keys::validate_name`]).
pub fn validate_name(what: &'static str, name: &str) -> Result<()> {
    shift_proto::keys::validate_name(what, name).map_err(|e| EngineError::InvalidRequest(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_source_parses_and_round_trips() {
        let text = r#"{"resolution": 0.5, "origin": [0, 0], "width": 2, "height": 2, "cells": [0, 0, 100, -1]}"#;
        let src = MapSource::Json { text: text.into() };
        let map = src.parse().expect("valid grid");
        assert_eq!(map.grid.free_count(), 2);
        let ros = MapSource::Ros {
            yaml: "image: m.pgm".into(),
            image: vec![0, 1, 0xab, 0xff],
        };
        let back: MapSource = serde_json::from_str(&serde_json::to_string(&ros).expect("ser")).expect("de");
        assert_eq!(back, ros);
    }

    #[test]
    fn bad_maps_are_errors() {
        let src = MapSource::Json {
            text: r#"{"resolution": 0, "origin": [0, 0], "width": 1, "height": 1, "cells": [0]}"#.into(),
        };
        assert!(matches!(src.parse(), Err(EngineError::Map(_))));
        let src = MapSource::Ros {
            yaml: "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]".into(),
            image: b"not an image".to_vec(),
        };
        assert!(src.parse().is_err());
    }

    #[test]
    fn site_names_follow_the_one_rule() {
        // The rule itself is tested once, in proto; here only that its error names the field.
        let e = validate_site_name("a/b").expect_err("slash");
        assert!(
            matches!(&e, EngineError::InvalidRequest(m) if m.starts_with("invalid site `a/b`")),
            "{e}"
        );
    }
}
