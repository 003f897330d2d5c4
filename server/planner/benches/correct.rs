//! Correction bench (DESIGN §7: cloud → correction p99 < 20 ms; optimiser median < 1 ms): a 40 m × 40 m
//! site at 0.05 m with a live tree of about 50 k obstacle points, a 30 m lane through it, and an obstacle
//! cluster of 20, 200 or 2000 points (a filled disk at 5 cm spacing, like an unfiltered scan at map
//! resolution) dropped on the lane 2.5 m ahead of the robot. Measures `judge` (3 m circle), the IKD-SWOpt
//! stage alone (`optimise`) and the whole `repair`.
//!
//! Also the IKD-SWOpt stage with `argmin`'s L-BFGS (More–Thuente and Hager–Zhang line searches) in place of
//! ours, on the same window cost and gradient (`correct::hooks`): `correct/lbfgs/{ours,argmin-mt,argmin-hz}`,
//! and a printed line per cluster with each solver's median time, iterations, cost evaluations, final J and
//! whether its window passed `verify` (the figures are in the docs of `correct/lbfgs.rs`).

use argmin::core::{CostFunction, Error, Executor, Gradient, IterState, Solver, State};
use argmin::solver::linesearch::{HagerZhangLineSearch, MoreThuenteLineSearch};
use argmin::solver::quasinewton::LBFGS;
use criterion::{Criterion, criterion_group, criterion_main};
use shift_planner::correct::World;
use shift_planner::correct::hooks::{self, Minimum, Objective};
use shift_planner::correct::{CorrectParams, judge, optimise, repair};
use shift_planner::geom::Point2;
use shift_planner::map::ikd_tree::Point3;
use shift_planner::map::{CellState, DistanceField, GridGeometry, IkdParams, IkdTree, LivePoints, OccupancyGrid};
use std::cell::RefCell;
use std::time::{Duration, Instant};

/// The window cost as an argmin problem. argmin asks for the cost and the gradient separately, often at the
/// same point: the last evaluation is kept so that each point costs one evaluation, as in our L-BFGS.
struct ArgminWindow<'a> {
    obj: RefCell<&'a mut dyn Objective>,
    last: RefCell<(Vec<f64>, f64, Vec<f64>)>,
}

impl ArgminWindow<'_> {
    fn at(&self, x: &[f64]) -> (f64, Vec<f64>) {
        let mut last = self.last.borrow_mut();
        if last.0.as_slice() != x || last.2.is_empty() {
            let mut g = vec![0.0; x.len()];
            let f = self.obj.borrow_mut().eval(x, &mut g);
            *last = (x.to_vec(), f, g);
        }
        (last.1, last.2.clone())
    }
}

impl CostFunction for ArgminWindow<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        Ok(self.at(x).0)
    }
}

impl Gradient for ArgminWindow<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, Error> {
        Ok(self.at(x).1)
    }
}

/// argmin's L-BFGS (memory 6, like ours) with line search `ls` from `x0`: at most `max_iters` iterations,
/// stopping at our tolerances' values (argmin reads them as the gradient's L2 norm and an absolute cost
/// change). Returns `x0` itself when argmin fails or ends costlier.
fn argmin_solve<'a, L>(obj: &'a mut dyn Objective, x0: &[f64], ls: L, max_iters: u32) -> Minimum
where
    L: Clone,
    LBFGS<L, Vec<f64>, Vec<f64>, f64>: Solver<ArgminWindow<'a>, IterState<Vec<f64>, Vec<f64>, (), (), (), f64>>,
{
    let problem = ArgminWindow {
        obj: RefCell::new(obj),
        last: RefCell::new((Vec::new(), 0.0, Vec::new())),
    };
    let f0 = problem.at(x0).0;
    let (g_tol, f_tol) = hooks::TOLERANCES;
    let solver = LBFGS::new(ls, 6)
        .with_tolerance_grad(g_tol)
        .and_then(|s| s.with_tolerance_cost(f_tol))
        .expect("tolerances");
    let run = Executor::new(problem, solver)
        .configure(|st| st.param(x0.to_vec()).max_iters(u64::from(max_iters)))
        .run();
    let fallback = Minimum {
        x: x0.to_vec(),
        f: f0,
        iterations: 0,
    };
    let Ok(res) = run else {
        return fallback;
    };
    let st = res.state();
    match st.get_best_param() {
        Some(x) if st.get_best_cost() <= f0 => Minimum {
            x: x.clone(),
            f: st.get_best_cost(),
            iterations: st.get_iter() as u32,
        },
        _ => fallback,
    }
}

/// An objective that counts its evaluations.
struct Counting<'a> {
    inner: &'a mut dyn Objective,
    evals: u32,
}

impl Objective for Counting<'_> {
    fn eval(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
        self.evals += 1;
        self.inner.eval(x, g)
    }
    fn precondition(&mut self, v: &mut [f64]) {
        self.inner.precondition(v);
    }
}

/// A minimiser for `hooks::optimise_with`.
type Solve<'s> = dyn FnMut(&mut dyn Objective, &[f64]) -> Minimum + 's;

/// Median wall time of `f` over `runs` calls, microseconds.
fn median_us(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

/// Deterministic xorshift in [0, 1).
fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 1_000_000) as f64 / 1_000_000.0
    }
}

