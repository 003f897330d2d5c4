//! Small 2-D geometry helpers shared by every stage. Coordinates are metres in the map frame.

/// A point in the map frame, metres.
pub type Point2 = nalgebra::Point2<f64>;
/// A vector in the map frame, metres.
pub type Vector2 = nalgebra::Vector2<f64>;

/// Distance from `p` to the segment `a`–`b` (metres).
pub fn point_segment_distance(p: Point2, a: Point2, b: Point2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 <= f64::EPSILON {
        return (p - a).norm();
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Even-odd point-in-polygon test; `poly` is `[[x, y], …]`, implicitly closed.
pub fn point_in_polygon(p: Point2, poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let [xi, yi] = poly[i];
        let [xj, yj] = poly[(i + n - 1) % n];
        if (yi > p.y) != (yj > p.y) && p.x < (xj - xi) * (p.y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
    }
    inside
}

/// True when the segments `a`–`b` and `c`–`d` cross at a point inside both (touching ends do not count).
pub fn segments_cross(a: Point2, b: Point2, c: Point2, d: Point2) -> bool {
    let side = |p: Point2, q: Point2, r: Point2| (q - p).perp(&(r - p));
    let (d1, d2) = (side(a, b, c), side(a, b, d));
    let (d3, d4) = (side(c, d, a), side(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// The exact bits of the directed pair `a` → `b`: a key for memo tables of per-connection results.
pub fn pair_key(a: Point2, b: Point2) -> [u64; 4] {
    [a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits()]
}

/// Total length of a polyline (metres).
pub fn polyline_length(points: &[Point2]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// Length of the shortest 8-connected way from `a` to `b` on an open grid, metres (straight runs and
/// diagonals: `max(|dx|, |dy|) + (√2 − 1) · min(|dx|, |dy|)`); at most 8.3 % more than the straight length.
/// A grid search's cost without obstacles, against which a bound on its cost is set.
pub fn octile_length(a: Point2, b: Point2) -> f64 {
    let (dx, dy) = ((b.x - a.x).abs(), (b.y - a.y).abs());
    dx.max(dy) + (std::f64::consts::SQRT_2 - 1.0) * dx.min(dy)
}

/// Unit direction of angle `theta_rad` (radians, counter-clockwise from +x).
pub fn direction(theta_rad: f64) -> Vector2 {
    Vector2::new(theta_rad.cos(), theta_rad.sin())
}

/// Absolute heading change between two direction vectors, radians in [0, π].
pub fn heading_change(d0: Vector2, d1: Vector2) -> f64 {
    let cross = d0.x * d1.y - d0.y * d1.x;
    cross.atan2(d0.dot(&d1)).abs()
}

/// Douglas–Peucker simplification that keeps a vertex whenever dropping it moves the polyline by more than
/// `tolerance` metres or when `keep_segment(a, b)` refuses the shortcut (e.g. it would lose clearance).
pub fn simplify_polyline(
    points: &[Point2],
    tolerance: f64,
    keep_segment: &dyn Fn(Point2, Point2) -> bool,
) -> Vec<Point2> {
    if points.len() <= 2 {
        return points.to_vec();
    }
    let mut keep = vec![false; points.len()];
    keep[0] = true;
    keep[points.len() - 1] = true;
    let mut stack = vec![(0usize, points.len() - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let (mut worst, mut worst_d) = (i + 1, -1.0);
        for (k, p) in points.iter().enumerate().take(j).skip(i + 1) {
            let d = point_segment_distance(*p, points[i], points[j]);
            if d > worst_d {
                worst_d = d;
                worst = k;
            }
        }
        if worst_d > tolerance || !keep_segment(points[i], points[j]) {
            keep[worst] = true;
            stack.push((i, worst));
            stack.push((worst, j));
        }
    }
    points.iter().zip(keep).filter_map(|(p, k)| k.then_some(*p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_distance_cases() {
        let a = Point2::new(0.0, 0.0);
        let b = Point2::new(2.0, 0.0);
        assert!((point_segment_distance(Point2::new(1.0, 1.0), a, b) - 1.0).abs() < 1e-12);
        assert!((point_segment_distance(Point2::new(3.0, 0.0), a, b) - 1.0).abs() < 1e-12);
        assert!((point_segment_distance(Point2::new(-3.0, 4.0), a, b) - 5.0).abs() < 1e-12);
        assert!((point_segment_distance(Point2::new(1.0, 1.0), a, a) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn simplify_keeps_corners_and_drops_collinear() {
        let pts: Vec<Point2> = (0..=10)
            .map(|i| Point2::new(f64::from(i), 0.0))
            .chain((1..=10).map(|i| Point2::new(10.0, f64::from(i))))
            .collect();
        let s = simplify_polyline(&pts, 0.01, &|_, _| true);
        assert_eq!(
            s,
            vec![Point2::new(0.0, 0.0), Point2::new(10.0, 0.0), Point2::new(10.0, 10.0)]
        );
        // A refusing predicate keeps every vertex.
        let all = simplify_polyline(&pts, 0.01, &|_, _| false);
        assert_eq!(all.len(), pts.len());
    }

    #[test]
    fn heading_change_is_unsigned() {
        let a = direction(0.0);
        assert!(
            (heading_change(a, direction(std::f64::consts::FRAC_PI_2)) - std::f64::consts::FRAC_PI_2).abs() < 1e-12
        );
        assert!(
            (heading_change(a, direction(-std::f64::consts::FRAC_PI_2)) - std::f64::consts::FRAC_PI_2).abs() < 1e-12
        );
    }

    /// Shortest 8-connected way between two cells of an open 12 × 12 grid, by Dijkstra (the oracle).
    fn grid_way(a: (usize, usize), b: (usize, usize)) -> f64 {
        const N: usize = 12;
        let mut dist = [f64::INFINITY; N * N];
        let mut done = [false; N * N];
        dist[a.1 * N + a.0] = 0.0;
        for _ in 0..N * N {
            let Some(u) = (0..N * N)
                .filter(|&i| !done[i])
                .min_by(|&i, &j| dist[i].total_cmp(&dist[j]))
            else {
                break;
            };
            done[u] = true;
            let (ux, uy) = ((u % N) as i64, (u / N) as i64);
            for (dx, dy) in [
                (-1i64, -1i64),
                (-1, 0),
                (-1, 1),
                (0, -1),
                (0, 1),
                (1, -1),
                (1, 0),
                (1, 1),
            ] {
                let (vx, vy) = (ux + dx, uy + dy);
                if (0..N as i64).contains(&vx) && (0..N as i64).contains(&vy) {
                    let v = vy as usize * N + vx as usize;
                    let step = if dx != 0 && dy != 0 {
                        std::f64::consts::SQRT_2
                    } else {
                        1.0
                    };
                    dist[v] = dist[v].min(dist[u] + step);
                }
            }
        }
        dist[b.1 * N + b.0]
    }

    #[test]
    fn octile_length_is_the_open_grids_shortest_way() {
        for (a, b) in [
            ((0, 0), (11, 4)),
            ((3, 9), (3, 2)),
            ((5, 5), (5, 5)),
            ((11, 0), (0, 11)),
            ((2, 7), (9, 1)),
        ] {
            let p = |(x, y): (usize, usize)| Point2::new(x as f64, y as f64);
            let octile = octile_length(p(a), p(b));
            assert!((octile - grid_way(a, b)).abs() < 1e-9, "{a:?} → {b:?}");
            let straight = (p(b) - p(a)).norm();
            assert!(straight <= octile + 1e-12 && octile <= 1.0824 * straight + 1e-12);
        }
    }
}
