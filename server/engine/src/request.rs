//! Checking a plan request against its site before it is accepted: every number finite and in range, the
//! start on the map, options that name real strategies. A request that passes here can still fail in the job
//! (an unreachable start, say), but never for a reason a client could have been told at once.

use shift_planner::decompose::DecompositionMethod;
use shift_planner::footprint::Footprint;
use shift_planner::geom::Point2;
pub use shift_planner::geom::point_in_polygon;
use shift_planner::map::grid::OccupancyGrid;
use shift_planner::order::OrderMethod;
use shift_planner::pattern::PatternMethod;
use shift_proto::{AttributeDoc, PlanRequest};

use crate::error::{EngineError, Result};

/// The planner's choices parsed from [`shift_proto::PlanOptions`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParsedOptions {
    /// Decomposition strategy.
    pub decomposition: DecompositionMethod,
    /// Visiting-order solver.
    pub order: OrderMethod,
    /// In-region pattern.
    pub pattern: PatternMethod,
    /// Seed.
    pub seed: u64,
}

fn invalid(msg: String) -> EngineError {
    EngineError::InvalidRequest(msg)
}

fn finite(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(format!("{name} must be a finite number, got {v}")))
    }
}

fn positive(name: &str, v: f64) -> Result<f64> {
    if finite(name, v)? > 0.0 {
        Ok(v)
    } else {
        Err(invalid(format!("{name} must be positive, got {v}")))
    }
}

/// Parses the options, defaulting each absent field to the best combination.
pub fn parse_options(req: &PlanRequest) -> Result<ParsedOptions> {
    let o = req.options.clone().unwrap_or_default();
    let decomposition = match o.decomposition.as_deref() {
        None => DecompositionMethod::Auto,
        Some(s) => s
            .parse()
            .map_err(|e: String| invalid(format!("options.decomposition: {e}")))?,
    };
    let order = match o.order.as_deref() {
        None => OrderMethod::default(),
        Some(s) => s.parse().map_err(|e: String| invalid(format!("options.order: {e}")))?,
    };
    let pattern = match o.pattern.as_deref() {
        None => PatternMethod::Lanes,
        Some(s) => s
            .parse()
            .map_err(|e: String| invalid(format!("options.pattern: {e}")))?,
    };
    Ok(ParsedOptions {
        decomposition,
        order,
        pattern,
        seed: o.seed.unwrap_or(1),
    })
}

