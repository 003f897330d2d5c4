//! Counting masked cells in discs around every cell: the tool's footprint on the grid, row by row, over
//! per-row prefix sums (O(disc rows) per count, whatever the disc's size), and 8-connected pieces of a mask.

use crate::map::GridGeometry;

/// The cells whose centre lies within a radius of a cell's centre: per row offset `dy`, the half-span `s`
/// (columns `x - s ..= x + s`). Membership is exact on cell-centre offsets with the coverage raster's
/// nanometre of tolerance ([`crate::metrics::CoverageRaster`]), so a disc of radius `tool_width / 2` is
/// what the tool sweeps when the robot's centre stands on the cell.
#[derive(Debug, Clone)]
pub(crate) struct Disc {
    /// `(dy, s)` for every row the disc touches.
    spans: Vec<(isize, usize)>,
    /// Cells in the disc.
    pub(crate) cells: usize,
}

impl Disc {
    /// The disc of `radius_m` on cells of `resolution` metres.
    pub(crate) fn new(radius_m: f64, resolution: f64) -> Self {
        let q = ((radius_m.max(0.0) + 1e-9) / resolution).powi(2);
        let r = q.sqrt().floor() as isize;
        let mut spans = Vec::with_capacity(2 * r as usize + 1);
        let mut cells = 0;
        for dy in -r..=r {
            let rest = q - (dy * dy) as f64;
            let mut s = rest.max(0.0).sqrt().floor() as usize;
            while ((s + 1) * (s + 1)) as f64 <= rest {
                s += 1;
            }
            while s > 0 && (s * s) as f64 > rest {
                s -= 1;
            }
            spans.push((dy, s));
            cells += 2 * s + 1;
        }
        Self { spans, cells }
    }

    /// Rows the disc reaches above and below its centre.
    pub(crate) fn rows(&self) -> usize {
        self.spans.len() / 2
    }
}

/// Per-row prefix sums of a mask: how many masked cells a row holds left of every column.
#[derive(Debug, Clone)]
pub(crate) struct RowSums {
    width: usize,
    height: usize,
    prefix: Vec<u32>,
}

impl RowSums {
    /// The sums of `mask` on `g`.
    pub(crate) fn new(g: &GridGeometry, mask: impl Fn(usize) -> bool) -> Self {
        let (w, h) = (g.width, g.height);
        let mut prefix = vec![0u32; (w + 1) * h];
        for y in 0..h {
            let (row, out) = (y * w, y * (w + 1));
            for x in 0..w {
                prefix[out + x + 1] = prefix[out + x] + u32::from(mask(row + x));
            }
        }
        Self {
            width: w,
            height: h,
            prefix,
        }
    }

    /// Masked cells of row `y` in columns `x0 ..= x1` (clipped to the grid).
    #[inline]
    fn range(&self, y: isize, x0: isize, x1: isize) -> u32 {
        if y < 0 || y >= self.height as isize {
            return 0;
        }
        let a = x0.max(0) as usize;
        let b = ((x1 + 1).max(0) as usize).min(self.width);
        if a >= b {
            return 0;
        }
        let row = y as usize * (self.width + 1);
        self.prefix[row + b] - self.prefix[row + a]
    }

    /// Masked cells in `disc` around cell `i`.
    #[inline]
    pub(crate) fn count(&self, disc: &Disc, i: usize) -> u32 {
        let (x, y) = ((i % self.width) as isize, (i / self.width) as isize);
        disc.spans
            .iter()
            .map(|&(dy, s)| self.range(y + dy, x - s as isize, x + s as isize))
            .sum()
    }

    /// True when `disc` around cell `i` holds a masked cell (stops at the first row that has one).
    #[inline]
    pub(crate) fn any(&self, disc: &Disc, i: usize) -> bool {
        let (x, y) = ((i % self.width) as isize, (i / self.width) as isize);
        disc.spans
            .iter()
            .any(|&(dy, s)| self.range(y + dy, x - s as isize, x + s as isize) > 0)
    }
}

