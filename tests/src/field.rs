//! Fields in lon/lat for the tests: a spot on the earth, metres ↔ degrees near it (a local approximation good
//! to a few centimetres over a few hundred metres, independent of the daemon's projection), rings and an
//! even-odd point-in-ring test in degrees.

use serde_json::{Value, json};

/// Longitude of the test fields' south-west corner, degrees (a field near Zurich).
pub const LON0: f64 = 8.55;
/// Its latitude, degrees.
pub const LAT0: f64 = 47.37;
/// Metres per degree of latitude there (WGS84 meridian arc).
pub const M_PER_DEG_LAT: f64 = 111_180.0;
/// Metres per degree of longitude there.
pub const M_PER_DEG_LON: f64 = 75_480.0;

/// `[lon, lat]` of the point `x` metres east and `y` metres north of (LON0, LAT0).
pub fn ll(x: f64, y: f64) -> [f64; 2] {
    [LON0 + x / M_PER_DEG_LON, LAT0 + y / M_PER_DEG_LAT]
}

/// A closed GeoJSON ring through `pts` (metres east/north of the corner), counter-clockwise as given.
pub fn ring(pts: &[(f64, f64)]) -> Value {
    let mut r: Vec<[f64; 2]> = pts.iter().map(|&(x, y)| ll(x, y)).collect();
    if let Some(&first) = r.first() {
        r.push(first);
    }
    json!(r)
}

/// Even-odd test of `p` against a ring of `[lon, lat]` (closed or not).
pub fn inside(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = ring.len();
    for i in 0..n {
        let [xi, yi] = ring[i];
        let [xj, yj] = ring[(i + n - 1) % n];
        if (yi > p[1]) != (yj > p[1]) && p[0] < (xj - xi) * (p[1] - yi) / (yj - yi) + xi {
            inside = !inside;
        }
    }
    inside
}
