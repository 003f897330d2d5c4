//! `shiftd eval --robots N`: every scene of a folder divided among N robots from spread docks and planned
//! ([`plan_fleet`]), one row per scene and fleet size: planned durations (longest, shortest, their ratio),
//! union coverage, seam overlap (coverable area two robots sweep), collisions and compute time.
//!
//! Docks: [`spread_docks`] (the scene's own start, then each next the reachable cell farthest from those
//! chosen), so the fleet starts spread over the site as the quality bar asks.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use shift_planner::divide::FleetRobot;
use shift_planner::divide::docks::spread_docks;
use shift_planner::pipeline::PlanParams;
use shift_planner::pipeline::fleet::{FleetParams, plan_fleet};
use shift_planner::speed::SpeedLimits;

use crate::error::Result;
use crate::eval::scene_space;
use crate::render_fleet::render_fleet_png;
use crate::scene_io::scene_dirs;

/// One row of the fleet evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct FleetRow {
    /// Scene name.
    pub scene: String,
    /// Robots.
    pub robots: usize,
    /// Longest planned duration, seconds.
    pub longest_s: f64,
    /// Shortest planned duration, seconds.
    pub shortest_s: f64,
    /// Longest over shortest.
    pub duration_ratio: f64,
    /// Coverable cells covered by some robot, percent.
    pub coverage_pct: f64,
    /// Coverable area covered by two robots or more, percent.
    pub seam_overlap_pct: f64,
    /// Sampled path points too close to an obstacle, all robots.
    pub collisions: usize,
    /// Divide-and-plan rounds.
    pub rounds: usize,
    /// Compute time, milliseconds.
    pub compute_ms: f64,
    /// The docks, map frame, metres.
    pub docks: Vec<[f64; 2]>,
    /// The division's remarks (a balance it could not reach, area left to no robot).
    pub warnings: Vec<String>,
}

/// Runs the fleet evaluation over every scene under `root` for each fleet size in `sizes`.
pub fn run_fleet_eval(
    root: &Path,
    sizes: &[usize],
    render: Option<&Path>,
    mut on_row: impl FnMut(&FleetRow),
) -> Result<Vec<FleetRow>> {
    if let Some(dir) = render {
        std::fs::create_dir_all(dir)?;
    }
    let mut rows = Vec::new();
    for dir in scene_dirs(root)? {
        let (name, space, attribute) = scene_space(&dir)?;
        for &n in sizes {
            let limits = SpeedLimits::default();
            let robots: Vec<FleetRobot> = spread_docks(&space, n)
                .into_iter()
                .map(|start| FleetRobot::disc(start, space.robot, limits))
                .collect();
            let t = Instant::now();
            let fleet = plan_fleet(
                &space.grid,
                &robots,
                &PlanParams::default(),
                attribute.as_ref(),
                &FleetParams::default(),
            )?;
            let compute_ms = t.elapsed().as_secs_f64() * 1e3;
            let m = &fleet.metrics;
            let row = FleetRow {
                scene: name.clone(),
                robots: robots.len(),
                longest_s: m.durations_s.iter().copied().fold(0.0, f64::max),
                shortest_s: m.durations_s.iter().copied().fold(f64::INFINITY, f64::min),
                duration_ratio: m.duration_ratio,
                coverage_pct: m.union_coverage_pct,
                seam_overlap_pct: m.seam_overlap_pct,
                collisions: fleet.plans.iter().map(|(_, p)| p.metrics.collisions).sum(),
                rounds: fleet.rounds,
                compute_ms,
                docks: robots.iter().map(|r| [r.start.x, r.start.y]).collect(),
                warnings: fleet.division.warnings.clone(),
            };
            if let Some(dir) = render {
                render_fleet_png(&space.grid, &fleet, &dir.join(format!("{name}-fleet{n}.png")), 900)?;
            }
            on_row(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The table header.
pub const FLEET_TABLE_HEADER: &str =
    "scene                 robots  longest_s  shortest_s  ratio  coverage%  seam%  collisions  rounds  compute_ms";

/// One table line.
pub fn fleet_table_line(r: &FleetRow) -> String {
    format!(
        "{:<21} {:>6} {:>10.0} {:>11.0} {:>6.3} {:>10.2} {:>6.2} {:>11} {:>7} {:>11.0}",
        r.scene,
        r.robots,
        r.longest_s,
        r.shortest_s,
        r.duration_ratio,
        r.coverage_pct,
        r.seam_overlap_pct,
        r.collisions,
        r.rounds,
        r.compute_ms
    )
}
