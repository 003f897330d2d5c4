//! The command line (clap derive).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use shift_client::DEFAULT_BASE_URL;

/// Operate a SHIFT daemon: sites, plans, missions, exports, pictures, robots.
///
/// Exit codes: 0 ok, 1 the server said no (or could not be reached), 2 bad input (arguments, local files).
#[derive(Debug, Parser)]
#[command(name = "shiftctl", version)]
pub struct Cli {
    /// The daemon's HTTP address.
    #[arg(long, global = true, env = "SHIFT_HTTP", default_value = DEFAULT_BASE_URL)]
    pub http: String,
    /// Bearer token for mutating routes (when the daemon has `auth_token` set).
    #[arg(long, global = true, env = "SHIFT_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Machine-readable output: the API's JSON on stdout (one document, or one per line for streams).
    #[arg(long, global = true)]
    pub json: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
// Parsed once per run: the size of the largest variant (plan's many options) costs nothing.
#[allow(clippy::large_enum_variant)]
pub enum Command {
    /// A site: upload its map, show its summary.
    Site {
        /// What to do with it.
        #[command(subcommand)]
        action: SiteAction,
    },
    /// Every site with its summary.
    Sites,
    /// Ask for a plan (`plan --site S --start X,Y`), or `plan show|cancel|assign ID`.
    Plan(PlanArgs),
    /// List plans, newest first.
    Plans(PlansArgs),
    /// Write a plan's path as GeoJSON, CSV or nav_msgs/Path JSON.
    Export(ExportArgs),
    /// Draw a plan on its site's map as a PNG.
    Render(RenderArgs),
    /// A mission for a fleet: `mission create --site S --robot ID:X,Y:RADIUS:TOOL_WIDTH …`, or
    /// `mission show|assign|replan|join|cancel ID`.
    Mission {
        /// What to do.
        #[command(subcommand)]
        action: MissionAction,
    },
    /// What robots swept on a site (`--png FILE` for the picture).
    Coverage(CoverageArgs),
    /// Every robot: alive or lost, pose, plan, progress.
    Robots,
    /// Follow a Zenoh stream.
    Tail {
        /// Which stream.
        #[command(subcommand)]
        stream: TailStream,
    },
}

/// `site …`.
#[derive(Debug, Subcommand)]
pub enum SiteAction {
    /// Upload a map_server map (the YAML and the image it names) as SITE's map.
    Upload {
        /// Site name (letters, digits, '-', '_').
        site: String,
        /// The map_server YAML; its `image` is read relative to it.
        #[arg(long)]
        yaml: PathBuf,
    },
    /// Upload a field drawn in GeoJSON (lon/lat; holes are obstacles) as SITE.
    Field {
        /// Site name (letters, digits, '-', '_').
        site: String,
        /// A GeoJSON Polygon, MultiPolygon, Feature or FeatureCollection.
        #[arg(long, value_name = "FILE")]
        geojson: PathBuf,
        /// A GeoJSON polygon not to enter (repeatable).
        #[arg(long, value_name = "FILE")]
        no_go: Vec<PathBuf>,
        /// The tool width the site is planned for, metres (chooses the grid's resolution).
        #[arg(long)]
        tool_width: Option<f64>,
        /// The grid's resolution, metres per cell.
        #[arg(long)]
        resolution_m: Option<f64>,
    },
    /// A site's summary.
    Show {
        /// Site name.
        site: String,
    },
}

/// `plan …`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct PlanArgs {
    /// show, cancel or assign an existing plan.
    #[command(subcommand)]
    pub action: Option<PlanAction>,
    /// Site to plan on.
    #[arg(long, required = true)]
    pub site: Option<String>,
    /// Start and return point X,Y (metres, map frame).
    #[arg(
        long,
        value_name = "X,Y",
        allow_hyphen_values = true,
        required_unless_present = "start_wgs84"
    )]
    pub start: Option<String>,
    /// Start and return point LON,LAT (degrees) on a site uploaded as a field, instead of --start.
    #[arg(long, value_name = "LON,LAT", allow_hyphen_values = true, conflicts_with = "start")]
    pub start_wgs84: Option<String>,
    /// Robot footprint radius, metres.
    #[arg(long, default_value_t = 0.15)]
    pub robot_radius: f64,
    /// Tool width, metres.
    #[arg(long, default_value_t = 0.3)]
    pub tool_width: f64,
    /// Slowest cover speed, m/s.
    #[arg(long, default_value_t = 0.1)]
    pub v_min: f64,
    /// Fastest speed, m/s.
    #[arg(long, default_value_t = 1.0)]
    pub v_max: f64,
    /// Largest acceleration, m/s².
    #[arg(long, default_value_t = 0.5)]
    pub a_max: f64,
    /// Only cover inside this polygon: "X,Y X,Y X,Y …" (metres, map frame).
    #[arg(long, value_name = "POLYGON", allow_hyphen_values = true)]
    pub region: Option<String>,
    // Attribute map, planner options, objective.
    #[command(flatten)]
    pub planner: PlannerArgs,
    /// Move a start whose traversable piece is small into the largest piece when it is this close, metres.
    #[arg(long, value_name = "M")]
    pub snap_start_m: Option<f64>,
    /// Follow the computation: a progress bar fed by the plan's events, then the metrics.
    #[arg(long)]
    pub watch: bool,
}

