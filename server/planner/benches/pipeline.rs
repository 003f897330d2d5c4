//! Whole-pipeline bench (DESIGN §7 budget: full plan of a 200 m × 200 m cluttered map at 0.1 m < 1 s).

use criterion::{Criterion, criterion_group, criterion_main};
use shift_planner::geom::Point2;
use shift_planner::pipeline::{NoMonitor, PlanParams, plan};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::testing::cluttered_site;

fn bench(c: &mut Criterion) {
    let grid = cluttered_site(200.0, 200.0, 0.1, 400, 7).expect("site");
    let robot = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    let mut group = c.benchmark_group("pipeline");
    group.sample_size(10);
    group.bench_function("space_200m", |b| {
        b.iter(|| CoverageSpace::new(grid.clone(), robot, Point2::new(1.0, 1.0)).expect("space"))
    });
    let space = CoverageSpace::new(grid.clone(), robot, Point2::new(1.0, 1.0)).expect("space");
    group.bench_function("plan_200m", |b| {
        b.iter(|| plan(&space, &PlanParams::default(), &mut NoMonitor).expect("plan"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
