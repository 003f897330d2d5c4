//! Plans over point-cloud terrain (issue 23): points in metres → the planner's terrain pipeline (seed 000
//! §IV.A–B) → a [`TerrainPlanDocument`]. The caller (the daemon's CLI or API) has read the file and says where
//! the points came from ([`CloudSourceDoc`]); nothing here touches a file.
//!
//! - Drones and sprayers: the smoothed surface, lanes spaced by the tool width on the surface, 3-D waypoints at
//!   the altitude offset, speeds from the RFICP law on the lanes ([`shift_planner::terrain::profile_drone`]).
//! - Ground robots: slope, step and roughness limits make the surface an occupancy grid, and the ordinary
//!   coverage pipeline plans on it; each waypoint's z is the ground height under it.

use shift_planner::geom::Point2;
use shift_planner::map::GridGeometry;
use shift_planner::metrics::count_turns;
use shift_planner::pipeline::{NoMonitor, PlanParams, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{AttributeMap, SpeedLimits, SpeedParams};
use shift_planner::terrain::{
    CurvatureMap, DroneParams, DroneProfile, GroundLimits, LaneChoice, Quantiles, SurfaceReport, TerrainParams,
    TerrainSurface, Traversability, VerticalLimits, ground_occupancy, plan_drone, profile_drone, vertical_speeds,
};
use shift_proto::{
    AttributeDoc, CloudSourceDoc, DroneMetricsDoc, GroundDoc, PlanDocument, PlanMetricsDoc, QuantilesDoc, RegionDoc,
    RobotKindDoc, SurfaceDoc, TerrainDoc, TerrainPlanDocument, WaypointDoc, WaypointKindDoc,
};

use crate::error::EngineError;
use crate::plan_doc::to_document;

/// What to plan over a cloud.
#[derive(Debug, Clone)]
pub struct TerrainRequest {
    /// Drone or ground robot.
    pub kind: RobotKindDoc,
    /// Swath width (on the surface for drones), metres.
    pub tool_width_m: f64,
    /// Height over the surface to fly at (drones), metres.
    pub altitude_offset_m: f64,
    /// Drones: the region flown is the ground measured or filled at most this far from measured points, metres
    /// (∞: the whole grid).
    pub region_fill_m: f64,
    /// Gridding cell size, metres.
    pub grid_m: f64,
    /// Ground robots: the robot's radius, metres (default: half the tool width).
    pub robot_radius_m: Option<f64>,
    /// Ground robots: the start, map frame, metres (default: the traversable point nearest the cloud's
    /// lower-left corner, in the largest traversable piece).
    pub start: Option<Point2>,
    /// Ground robots: what the robot can drive on.
    pub ground: GroundLimits,
    /// Speed limits (drones: along the 3-D path).
    pub limits: SpeedLimits,
    /// Drones: climb and descent limits.
    pub vertical: VerticalLimits,
    /// Attribute (dirtiness, dryness) as blobs in the map frame; lanes are slower where it is high. It is
    /// rasterised on the surface's own grid, whose origin and size the cloud decides.
    pub attribute: Option<AttributeDoc>,
    /// Seed of the ground pipeline's random choices.
    pub seed: u64,
}

/// A terrain plan and what it was made of (for renderings).
#[derive(Debug)]
pub struct TerrainPlanned {
    /// The plan JSON.
    pub doc: TerrainPlanDocument,
    /// The smoothed, gap-free elevation map.
    pub surface: TerrainSurface,
    /// Curvature of the smoothed surface.
    pub curvature: CurvatureMap,
    /// Ground robots: cells that are obstacles under the limits.
    pub blocked: Option<Vec<bool>>,
}

/// Plans over `points` (metres, map frame) from `source`.
pub fn plan_terrain(
    plan_id: &str,
    points: &[[f64; 3]],
    source: CloudSourceDoc,
    req: &TerrainRequest,
) -> Result<TerrainPlanned, EngineError> {
    let mut terrain = TerrainParams::default();
    terrain.grid.cell_m = req.grid_m;
    let job = Job {
        plan_id,
        points,
        source,
        req,
        terrain,
    };
    match req.kind {
        RobotKindDoc::Drone => plan_flight(job),
        RobotKindDoc::Ground => plan_ground(job),
    }
}

/// One terrain plan's inputs, as both robot kinds take them.
struct Job<'a> {
    plan_id: &'a str,
    points: &'a [[f64; 3]],
    source: CloudSourceDoc,
    req: &'a TerrainRequest,
    terrain: TerrainParams,
}

