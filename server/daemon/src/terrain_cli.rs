//! `shiftd plan --terrain FILE` (issue 23): a point cloud (LAS, LAZ, PLY, PCD) → a plan JSON with 3-D
//! waypoints, and optionally its renderings. Other programs call exactly
//! `shiftd plan --terrain FILE --robot-kind drone|ground --tool-width W [--altitude-offset H] [--grid-m G]
//! --out plan.json [--render plan.png]`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use shift_engine::terrain_plan::{TerrainPlanned, TerrainRequest, plan_terrain};
use shift_planner::geom::Point2;
use shift_planner::speed::SpeedLimits;
use shift_planner::terrain::{GroundLimits, VerticalLimits};
use shift_proto::{AttributeDoc, RobotKindDoc};

use crate::cloud::source::source_doc;
use crate::cloud::{GroundFilter, LengthUnit, LoadOptions, load_cloud_file};
use crate::err;
use crate::error::Result;
use crate::render_terrain::{render_curvature, render_elevation, render_terrain_plan};

/// The robot a terrain plan is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RobotKindArg {
    /// Flies over the surface at --altitude-offset.
    Drone,
    /// Drives on it within --max-slope-deg, --max-step-m, --max-roughness-m.
    Ground,
}

/// The unit of a file's coordinates, overriding what its header says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum UnitArg {
    /// Metres.
    Metre,
    /// International feet (0.3048 m).
    Foot,
    /// US survey feet (1200/3937 m).
    UsSurveyFoot,
}

/// The terrain options of `shiftd plan`.
#[derive(Debug, Clone, clap::Args)]
pub struct TerrainArgs {
    /// Point cloud to plan over (LAS, LAZ, PLY or PCD; units from the header, converted to metres).
    #[arg(long, conflicts_with_all = ["scene", "map"])]
    pub terrain: Option<PathBuf>,
    /// Drone (lanes on the surface at an altitude offset, 3-D waypoints) or ground robot.
    #[arg(long, value_enum, default_value = "drone")]
    pub robot_kind: RobotKindArg,
    /// Height over the surface to fly at, metres (drones).
    #[arg(long, default_value_t = 3.0)]
    pub altitude_offset: f64,
    /// Elevation grid cell, metres.
    #[arg(long, default_value_t = 0.5)]
    pub grid_m: f64,
    /// Drones fly the ground within this distance of measured points, metres (default: twice the tool width);
    /// a tile's corners without data are not flown, and the tool is off over holes.
    #[arg(long)]
    pub region_fill_m: Option<f64>,
    /// The file's unit when its header is wrong or silent (PLY and PCD have none: metres are assumed).
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Use every point, not only the ground class (LAS class 2, used by default when the file has any).
    #[arg(long)]
    pub all_points: bool,
    /// Steepest slope a ground robot drives, degrees.
    #[arg(long, default_value_t = 15.0)]
    pub max_slope_deg: f64,
    /// Highest step a ground robot climbs, metres.
    #[arg(long, default_value_t = 0.10)]
    pub max_step_m: f64,
    /// Roughest ground a ground robot drives (RMS over 3 × 3 cells), metres.
    #[arg(long, default_value_t = 0.05)]
    pub max_roughness_m: f64,
    /// Fastest climb of a drone, m/s (an autopilot's WPNAV_SPEED_UP); unlimited when absent.
    #[arg(long)]
    pub max_climb_mps: Option<f64>,
    /// Fastest descent of a drone, m/s (an autopilot's WPNAV_SPEED_DN); unlimited when absent.
    #[arg(long)]
    pub max_descent_mps: Option<f64>,
    /// Write elevation.png, gaussian-curvature.png and mean-curvature.png into this folder.
    #[arg(long)]
    pub render_maps: Option<PathBuf>,
}

/// What `shiftd plan` passes on besides the terrain options.
#[derive(Debug, Clone)]
pub struct TerrainCommon {
    /// Swath width, metres (required).
    pub tool_width_m: Option<f64>,
    /// Ground robot radius, metres.
    pub robot_radius_m: Option<f64>,
    /// Ground robot start, map frame.
    pub start: Option<Point2>,
    /// Speed limits.
    pub limits: SpeedLimits,
    /// Attribute blobs file (JSON `{"blobs": [...]}`), map frame.
    pub attribute: Option<PathBuf>,
    /// Seed.
    pub seed: u64,
    /// Plan JSON ("-" for stdout).
    pub out: PathBuf,
    /// Plan rendering.
    pub render: Option<PathBuf>,
}

