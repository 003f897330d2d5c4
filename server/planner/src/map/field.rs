//! Fields drawn as polygons (issue 23: GeoJSON fields, already projected to metres by the caller): the
//! outer rings are the field, holes and no-go polygons are obstacles, and everything outside is occupied, so
//! the existing pipeline plans on the grid like on any map. Rasterised by scanlines at cell centres
//! (even-odd rule per ring), with a ring of occupied cells around the field so its edge is a wall.

use super::grid::{CellState, GridGeometry, OccupancyGrid};
use crate::error::{PlannerError, Result};
use crate::geom::Point2;

/// A ring: `[x, y]` vertices in metres, implicitly closed.
pub type Ring = Vec<[f64; 2]>;

/// Cells of occupied border around the field's bounding box.
const BORDER_CELLS: usize = 2;

/// The field in metres: cells inside an outer ring and outside every hole are free.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FieldRings {
    /// The field's parts.
    pub outers: Vec<Ring>,
    /// Holes and no-go areas.
    pub holes: Vec<Ring>,
}

impl FieldRings {
    /// The bounding box of the outer rings, `(min, max)`.
    fn bounds(&self) -> Option<([f64; 2], [f64; 2])> {
        let mut pts = self.outers.iter().flatten();
        let first = *pts.next()?;
        Some(pts.fold((first, first), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        }))
    }

    /// Rasterises the field at `resolution` metres per cell: free inside, occupied elsewhere.
    pub fn rasterise(&self, resolution: f64) -> Result<OccupancyGrid> {
        let bad = |reason: &str| PlannerError::InvalidParam {
            name: "field",
            reason: reason.to_owned(),
        };
        if self.outers.is_empty() {
            return Err(bad("no outer ring"));
        }
        for ring in self.outers.iter().chain(&self.holes) {
            if ring.len() < 3 {
                return Err(bad("a ring has fewer than 3 vertices"));
            }
            if ring.iter().flatten().any(|v| !v.is_finite()) {
                return Err(bad("a vertex is not finite"));
            }
        }
        let (lo, hi) = self.bounds().ok_or_else(|| bad("no outer ring"))?;
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(PlannerError::InvalidResolution(resolution));
        }
        let border = BORDER_CELLS as f64 * resolution;
        let origin = Point2::new(lo[0] - border, lo[1] - border);
        let cols = ((hi[0] - lo[0]) / resolution).ceil() as usize + 2 * BORDER_CELLS;
        let rows = ((hi[1] - lo[1]) / resolution).ceil() as usize + 2 * BORDER_CELLS;
        let geometry = GridGeometry::new(cols, rows, resolution, origin)?;
        let mut inside = vec![false; geometry.len()];
        for ring in &self.outers {
            fill(&geometry, ring, &mut inside, true);
        }
        for ring in &self.holes {
            fill(&geometry, ring, &mut inside, false);
        }
        let cells = inside
            .into_iter()
            .map(|free| if free { CellState::Free } else { CellState::Occupied })
            .collect();
        OccupancyGrid::new(geometry, cells)
    }
}

/// Sets `to` on every cell whose centre lies inside `ring` (even-odd), one scanline per row.
fn fill(g: &GridGeometry, ring: &[[f64; 2]], mask: &mut [bool], to: bool) {
    let n = ring.len();
    let mut xs = Vec::new();
    for row in 0..g.height {
        let y = g.origin.y + (row as f64 + 0.5) * g.resolution;
        xs.clear();
        for i in 0..n {
            let [xa, ya] = ring[i];
            let [xb, yb] = ring[(i + 1) % n];
            // Half-open in y, so a vertex on the scanline counts once.
            if (ya > y) != (yb > y) {
                xs.push(xa + (y - ya) * (xb - xa) / (yb - ya));
            }
        }
        xs.sort_by(f64::total_cmp);
        for pair in xs.chunks_exact(2) {
            // Columns whose centre x lies in [pair[0], pair[1]).
            let first = ((pair[0] - g.origin.x) / g.resolution - 0.5).ceil().max(0.0) as usize;
            let end = ((pair[1] - g.origin.x) / g.resolution - 0.5).ceil().max(0.0) as usize;
            for col in first..end.min(g.width) {
                mask[row * g.width + col] = to;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::point_in_polygon;
    use proptest::prelude::*;

    fn square(x0: f64, y0: f64, side: f64) -> Ring {
        vec![[x0, y0], [x0 + side, y0], [x0 + side, y0 + side], [x0, y0 + side]]
    }

    #[test]
    fn a_square_field_with_a_hole_is_free_inside_and_walled() {
        let field = FieldRings {
            outers: vec![square(0.0, 0.0, 10.0)],
            holes: vec![square(4.0, 4.0, 2.0)],
        };
        let g = field.rasterise(0.1).expect("rasterises");
        let free = g.cells.iter().filter(|c| **c == CellState::Free).count();
        // 100 m² − 4 m² at 0.01 m² per cell.
        assert_eq!(free, 9600);
        let at = |x: f64, y: f64| g.cells[g.geometry.locate(Point2::new(x, y)).map_or(0, |c| g.geometry.index(c))];
        assert_eq!(at(1.0, 1.0), CellState::Free);
        assert_eq!(at(5.0, 5.0), CellState::Occupied);
        assert_eq!(at(-0.1, 5.0), CellState::Occupied);
        // The border is occupied all round.
        assert!(g.cells[..g.geometry.width].iter().all(|c| *c == CellState::Occupied));
    }

    #[test]
    fn bad_rings_name_the_field() {
        for field in [
            FieldRings::default(),
            FieldRings {
                outers: vec![vec![[0.0, 0.0], [1.0, 1.0]]],
                holes: vec![],
            },
            FieldRings {
                outers: vec![vec![[0.0, 0.0], [1.0, f64::NAN], [1.0, 1.0]]],
                holes: vec![],
            },
        ] {
            let e = field.rasterise(0.1).expect_err("refused");
            assert!(e.to_string().contains("field"), "{e}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Scanlines agree with the point-in-polygon oracle at every cell centre (star-shaped random rings,
        /// plus a random hole).
        #[test]
        fn scanlines_match_the_point_in_polygon_oracle(
            radii in prop::collection::vec(2.0f64..9.0, 3..14),
            hole in prop::collection::vec(0.5f64..1.5, 3..8),
            res in 0.07f64..0.4,
        ) {
            let star = |r: &[f64], cx: f64, cy: f64| -> Ring {
                let n = r.len() as f64;
                r.iter().enumerate().map(|(i, &ri)| {
                    let a = std::f64::consts::TAU * i as f64 / n;
                    [cx + ri * a.cos(), cy + ri * a.sin()]
                }).collect()
            };
            let field = FieldRings { outers: vec![star(&radii, 10.0, 10.0)], holes: vec![star(&hole, 10.0, 10.0)] };
            let g = field.rasterise(res).expect("rasterises");
            for i in 0..g.geometry.len() {
                let c = g.geometry.center_of(i);
                let want = point_in_polygon(c, &field.outers[0]) && !point_in_polygon(c, &field.holes[0]);
                prop_assert_eq!(g.cells[i] == CellState::Free, want, "cell {} at {:?}", i, c);
            }
        }
    }
}