impl Job<'_> {
    /// The request's attribute rasterised on `geometry` (the surface's grid).
    fn attribute(&self, geometry: GridGeometry) -> Result<Option<AttributeMap>, EngineError> {
        self.req
            .attribute
            .as_ref()
            .map(|doc| crate::attribute_map(doc, geometry))
            .transpose()
            .map_err(|e| EngineError::InvalidRequest(format!("attribute: {e}")))
    }
}

fn quantiles(q: &Quantiles) -> QuantilesDoc {
    QuantilesDoc {
        p5: q.p5,
        p50: q.p50,
        p95: q.p95,
        max: q.max,
    }
}

fn surface_doc(s: &TerrainSurface, report: &SurfaceReport) -> SurfaceDoc {
    let (lo, hi) = s
        .heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &z| {
            (lo.min(z), hi.max(z))
        });
    SurfaceDoc {
        width: s.geometry.width as u64,
        height: s.geometry.height as u64,
        z_range_m: [lo, hi],
        outlier_cells: report.smooth.outlier.iter().filter(|&&o| o).count() as u64,
        filled_cells: report.filled_cells as u64,
    }
}

/// The surface's domain (cell centres) as a region polygon.
fn domain_polygon(s: &TerrainSurface) -> Vec<[f64; 2]> {
    let (lo, hi) = s.domain();
    vec![[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]]
}

fn plan_flight(job: Job<'_>) -> Result<TerrainPlanned, EngineError> {
    let req = job.req;
    let drone = DroneParams {
        tool_width_m: req.tool_width_m,
        altitude_offset_m: req.altitude_offset_m,
        station_spacing_m: 0.0,
        lanes: LaneChoice::Auto,
        region_fill_m: req.region_fill_m,
    };
    let out = plan_drone(job.points, &job.terrain, &drone)?;
    let attribute = job.attribute(out.surface.geometry)?;
    let profile: DroneProfile = profile_drone(&out.plan, attribute.as_ref(), &req.limits, &req.vertical)?;
    let (max_climb_mps, max_descent_mps) = vertical_speeds(&out.plan.path, &profile.time_s);
    let m = &out.metrics;
    let waypoints: Vec<WaypointDoc> = out
        .plan
        .path
        .iter()
        .zip(&out.plan.on_lane)
        .zip(profile.speed_mps.iter().zip(&profile.time_s))
        .map(|((p, &lane), (&v, &t))| WaypointDoc {
            x: p[0],
            y: p[1],
            z: p[2],
            v,
            t,
            kind: if lane {
                WaypointKindDoc::Cover
            } else {
                WaypointKindDoc::Transit
            },
            region: lane.then_some(0),
        })
        .collect();
    // DESIGN §6 turns, in the horizontal.
    let flat: Vec<Point2> = waypoints.iter().map(|w| Point2::new(w.x, w.y)).collect();
    let turns = count_turns(&flat) as u64;
    let coverage_pct = 100.0 * m.surface_coverage;
    let plan = PlanDocument {
        plan_id: job.plan_id.to_owned(),
        version: 1,
        frame: "map".into(),
        waypoints,
        regions: vec![RegionDoc {
            id: 0,
            polygon: domain_polygon(&out.surface),
        }],
        metrics: PlanMetricsDoc {
            coverage_pct,
            overlap_pct: if m.covered_area_m2 > 0.0 {
                100.0 * m.overlap_area_m2 / m.covered_area_m2
            } else {
                0.0
            },
            length_m: m.path_length_m,
            turns,
            collisions: 0,
            duration_s: profile.duration_s(),
            compute_ms: 0.0,
            coverable_area_m2: Some(m.total_area_m2),
            ..PlanMetricsDoc::default()
        },
    };
    let curvature = CurvatureMap::new(&out.surface.heights, &out.surface.geometry)?;
    let doc = TerrainPlanDocument {
        plan,
        terrain: TerrainDoc {
            robot_kind: RobotKindDoc::Drone,
            source: job.source,
            grid_m: req.grid_m,
            altitude_offset_m: Some(req.altitude_offset_m),
            surface: surface_doc(&out.surface, &out.report),
            drone: Some(DroneMetricsDoc {
                surface_coverage_pct: coverage_pct,
                surface_area_m2: m.total_area_m2,
                altitude_error_m: quantiles(&m.altitude_error_m),
                max_path_slope_deg: m.max_path_slope_rad.to_degrees(),
                lane_spacing_m: quantiles(&m.lane_spacing_m),
                tool_width_m: req.tool_width_m,
                lanes: m.lanes as u64,
                max_climb_mps,
                max_descent_mps,
            }),
            ground: None,
        },
    };
    Ok(TerrainPlanned {
        doc,
        surface: out.surface,
        curvature,
        blocked: None,
    })
}

