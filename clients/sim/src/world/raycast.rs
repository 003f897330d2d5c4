//! Casting a ray through the map grid (Amanatides & Woo's voxel traversal): the distance at which a ray first
//! enters a solid cell.

use shift_planner::geom::Point2;
use shift_planner::map::GridGeometry;

/// Distance from `origin` along the unit direction `(dx, dy)` to the boundary of the first cell of `solid` the
/// ray enters, if within `max_range` metres. A ray that starts inside a solid cell hits at 0; a ray that leaves
/// the grid hits nothing more.
pub fn cast_grid(
    g: &GridGeometry,
    solid: &[bool],
    origin: Point2,
    (dx, dy): (f64, f64),
    max_range: f64,
) -> Option<f64> {
    let res = g.resolution;
    let (fx, fy) = g.to_cell_coords(origin);
    let (w, h) = (g.width as i64, g.height as i64);
    let (mut cx, mut cy) = (fx.floor() as i64, fy.floor() as i64);
    let inside = |cx: i64, cy: i64| cx >= 0 && cy >= 0 && cx < w && cy < h;
    let is_solid = |cx: i64, cy: i64| inside(cx, cy) && solid[cy as usize * g.width + cx as usize];
    if is_solid(cx, cy) {
        return Some(0.0);
    }
    // Per axis: the step direction, the distance (metres) to the first boundary and between boundaries.
    let axis = |f: f64, c: i64, d: f64| -> (i64, f64, f64) {
        if d > 0.0 {
            (1, ((c + 1) as f64 - f) * res / d, res / d)
        } else if d < 0.0 {
            (-1, (f - c as f64) * res / -d, res / -d)
        } else {
            (0, f64::INFINITY, f64::INFINITY)
        }
    };
    let (sx, mut tx, delta_x) = axis(fx, cx, dx);
    let (sy, mut ty, delta_y) = axis(fy, cy, dy);
    // The walk ends when the ray leaves the grid on the side it travels towards (outside the grid is open).
    loop {
        let t = tx.min(ty);
        if t > max_range {
            return None;
        }
        if tx < ty {
            cx += sx;
            tx += delta_x;
        } else {
            cy += sy;
            ty += delta_y;
        }
        if is_solid(cx, cy) {
            return Some(t);
        }
        let leaving = (sx > 0 && cx >= w) || (sx < 0 && cx < 0) || (sy > 0 && cy >= h) || (sy < 0 && cy < 0);
        if leaving {
            return None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn geometry() -> GridGeometry {
        GridGeometry::new(20, 15, 0.1, Point2::new(-0.5, 0.3)).expect("geometry")
    }

    /// Brute force: march in steps of a micrometre-scale fraction of a cell and report the first solid cell.
    fn oracle(g: &GridGeometry, solid: &[bool], o: Point2, d: (f64, f64), max: f64) -> Option<f64> {
        march(g, solid, o, d, 0.0, max, g.resolution / 2000.0)
    }

    /// The first solid cell met marching from `from` to `to` along the ray in steps of `step`.
    fn march(g: &GridGeometry, solid: &[bool], o: Point2, d: (f64, f64), from: f64, to: f64, step: f64) -> Option<f64> {
        let mut t = from;
        while t <= to {
            let p = Point2::new(o.x + d.0 * t, o.y + d.1 * t);
            if let Some(c) = g.locate(p)
                && solid[g.index(c)]
            {
                return Some(t);
            }
            t += step;
        }
        None
    }

    #[test]
    fn a_wall_ahead_is_hit_at_its_face() {
        let g = geometry();
        let mut solid = vec![false; g.len()];
        for y in 0..g.height {
            solid[y * g.width + 15] = true; // the column whose left face is at x = -0.5 + 1.5 = 1.0
        }
        let t = cast_grid(&g, &solid, Point2::new(0.0, 1.0), (1.0, 0.0), 10.0).expect("hit");
        assert!((t - 1.0).abs() < 1e-9, "{t}");
        assert_eq!(cast_grid(&g, &solid, Point2::new(0.0, 1.0), (-1.0, 0.0), 10.0), None);
        assert_eq!(cast_grid(&g, &solid, Point2::new(0.0, 1.0), (1.0, 0.0), 0.9), None);
    }

    proptest! {
        #[test]
        fn the_traversal_agrees_with_a_fine_march(
            cells in proptest::collection::vec(proptest::bool::weighted(0.08), 300),
            ox in -0.45f64..1.45, oy in 0.35f64..1.75, angle in 0.0f64..std::f64::consts::TAU,
        ) {
            let g = geometry();
            let o = Point2::new(ox, oy);
            let d = (angle.cos(), angle.sin());
            let got = cast_grid(&g, &cells, o, d, 3.0);
            let want = oracle(&g, &cells, o, d, 3.0);
            match (got, want) {
                (Some(a), Some(b)) => prop_assert!((a - b).abs() <= g.resolution / 1000.0, "{a} vs {b}"),
                // A ray grazing a cell corner crosses it over less than the march's step: the march misses what
                // the traversal hits. A march a million times finer round the hit must find it.
                (Some(a), None) => {
                    let fine = march(&g, &cells, o, d, a - 1e-6, a + 1e-6, 1e-10);
                    prop_assert!(fine.is_some() || a > 2.999, "{a} vs none, none finer either");
                }
                (a, b) => prop_assert!(a.is_none() && b.is_none() || a.or(b).is_some_and(|t| t > 2.999), "{a:?} vs {b:?}"),
            }
        }
    }
}
