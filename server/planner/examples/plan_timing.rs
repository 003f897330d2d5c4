//! Times each stage of a default plan on generated cluttered sites of growing size:
//! `cargo run --release -p shift-planner --example plan_timing -- [SIDE_M ...]`; `first_region_ms` is when
//! the first region of the final plan was ready (streamed to clients while the rest link). `STAGES=1`
//! prints the progress timeline; `DECOMP`, `PATTERN` and `PLACE` fix the strategy; `NOISE=k` adds k single
//! occupied cells per 100 m² (the speckle of real SLAM maps).

use std::time::Instant;

use shift_planner::geom::Point2;
use shift_planner::pipeline::{PlanMonitor, PlanParams, RegionSummary, plan};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::testing::cluttered_site;

fn main() {
    let sides: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let sides = if sides.is_empty() {
        vec![25.0, 50.0, 100.0]
    } else {
        sides
    };
    for side in sides {
        let mut grid = cluttered_site(side, side, 0.1, (side * side / 100.0) as usize, 7).expect("site");
        // NOISE=k: k single occupied cells per 100 m², like the speckle of a real SLAM map.
        if let Some(k) = std::env::var("NOISE").ok().and_then(|v| v.parse::<f64>().ok()) {
            let n = (k * side * side / 100.0) as u64;
            let len = grid.cells.len() as u64;
            let mut x = 0x9E37_79B9_7F4A_7C15_u64;
            for _ in 0..n {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                grid.cells[(x % len) as usize] = shift_planner::map::CellState::Occupied;
            }
        }
        let t = Instant::now();
        let space = CoverageSpace::new(
            grid,
            RobotShape {
                radius_m: 0.3,
                tool_width_m: 0.6,
            },
            Point2::new(1.0, 1.0),
        )
        .expect("space");
        let space_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let mut stages = Stages(Instant::now(), Vec::new(), None);
        let out = plan(&space, &params(), &mut stages).expect("plan");
        if std::env::var("STAGES").is_ok() {
            eprintln!("stages (progress, ms): {:?}", stages.1);
        }
        let plan_ms = t.elapsed().as_secs_f64() * 1e3;
        let m = out.metrics;
        println!(
            "{{\"side_m\": {side}, \"cells\": {}, \"space_ms\": {space_ms:.0}, \"plan_ms\": {plan_ms:.0}, \"first_region_ms\": {}, \"regions\": {}, \"coverage_pct\": {:.2}, \"overlap_pct\": {:.2}, \"collisions\": {}, \"chose\": \"{}/{}/{:?}\"}}",
            space.geometry().len(),
            stages.2.map_or(-1, |t| t as i64),
            out.regions.len(),
            m.coverage_pct,
            m.overlap_pct,
            m.collisions,
            out.decomposition.name(),
            out.pattern.name(),
            out.lane_placement
        );
    }
}

/// Default params, with `DECOMP` and `PLACE` (lattice, fit, framed) overrides for stage profiling.
fn params() -> PlanParams {
    let mut p = PlanParams::default();
    if let Some(d) = std::env::var("DECOMP").ok().and_then(|d| d.parse().ok()) {
        p.decomposition = d;
    }
    if let Some(pt) = std::env::var("PATTERN").ok().and_then(|d| d.parse().ok()) {
        p.pattern = pt;
    }
    if let Ok(pl) = std::env::var("PLACE") {
        use shift_planner::pattern::lanes::Placement;
        p.lanes.placement = match pl.as_str() {
            "lattice" => Some(Placement::Lattice),
            "fit" => Some(Placement::Fit),
            "framed" => Some(Placement::Framed),
            _ => None,
        };
    }
    p
}

/// Records elapsed milliseconds at every progress report and when the first region is ready.
struct Stages(Instant, Vec<(f64, u64)>, Option<u64>);

impl PlanMonitor for Stages {
    fn progress(&mut self, fraction: f64) {
        self.1.push((fraction, self.0.elapsed().as_millis() as u64));
    }
    fn region_ready(&mut self, _region: &RegionSummary, _path: &[Point2]) {
        self.2.get_or_insert(self.0.elapsed().as_millis() as u64);
    }
}
