//! Fields in WGS84 (issue 23): a GeoJSON field ([`geojson`]) is projected into a local metric frame
//! ([`frame::LocalFrame`], proj4rs) centred on it, rasterised by the planner
//! ([`shift_planner::map::FieldRings`]) at a resolution chosen from the tool width, and kept as a site like
//! any map, with its geo-reference so plans can start from `[lon, lat]` and come back as GeoJSON.

pub mod frame;
pub mod geojson;

use shift_planner::map::{FieldRings, GridGeometry, OccupancyGrid};
use shift_proto::{FieldRequest, GeoReference};

use crate::error::{EngineError, Result};
use frame::LocalFrame;
use geojson::{PolygonLl, polygons};

/// Coarsest and finest resolution a field is rasterised at, metres.
const RESOLUTION_RANGE: (f64, f64) = (0.02, 5.0);

/// A field read, projected and rasterised.
#[derive(Debug)]
pub struct LoadedField {
    /// The grid (free inside, occupied outside and in holes and no-go areas).
    pub grid: OccupancyGrid,
    /// Where its frame lies.
    pub georef: GeoReference,
    /// Remarks (a resolution coarsened to fit).
    pub warnings: Vec<String>,
}

fn bad(field: &str, reason: impl std::fmt::Display) -> EngineError {
    EngineError::InvalidRequest(format!("{field}: {reason}"))
}

/// The resolution asked for, or one chosen from the tool width.
fn resolution(req: &FieldRequest) -> Result<(f64, bool)> {
    let (lo, hi) = RESOLUTION_RANGE;
    if let Some(r) = req.resolution_m {
        if !(r.is_finite() && (lo..=hi).contains(&r)) {
            return Err(bad("resolution_m", format!("{r} is outside {lo}..{hi} m")));
        }
        return Ok((r, true));
    }
    match req.tool_width {
        Some(w) if !(w.is_finite() && w > 0.0) => Err(bad("tool_width", format!("{w} is not a positive width"))),
        Some(w) => Ok(((w / 4.0).clamp(0.05, 1.0), false)),
        None => Ok((0.25, false)),
    }
}

/// Reads `req`, projects it around the centre of its bounding box and rasterises it.
pub fn load(req: &FieldRequest) -> Result<LoadedField> {
    let parts = polygons(&req.field, "field")?;
    let mut no_go = Vec::new();
    for (i, v) in req.no_go.iter().enumerate() {
        no_go.extend(polygons(v, &format!("no_go[{i}]"))?);
    }
    let (mut res, asked) = resolution(req)?;
    let origin = centre(&parts);
    let frame = LocalFrame::new(origin)?;
    let project = |ring: &[[f64; 2]]| ring.iter().map(|&p| frame.to_map(p)).collect::<Result<Vec<_>>>();
    let mut rings = FieldRings::default();
    let mut warnings = Vec::new();
    for p in &parts {
        rings.outers.push(project(&p.outer)?);
        for h in &p.holes {
            rings.holes.push(project(h)?);
        }
    }
    for (i, p) in no_go.iter().enumerate() {
        rings.holes.push(project(&p.outer)?);
        if !p.holes.is_empty() {
            warnings.push(format!("no_go[{i}]: its holes are not entered either"));
        }
    }
    // A field too large for the grid at the resolution chosen for it is rasterised coarser (said); one asked
    // for is refused.
    let span = span_m(&rings);
    let cells = |r: f64| (span[0] / r + 5.0) * (span[1] / r + 5.0);
    if cells(res) > GridGeometry::MAX_CELLS as f64 {
        if asked {
            return Err(bad(
                "resolution_m",
                format!(
                    "{res} m makes {:.0} cells of a {:.0} × {:.0} m field; at most {}",
                    cells(res),
                    span[0],
                    span[1],
                    GridGeometry::MAX_CELLS
                ),
            ));
        }
        let fine = res;
        while cells(res) > GridGeometry::MAX_CELLS as f64 {
            res *= 1.25;
        }
        if res > RESOLUTION_RANGE.1 {
            return Err(bad(
                "field",
                format!("{:.0} × {:.0} m is too large for one site", span[0], span[1]),
            ));
        }
        warnings.push(format!(
            "rasterised at {res:.3} m, not {fine:.3} m: the field is {:.0} × {:.0} m",
            span[0], span[1]
        ));
    }
    let grid = rings.rasterise(res).map_err(|e| bad("field", e))?;
    Ok(LoadedField {
        grid,
        georef: GeoReference {
            crs: frame.proj_string(),
            origin_wgs84: frame.origin_wgs84(),
        },
        warnings,
    })
}

