//! The attribute map A(x, y) ∈ [0, 1] of seed 000 §V (dirtiness, dryness…): a raster aligned with the
//! occupancy grid, read from a grey image (A = value / 255, brighter = more) or rasterised from Gaussian blobs.

use crate::error::{PlannerError, Result, finite};
use crate::geom::Point2;
use crate::map::GridGeometry;

/// One Gaussian bump of attribute: `amplitude · exp(−|p − centre|² / (2 sigma²))`, summed over blobs and
/// clamped to [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttributeBlob {
    /// Centre, map frame, metres.
    pub centre: Point2,
    /// Standard deviation, metres (> 0).
    pub sigma_m: f64,
    /// Peak value, dimensionless (usually in [0, 1]).
    pub amplitude: f64,
}

/// A(x, y) ∈ [0, 1] per cell of a grid geometry (row 0 at the map origin, like the occupancy grid).
#[derive(Debug, Clone, PartialEq)]
pub struct AttributeMap {
    geometry: GridGeometry,
    values: Vec<f32>,
}

impl AttributeMap {
    /// A = `value` everywhere (clamped to [0, 1]); `uniform(g, 1.0)` is the "no attribute" map.
    pub fn uniform(geometry: GridGeometry, value: f64) -> Self {
        let v = if value.is_finite() { value.clamp(0.0, 1.0) } else { 1.0 };
        Self {
            geometry,
            values: vec![v as f32; geometry.len()],
        }
    }

    /// Per-cell values, row-major from the origin row; each is clamped to [0, 1] and must be finite.
    pub fn from_values(geometry: GridGeometry, values: Vec<f64>) -> Result<Self> {
        if values.len() != geometry.len() {
            return Err(PlannerError::SizeMismatch {
                width: geometry.width,
                height: geometry.height,
                expected: geometry.len(),
                got: values.len(),
            });
        }
        let mut out = Vec::with_capacity(values.len());
        for v in values {
            out.push(finite("attribute value", v)?.clamp(0.0, 1.0) as f32);
        }
        Ok(Self { geometry, values: out })
    }

    /// Decodes a grey image (PGM or PNG bytes; colour is averaged) of exactly the grid's size. Image row 0 is
    /// the top of the map, as in map_server images; A = value / 255.
    pub fn from_image_bytes(geometry: GridGeometry, bytes: &[u8]) -> Result<Self> {
        let img = image::load_from_memory(bytes).map_err(|e| PlannerError::ImageDecode(e.to_string()))?;
        let rgb = img.to_rgb8();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        if (w, h) != (geometry.width, geometry.height) {
            return Err(PlannerError::InvalidParam {
                name: "attribute",
                reason: format!(
                    "image is {w} × {h} pixels, the map is {} × {} cells",
                    geometry.width, geometry.height
                ),
            });
        }
        let mut values = vec![0.0f32; w * h];
        for (px, py, p) in rgb.enumerate_pixels() {
            let grey = (f32::from(p.0[0]) + f32::from(p.0[1]) + f32::from(p.0[2])) / 3.0;
            values[(h - 1 - py as usize) * w + px as usize] = grey / 255.0;
        }
        Ok(Self { geometry, values })
    }

    /// Rasterises blobs at the cell centres (sum, clamped to [0, 1]). No blobs gives A = 0 everywhere.
    pub fn from_blobs(geometry: GridGeometry, blobs: &[AttributeBlob]) -> Result<Self> {
        for b in blobs {
            finite("blob x", b.centre.x)?;
            finite("blob y", b.centre.y)?;
            finite("blob amplitude", b.amplitude)?;
            if !(b.sigma_m.is_finite() && b.sigma_m > 0.0) {
                return Err(PlannerError::InvalidParam {
                    name: "blob sigma",
                    reason: format!("must be a positive number of metres, got {}", b.sigma_m),
                });
            }
        }
        let values = (0..geometry.len())
            .map(|i| {
                let p = geometry.center_of(i);
                let a: f64 = blobs
                    .iter()
                    .map(|b| {
                        let d2 = (p - b.centre).norm_squared();
                        b.amplitude * (-d2 / (2.0 * b.sigma_m * b.sigma_m)).exp()
                    })
                    .sum();
                a.clamp(0.0, 1.0) as f32
            })
            .collect();
        Ok(Self { geometry, values })
    }

