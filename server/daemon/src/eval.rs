//! `shiftd eval`: every decomposition × order (default pattern) and the three baselines on every scene of a
//! folder, as one table (or JSON lines), optionally rendering each plan. Every plan is speed-profiled
//! (default limits, the scene's attribute map or A = 1) for its duration and dwell uniformity.

use std::path::Path;
use std::time::Instant;

use crate::error::Result;
use serde::Serialize;
use shift_planner::baseline::{Baseline, run_baseline};
use shift_planner::decompose::DecompositionMethod;
use shift_planner::geom::Point2;
use shift_planner::order::OrderMethod;
use shift_planner::pipeline::{NoMonitor, PlanOutput, PlanParams, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{AttributeMap, SpeedLimits, SpeedParams, SpeedProfile, profile_path};

use crate::render::render_png;
use crate::scene_io::{load_attribute, load_scene, scene_attribute_path, scene_dirs};

/// One row of the evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct EvalRow {
    /// Scene name.
    pub scene: String,
    /// Decomposition (or `none` for baselines).
    pub decomposition: String,
    /// Order solver (or the baseline's name).
    pub order: String,
    /// Pattern.
    pub pattern: String,
    /// Time to drive the profiled plan, seconds.
    pub duration_s: f64,
    /// Coverage, percent.
    pub coverage_pct: f64,
    /// Overlap, percent.
    pub overlap_pct: f64,
    /// Length, metres.
    pub length_m: f64,
    /// Turns.
    pub turns: usize,
    /// Compute time, milliseconds.
    pub compute_ms: f64,
    /// Collisions.
    pub collisions: usize,
    /// Dwell uniformity with the profiled speeds (scenes with an attribute map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dwell_cv: Option<f64>,
    /// Dwell uniformity at constant speed, same path and time (scenes with an attribute map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dwell_cv_const_speed: Option<f64>,
}

/// Builds the coverage space of a loaded scene, with its attribute map when it names one.
pub fn scene_space(dir: &Path) -> Result<(String, CoverageSpace, Option<AttributeMap>)> {
    let s = load_scene(dir)?;
    let robot = RobotShape {
        radius_m: s.scene.robot_radius,
        tool_width_m: s.scene.tool_width,
    };
    let attribute = match scene_attribute_path(&s) {
        Some(p) => Some(load_attribute(&p, s.map.grid.geometry)?),
        None => None,
    };
    let space = CoverageSpace::new(s.map.grid, robot, Point2::new(s.scene.start[0], s.scene.start[1]))?;
    Ok((s.name, space, attribute))
}

/// Runs the evaluation over every scene under `root`.
pub fn run_eval(root: &Path, render: Option<&Path>, mut on_row: impl FnMut(&EvalRow)) -> Result<Vec<EvalRow>> {
    let mut rows = Vec::new();
    if let Some(dir) = render {
        std::fs::create_dir_all(dir)?;
    }
    for dir in scene_dirs(root)? {
        let (name, space, attribute) = scene_space(&dir)?;
        let limits = SpeedLimits::default();
        let speed = SpeedParams::new(limits, space.robot.tool_width_m);
        let mut emit = |decomposition: &str,
                        order: &str,
                        pattern: &str,
                        (out, profile): (&PlanOutput, &SpeedProfile),
                        ms: f64|
         -> Result<()> {
            let m = profile.metrics;
            let d = profile.dwell;
            let row = EvalRow {
                scene: name.clone(),
                decomposition: decomposition.into(),
                order: order.into(),
                pattern: pattern.into(),
                duration_s: d.duration_s,
                coverage_pct: m.coverage_pct,
                overlap_pct: m.overlap_pct,
                length_m: m.length_m,
                turns: m.turns,
                compute_ms: ms,
                collisions: m.collisions,
                dwell_cv: attribute.is_some().then_some(d.dwell_cv),
                dwell_cv_const_speed: attribute.is_some().then_some(d.dwell_cv_const_speed),
            };
            if let Some(dir) = render {
                render_png(
                    &space,
                    out,
                    Some((profile, &limits)),
                    &dir.join(format!("{name}-{decomposition}-{order}-{pattern}.png")),
                    900,
                )?;
            }
            on_row(&row);
            rows.push(row);
            Ok(())
        };
        let mut default_len = 0.0;
        for d in std::iter::once(DecompositionMethod::Auto).chain(DecompositionMethod::ALL) {
            let orders: &[OrderMethod] = if d == DecompositionMethod::Auto {
                &[OrderMethod::default()]
            } else {
                &OrderMethod::ALL
            };
            for &o in orders {
                let params = PlanParams {
                    decomposition: d,
                    order: o,
                    ..PlanParams::default()
                };
                let t = Instant::now();
                // With an attribute map the strategy is chosen on the profiled dwell (part of planning).
                let (out, profile) = plan_shaped(&space, &params, attribute.as_ref(), &speed, &mut NoMonitor)?;
                let ms = t.elapsed().as_secs_f64() * 1e3;
                if d == DecompositionMethod::default() && o == OrderMethod::default() {
                    default_len = out.metrics.length_m;
                }
                // For `auto`, say which member won.
                let dname = if d == DecompositionMethod::Auto {
                    format!("auto:{}", out.decomposition.name())
                } else {
                    d.name().to_owned()
                };
                emit(&dname, o.name(), out.pattern.name(), (&out, &profile), ms)?;
            }
        }
        for b in Baseline::ALL {
            let t = Instant::now();
            let out = run_baseline(&space, b, 1, default_len)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let profile = profile_path(&space, &out.waypoints, attribute.as_ref(), &speed)?;
            emit("none", b.name(), "baseline", (&out, &profile), ms)?;
        }
    }
    Ok(rows)
}

/// The table header.
pub const TABLE_HEADER: &str = "scene                 decomposition order        pattern     duration_s  coverage%  overlap%   length_m  turns  compute_ms  collisions  dwell_cv  dwell_cv_const";

/// One table line, duration first (the default objective), then coverage, length, turns and collisions of
/// the smoothed path; "-" for the dwell figures of scenes without an attribute map.
pub fn table_line(r: &EvalRow) -> String {
    let opt = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.3}"));
    format!(
        "{:<21} {:<13} {:<12} {:<10} {:>11.0} {:>9.2} {:>9.2} {:>10.1} {:>6} {:>11.1} {:>11} {:>9} {:>15}",
        r.scene,
        r.decomposition,
        r.order,
        r.pattern,
        r.duration_s,
        r.coverage_pct,
        r.overlap_pct,
        r.length_m,
        r.turns,
        r.compute_ms,
        r.collisions,
        opt(r.dwell_cv),
        opt(r.dwell_cv_const_speed)
    )
}
