//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012) with the nearest site of every
//! cell (feature transform), in linear time.
//!
//! Distances are between cell centres, in metres. Sites are given by a predicate; optionally the ring of
//! cells just outside the map counts as sites too (so the map edge behaves like a wall: the robot never
//! plans to hang over the edge of what was mapped).

use super::grid::GridGeometry;
use crate::geom::Point2;

const INF: f64 = 1e20;

/// Distance from every cell centre to the nearest site, with that site.
#[derive(Debug, Clone)]
pub struct DistanceField {
    geometry: GridGeometry,
    /// Padding applied around the grid for feature coordinates (1 when the border is a site, else 0).
    pad: usize,
    /// Distance in metres per cell (`f32::INFINITY` when there is no site at all).
    dist_m: Vec<f32>,
    /// Nearest site per cell as a linear index in the padded grid (`u32::MAX` when none).
    feature: Vec<u32>,
}

/// Grids of at least this many cells compute the row pass of the transform on two threads.
const PARALLEL_CELLS: usize = 250_000;

impl DistanceField {
    /// Heap bytes held (the distances and nearest sites, by capacity).
    pub fn memory_bytes(&self) -> usize {
        self.dist_m.capacity() * size_of::<f32>() + self.feature.capacity() * size_of::<u32>()
    }

    /// Computes the transform. `is_site(i)` tells whether cell `i` is a site; `border_is_site` adds the ring of
    /// cells around the map as sites.
    pub fn compute(geometry: GridGeometry, is_site: impl Fn(usize) -> bool, border_is_site: bool) -> Self {
        let pad = usize::from(border_is_site);
        let (w, h) = (geometry.width, geometry.height);
        let (pw, ph) = (w + 2 * pad, h + 2 * pad);
        let site = |px: usize, py: usize| -> bool {
            if px < pad || py < pad || px >= w + pad || py >= h + pad {
                return true;
            }
            is_site((py - pad) * w + (px - pad))
        };
        // Pass 1: along each padded column, squared distance to the nearest site row and that row. Swept
        // row by row (every column at once) so that memory is read in order: the nearest site at or above,
        // then at or below.
        let mut g = vec![INF; pw * ph];
        let mut gy = vec![u32::MAX; pw * ph];
        let mut sites = vec![false; pw * ph];
        let mut last = vec![u32::MAX; pw];
        for y in 0..ph {
            for (x, l) in last.iter_mut().enumerate() {
                let i = y * pw + x;
                if site(x, y) {
                    sites[i] = true;
                    *l = y as u32;
                }
                if *l != u32::MAX {
                    let d = (y - *l as usize) as f64;
                    g[i] = d * d;
                    gy[i] = *l;
                }
            }
        }
        let mut next = vec![u32::MAX; pw];
        for y in (0..ph).rev() {
            for (x, s) in next.iter_mut().enumerate() {
                let i = y * pw + x;
                if sites[i] {
                    *s = y as u32;
                }
                if *s != u32::MAX {
                    let d = (*s as usize - y) as f64;
                    if d * d < g[i] {
                        g[i] = d * d;
                        gy[i] = *s;
                    }
                }
            }
        }
        // Pass 2: along each row, lower envelope of parabolas. Rows are independent: large grids split them
        // between two threads.
        let mut dist_m = vec![f32::INFINITY; w * h];
        let mut feature = vec![u32::MAX; w * h];
        let rows = |first: usize, dist_m: &mut [f32], feature: &mut [u32]| {
            let mut f = vec![0.0; pw];
            let mut d = vec![0.0; pw];
            let mut arg = vec![0usize; pw];
            let mut v = vec![0usize; pw];
            let mut z = vec![0.0; pw + 1];
            for (r, (dist_row, feature_row)) in dist_m.chunks_mut(w).zip(feature.chunks_mut(w)).enumerate() {
                let y = first + r + pad;
                f.copy_from_slice(&g[y * pw..(y + 1) * pw]);
                lower_envelope(&f, &mut d, &mut arg, &mut v, &mut z);
                for x in 0..w {
                    if d[x + pad] < INF * 0.5 {
                        let fx = arg[x + pad];
                        dist_row[x] = (d[x + pad].sqrt() * geometry.resolution) as f32;
                        feature_row[x] = (gy[y * pw + fx] as usize * pw + fx) as u32;
                    }
                }
            }
        };
        if w * h >= PARALLEL_CELLS && h >= 2 {
            let half = h / 2;
            let (dist_a, dist_b) = dist_m.split_at_mut(half * w);
            let (feature_a, feature_b) = feature.split_at_mut(half * w);
            std::thread::scope(|scope| {
                scope.spawn(|| rows(half, dist_b, feature_b));
                rows(0, dist_a, feature_a);
            });
        } else {
            rows(0, &mut dist_m, &mut feature);
        }
        Self {
            geometry,
            pad,
            dist_m,
            feature,
        }
    }