/// Centre of the outer rings' lon/lat bounding box.
fn centre(parts: &[PolygonLl]) -> [f64; 2] {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in parts.iter().flat_map(|p| &p.outer) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0]
}

fn span_m(rings: &FieldRings) -> [f64; 2] {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in rings.outers.iter().flatten() {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    [hi[0] - lo[0], hi[1] - lo[1]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use shift_planner::geom::Point2;
    use shift_planner::map::CellState;

    /// A ~200 × 150 m field near Zurich with a ~40 m square hole.
    fn request() -> FieldRequest {
        let (lon, lat) = (8.55, 47.37);
        let (dlon, dlat) = (200.0 / 75_500.0, 150.0 / 111_200.0);
        let (hlon, hlat) = (40.0 / 75_500.0, 40.0 / 111_200.0);
        let (clon, clat) = (lon + dlon / 2.0, lat + dlat / 2.0);
        FieldRequest {
            field: json!({"type": "Polygon", "coordinates": [
                [[lon, lat], [lon + dlon, lat], [lon + dlon, lat + dlat], [lon, lat + dlat], [lon, lat]],
                [[clon, clat], [clon + hlon, clat], [clon + hlon, clat + hlat], [clon, clat + hlat], [clon, clat]],
            ]}),
            no_go: vec![],
            resolution_m: None,
            tool_width: Some(2.0),
        }
    }

    #[test]
    fn a_field_becomes_a_grid_centred_on_it_with_its_hole_occupied() {
        let f = load(&request()).expect("loads");
        assert_eq!(f.grid.geometry.resolution, 0.5);
        let free_m2 = f.grid.free_count() as f64 * 0.25;
        // 200 × 150 − 40 × 40 = 28 400 m², to the grid's and the degree arithmetic's precision.
        assert!((free_m2 - 28_400.0).abs() < 0.03 * 28_400.0, "{free_m2}");
        let frame = LocalFrame::new(f.georef.origin_wgs84).expect("frame");
        let hole_centre = frame
            .to_map([8.55 + 120.0 / 75_500.0, 47.37 + 95.0 / 111_200.0])
            .expect("projects");
        let g = &f.grid;
        let at = |p: [f64; 2]| {
            g.geometry
                .locate(Point2::new(p[0], p[1]))
                .map(|c| g.cells[g.geometry.index(c)])
        };
        assert_eq!(at(hole_centre), Some(CellState::Occupied));
        assert_eq!(
            at(frame.to_map([8.5502, 47.3702]).expect("projects")),
            Some(CellState::Free)
        );
        assert!(f.georef.crs.contains("+proj=etmerc"));
    }

    #[test]
    fn a_no_go_polygon_is_an_obstacle_and_bad_fields_name_themselves() {
        let mut req = request();
        let (lon, lat) = (8.5505, 47.3702);
        req.no_go = vec![
            json!({"type": "Polygon", "coordinates": [[[lon, lat], [lon + 0.0002, lat], [lon + 0.0002, lat + 0.0002], [lon, lat]]]}),
        ];
        let with = load(&req).expect("loads").grid.free_count();
        assert!(with < load(&request()).expect("loads").grid.free_count());
        req.no_go = vec![json!({"type": "Polygon", "coordinates": [[[lon, lat]]]})];
        assert!(
            load(&req)
                .expect_err("refused")
                .to_string()
                .starts_with("no_go[0].coordinates[0]")
        );
        let mut req = request();
        req.resolution_m = Some(0.0);
        assert!(load(&req).expect_err("refused").to_string().contains("resolution_m"));
        let mut req = request();
        req.resolution_m = Some(0.02);
        req.field = json!({"type": "Polygon", "coordinates": [[[8.0, 47.0], [8.2, 47.0], [8.2, 47.2], [8.0, 47.0]]]});
        assert!(load(&req).expect_err("refused").to_string().contains("resolution_m"));
    }
}
