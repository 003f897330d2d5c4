//! Reading fields drawn in GeoJSON (RFC 7946): a Polygon, MultiPolygon, a Feature holding one, or a
//! FeatureCollection of them, in `[lon, lat]` degrees. Rings must be closed (first position = last) with at
//! least four positions; holes are obstacles. Every refusal names where it is (`field.coordinates[0][3]`),
//! and the polygons are checked for self-intersections and crossing rings with `geo`'s OGC validation.

use geo::{Coord, LineString, Polygon, Validation};
use serde_json::Value;

use crate::error::{EngineError, Result};

/// A polygon in `[lon, lat]` degrees, rings without their closing position.
#[derive(Debug, Clone, PartialEq)]
pub struct PolygonLl {
    /// The boundary.
    pub outer: Vec<[f64; 2]>,
    /// Holes.
    pub holes: Vec<Vec<[f64; 2]>>,
}

/// Most positions a field may have in all (rasterising tests every row against every edge).
pub const MAX_POSITIONS: usize = 100_000;

fn bad(path: &str, reason: impl std::fmt::Display) -> EngineError {
    EngineError::InvalidRequest(format!("{path}: {reason}"))
}

/// The polygons of `value` (a GeoJSON object) at `path`.
pub fn polygons(value: &Value, path: &str) -> Result<Vec<PolygonLl>> {
    let kind = value
        .get("type")
        .and_then(Value::as_str)
        .ok_or_else(|| bad(path, "a GeoJSON object with a \"type\" is expected"))?;
    let coords = |v: &Value| {
        v.get("coordinates")
            .ok_or_else(|| bad(path, format!("{kind} without \"coordinates\"")))
            .cloned()
    };
    let out = match kind {
        "Polygon" => vec![polygon(&coords(value)?, &format!("{path}.coordinates"))?],
        "MultiPolygon" => {
            let c = coords(value)?;
            let parts = c
                .as_array()
                .ok_or_else(|| bad(&format!("{path}.coordinates"), "an array of polygons is expected"))?;
            parts
                .iter()
                .enumerate()
                .map(|(i, p)| polygon(p, &format!("{path}.coordinates[{i}]")))
                .collect::<Result<_>>()?
        }
        "Feature" => {
            let g = value
                .get("geometry")
                .filter(|g| !g.is_null())
                .ok_or_else(|| bad(path, "a Feature without geometry"))?;
            polygons(g, &format!("{path}.geometry"))?
        }
        "FeatureCollection" => {
            let fs = value
                .get("features")
                .and_then(Value::as_array)
                .ok_or_else(|| bad(path, "a FeatureCollection without \"features\""))?;
            let mut all = Vec::new();
            for (i, f) in fs.iter().enumerate() {
                all.extend(polygons(f, &format!("{path}.features[{i}]"))?);
            }
            all
        }
        other => {
            return Err(bad(
                path,
                format!("{other:?} is not a field: send a Polygon, MultiPolygon, Feature or FeatureCollection"),
            ));
        }
    };
    if out.is_empty() {
        return Err(bad(path, "no polygon"));
    }
    let positions: usize = out
        .iter()
        .map(|p| p.outer.len() + p.holes.iter().map(Vec::len).sum::<usize>())
        .sum();
    if positions > MAX_POSITIONS {
        return Err(bad(path, format!("{positions} positions; at most {MAX_POSITIONS}")));
    }
    Ok(out)
}

fn polygon(value: &Value, path: &str) -> Result<PolygonLl> {
    let rings = value
        .as_array()
        .ok_or_else(|| bad(path, "an array of linear rings is expected"))?;
    if rings.is_empty() {
        return Err(bad(path, "a polygon needs its boundary ring"));
    }
    let mut read = rings
        .iter()
        .enumerate()
        .map(|(i, r)| ring(r, &format!("{path}[{i}]")))
        .collect::<Result<Vec<_>>>()?;
    let outer = read.remove(0);
    let poly = PolygonLl { outer, holes: read };
    let line = |r: &[[f64; 2]]| LineString::from(r.iter().map(|&[x, y]| Coord { x, y }).collect::<Vec<_>>());
    let shape = Polygon::new(line(&poly.outer), poly.holes.iter().map(|h| line(h)).collect());
    if let Err(e) = shape.check_validation() {
        return Err(bad(path, format!("not a valid polygon: {e}")));
    }
    Ok(poly)
}

