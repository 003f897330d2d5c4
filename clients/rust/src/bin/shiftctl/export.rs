//! `export PLAN --format geojson|csv|nav-path`: the plan's current path in formats other tools read.
//!
//! Coordinates are the plan's (metres, map frame — not WGS84, so GeoJSON readers show them on a plain plane).
//! Numbers are written in Rust's shortest round-trip form: reading them back gives the plan's exact values.

use std::io::Write as _;

use serde_json::{Value, json};
use shift_client::Client;
use shift_client::proto::ros::geometry::Quaternion;
use shift_client::proto::ros::path::plan_poses;
use shift_client::proto::{PlanDocument, WaypointKindDoc};

use crate::cli::{Crs, ExportArgs, Format};
use crate::input::bad;

/// Runs the command.
pub async fn run(client: &Client, args: ExportArgs) -> anyhow::Result<()> {
    if args.crs == Crs::Wgs84 {
        if args.format != Format::Geojson {
            return Err(bad("--crs wgs84 goes with --format geojson"));
        }
        let feature = client.path_geojson(&args.plan).await?;
        return write(&args, &serde_json::to_string_pretty(&feature)?);
    }
    let doc = client.path(&args.plan).await?;
    let text = match args.format {
        Format::Geojson => serde_json::to_string_pretty(&geojson(&doc))?,
        Format::Csv => csv(&doc),
        Format::NavPath => serde_json::to_string_pretty(&nav_path(&doc))?,
    };
    write(&args, &text)
}

/// The text to `--out` or stdout.
fn write(args: &ExportArgs, text: &str) -> anyhow::Result<()> {
    match &args.out {
        Some(path) => std::fs::write(path, text.as_bytes()).map_err(|e| bad(format!("--out {}: {e}", path.display()))),
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())?;
            if !text.ends_with('\n') {
                out.write_all(b"\n")?;
            }
            Ok(())
        }
    }
}

fn kind(k: WaypointKindDoc) -> &'static str {
    match k {
        WaypointKindDoc::Cover => "cover",
        WaypointKindDoc::Transit => "transit",
    }
}

/// A FeatureCollection: feature 0 is the path (LineString of [x, y, z]) with the per-point arrays `v` (m/s),
/// `t` (s) and `kind` aligned with its coordinates; then one Polygon per region (`region`: its id).
pub fn geojson(doc: &PlanDocument) -> Value {
    let w = &doc.waypoints;
    let path = json!({
        "type": "Feature",
        "geometry": {"type": "LineString", "coordinates": w.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>()},
        "properties": {
            "plan_id": doc.plan_id, "version": doc.version, "frame": doc.frame,
            "v": w.iter().map(|p| p.v).collect::<Vec<_>>(),
            "t": w.iter().map(|p| p.t).collect::<Vec<_>>(),
            "kind": w.iter().map(|p| kind(p.kind)).collect::<Vec<_>>(),
            "region": w.iter().map(|p| p.region).collect::<Vec<_>>(),
        },
    });
    let regions = doc.regions.iter().map(|r| {
        // GeoJSON rings are closed.
        let mut ring = r.polygon.clone();
        if let (Some(first), Some(last)) = (ring.first().copied(), ring.last().copied())
            && first != last
        {
            ring.push(first);
        }
        json!({
            "type": "Feature",
            "geometry": {"type": "Polygon", "coordinates": [ring]},
            "properties": {"region": r.id},
        })
    });
    let features: Vec<Value> = std::iter::once(path).chain(regions).collect();
    json!({"type": "FeatureCollection", "features": features})
}

/// `x,y,v,t,kind`, one row per waypoint.
pub fn csv(doc: &PlanDocument) -> String {
    let mut out = String::from("x,y,v,t,kind\n");
    for p in &doc.waypoints {
        out.push_str(&format!("{},{},{},{},{}\n", p.x, p.y, p.v, p.t, kind(p.kind)));
    }
    out
}

/// nav_msgs/Path as JSON, field for field as ROS 2 names them: the poses the daemon publishes on
/// `…/plan_path` (yaw along the path), stamped 0 in the plan's frame.
pub fn nav_path(doc: &PlanDocument) -> Value {
    let header = json!({"stamp": {"sec": 0, "nanosec": 0}, "frame_id": doc.frame});
    let poses: Vec<Value> = plan_poses(doc)
        .into_iter()
        .zip(&doc.waypoints)
        .map(|((x, y, yaw), w)| {
            let q = Quaternion::from_yaw(yaw);
            json!({
                "header": header,
                "pose": {
                    "position": {"x": x, "y": y, "z": w.z},
                    "orientation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w},
                },
            })
        })
        .collect();
    json!({"header": header, "poses": poses})
}