/// Validates a request against the site's grid.
pub fn validate(req: &PlanRequest, grid: &OccupancyGrid) -> Result<ParsedOptions> {
    crate::site::validate_name("site", &req.site)?;
    let r = &req.robot;
    // A disc (`radius`) or a polygon (`footprint`), exactly one; the polygon is validated by the planner.
    match &r.footprint {
        None => {
            positive("robot.radius", r.radius)?;
        }
        Some(_) if r.radius != 0.0 => {
            return Err(invalid(format!(
                "robot.radius ({}) and robot.footprint are alternatives: give one of them",
                r.radius
            )));
        }
        Some(vertices) => {
            Footprint::new(vertices).map_err(|e| invalid(e.to_string()))?;
        }
    }
    positive("robot.tool_width", r.tool_width)?;
    // Lanes are a tool width apart: a tool much narrower than a cell asks for more lanes than the map has
    // cells across (a 1e-9 m tool on a 10 m room is 10^10 lanes).
    let cell = grid.geometry.resolution;
    if r.tool_width < cell / 2.0 {
        return Err(invalid(format!(
            "robot.tool_width must be at least half a map cell ({} m on this site), got {}",
            cell / 2.0,
            r.tool_width
        )));
    }
    positive("robot.v_min", r.v_min)?;
    positive("robot.v_max", r.v_max)?;
    positive("robot.a_max", r.a_max)?;
    if r.v_min > r.v_max {
        return Err(invalid(format!(
            "robot.v_min {} exceeds robot.v_max {}",
            r.v_min, r.v_max
        )));
    }
    let start = Point2::new(finite("start[0]", req.start[0])?, finite("start[1]", req.start[1])?);
    let g = &grid.geometry;
    if g.locate(start).is_none() {
        let (x1, y1) = (
            g.origin.x + g.width as f64 * g.resolution,
            g.origin.y + g.height as f64 * g.resolution,
        );
        return Err(invalid(format!(
            "start ({}, {}) is outside the map [{}, {}] × [{}, {}]",
            start.x, start.y, g.origin.x, x1, g.origin.y, y1
        )));
    }
    if let Some(d) = req.snap_start_m
        && finite("snap_start_m", d)? < 0.0
    {
        return Err(invalid(format!("snap_start_m must be zero or more metres, got {d}")));
    }
    if let Some(a) = &req.attribute {
        if a.blobs.len() > AttributeDoc::MAX_BLOBS {
            return Err(invalid(format!(
                "attribute.blobs holds {} blobs; at most {} are accepted",
                a.blobs.len(),
                AttributeDoc::MAX_BLOBS
            )));
        }
        for (i, b) in a.blobs.iter().enumerate() {
            finite(&format!("attribute.blobs[{i}].x"), b.x)?;
            finite(&format!("attribute.blobs[{i}].y"), b.y)?;
            positive(&format!("attribute.blobs[{i}].sigma"), b.sigma)?;
            let amp = finite(&format!("attribute.blobs[{i}].amplitude"), b.amplitude)?;
            if !(0.0..=1.0).contains(&amp) {
                return Err(invalid(format!(
                    "attribute.blobs[{i}].amplitude must be in [0, 1], got {amp}"
                )));
            }
        }
    }
    if let Some(poly) = &req.region {
        if poly.len() < 3 {
            return Err(invalid(format!("region needs at least 3 vertices, got {}", poly.len())));
        }
        if poly.len() > PlanRequest::MAX_REGION_VERTICES {
            return Err(invalid(format!(
                "region has {} vertices; at most {} are accepted",
                poly.len(),
                PlanRequest::MAX_REGION_VERTICES
            )));
        }
        for (i, p) in poly.iter().enumerate() {
            finite(&format!("region[{i}][0]"), p[0])?;
            finite(&format!("region[{i}][1]"), p[1])?;
        }
        if !point_in_polygon(start, poly) {
            return Err(invalid(format!(
                "start ({}, {}) must lie inside the region polygon (the plan stays inside it)",
                start.x, start.y
            )));
        }
    }
    parse_options(req)
}

#[cfg(test)]
mod tests {
    use shift_planner::map::grid::{CellState, GridGeometry};
    use shift_proto::{PlanObjective, PlanOptions, RobotSpec};

    use super::*;