/// A closed linear ring; returned without its closing position.
fn ring(value: &Value, path: &str) -> Result<Vec<[f64; 2]>> {
    let positions = value
        .as_array()
        .ok_or_else(|| bad(path, "an array of positions is expected"))?;
    if positions.len() < 4 {
        return Err(bad(
            path,
            format!("a linear ring needs at least 4 positions, got {}", positions.len()),
        ));
    }
    let mut out = Vec::with_capacity(positions.len());
    for (i, p) in positions.iter().enumerate() {
        out.push(position(p, &format!("{path}[{i}]"))?);
    }
    if out.first() != out.last() {
        return Err(bad(
            path,
            "the ring is not closed (its last position must repeat its first)",
        ));
    }
    out.pop();
    Ok(out)
}

fn position(value: &Value, path: &str) -> Result<[f64; 2]> {
    let nums = value
        .as_array()
        .filter(|a| (2..=3).contains(&a.len()))
        .ok_or_else(|| bad(path, "a position [lon, lat] (or [lon, lat, alt]) is expected"))?;
    let num = |i: usize| nums[i].as_f64().filter(|v| v.is_finite());
    let (Some(lon), Some(lat)) = (num(0), num(1)) else {
        return Err(bad(path, "longitude and latitude must be finite numbers"));
    };
    if !(-90.0..=90.0).contains(&lat) {
        let hint = if (-90.0..=90.0).contains(&lon) {
            " (GeoJSON is [lon, lat]: are they swapped?)"
        } else {
            ""
        };
        return Err(bad(path, format!("latitude {lat} is outside -90..90{hint}")));
    }
    if !(-180.0..=180.0).contains(&lon) {
        return Err(bad(path, format!("longitude {lon} is outside -180..180")));
    }
    Ok([lon, lat])
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn square(lon: f64, lat: f64, d: f64) -> Value {
        json!([
            [lon, lat],
            [lon + d, lat],
            [lon + d, lat + d],
            [lon, lat + d],
            [lon, lat]
        ])
    }

    #[test]
    fn polygons_features_and_collections_are_read_with_their_holes() {
        let poly = json!({"type": "Polygon", "coordinates": [square(8.0, 47.0, 0.01), square(8.004, 47.004, 0.001)]});
        let got = polygons(&poly, "field").expect("reads");
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].outer.len(), got[0].holes.len()), (4, 1));
        let feature = json!({"type": "Feature", "properties": {}, "geometry": poly});
        let multi =
            json!({"type": "MultiPolygon", "coordinates": [[square(8.0, 47.0, 0.01)], [square(8.02, 47.0, 0.01)]]});
        let coll = json!({"type": "FeatureCollection", "features": [feature, {"type": "Feature", "geometry": multi}]});
        assert_eq!(polygons(&coll, "field").expect("reads").len(), 3);
    }

    #[test]
    fn every_refusal_names_where_it_is() {
        let cases = [
            (
                json!({"type": "Point", "coordinates": [8.0, 47.0]}),
                "field: \"Point\" is not a field",
            ),
            (json!({"type": "Polygon"}), "without \"coordinates\""),
            (
                json!({"type": "Polygon", "coordinates": [[[8.0, 47.0], [8.1, 47.0], [8.1, 47.1], [8.0, 47.0 ]], [[8.0, 47.0], [8.0, 47.0]]]}),
                "field.coordinates[1]: a linear ring needs at least 4 positions",
            ),
            (
                json!({"type": "Polygon", "coordinates": [[[8.0, 47.0], [8.1, 47.0], [8.1, 47.1], [8.0, 47.1]]]}),
                "field.coordinates[0]: the ring is not closed",
            ),
            (
                json!({"type": "Polygon", "coordinates": [[[47.0, 8.0], [47.0, 98.0], [47.1, 98.1], [47.0, 8.0]]]}),
                "field.coordinates[0][1]: latitude 98 is outside -90..90 (GeoJSON is [lon, lat]: are they swapped?)",
            ),
            (
                json!({"type": "Polygon", "coordinates": [[[8.0, 47.0], ["x", 47.0], [8.1, 47.1], [8.0, 47.0]]]}),
                "field.coordinates[0][1]: longitude and latitude must be finite",
            ),
            (
                // A bow tie crosses itself.
                json!({"type": "Polygon", "coordinates": [[[8.0, 47.0], [8.1, 47.1], [8.1, 47.0], [8.0, 47.1], [8.0, 47.0]]]}),
                "field.coordinates: not a valid polygon",
            ),
            (
                json!({"type": "FeatureCollection", "features": []}),
                "field: no polygon",
            ),
            (
                json!({"type": "Feature", "geometry": null}),
                "field: a Feature without geometry",
            ),
        ];
        for (value, want) in cases {
            let e = polygons(&value, "field").expect_err("refused").to_string();
            assert!(e.contains(want), "{value}: {e}");
        }
    }
}
