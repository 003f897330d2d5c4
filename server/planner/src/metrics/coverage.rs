//! Swept coverage on the grid: which cells lie within `tool_width / 2` of a path (DESIGN §6 "covered").
//!
//! Each segment sweeps a capsule (the segment dilated by the half-width). The capsule is convex, so each grid
//! row meets it in one interval, computed exactly from the two end disks and the swept rectangle; stamping a
//! segment costs O(cells covered), independent of its direction.

use crate::geom::{Point2, Vector2};
use crate::map::GridGeometry;

/// A boolean layer of covered cells.
#[derive(Debug, Clone)]
pub struct CoverageRaster {
    geometry: GridGeometry,
    half_width_m: f64,
    covered: Vec<bool>,
}

impl CoverageRaster {
    /// An empty raster for a tool of width `2 · half_width_m`. A cell exactly at the half-width counts as
    /// covered (a nanometre of tolerance absorbs floating-point noise in lane offsets).
    pub fn new(geometry: GridGeometry, half_width_m: f64) -> Self {
        Self {
            covered: vec![false; geometry.len()],
            geometry,
            half_width_m: half_width_m + 1e-9,
        }
    }

    /// The covered flags, row-major.
    pub fn covered(&self) -> &[bool] {
        &self.covered
    }

    /// True when cell `i` is covered.
    #[inline]
    pub fn is_covered(&self, i: usize) -> bool {
        self.covered[i]
    }

    /// Number of covered cells.
    pub fn count(&self) -> usize {
        self.covered.iter().filter(|&&c| c).count()
    }

    /// Marks the cells whose centre is within the half-width of a polyline.
    pub fn stamp_polyline(&mut self, points: &[Point2]) {
        match points {
            [] => {}
            [p] => {
                self.stamp_segment(*p, *p);
            }
            _ => {
                for w in points.windows(2) {
                    self.stamp_segment(w[0], w[1]);
                }
            }
        }
    }

    /// Marks the cells whose centre is within the half-width of segment `a`–`b`; returns how many were newly
    /// covered.
    pub fn stamp_segment(&mut self, a: Point2, b: Point2) -> usize {
        let mut fresh = 0;
        for_each_cell_in_capsule(&self.geometry, a, b, self.half_width_m, |i| {
            if !self.covered[i] {
                self.covered[i] = true;
                fresh += 1;
            }
        });
        fresh
    }
}

/// Calls `f` with the index of every cell whose centre lies within `radius` of segment `a`–`b`.
pub fn for_each_cell_in_capsule(g: &GridGeometry, a: Point2, b: Point2, radius: f64, mut f: impl FnMut(usize)) {
    if !(a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite() && radius >= 0.0) {
        return;
    }
    let res = g.resolution;
    let ymin = a.y.min(b.y) - radius;
    let ymax = a.y.max(b.y) + radius;
    // Rows whose centre y is within [ymin, ymax].
    let row0 = (((ymin - g.origin.y) / res - 0.5).ceil()).max(0.0) as usize;
    let row1f = ((ymax - g.origin.y) / res - 0.5).floor();
    if row1f < 0.0 {
        return;
    }
    let row1 = (row1f as usize).min(g.height - 1);
    let d = b - a;
    let len = d.norm();
    let n = if len > 1e-12 {
        Vector2::new(-d.y / len, d.x / len)
    } else {
        Vector2::new(0.0, 1.0)
    };
    let corners = [a + n * radius, b + n * radius, b - n * radius, a - n * radius];
    for row in row0..=row1 {
        let yc = g.origin.y + (row as f64 + 0.5) * res;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for c in [a, b] {
            let dy = yc - c.y;
            let r2 = radius * radius - dy * dy;
            if r2 >= 0.0 {
                let s = r2.sqrt();
                lo = lo.min(c.x - s);
                hi = hi.max(c.x + s);
            }
        }
        if len > 1e-12 {
            // The swept rectangle's intersection with the row line.
            for k in 0..4 {
                let (p, q) = (corners[k], corners[(k + 1) % 4]);
                if (p.y - yc) * (q.y - yc) <= 0.0 {
                    let x = if (q.y - p.y).abs() < 1e-15 {
                        lo = lo.min(p.x.min(q.x));
                        hi = hi.max(p.x.max(q.x));
                        continue;
                    } else {
                        p.x + (yc - p.y) * (q.x - p.x) / (q.y - p.y)
                    };
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
        if lo > hi {
            continue;
        }
        let c0 = (((lo - g.origin.x) / res - 0.5).ceil()).max(0.0);
        let c1 = ((hi - g.origin.x) / res - 0.5).floor();
        if c1 < 0.0 || c0 > (g.width - 1) as f64 {
            continue;
        }
        let (c0, c1) = (c0 as usize, (c1 as usize).min(g.width - 1));
        for col in c0..=c1 {
            f(row * g.width + col);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::point_segment_distance;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn capsule_matches_brute_force(ax in -1.0f64..6.0, ay in -1.0f64..6.0, bx in -1.0f64..6.0, by in -1.0f64..6.0, r in 0.0f64..1.5) {
            let g = GridGeometry::new(50, 40, 0.1, Point2::new(0.3, 0.2)).expect("valid");
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            let mut got = vec![false; g.len()];
            for_each_cell_in_capsule(&g, a, b, r, |i| got[i] = true);
            for (i, &hit) in got.iter().enumerate() {
                let d = point_segment_distance(g.center_of(i), a, b);
                if (d - r).abs() > 1e-9 {
                    prop_assert_eq!(hit, d <= r, "cell {} distance {} radius {}", i, d, r);
                }
            }
        }
    }
}
