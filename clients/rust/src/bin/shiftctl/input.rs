//! Reading what the user typed: points, polygons, statuses, robots, planner choices; and the error that means
//! "bad input" (exit 2).

use std::path::Path;

use shift_client::proto::{AttributeDoc, MissionRobot, PlanObjective, PlanOptions, PlanStatus};

use crate::cli::PlannerArgs;

/// The user's input is wrong (exit code 2).
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// A bad-input error.
pub fn bad(message: impl Into<String>) -> anyhow::Error {
    BadInput(message.into()).into()
}

/// `X,Y` → a finite point.
pub fn point(what: &str, text: &str) -> anyhow::Result<[f64; 2]> {
    let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    match text.split_once(',') {
        Some((x, y)) => match (parse(x), parse(y)) {
            (Some(x), Some(y)) => Ok([x, y]),
            _ => Err(bad(format!("{what}: {text:?} is not two finite numbers X,Y"))),
        },
        None => Err(bad(format!("{what}: {text:?} is not X,Y"))),
    }
}

/// `X,Y X,Y X,Y …` (spaces or semicolons between points) → at least three points.
pub fn polygon(what: &str, text: &str) -> anyhow::Result<Vec<[f64; 2]>> {
    let pts = text
        .split(|c: char| c.is_whitespace() || c == ';')
        .filter(|s| !s.is_empty())
        .map(|p| point(what, p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    if pts.len() < 3 {
        return Err(bad(format!(
            "{what}: a polygon needs at least 3 points, got {}",
            pts.len()
        )));
    }
    Ok(pts)
}

/// A plan status by its wire name.
pub fn status(text: &str) -> anyhow::Result<PlanStatus> {
    PlanStatus::ALL.into_iter().find(|s| s.as_str() == text).ok_or_else(|| {
        let names: Vec<&str> = PlanStatus::ALL.iter().map(|s| s.as_str()).collect();
        bad(format!("--status: {text:?} is not one of {}", names.join(", ")))
    })
}

/// A finite number above zero.
pub fn positive(what: &str, v: f64) -> anyhow::Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(bad(format!("{what}: {v} is not a positive number")))
    }
}

/// `ID:X,Y:RADIUS:TOOL_WIDTH` → a mission robot with the API's default speed limits.
pub fn robot(what: &str, text: &str) -> anyhow::Result<MissionRobot> {
    let parts: Vec<&str> = text.split(':').collect();
    let [id, start, radius, tool_width] = parts[..] else {
        return Err(bad(format!("{what}: {text:?} is not ID:X,Y:RADIUS:TOOL_WIDTH")));
    };
    let id = id.trim();
    if id.is_empty() {
        return Err(bad(format!("{what}: {text:?} has no robot id")));
    }
    let number = |name: &str, s: &str| {
        let v = s
            .trim()
            .parse::<f64>()
            .map_err(|_| bad(format!("{what} {id}: {name} {s:?} is not a number")))?;
        positive(&format!("{what} {id}: {name}"), v)
    };
    Ok(MissionRobot::new(
        id,
        point(&format!("{what} {id}"), start)?,
        number("radius", radius)?,
        number("tool width", tool_width)?,
    ))
}

/// The attribute map in a JSON file.
pub fn attribute(path: &Path) -> anyhow::Result<AttributeDoc> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("--attribute {}: {e}", path.display())))?;
    serde_json::from_str::<AttributeDoc>(&text).map_err(|e| bad(format!("--attribute {}: {e}", path.display())))
}

/// The attribute map, planner options (none when all are left to the daemon) and objective asked for.
pub fn planner(
    args: &PlannerArgs,
) -> anyhow::Result<(Option<AttributeDoc>, Option<PlanOptions>, Option<PlanObjective>)> {
    let attribute = args.attribute.as_deref().map(attribute).transpose()?;
    let options = PlanOptions {
        decomposition: args.decomposition.clone(),
        order: args.order.clone(),
        pattern: args.pattern.clone(),
        seed: args.seed,
    };
    let objective = match &args.objective {
        None => None,
        Some(name) => Some(
            serde_json::from_value::<PlanObjective>(serde_json::Value::String(name.clone())).map_err(|_| {
                bad(format!(
                    "--objective {name}: expected one of time, length, overlap, turns"
                ))
            })?,
        ),
    };
    Ok((
        attribute,
        (options != PlanOptions::default()).then_some(options),
        objective,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_polygons_statuses() {
        assert_eq!(point("--start", "0.5,-1").ok(), Some([0.5, -1.0]));
        assert!(point("--start", "0.5").is_err());
        assert!(point("--start", "a,b").is_err());
        assert!(point("--start", "nan,1").is_err());
        assert_eq!(polygon("--region", "0,0 4,0;4,4").map(|p| p.len()).ok(), Some(3));
        assert!(polygon("--region", "0,0 4,0").is_err());
        assert!(status("ready").is_ok());
        assert!(status("busy").is_err());
    }

    #[test]
    fn robots() {
        let r = robot("--robot", "r1:-1.5,2:0.25:0.5").expect("parses");
        assert_eq!(r, MissionRobot::new("r1", [-1.5, 2.0], 0.25, 0.5));
        for text in [
            "r1:1,2:0.25",
            "r1:1,2:0.25:0.5:9",
            ":1,2:0.25:0.5",
            "r1:1:0.25:0.5",
            "r1:1,2:-1:0.5",
            "r1:1,2:0.2:w",
        ] {
            assert!(robot("--robot", text).is_err(), "{text}");
        }
    }
}
