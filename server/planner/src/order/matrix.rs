//! The symmetric point-to-point distance matrix of a visiting-order problem, metres.

/// Symmetric distance matrix over "points" (region entry/exit points and the depot), metres.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceMatrix {
    n: usize,
    data: Vec<f64>,
}

impl DistanceMatrix {
    /// An `n` × `n` matrix of zeros.
    ///
    /// # Panics
    /// Only when `n²` values (8 bytes each) cannot be allocated.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            data: vec![0.0; n.saturating_mul(n)],
        }
    }

    /// A matrix whose entry (i, j) is `f(i, j)` for `i < j`, mirrored to (j, i); the diagonal is zero.
    /// `f` is called once per unordered pair, n(n−1)/2 times, in row-major order.
    pub fn from_fn(n: usize, f: impl Fn(usize, usize) -> f64) -> Self {
        let mut m = Self::new(n);
        // Upper triangle row by row (contiguous writes), then mirrored tile by tile so that the strided
        // writes of the lower triangle stay in cache.
        for i in 0..n {
            let row = &mut m.data[i * n..(i + 1) * n];
            for (j, v) in row.iter_mut().enumerate().skip(i + 1) {
                *v = f(i, j);
            }
        }
        const TILE: usize = 64;
        for bi in (0..n).step_by(TILE) {
            for bj in (bi..n).step_by(TILE) {
                for i in bi..(bi + TILE).min(n) {
                    for j in bj.max(i + 1)..(bj + TILE).min(n) {
                        m.data[j * n + i] = m.data[i * n + j];
                    }
                }
            }
        }
        m
    }

    /// Number of points (rows).
    pub fn len(&self) -> usize {
        self.n
    }

    /// True when the matrix has no points.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Distance from point `i` to point `j`, metres; `f64::INFINITY` when either index is outside the matrix.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if i < self.n && j < self.n {
            self.data[i * self.n + j]
        } else {
            f64::INFINITY
        }
    }

    /// Distances from point `i` to every point (row `i`), metres; `None` when `i` is outside the matrix.
    pub fn row(&self, i: usize) -> Option<&[f64]> {
        (i < self.n).then(|| &self.data[i * self.n..(i + 1) * self.n])
    }

    /// Sets the distance between points `i` and `j` (both (i, j) and (j, i)), metres. Indices outside the
    /// matrix are ignored (check them against [`DistanceMatrix::len`]).
    pub fn set(&mut self, i: usize, j: usize, d: f64) {
        if i < self.n && j < self.n {
            self.data[i * self.n + j] = d;
            self.data[j * self.n + i] = d;
        }
    }
}
