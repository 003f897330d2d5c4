//! Docks spread over a site, for evaluations and benches of a fleet (`shiftd eval --robots N`, the division
//! and handover benches): the space's own start, then each next dock the reachable cell farthest (straight
//! line) from the docks chosen so far among cells with room around them (clearance of the robot radius plus
//! half a metre), so a fleet starts spread over the site as issue 20's quality bar asks.

use crate::geom::Point2;
use crate::space::CoverageSpace;

/// `n` docks spread over `space` (see the module docs), the space's start first; fewer when the space has
/// no more room.
pub fn spread_docks(space: &CoverageSpace, n: usize) -> Vec<Point2> {
    let g = space.geometry();
    let room = space.robot.radius_m + 0.5;
    let candidates: Vec<Point2> = (0..g.len())
        .filter(|&i| space.reachable[i] && space.clearance.at(i) >= room)
        .map(|i| g.center_of(i))
        .collect();
    let mut docks = vec![space.start];
    while docks.len() < n {
        let far = candidates
            .iter()
            .map(|&c| (docks.iter().map(|d| (c - d).norm()).fold(f64::INFINITY, f64::min), c))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        match far {
            Some((d, c)) if d > 0.0 => docks.push(c),
            _ => break,
        }
    }
    docks
}
