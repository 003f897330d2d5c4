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
}