fn plan_ground(job: Job<'_>) -> Result<TerrainPlanned, EngineError> {
    let req = job.req;
    // Interpolated ground counts as drivable as far as the cloud's own sampling gaps reach, no farther.
    let out = ground_occupancy(job.points, &job.terrain, &req.ground, None)?;
    let g = out.occupancy.geometry;
    let robot = RobotShape {
        radius_m: req.robot_radius_m.unwrap_or(req.tool_width_m / 2.0),
        tool_width_m: req.tool_width_m,
    };
    let (lo, hi) = out.surface.domain();
    let (start, snap) = match req.start {
        Some(p) => (p, None),
        // The lower-left corner, moved into the largest traversable piece wherever that is.
        None => (Point2::new(lo[0], lo[1]), Some((hi[0] - lo[0]).hypot(hi[1] - lo[1]))),
    };
    let blocked: Vec<bool> = (0..g.len()).map(|i| !out.occupancy.is_free(i)).collect();
    let space = CoverageSpace::with_start_snap(out.occupancy, robot, start, snap)?;
    let params = PlanParams {
        seed: req.seed,
        limits: req.limits,
        ..PlanParams::default()
    };
    let speed = SpeedParams::new(req.limits, req.tool_width_m);
    let attribute = job.attribute(g)?;
    let (plan, profile) = plan_shaped(&space, &params, attribute.as_ref(), &speed, &mut NoMonitor)?;
    let mut doc = to_document(job.plan_id, (&space, &plan), &profile, attribute.is_some(), 0.0);
    let mut max_slope = 0.0f64;
    let trav: &Traversability = &out.traversability;
    crate::terrain_site::set_ground_height(&out.surface, &mut doc.waypoints);
    for w in &doc.waypoints {
        if let Some(c) = g.locate(Point2::new(w.x, w.y)) {
            max_slope = max_slope.max(trav.slope_rad[g.index(c)]);
        }
    }
    let blocked_pct = 100.0 * blocked.iter().filter(|&&b| b).count() as f64 / g.len().max(1) as f64;
    let curvature = CurvatureMap::new(&out.surface.heights, &out.surface.geometry)?;
    let doc = TerrainPlanDocument {
        plan: doc,
        terrain: TerrainDoc {
            robot_kind: RobotKindDoc::Ground,
            source: job.source,
            grid_m: req.grid_m,
            altitude_offset_m: None,
            surface: surface_doc(&out.surface, &out.report),
            drone: None,
            ground: Some(GroundDoc {
                max_slope_deg: req.ground.max_slope_rad.to_degrees(),
                max_step_m: req.ground.max_step_m,
                max_roughness_m: req.ground.max_roughness_m,
                blocked_pct,
                max_path_slope_deg: max_slope.to_degrees(),
            }),
        },
    };
    Ok(TerrainPlanned {
        doc,
        surface: out.surface,
        curvature,
        blocked: Some(blocked),
    })
}