/// Runs the terrain plan: load, plan, write, render. Prints a summary on stderr.
pub fn run(t: &TerrainArgs, c: &TerrainCommon) -> Result<()> {
    let Some(file) = &t.terrain else {
        return Err(err!("--terrain FILE is required"));
    };
    let tool_width_m = c
        .tool_width_m
        .ok_or_else(|| err!("--tool-width is required with --terrain"))?;
    let opts = LoadOptions {
        units: t.units.map(|u| match u {
            UnitArg::Metre => LengthUnit::Metre,
            UnitArg::Foot => LengthUnit::Foot,
            UnitArg::UsSurveyFoot => LengthUnit::UsSurveyFoot,
        }),
        ground_only: if t.all_points {
            GroundFilter::All
        } else {
            GroundFilter::Auto
        },
        ..LoadOptions::default()
    };
    let started = Instant::now();
    let cloud = load_cloud_file(file, &opts).map_err(|e| err!("{}: {e}", file.display()))?;
    let name = file
        .file_name()
        .map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
    let source = source_doc(&cloud, &name);
    let attribute = match &c.attribute {
        Some(path) => Some(attribute_blobs(path)?),
        None => None,
    };
    let req = TerrainRequest {
        kind: match t.robot_kind {
            RobotKindArg::Drone => RobotKindDoc::Drone,
            RobotKindArg::Ground => RobotKindDoc::Ground,
        },
        tool_width_m,
        altitude_offset_m: t.altitude_offset,
        region_fill_m: t.region_fill_m.unwrap_or(2.0 * tool_width_m),
        grid_m: t.grid_m,
        robot_radius_m: c.robot_radius_m,
        start: c.start,
        ground: GroundLimits {
            max_slope_rad: t.max_slope_deg.to_radians(),
            max_step_m: t.max_step_m,
            max_roughness_m: t.max_roughness_m,
        },
        limits: c.limits,
        vertical: VerticalLimits {
            climb_mps: t.max_climb_mps,
            descent_mps: t.max_descent_mps,
        },
        attribute,
        seed: c.seed,
    };
    let mut planned = plan_terrain("p-cli", &cloud.points, source, &req)?;
    planned.doc.plan.metrics.compute_ms = started.elapsed().as_secs_f64() * 1e3;
    let text = serde_json::to_string_pretty(&planned.doc)?;
    if c.out.as_os_str() == "-" {
        println!("{text}");
    } else {
        std::fs::write(&c.out, text).map_err(|e| err!("writing {}: {e}", c.out.display()))?;
    }
    render_all(&planned, t, c)?;
    eprintln!("{}", summary(&planned));
    Ok(())
}

/// An attribute given as Gaussian blobs (map frame, metres); the engine rasterises it on the surface's grid.
fn attribute_blobs(path: &Path) -> Result<AttributeDoc> {
    let text = std::fs::read_to_string(path).map_err(|e| err!("reading {}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| err!("{}: attribute blobs JSON: {e}", path.display()))
}

fn render_all(p: &TerrainPlanned, t: &TerrainArgs, c: &TerrainCommon) -> Result<()> {
    if let Some(png) = &c.render {
        render_terrain_plan(
            &p.surface,
            p.blocked.as_deref(),
            &p.doc.plan.waypoints,
            &c.limits,
            png,
            1400,
        )?;
    }
    if let Some(dir) = &t.render_maps {
        std::fs::create_dir_all(dir).map_err(|e| err!("creating {}: {e}", dir.display()))?;
        render_elevation(&p.surface, &dir.join("elevation.png"), 1400)?;
        render_curvature(
            &p.curvature,
            &p.curvature.gaussian,
            &dir.join("gaussian-curvature.png"),
            1400,
        )?;
        render_curvature(&p.curvature, &p.curvature.mean, &dir.join("mean-curvature.png"), 1400)?;
    }
    Ok(())
}

/// One line for the terminal.
pub fn summary(p: &TerrainPlanned) -> String {
    let m = &p.doc.plan.metrics;
    let t = &p.doc.terrain;
    let s = &t.source;
    let mut line = format!(
        "{} {} points ({} used, {}; {}), grid {} × {} at {} m: ",
        s.format,
        s.points_read,
        s.points_used,
        s.ground_filter,
        s.conversion,
        t.surface.width,
        t.surface.height,
        t.grid_m
    );
    if let Some(d) = &t.drone {
        line += &format!(
            "surface coverage {:.2} %  altitude error p50 {:.3} p95 {:.3} max {:.3} m  lane spacing p5 {:.3} p95 {:.3} m (tool {} m)  max path slope {:.1}°  climb {:.2} / descent {:.2} m/s  lanes {}",
            d.surface_coverage_pct,
            d.altitude_error_m.p50,
            d.altitude_error_m.p95,
            d.altitude_error_m.max,
            d.lane_spacing_m.p5,
            d.lane_spacing_m.p95,
            d.tool_width_m,
            d.max_path_slope_deg,
            d.max_climb_mps,
            d.max_descent_mps,
            d.lanes
        );
    }
    if let Some(g) = &t.ground {
        line += &format!(
            "coverage {:.2} %  blocked {:.1} % of the cells  max path slope {:.1}° (limit {:.1}°)  collisions {}",
            m.coverage_pct, g.blocked_pct, g.max_path_slope_deg, g.max_slope_deg, m.collisions
        );
    }
    line + &format!(
        "  length {:.1} m  duration {:.1} s  compute {:.0} ms",
        m.length_m, m.duration_s, m.compute_ms
    )
}
