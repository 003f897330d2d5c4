//! The local metric frame of a field: a transverse Mercator projection (proj4rs' `etmerc`, the
//! Poder/Engsager series PROJ uses for `tmerc`) on the WGS84 ellipsoid, centred on the field's origin, with
//! scale 1 there. Chosen over UTM because a field near a zone edge would carry up to 0.04 % scale error in
//! UTM, and over a flat-earth ENU because this is conformal: lanes keep their angles. A few kilometres from
//! the origin the scale error stays under 1e-6 (1 mm per km); the round trip lon/lat → metres → lon/lat is
//! exact to well under a millimetre (tests).

use proj4rs::Proj;
use proj4rs::transform::{Transform, TransformClosure, transform};

use crate::error::{EngineError, Result};

/// A lon/lat ↔ map-frame converter for one origin.
#[derive(Debug)]
pub struct LocalFrame {
    origin_wgs84: [f64; 2],
    wgs84: Proj,
    local: Proj,
}

/// One coordinate for proj4rs.
struct Xy(f64, f64);

impl Transform for Xy {
    fn transform_coordinates<F: TransformClosure>(&mut self, f: &mut F) -> proj4rs::errors::Result<()> {
        let (x, y, _) = f(self.0, self.1, 0.0)?;
        (self.0, self.1) = (x, y);
        Ok(())
    }
}

fn proj_error(what: &str, e: impl std::fmt::Display) -> EngineError {
    EngineError::InvalidRequest(format!("field: {what}: {e}"))
}

impl LocalFrame {
    /// The frame whose map origin (0, 0) is `origin_wgs84` = `[lon, lat]` in degrees.
    pub fn new(origin_wgs84: [f64; 2]) -> Result<Self> {
        let [lon, lat] = origin_wgs84;
        if !(lon.is_finite() && lat.is_finite() && (-180.0..=180.0).contains(&lon) && lat.abs() < 89.0) {
            return Err(proj_error("origin", format!("[{lon}, {lat}] is no usable lon/lat")));
        }
        let wgs84 = Proj::from_proj_string("+proj=longlat +ellps=WGS84 +datum=WGS84 +no_defs")
            .map_err(|e| proj_error("WGS84", e))?;
        let local =
            Proj::from_proj_string(&Self::proj_string_of(origin_wgs84)).map_err(|e| proj_error("local frame", e))?;
        Ok(Self {
            origin_wgs84,
            wgs84,
            local,
        })
    }

    fn proj_string_of([lon, lat]: [f64; 2]) -> String {
        format!("+proj=etmerc +lat_0={lat} +lon_0={lon} +k=1 +x_0=0 +y_0=0 +ellps=WGS84 +datum=WGS84 +units=m +no_defs")
    }

    /// The frame's PROJ string (what a plan names as its CRS).
    pub fn proj_string(&self) -> String {
        Self::proj_string_of(self.origin_wgs84)
    }

    /// Its origin, `[lon, lat]` degrees.
    pub fn origin_wgs84(&self) -> [f64; 2] {
        self.origin_wgs84
    }

    /// `[lon, lat]` degrees → `[x, y]` metres (x east, y north at the origin).
    pub fn to_map(&self, [lon, lat]: [f64; 2]) -> Result<[f64; 2]> {
        let mut p = Xy(lon.to_radians(), lat.to_radians());
        transform(&self.wgs84, &self.local, &mut p).map_err(|e| proj_error("projection", e))?;
        Ok([p.0, p.1])
    }

    /// `[x, y]` metres → `[lon, lat]` degrees.
    pub fn to_wgs84(&self, [x, y]: [f64; 2]) -> Result<[f64; 2]> {
        let mut p = Xy(x, y);
        transform(&self.local, &self.wgs84, &mut p).map_err(|e| proj_error("projection", e))?;
        Ok([p.0.to_degrees(), p.1.to_degrees()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Metres between two lon/lat points on the ellipsoid (radii of curvature at the mean latitude: good to
    /// about 1e-6 over a few km).
    fn metres_apart(a: [f64; 2], b: [f64; 2]) -> f64 {
        let lat = ((a[1] + b[1]) / 2.0).to_radians();
        // WGS84 radii of curvature at `lat`.
        let (aa, e2) = (6_378_137.0, 6.694_379_990_14e-3);
        let w = (1.0 - e2 * lat.sin().powi(2)).sqrt();
        let (n, m) = (aa / w, aa * (1.0 - e2) / w.powi(3));
        let dx = (b[0] - a[0]).to_radians() * n * lat.cos();
        let dy = (b[1] - a[1]).to_radians() * m;
        dx.hypot(dy)
    }

    #[test]
    fn the_origin_is_zero_and_the_round_trip_is_under_a_millimetre() {
        for origin in [
            [8.55, 47.37],
            [-122.97, 44.05],
            [151.2, -33.86],
            [0.0, 0.0],
            [179.9, 60.0],
        ] {
            let f = LocalFrame::new(origin).expect("frame");
            let o = f.to_map(origin).expect("projects");
            assert!(o[0].abs() < 1e-6 && o[1].abs() < 1e-6, "{origin:?} → {o:?}");
            let mut worst: f64 = 0.0;
            for (dlon, dlat) in [(0.01, 0.0), (0.0, 0.01), (-0.02, 0.015), (0.03, -0.02)] {
                let ll = [origin[0] + dlon, origin[1] + dlat];
                let xy = f.to_map(ll).expect("projects");
                let back = f.to_wgs84(xy).expect("inverts");
                worst = worst.max(metres_apart(ll, back));
                // Distances from the origin agree with the ellipsoid's to 1e-5 relative (scale 1 at the origin).
                let d = xy[0].hypot(xy[1]);
                let want = metres_apart(origin, ll);
                assert!(
                    (d - want).abs() < 1e-5 * want + 0.05,
                    "{origin:?} {ll:?}: {d} vs {want}"
                );
            }
            assert!(worst < 1e-3, "{origin:?}: round trip off by {worst} m");
        }
    }

    #[test]
    fn north_is_y_and_east_is_x() {
        let f = LocalFrame::new([10.0, 50.0]).expect("frame");
        let north = f.to_map([10.0, 50.001]).expect("projects");
        let east = f.to_map([10.001, 50.0]).expect("projects");
        assert!(north[1] > 100.0 && north[0].abs() < 1e-6, "{north:?}");
        assert!(east[0] > 60.0 && east[1].abs() < 0.01, "{east:?}");
    }

    #[test]
    fn unusable_origins_are_refused() {
        for origin in [[f64::NAN, 0.0], [200.0, 10.0], [10.0, 89.5]] {
            assert!(LocalFrame::new(origin).is_err(), "{origin:?}");
        }
    }
}