    fn grid() -> OccupancyGrid {
        let g = GridGeometry::new(40, 40, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        OccupancyGrid::filled(g, CellState::Free)
    }

    fn request() -> PlanRequest {
        PlanRequest {
            site: "s".into(),
            start: [1.0, 1.0],
            robot: RobotSpec {
                radius: 0.15,
                footprint: None,
                tool_width: 0.3,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: None,
            options: None,
            objective: None,
            snap_start_m: None,
        }
    }

    #[test]
    fn good_request_gets_defaults() {
        let o = validate(&request(), &grid()).expect("valid");
        assert_eq!(o.decomposition, DecompositionMethod::Auto);
        assert_eq!(o.seed, 1);
    }

    #[test]
    fn bad_numbers_and_names_are_refused() {
        let g = grid();
        let mut r = request();
        r.robot.radius = f64::NAN;
        assert!(validate(&r, &g).is_err());
        let mut r = request();
        r.robot.radius = -0.1;
        assert!(validate(&r, &g).is_err());
        let mut r = request();
        r.start = [10.0, 1.0];
        let e = validate(&r, &g).expect_err("outside");
        assert!(e.to_string().contains("outside the map"), "{e}");
        let mut r = request();
        r.robot.v_min = 2.0;
        assert!(validate(&r, &g).is_err());
        let mut r = request();
        r.options = Some(PlanOptions {
            decomposition: Some("magic".into()),
            ..PlanOptions::default()
        });
        assert!(validate(&r, &g).is_err());
        let mut r = request();
        r.region = Some(vec![[2.0, 2.0], [3.0, 2.0], [3.0, 3.0]]);
        assert!(validate(&r, &g).is_err(), "start outside the region");
        let mut r = request();
        r.robot.tool_width = 1e-9;
        let e = validate(&r, &g).expect_err("a tool narrower than half a cell");
        assert!(e.to_string().contains("robot.tool_width"), "{e}");
        let mut r = request();
        r.site = "a/b".into();
        let e = validate(&r, &g).expect_err("site name");
        assert!(e.to_string().contains("invalid site"), "{e}");
        let mut r = request();
        r.region = Some(vec![[1.0, 1.0]; PlanRequest::MAX_REGION_VERTICES + 1]);
        let e = validate(&r, &g).expect_err("too many vertices");
        assert!(e.to_string().contains("region has"), "{e}");
        let mut r = request();
        let blob = shift_proto::AttributeBlobDoc {
            x: 1.0,
            y: 1.0,
            sigma: 1.0,
            amplitude: 0.5,
        };
        r.attribute = Some(AttributeDoc {
            blobs: vec![blob; AttributeDoc::MAX_BLOBS + 1],
        });
        let e = validate(&r, &g).expect_err("too many blobs");
        assert!(e.to_string().contains("attribute.blobs"), "{e}");
        for d in [f64::NAN, -1.0, f64::INFINITY] {
            let mut r = request();
            r.snap_start_m = Some(d);
            let e = validate(&r, &g).expect_err("bad snap");
            assert!(e.to_string().contains("snap_start_m"), "{e}");
        }
    }

    #[test]
    fn a_robot_is_a_radius_or_a_footprint() {
        let g = grid();
        let rect = vec![[0.3, 0.2], [-0.3, 0.2], [-0.3, -0.2], [0.3, -0.2]];
        let mut r = request();
        r.robot.radius = 0.0;
        r.robot.footprint = Some(rect.clone());
        validate(&r, &g).expect("a footprint alone");
        r.robot.radius = 0.15;
        let e = validate(&r, &g).expect_err("both");
        assert!(e.to_string().contains("robot.radius"), "{e}");
        let mut r = request();
        r.robot.radius = 0.0;
        let e = validate(&r, &g).expect_err("neither");
        assert!(e.to_string().contains("robot.radius"), "{e}");
        for bad in [
            vec![[0.3, 0.2], [-0.3, 0.2]],
            vec![[1.0, 1.0], [2.0, 1.0], [2.0, 2.0]],
            vec![[0.3, 0.2], [-0.3, 0.2], [f64::NAN, -0.2]],
        ] {
            let mut r = request();
            r.robot.radius = 0.0;
            r.robot.footprint = Some(bad);
            let e = validate(&r, &g).expect_err("a bad polygon");
            assert!(e.to_string().contains("robot.footprint"), "{e}");
        }
    }

    #[test]
    fn the_objective_is_a_known_name() {
        let body = |o: &str| {
            format!(
                r#"{{"site": "s", "start": [1, 1], "robot": {{"radius": 0.15, "tool_width": 0.3}}, "objective": "{o}"}}"#
            )
        };
        for (name, want) in [("time", PlanObjective::Time), ("turns", PlanObjective::Turns)] {
            let r: PlanRequest = serde_json::from_str(&body(name)).expect("parses");
            assert_eq!(r.objective, Some(want));
        }
        let e = serde_json::from_str::<PlanRequest>(&body("fast")).expect_err("unknown objective");
        assert!(e.to_string().contains("unknown variant"), "{e}");
    }

    #[test]
    fn polygon_test_matches_a_square() {
        let sq = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        assert!(point_in_polygon(Point2::new(1.0, 1.0), &sq));
        assert!(!point_in_polygon(Point2::new(3.0, 1.0), &sq));
        assert!(!point_in_polygon(Point2::new(-0.1, 1.9), &sq));
    }
}
