//! JSON Schemas (MCAP schema encoding `jsonschema`) of the JSON channels SHIFT records. They describe the
//! top level of each message; nested wire types are documented in `shift-proto` and DESIGN §5.

/// `shift.EngineInput`: one event the engine handled (`shift_engine::recorded::RecordedInput`).
pub const ENGINE_INPUT: &str = r#"{
  "title": "shift.EngineInput",
  "description": "An event the engine handled, with the time it was handled at (milliseconds since the Unix epoch).",
  "type": "object",
  "properties": {
    "run": {"type": "integer", "description": "daemon run (its start, ms since the Unix epoch)"},
    "seq": {"type": "integer", "description": "handling order within the run, from 1"},
    "now_ms": {"type": "integer", "description": "engine clock, ms since the Unix epoch"},
    "event": {"type": "object", "description": "the event; its `type` names the variant", "properties": {"type": {"type": "string"}}}
  },
  "required": ["run", "seq", "now_ms", "event"]
}"#;

/// `shift.EngineDecisions`: what the engine decided for one input (`RecordedDecisions`).
pub const ENGINE_DECISIONS: &str = r#"{
  "title": "shift.EngineDecisions",
  "description": "The engine's commands for the input of the same run and seq, summarised.",
  "type": "object",
  "properties": {
    "run": {"type": "integer"},
    "seq": {"type": "integer"},
    "now_ms": {"type": "integer"},
    "decisions": {"type": "array", "items": {"type": "object", "properties": {"type": {"type": "string"}}}}
  },
  "required": ["run", "seq", "now_ms", "decisions"]
}"#;

/// `shift.EngineConfig`: the engine's sizes, at the start of every file.
pub const ENGINE_CONFIG: &str = r#"{
  "title": "shift.EngineConfig",
  "type": "object",
  "properties": {
    "run": {"type": "integer"},
    "workers": {"type": "integer", "minimum": 1},
    "queue_capacity": {"type": "integer", "minimum": 0}
  },
  "required": ["run", "workers", "queue_capacity"]
}"#;

/// `shift.PlanDocument`: the plan JSON of DESIGN §5.1.
pub const PLAN_DOCUMENT: &str = r#"{
  "title": "shift.PlanDocument",
  "description": "A coverage plan: x, y, z in metres (frame), v in m/s, t in s from the plan's start.",
  "type": "object",
  "properties": {
    "plan_id": {"type": "string"},
    "version": {"type": "integer"},
    "frame": {"type": "string"},
    "waypoints": {"type": "array", "items": {"type": "object", "properties": {
      "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"},
      "v": {"type": "number"}, "t": {"type": "number"},
      "kind": {"type": "string", "enum": ["cover", "transit"]}, "region": {"type": "integer"}}}},
    "regions": {"type": "array", "items": {"type": "object", "properties": {
      "id": {"type": "integer"}, "polygon": {"type": "array", "items": {"type": "array", "items": {"type": "number"}}}}}},
    "metrics": {"type": "object"}
  },
  "required": ["plan_id", "version", "frame", "waypoints", "regions", "metrics"]
}"#;

/// `shift.PlanStatus`: `GET /v1/plans/{id}` (DESIGN §5.3).
pub const PLAN_STATUS: &str = r#"{
  "title": "shift.PlanStatus",
  "type": "object",
  "properties": {
    "plan_id": {"type": "string"},
    "site": {"type": "string"},
    "status": {"type": "string", "enum": ["queued", "planning", "ready", "active", "done", "failed", "cancelled"]},
    "progress": {"type": "number"},
    "version": {"type": "integer"},
    "regions_ready": {"type": "integer"},
    "metrics": {"type": "object"},
    "error": {"type": "string"},
    "warnings": {"type": "array", "items": {"type": "string"}},
    "robot": {"type": "string"},
    "driven_fraction": {"type": "number"},
    "created_ms": {"type": "integer"},
    "updated_ms": {"type": "integer"}
  },
  "required": ["plan_id", "site", "status", "progress", "version", "created_ms", "updated_ms"]
}"#;

/// `shift.Liveliness`: a robot's liveliness token appeared or went.
pub const LIVELINESS: &str = r#"{
  "title": "shift.Liveliness",
  "type": "object",
  "properties": {
    "key": {"type": "string", "description": "the token's key expression"},
    "alive": {"type": "boolean", "description": "true: declared, false: undeclared"}
  },
  "required": ["key", "alive"]
}"#;

/// `shift.OdomJson`: JSON odometry of DESIGN §5.4.
pub const ODOM_JSON: &str = r#"{
  "title": "shift.OdomJson",
  "description": "Planar odometry: x, y in metres and yaw in radians (map frame), velocities in m/s and rad/s, stamp in s.",
  "type": "object",
  "properties": {
    "x": {"type": "number"}, "y": {"type": "number"}, "yaw": {"type": "number"},
    "vx": {"type": "number"}, "vy": {"type": "number"}, "wz": {"type": "number"},
    "stamp": {"type": "number"}, "frame_id": {"type": "string"}
  },
  "required": ["x", "y", "yaw"]
}"#;

/// `foxglove.Grid` (Foxglove's well-known schema, so Foxglove draws the occupancy as a map).
pub const FOXGLOVE_GRID: &str = r#"{
  "title": "foxglove.Grid",
  "description": "A 2D grid of data",
  "type": "object",
  "properties": {
    "timestamp": {"type": "object", "title": "time", "properties": {
      "sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}},
    "frame_id": {"type": "string"},
    "pose": {"title": "foxglove.Pose", "type": "object", "properties": {
      "position": {"title": "foxglove.Vector3", "type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}},
      "orientation": {"title": "foxglove.Quaternion", "type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}}}},
    "column_count": {"type": "integer", "minimum": 0},
    "cell_size": {"title": "foxglove.Vector2", "type": "object", "properties": {
      "x": {"type": "number"}, "y": {"type": "number"}}},
    "row_stride": {"type": "integer", "minimum": 0},
    "cell_stride": {"type": "integer", "minimum": 0},
    "fields": {"type": "array", "items": {"title": "foxglove.PackedElementField", "type": "object", "properties": {
      "name": {"type": "string"},
      "offset": {"type": "integer", "minimum": 0},
      "type": {"title": "foxglove.NumericType", "oneOf": [
        {"title": "UNKNOWN", "const": 0}, {"title": "UINT8", "const": 1}, {"title": "INT8", "const": 2},
        {"title": "UINT16", "const": 3}, {"title": "INT16", "const": 4}, {"title": "UINT32", "const": 5},
        {"title": "INT32", "const": 6}, {"title": "FLOAT32", "const": 7}, {"title": "FLOAT64", "const": 8}]}}}},
    "data": {"type": "string", "contentEncoding": "base64"}
  }
}"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_schema_is_json_with_a_title() {
        for s in [
            ENGINE_INPUT,
            ENGINE_DECISIONS,
            ENGINE_CONFIG,
            PLAN_DOCUMENT,
            PLAN_STATUS,
            LIVELINESS,
            ODOM_JSON,
            FOXGLOVE_GRID,
        ] {
            let v: serde_json::Value = serde_json::from_str(s).expect("schema is JSON");
            assert!(v["title"].is_string(), "{s}");
            assert_eq!(v["type"], "object");
        }
    }
}
