//! Baselines for comparison, as seed 003's Table 1: a random walk, a single S-shape over the whole map with
//! no decomposition, and a spiral over the whole map. They share the pipeline's links and metrics.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::decompose::DecompositionMethod;
use crate::error::Result;
use crate::geom::{Point2, direction};
use crate::metrics::evaluate;
use crate::pattern::PatternMethod;
use crate::pattern::lanes::LaneParams;
use crate::pipeline::{NoMonitor, PlanOutput, PlanParams, PlanStats, Waypoint, WaypointKind, plan};
use crate::space::CoverageSpace;

/// The baselines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Baseline {
    /// Straight runs in random directions, bouncing off obstacles.
    RandomWalk,
    /// One S-shape (lanes along x) over the whole reachable set, no decomposition, no targeted passes.
    SShape,
    /// One spiral over the whole reachable set, no targeted passes.
    Spiral,
}

impl Baseline {
    /// Every baseline.
    pub const ALL: [Self; 3] = [Self::RandomWalk, Self::SShape, Self::Spiral];

    /// Table name.
    pub fn name(self) -> &'static str {
        match self {
            Self::RandomWalk => "random-walk",
            Self::SShape => "s-shape",
            Self::Spiral => "spiral",
        }
    }
}

/// Runs a baseline. The random walk drives as far as `length_budget_m` (e.g. the real plan's length).
pub fn run_baseline(space: &CoverageSpace, which: Baseline, seed: u64, length_budget_m: f64) -> Result<PlanOutput> {
    match which {
        Baseline::SShape | Baseline::Spiral => {
            let params = PlanParams {
                decomposition: DecompositionMethod::Single,
                pattern: if which == Baseline::Spiral {
                    PatternMethod::Spiral
                } else {
                    PatternMethod::Lanes
                },
                lanes: LaneParams {
                    fixed_angle_rad: Some(0.0),
                    ..LaneParams::default()
                },
                targeted_passes: false,
                seed,
                ..PlanParams::default()
            };
            plan(space, &params, &mut NoMonitor)
        }
        Baseline::RandomWalk => Ok(random_walk(space, seed, length_budget_m)),
    }
}

/// A bouncing random walk from the start: straight in a random heading until the next step would lose
/// clearance, then a new random heading; stops after `length_budget_m` metres.
pub fn random_walk(space: &CoverageSpace, seed: u64, length_budget_m: f64) -> PlanOutput {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let step = space.geometry().resolution;
    let mut pos = space.start;
    let mut pts = vec![pos];
    let mut travelled = 0.0;
    let mut heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let mut stuck = 0;
    while travelled < length_budget_m && stuck < 1000 {
        let next = pos + direction(heading) * step;
        if space.segment_ok(pos, next) {
            pos = next;
            travelled += step;
            stuck = 0;
        } else {
            if pts.last() != Some(&pos) {
                pts.push(pos);
            }
            heading = rng.random_range(0.0..std::f64::consts::TAU);
            stuck += 1;
        }
    }
    if pts.last() != Some(&pos) {
        pts.push(pos);
    }
    let metrics = evaluate(space, &pts);
    let waypoints = pts
        .iter()
        .map(|&p: &Point2| Waypoint {
            position: p,
            kind: WaypointKind::Cover,
            region: None,
        })
        .collect();
    PlanOutput {
        waypoints,
        regions: Vec::new(),
        labels: Vec::new(),
        metrics,
        stats: PlanStats {
            pattern_m: metrics.length_m,
            ..PlanStats::default()
        },
        warnings: Vec::new(),
        decomposition: DecompositionMethod::Single,
        pattern: PatternMethod::Lanes,
        lane_placement: None,
    }
}