fn bench(c: &mut Criterion) {
    let (w, h, res) = (40.0, 40.0, 0.05);
    let g = GridGeometry::new((w / res) as usize, (h / res) as usize, res, Point2::origin()).expect("geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(0.0, 0.0, w, 0.1, CellState::Occupied);
    grid.fill_rect(0.0, h - 0.1, w, h, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, 0.1, h, CellState::Occupied);
    grid.fill_rect(w - 0.1, 0.0, w, h, CellState::Occupied);
    let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
    // Background clutter: ~50 k live points in short wall pieces, none within 2 m of the lane (y = 20).
    let mut next = rng(7);
    let mut background = Vec::new();
    while background.len() < 50_000 {
        let (x, y) = (0.5 + next() * 39.0, 0.5 + next() * 39.0);
        if (y - 20.0).abs() < 2.0 {
            continue;
        }
        let ang = next() * std::f64::consts::PI;
        for k in 0..40 {
            let t = f64::from(k) * 0.05;
            let (px, py) = (x + t * ang.cos(), y + t * ang.sin());
            if (py - 20.0).abs() >= 2.0 && px > 0.2 && px < w - 0.2 && py < h - 0.2 {
                background.push(Point3::new(px as f32, py as f32, 0.0));
            }
        }
    }
    let path = vec![Point2::new(5.0, 20.0), Point2::new(35.0, 20.0)];
    let robot = Point2::new(16.0, 20.0);
    let p = CorrectParams::for_robot(0.3);
    for n in [20usize, 200, 2000] {
        // A filled disk of n points at about 5 cm spacing, its near edge 2.5 m ahead of the robot.
        let radius = (n as f64 / (std::f64::consts::PI * 400.0)).sqrt();
        let centre = Point2::new(robot.x + 2.5 + radius, 20.05);
        let mut pts = background.clone();
        let mut next = rng(n as u64);
        let mut placed = 0;
        while placed < n {
            let (a, r) = (next() * std::f64::consts::TAU, radius * next().sqrt());
            pts.push(Point3::new(
                (centre.x + r * a.cos()) as f32,
                (centre.y + r * a.sin()) as f32,
                0.0,
            ));
            placed += 1;
        }
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        tree.build(&pts);
        let world = World::new(&grid, &field, Some(LivePoints::new(&tree, Point2::origin()))).expect("world");
        let breaches = judge(&path, 0, robot, &world, &p);
        let Some(b) = breaches.first().copied() else {
            println!("cluster {n}: no breach judged");
            continue;
        };
        let r = repair(&path, &b, &world, &p).expect("repair");
        let o = optimise(&path, &b, &world, &p).expect("optimise");
        println!(
            "cluster {n} (radius {radius:.2} m, tree {} points): repair {:?}, {} waypoints, {} iterations, J {:.3} -> {:.3}; optimiser alone {}",
            tree.len(),
            r.kind,
            r.waypoints.len(),
            r.iterations,
            r.cost_before,
            r.cost_after,
            o.as_ref().map_or("found no feasible window".to_string(), |o| format!(
                "{} iterations",
                o.iterations
            )),
        );
        // Our L-BFGS and argmin's on the same window cost.
        let max_it = p.max_iterations;
        let mut ours = |o: &mut dyn Objective, x0: &[f64]| hooks::ours(o, x0, max_it);
        let mut mt = |o: &mut dyn Objective, x0: &[f64]| argmin_solve(o, x0, MoreThuenteLineSearch::new(), max_it);
        let mut hz = |o: &mut dyn Objective, x0: &[f64]| argmin_solve(o, x0, HagerZhangLineSearch::new(), max_it);
        let solvers: [(&str, &mut Solve<'_>); 3] =
            [("ours", &mut ours), ("argmin-mt", &mut mt), ("argmin-hz", &mut hz)];
        let mut line = format!("lbfgs cluster {n}:");
        for (name, solve) in solvers {
            let mut evals = 0u32;
            // One extra run through a counting objective for the evaluation count.
            let mut counting = |o: &mut dyn Objective, x0: &[f64]| {
                let mut c = Counting { inner: o, evals: 0 };
                let m = solve(&mut c, x0);
                evals += c.evals;
                m
            };
            let out = hooks::optimise_with(&path, &b, &world, &p, &mut counting).expect("optimise");
            let desc = out.as_ref().map_or("no feasible window".to_string(), |r| {
                format!(
                    "{} iterations, J {:.3} -> {:.3}",
                    r.iterations, r.cost_before, r.cost_after
                )
            });
            let med = median_us(101, || {
                let _ = hooks::optimise_with(&path, &b, &world, &p, &mut *solve);
            });
            line += &format!(" {name} median {med:.0} us ({desc}, {evals} evaluations);");
            c.bench_function(&format!("correct/lbfgs/{name}/{n}"), |bch| {
                bch.iter(|| hooks::optimise_with(&path, &b, &world, &p, &mut *solve))
            });
        }
        println!("{line}");
        c.bench_function(&format!("correct/judge/{n}"), |bch| {
            bch.iter(|| judge(&path, 0, robot, &world, &p))
        });
        c.bench_function(&format!("correct/optimise/{n}"), |bch| {
            bch.iter(|| optimise(&path, &b, &world, &p))
        });
        c.bench_function(&format!("correct/repair/{n}"), |bch| {
            bch.iter(|| repair(&path, &b, &world, &p))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_millis(500));
    targets = bench
}
criterion_main!(benches);