/// The planner's choices, shared by `plan` and `mission create`.
#[derive(Debug, Args)]
pub struct PlannerArgs {
    /// Attribute map: a JSON file `{"blobs": [{"x", "y", "sigma", "amplitude"}]}`.
    #[arg(long, value_name = "FILE")]
    pub attribute: Option<PathBuf>,
    /// Decomposition (auto, bcd, walls, voronoi, grid, none).
    #[arg(long)]
    pub decomposition: Option<String>,
    /// Visiting order (two-opt, rrt, anneal).
    #[arg(long)]
    pub order: Option<String>,
    /// In-region pattern (lanes, spiral).
    #[arg(long)]
    pub pattern: Option<String>,
    /// Seed for every random choice.
    #[arg(long)]
    pub seed: Option<u64>,
    /// What a plan minimises among those that cover ≥ 99 % (time, length, overlap, turns; default time).
    #[arg(long)]
    pub objective: Option<String>,
}

/// `plan show|cancel|assign`.
#[derive(Debug, Subcommand)]
pub enum PlanAction {
    /// Status, progress and metrics.
    Show {
        /// Plan id.
        id: String,
    },
    /// Cancel a queued or planning plan.
    Cancel {
        /// Plan id.
        id: String,
    },
    /// Send a computed plan to a robot.
    Assign {
        /// Plan id.
        id: String,
        /// Robot id.
        robot: String,
    },
}

/// `mission …`.
#[derive(Debug, Subcommand)]
pub enum MissionAction {
    /// Ask for a mission: the site divided among the robots, each part planned.
    Create(MissionCreateArgs),
    /// Status, coverage and one plan per robot.
    Show {
        /// Mission id.
        id: String,
    },
    /// Send every part's plan to its robot (all or none).
    Assign {
        /// Mission id.
        id: String,
    },
    /// Divide what the mission has left again among its robots, each from where it is.
    Replan {
        /// Mission id.
        id: String,
    },
    /// Add a robot to a mission: it takes a balanced share of what is left.
    Join {
        /// Mission id.
        id: String,
        /// The robot: its id, dock X,Y (metres, map frame), footprint radius and tool width (metres).
        #[arg(long = "robot", value_name = "ID:X,Y:RADIUS:TOOL_WIDTH", allow_hyphen_values = true)]
        robot: String,
    },
    /// Cancel a mission and its plans not yet driven.
    Cancel {
        /// Mission id.
        id: String,
    },
}

/// `mission create`.
#[derive(Debug, Args)]
pub struct MissionCreateArgs {
    /// Site to cover.
    #[arg(long)]
    pub site: String,
    /// A robot: its id, dock X,Y (metres, map frame), footprint radius and tool width (metres); once per robot.
    #[arg(
        long = "robot",
        required = true,
        value_name = "ID:X,Y:RADIUS:TOOL_WIDTH",
        allow_hyphen_values = true
    )]
    pub robots: Vec<String>,
    // Attribute map, planner options, objective.
    #[command(flatten)]
    pub planner: PlannerArgs,
    /// Follow the planning: a progress bar fed by the mission's events, then its table.
    #[arg(long)]
    pub watch: bool,
}

/// `coverage`.
#[derive(Debug, Args)]
pub struct CoverageArgs {
    /// Site name.
    pub site: String,
    /// Write the raster as a PNG here (the map in greys, swept cells green) instead of printing its figures.
    #[arg(long, value_name = "FILE")]
    pub png: Option<PathBuf>,
}

/// `plans`.
#[derive(Debug, Args)]
pub struct PlansArgs {
    /// Only this site's plans.
    #[arg(long)]
    pub site: Option<String>,
    /// Only plans in this state (queued, planning, ready, active, done, failed, cancelled).
    #[arg(long)]
    pub status: Option<String>,
    /// Only plans assigned to this robot.
    #[arg(long)]
    pub robot: Option<String>,
    /// Plans per page (1-500).
    #[arg(long)]
    pub limit: Option<u32>,
    /// Continue after this cursor (the `next` of a previous page).
    #[arg(long)]
    pub after: Option<String>,
    /// Follow every page (else one page).
    #[arg(long)]
    pub all: bool,
}

/// Export formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// A FeatureCollection: the path as a LineString with per-point `v`, `t`, `kind`, and the regions.
    Geojson,
    /// `x,y,v,t,kind`, one row per waypoint.
    Csv,
    /// nav_msgs/Path as JSON (map frame, yaw along the path).
    NavPath,
}

/// `export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Plan id.
    pub plan: String,
    /// Output format.
    #[arg(long, value_enum)]
    pub format: Format,
    /// Write here instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Coordinates of `--format geojson`: the map frame (metres), or wgs84 (lon/lat, plans on field sites).
    #[arg(long, value_enum, default_value_t = Crs::Map)]
    pub crs: Crs,
}

/// Coordinates of an export.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Crs {
    /// Metres, the plan's map frame.
    Map,
    /// Longitude and latitude (GeoJSON's RFC 7946 CRS).
    Wgs84,
}

/// `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Plan id.
    pub plan: String,
    /// PNG to write.
    pub out: PathBuf,
    /// Long side of the map part of the picture, pixels.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(100..=8000))]
    pub size: u32,
}

/// `tail …`.
#[derive(Debug, Subcommand)]
pub enum TailStream {
    /// Print the corrections the daemon sends to ROBOT as they arrive.
    Corrections {
        /// Robot id.
        robot: String,
        /// Zenoh endpoint to connect to (peer mode, no scouting).
        #[arg(long, default_value = "tcp/127.0.0.1:7447")]
        zenoh: String,
        /// Key prefix.
        #[arg(long, default_value = "shift")]
        prefix: String,
        /// Fleet.
        #[arg(long, default_value = "default")]
        fleet: String,
        /// Stop after this many corrections.
        #[arg(long)]
        count: Option<u64>,
    },
}