/// 8-connected pieces of `mask`: a piece id per cell (`u32::MAX` off the mask) and every piece's size, ids in
/// order of each piece's lowest cell. Runs of masked cells row by row, joined to the runs they touch in the
/// row before (union-find): linear in the cells, with far fewer steps than a flood fill.
pub(crate) fn pieces(g: &GridGeometry, mask: &[bool]) -> (Vec<u32>, Vec<usize>) {
    let (w, h) = (g.width, g.height);
    // Runs (row, first column, last column) and their parents.
    let mut runs: Vec<(usize, usize, usize)> = Vec::new();
    let mut parent: Vec<u32> = Vec::new();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    let mut prev = 0..0;
    for y in 0..h {
        let start = runs.len();
        let row = &mask[y * w..(y + 1) * w];
        let mut j = prev.start;
        let mut x = 0;
        while x < w {
            if !row[x] {
                x += 1;
                continue;
            }
            let x0 = x;
            while x < w && row[x] {
                x += 1;
            }
            let x1 = x - 1;
            let k = runs.len() as u32;
            runs.push((y, x0, x1));
            parent.push(k);
            // Runs of the row before touching columns x0 - 1 ..= x1 + 1 (8-connected).
            while j < prev.end && runs[j].2 + 1 < x0 {
                j += 1;
            }
            let mut t = j;
            while t < prev.end && runs[t].1 <= x1 + 1 {
                let (a, b) = (root(&mut parent, k), root(&mut parent, t as u32));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
                t += 1;
            }
        }
        prev = start..runs.len();
    }
    let mut dense = vec![u32::MAX; runs.len()];
    let mut sizes = Vec::new();
    let mut id = vec![u32::MAX; g.len()];
    for (k, &(y, x0, x1)) in runs.iter().enumerate() {
        let r = root(&mut parent, k as u32) as usize;
        if dense[r] == u32::MAX {
            dense[r] = sizes.len() as u32;
            sizes.push(0);
        }
        let d = dense[r];
        sizes[d as usize] += x1 - x0 + 1;
        id[y * w + x0..=y * w + x1].fill(d);
    }
    (id, sizes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;

    /// Disc counts agree with counting the cells whose centre lies within the radius (oracle).
    #[test]
    fn disc_counts_match_brute_force() {
        let g = GridGeometry::new(23, 17, 0.1, Point2::origin()).expect("valid");
        let mask: Vec<bool> = (0..g.len()).map(|i| (i * 7919) % 5 < 2).collect();
        let sums = RowSums::new(&g, |i| mask[i]);
        for radius in [0.0, 0.05, 0.1, 0.2, 0.3, 0.45] {
            let disc = Disc::new(radius, 0.1);
            for i in 0..g.len() {
                let want = (0..g.len())
                    .filter(|&j| mask[j] && (g.center_of(i) - g.center_of(j)).norm() <= radius + 1e-9)
                    .count() as u32;
                assert_eq!(sums.count(&disc, i), want, "radius {radius} cell {i}");
                assert_eq!(sums.any(&disc, i), want > 0);
            }
        }
        assert_eq!(Disc::new(0.3, 0.1).cells, 29);
    }

    /// Pieces agree with an 8-connected flood fill (oracle): same partition, ids in order of lowest cell.
    #[test]
    fn pieces_match_a_flood_fill() {
        let g = GridGeometry::new(31, 19, 0.1, Point2::origin()).expect("valid");
        for seed in 1..40_u64 {
            let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
            let mask: Vec<bool> = (0..g.len())
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    s % 100 < 30 + seed
                })
                .collect();
            let (id, sizes) = pieces(&g, &mask);
            let mut next = 0;
            for i in 0..g.len() {
                assert_eq!(id[i] == u32::MAX, !mask[i]);
                if !mask[i] || id[i] < next {
                    continue;
                }
                assert_eq!(id[i], next, "ids in order of lowest cell");
                let fill = crate::space::flood_fill8(&g, &mask, g.cell(i));
                let members: Vec<usize> = (0..g.len()).filter(|&j| fill[j]).collect();
                assert!(members.iter().all(|&j| id[j] == next));
                assert_eq!(sizes[next as usize], members.len());
                assert_eq!(id.iter().filter(|&&d| d == next).count(), members.len());
                next += 1;
            }
            assert_eq!(next as usize, sizes.len());
        }
    }
}
