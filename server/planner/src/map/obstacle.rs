//! Obstacle distance as one interface, so that every consumer (link clearance checks today, IKD-SWOpt
//! corrections next) can run on the static map's distance field or on the live ikd-tree of obstacle points.

use super::distance::DistanceField;
use super::ikd_tree::{IkdTree, Point3};
use crate::geom::Point2;

/// Distance from a map-frame point to the nearest obstacle, metres (`f64::INFINITY` when there is none).
pub trait ObstacleDistance {
    /// Distance from `p` (map frame, metres) to the nearest obstacle, metres.
    fn obstacle_distance(&self, p: Point2) -> f64;
}

impl ObstacleDistance for DistanceField {
    /// Distance to the nearest site (non-free cell centre) of the field.
    fn obstacle_distance(&self, p: Point2) -> f64 {
        self.at_point(p)
    }
}

impl ObstacleDistance for IkdTree {
    /// Distance to the nearest obstacle point from (x, y, 0), in 3-D. That is the ground-plane distance for
    /// points at z = 0 (2-D scans, and this trait's tests); the live map keeps a cloud's points at their
    /// map-frame heights, so the corrections measure those in the ground plane from a box query instead
    /// (`correct::local`).
    fn obstacle_distance(&self, p: Point2) -> f64 {
        self.nearest_distance(&Point3::new(p.x as f32, p.y as f32, 0.0))
            .map_or(f64::INFINITY, f64::from)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, IkdParams, OccupancyGrid};

    /// The live tree and the static distance field agree on the same obstacles.
    #[test]
    fn tree_and_field_agree() {
        let g = GridGeometry::new(60, 40, 0.1, Point2::new(-1.0, 2.0)).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_disk(Point2::new(1.5, 4.0), 0.4, CellState::Occupied);
        grid.fill_rect(3.0, 2.5, 3.3, 5.5, CellState::Occupied);
        let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
        let obstacles: Vec<Point3> = (0..g.len())
            .filter(|&i| !grid.is_free(i))
            .map(|i| {
                let c = g.center_of(i);
                Point3::new(c.x as f32, c.y as f32, 0.0)
            })
            .collect();
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        tree.build(&obstacles);
        for k in 0..200 {
            let p = Point2::new(-0.9 + (k % 20) as f64 * 0.29, 2.1 + (k / 20) as f64 * 0.37);
            let (a, b) = (field.obstacle_distance(p), tree.obstacle_distance(p));
            assert!((a - b).abs() < 1e-3, "at {p:?}: field {a} tree {b}");
        }
    }
}