    /// The raster geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// A of cell `i`.
    #[inline]
    pub fn at(&self, i: usize) -> f64 {
        f64::from(self.values[i])
    }

    /// A at a map-frame point, bilinear between cell centres (edge cells extend to the border; 0 off the map
    /// or for a non-finite point).
    pub fn at_point(&self, p: Point2) -> f64 {
        let g = &self.geometry;
        let (cx, cy) = g.to_cell_coords(p);
        if !(cx >= 0.0 && cy >= 0.0 && cx <= g.width as f64 && cy <= g.height as f64) {
            return 0.0;
        }
        let (fx, fy) = (
            (cx - 0.5).clamp(0.0, (g.width - 1) as f64),
            (cy - 0.5).clamp(0.0, (g.height - 1) as f64),
        );
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(g.width - 1), (y0 + 1).min(g.height - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let v = |x: usize, y: usize| self.at(y * g.width + x);
        let bottom = v(x0, y0) * (1.0 - tx) + v(x1, y0) * tx;
        let top = v(x0, y1) * (1.0 - tx) + v(x1, y1) * tx;
        bottom * (1.0 - ty) + top * ty
    }

    /// Smallest and largest A over the cells where `mask` holds; `None` when no cell does.
    pub fn range_over(&self, mask: &[bool]) -> Option<(f64, f64)> {
        let mut r: Option<(f64, f64)> = None;
        for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
            let a = self.at(i);
            r = Some(r.map_or((a, a), |(lo, hi)| (lo.min(a), hi.max(a))));
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geom() -> GridGeometry {
        GridGeometry::new(4, 3, 0.5, Point2::new(1.0, 2.0)).expect("valid")
    }

    #[test]
    fn image_rows_flip_and_scale() {
        // 4 × 3 PGM: top row 255, others 0.
        let mut pgm = b"P5\n4 3\n255\n".to_vec();
        pgm.extend([255u8; 4]);
        pgm.extend([0u8; 8]);
        let a = AttributeMap::from_image_bytes(geom(), &pgm).expect("decodes");
        assert_eq!(a.at(0), 0.0);
        assert_eq!(a.at(2 * 4 + 1), 1.0);
        // Halfway between row 1 and row 2 centres: 0.5.
        let p = Point2::new(1.0 + 0.75, 2.0 + 1.0);
        assert!((a.at_point(p) - 0.5).abs() < 1e-9);
        assert_eq!(a.at_point(Point2::new(-5.0, 0.0)), 0.0);
        let mut wrong = b"P5\n2 2\n255\n".to_vec();
        wrong.extend([0u8; 4]);
        assert!(AttributeMap::from_image_bytes(geom(), &wrong).is_err());
        assert!(AttributeMap::from_image_bytes(geom(), b"garbage").is_err());
    }

    #[test]
    fn blobs_sum_and_clamp() {
        let g = geom();
        let c = g.center_of(5);
        let one = AttributeBlob {
            centre: c,
            sigma_m: 0.5,
            amplitude: 0.7,
        };
        let a = AttributeMap::from_blobs(g, &[one]).expect("ok");
        assert!((a.at(5) - 0.7).abs() < 1e-6);
        assert!(a.at(0) < 0.7);
        let two = AttributeMap::from_blobs(g, &[one, one]).expect("ok");
        assert_eq!(two.at(5), 1.0);
        let bad = AttributeBlob { sigma_m: 0.0, ..one };
        assert!(AttributeMap::from_blobs(g, &[bad]).is_err());
        assert!(AttributeMap::from_values(g, vec![0.5; 3]).is_err());
        let range = a.range_over(&[true; 12]).expect("cells");
        assert!(range.0 < range.1);
    }
}
