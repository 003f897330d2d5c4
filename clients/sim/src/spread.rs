//! `--robots N` with fewer robots in the world file: the rest are placed on free cells, seeded, clear of walls
//! and of each other, copying the last listed robot's body (or a 0.25 m robot with a 0.5 m tool).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shift_planner::geom::Point2;
use shift_planner::map::OccupancyGrid;
use shift_planner::map::distance::DistanceField;

use crate::error::{SimError, bad};
use crate::world::file::RobotSpecFile;

/// Spacing kept between placed robots, metres (plus their radii).
const APART_M: f64 = 1.0;
/// Room kept from walls beyond the radius, metres.
const WALL_MARGIN_M: f64 = 0.1;

/// The first `n` of `listed`, then robots `sim-K` placed on `grid` with `seed` until there are `n`.
pub fn robots(
    listed: &[RobotSpecFile],
    n: usize,
    grid: &OccupancyGrid,
    seed: u64,
) -> Result<Vec<RobotSpecFile>, SimError> {
    let mut out: Vec<RobotSpecFile> = listed.iter().take(n).cloned().collect();
    if out.len() == n {
        return Ok(out);
    }
    let template = listed.last().cloned().unwrap_or(RobotSpecFile {
        id: String::new(),
        start: [0.0; 3],
        radius: 0.25,
        tool_width: 0.5,
        v_max: None,
        a_max: None,
        w_max: None,
        region: None,
    });
    let g = grid.geometry;
    let clearance = DistanceField::compute(g, |i| !grid.is_free(i), true);
    let need = template.radius + WALL_MARGIN_M;
    let candidates: Vec<usize> = (0..g.len())
        .filter(|&i| grid.is_free(i) && clearance.at(i) >= need)
        .collect();
    if candidates.is_empty() {
        return Err(bad(
            "--robots",
            "the map has no free cell clear enough for another robot",
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut tries = 0;
    while out.len() < n {
        tries += 1;
        if tries > 100 * n + 1000 {
            return Err(bad(
                "--robots",
                format!("room for only {} robots {APART_M} m apart", out.len()),
            ));
        }
        let p = g.center_of(candidates[rng.random_range(0..candidates.len())]);
        let clear = out
            .iter()
            .all(|r| (Point2::new(r.start[0], r.start[1]) - p).norm() >= r.radius + template.radius + APART_M);
        if !clear {
            continue;
        }
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        out.push(RobotSpecFile {
            id: format!("sim-{}", out.len() + 1),
            start: [p.x, p.y, yaw],
            region: None,
            ..template.clone()
        });
    }
    Ok(out)
}