    /// The raster geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// True when the ring of cells just outside the map counts as sites (the map edge is a wall).
    pub fn border_is_site(&self) -> bool {
        self.pad == 1
    }

    /// Distance in metres from the centre of cell `i` to the nearest site's centre.
    #[inline]
    pub fn at(&self, i: usize) -> f64 {
        f64::from(self.dist_m[i])
    }

    /// All distances, metres, row-major.
    pub fn values(&self) -> &[f32] {
        &self.dist_m
    }

    /// Map-frame centre of the site nearest to cell `i`, if any site exists.
    #[inline]
    pub fn nearest_site(&self, i: usize) -> Option<Point2> {
        let f = self.feature[i];
        if f == u32::MAX {
            return None;
        }
        let pw = self.geometry.width + 2 * self.pad;
        let (fx, fy) = ((f as usize % pw) as f64, (f as usize / pw) as f64);
        let r = self.geometry.resolution;
        let pad = self.pad as f64;
        Some(Point2::new(
            self.geometry.origin.x + (fx - pad + 0.5) * r,
            self.geometry.origin.y + (fy - pad + 0.5) * r,
        ))
    }

    /// Linear index (in this grid) of the site nearest to cell `i`; `None` when there is no site or the nearest
    /// site is the ring outside the map.
    #[inline]
    pub fn nearest_site_index(&self, i: usize) -> Option<usize> {
        let f = self.feature[i];
        if f == u32::MAX {
            return None;
        }
        let pw = self.geometry.width + 2 * self.pad;
        let (fx, fy) = (f as usize % pw, f as usize / pw);
        let (x, y) = (fx.checked_sub(self.pad)?, fy.checked_sub(self.pad)?);
        (x < self.geometry.width && y < self.geometry.height).then_some(y * self.geometry.width + x)
    }

    /// Distance in metres from an arbitrary map-frame point to the nearest site centre. Exact in practice: the
    /// minimum over the nearest sites of the 3 × 3 cells around `p` (the nearest site of a point is the
    /// nearest site of one of the cells whose Voronoi region it lies in). Points off the map return 0 when the
    /// border is a site.
    pub fn at_point(&self, p: Point2) -> f64 {
        let (cx, cy) = self.geometry.to_cell_coords(p);
        if !(cx.is_finite() && cy.is_finite()) {
            return 0.0;
        }
        let (w, h) = (self.geometry.width as isize, self.geometry.height as isize);
        let (ix, iy) = (cx.floor() as isize, cy.floor() as isize);
        if self.pad == 1 && (ix < 0 || iy < 0 || ix >= w || iy >= h) {
            return 0.0;
        }
        let mut best = f64::INFINITY;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y) = (ix + dx, iy + dy);
                if x < 0 || y < 0 || x >= w || y >= h {
                    continue;
                }
                if let Some(s) = self.nearest_site((y * w + x) as usize) {
                    best = best.min((s - p).norm());
                }
            }
        }
        best
    }
}

