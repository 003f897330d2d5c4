//! Reading what the user typed: points, polygons, statuses; and the error that means "bad input" (exit 2).

use shift_client::proto::PlanStatus;

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
}