/// One-dimensional squared-distance transform of sampled function `f` (Felzenszwalb & Huttenlocher):
/// `d[q] = min_p (q − p)² + f[p]`, `arg[q]` the minimising `p`. `v` and `z` are scratch of len n and n+1.
fn lower_envelope(f: &[f64], d: &mut [f64], arg: &mut [usize], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    // Only parabolas with a finite base take part.
    let mut k: isize = -1;
    for q in 0..n {
        if f[q] >= INF * 0.5 {
            continue;
        }
        if k < 0 {
            k = 0;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        loop {
            let p = v[k as usize];
            let s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            // z[0] = -inf stops this at k = 0.
            if s <= z[k as usize] {
                k -= 1;
                continue;
            }
            k += 1;
            v[k as usize] = q;
            z[k as usize] = s;
            z[k as usize + 1] = f64::INFINITY;
            break;
        }
    }
    if k < 0 {
        d[..n].fill(INF);
        return;
    }
    let mut j = 0usize;
    for q in 0..n {
        while z[j + 1] < q as f64 {
            j += 1;
        }
        let p = v[j];
        let dq = q as f64 - p as f64;
        d[q] = dq * dq + f[p];
        arg[q] = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(geometry: &GridGeometry, sites: &[bool], border: bool) -> Vec<f64> {
        let (w, h) = (geometry.width as isize, geometry.height as isize);
        let mut all: Vec<(isize, isize)> = Vec::new();
        for y in 0..h {
            for x in 0..w {
                if sites[(y * w + x) as usize] {
                    all.push((x, y));
                }
            }
        }
        if border {
            for x in -1..=w {
                all.push((x, -1));
                all.push((x, h));
            }
            for y in -1..=h {
                all.push((-1, y));
                all.push((w, y));
            }
        }
        (0..(w * h))
            .map(|i| {
                let (x, y) = (i % w, i / w);
                all.iter()
                    .map(|&(sx, sy)| (((sx - x).pow(2) + (sy - y).pow(2)) as f64).sqrt() * geometry.resolution)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    #[test]
    fn grids_split_between_threads_match_brute_force() {
        let (w, h) = (520, 490);
        assert!(w * h >= PARALLEL_CELLS);
        let geometry = GridGeometry::new(w, h, 0.1, Point2::origin()).expect("valid");
        let mut state = 0x2545_F491_4F6C_DD1D_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let sites: Vec<usize> = (0..40).map(|_| (next() % (w * h) as u64) as usize).collect();
        let df = DistanceField::compute(geometry, |i| sites.contains(&i), false);
        // Cells all over, and every cell of the rows either side of the split.
        let mut probe: Vec<usize> = (0..500).map(|_| (next() % (w * h) as u64) as usize).collect();
        probe.extend((h / 2 - 1) * w..(h / 2 + 1) * w);
        for i in probe {
            let c = geometry.center_of(i);
            let want = sites
                .iter()
                .map(|&s| (geometry.center_of(s) - c).norm())
                .fold(f64::INFINITY, f64::min);
            assert!((df.at(i) - want).abs() < 1e-4, "cell {i}: {} vs {want}", df.at(i));
            let s = df.nearest_site(i).expect("site");
            assert!(((s - c).norm() - want).abs() < 1e-4);
        }
    }

    proptest! {
        #[test]
        fn matches_brute_force(w in 1usize..24, h in 1usize..24, seed in any::<u64>(), density in 0.0f64..0.5, border in any::<bool>()) {
            let geometry = GridGeometry::new(w, h, 0.1, Point2::new(-0.3, 0.7)).expect("valid");
            let mut state = seed | 1;
            let sites: Vec<bool> = (0..w * h).map(|_| {
                state ^= state << 13; state ^= state >> 7; state ^= state << 17;
                (state % 1000) as f64 / 1000.0 < density
            }).collect();
            let df = DistanceField::compute(geometry, |i| sites[i], border);
            let expect = brute(&geometry, &sites, border);
            for (i, &want) in expect.iter().enumerate() {
                if want.is_infinite() {
                    prop_assert!(df.at(i).is_infinite());
                } else {
                    prop_assert!((df.at(i) - want).abs() < 1e-5, "cell {} got {} want {}", i, df.at(i), want);
                    let s = df.nearest_site(i).expect("site");
                    prop_assert!(((s - geometry.center_of(i)).norm() - want).abs() < 1e-5);
                    // At a cell centre the point query agrees with the cell value.
                    prop_assert!((df.at_point(geometry.center_of(i)) - want).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn border_acts_as_wall() {
        let g = GridGeometry::new(5, 5, 1.0, Point2::origin()).expect("valid");
        let df = DistanceField::compute(g, |_| false, true);
        assert!((df.at(g.index(crate::map::grid::Cell::new(2, 2))) - 3.0).abs() < 1e-9);
        assert!((df.at(0) - 1.0).abs() < 1e-9);
        assert_eq!(df.at_point(Point2::new(-0.5, 2.0)), 0.0);
    }
}
