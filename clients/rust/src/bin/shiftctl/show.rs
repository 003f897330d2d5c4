//! Human output: aligned tables and the blocks `plan show`, `site show`, `mission show`, `coverage` and the
//! `--watch` followers print.

use std::fmt::Write as _;

use serde::Serialize;
use shift_client::proto::{MissionView, OccupancyGridDoc, PlanMetricsDoc, PlanStatusResponse, RobotView, SiteSummary};

/// Prints `value` as JSON on stdout.
pub fn json<T: Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

/// Columns padded to their widest cell; numbers (cells starting with a digit or '-') right-aligned.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let mut out = String::new();
    let line = |out: &mut String, cells: Vec<&str>| {
        let parts: Vec<String> = cells
            .iter()
            .zip(&widths)
            .map(|(c, &w)| {
                let numeric = c.starts_with(|ch: char| ch.is_ascii_digit() || ch == '-');
                if numeric {
                    format!("{c:>w$}")
                } else {
                    format!("{c:<w$}")
                }
            })
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(&mut out, header.to_vec());
    for row in rows {
        line(&mut out, row.iter().map(String::as_str).collect());
    }
    out
}

/// Label/value lines.
pub fn pairs(rows: &[(&str, String)]) -> String {
    let w = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    rows.iter().fold(String::new(), |mut out, (k, v)| {
        let _ = writeln!(out, "{k:<w$}  {v}");
        out
    })
}

/// A plan's figures of merit (DESIGN §6).
pub fn metrics(m: &PlanMetricsDoc) -> String {
    let mut rows = vec![
        ("coverage", format!("{:.1} %", m.coverage_pct)),
        ("overlap", format!("{:.1} %", m.overlap_pct)),
        ("length", format!("{:.1} m", m.length_m)),
        ("turns", m.turns.to_string()),
        ("collisions", m.collisions.to_string()),
        ("duration", format!("{:.1} s", m.duration_s)),
        ("compute", format!("{:.0} ms", m.compute_ms)),
    ];
    if let (Some(a), Some(b)) = (m.dwell_cv, m.dwell_cv_const_speed) {
        rows.push(("dwell CV", format!("{a:.3} (constant speed {b:.3})")));
    }
    pairs(&rows)
}

/// `plan show`.
pub fn plan(s: &PlanStatusResponse) -> String {
    let mut rows = vec![
        ("plan", s.plan_id.clone()),
        ("site", s.site.clone()),
        ("status", s.status.as_str().to_owned()),
        ("progress", format!("{:.0} %", s.progress * 100.0)),
        ("version", s.version.to_string()),
        ("regions", s.regions_ready.to_string()),
    ];
    if let Some(r) = &s.robot {
        rows.push(("robot", r.clone()));
    }
    if let Some(f) = s.driven_fraction {
        rows.push(("driven", format!("{:.0} %", f * 100.0)));
    }
    if s.corrections > 0 {
        rows.push(("corrections", s.corrections.to_string()));
    }
    if let Some(e) = &s.error {
        rows.push(("error", e.clone()));
    }
    for w in &s.warnings {
        rows.push(("warning", w.clone()));
    }
    let mut out = pairs(&rows);
    if let Some(m) = &s.metrics {
        out.push('\n');
        out.push_str(&metrics(m));
    }
    out
}

/// `mission show` (and what `mission assign|cancel` and `mission create --watch` answer): the mission's
/// figures, then one row per robot's plan.
pub fn mission(m: &MissionView) -> String {
    let pct = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1} %"));
    let mut rows = vec![
        ("mission", m.mission_id.clone()),
        ("site", m.site.clone()),
        ("status", m.status.as_str().to_owned()),
        ("progress", format!("{:.0} %", m.progress * 100.0)),
        ("planned", pct(m.coverage.planned_pct)),
        ("seams", pct(m.coverage.seam_pct)),
        ("measured", format!("{:.1} %", m.coverage.measured_pct)),
    ];
    if let Some(eta) = m.eta_s {
        rows.push(("eta", format!("{eta:.0} s")));
    }
    rows.push(("updated", ago_ms(m.updated_ms)));
    if let Some(e) = &m.error {
        rows.push(("error", e.clone()));
    }
    for w in &m.warnings {
        rows.push(("warning", w.clone()));
    }
    let plans: Vec<Vec<String>> = m
        .plans
        .iter()
        .map(|p| {
            vec![
                p.robot.clone(),
                p.plan_id.clone(),
                p.status.as_str().to_owned(),
                p.version.to_string(),
                p.area_m2.map_or("-".into(), |a| format!("{a:.1}")),
                p.planned_duration_s.map_or("-".into(), |t| format!("{t:.0}")),
                format!("{:.0}%", p.driven_fraction * 100.0),
            ]
        })
        .collect();
    let mut out = pairs(&rows);
    out.push('\n');
    out.push_str(&table(
        &["ROBOT", "PLAN", "STATUS", "VERSION", "AREA_M2", "TIME_S", "DRIVEN"],
        &plans,
    ));
    out
}

/// `coverage SITE`: the raster's size and what share of the free cells was swept.
pub fn coverage(site: &str, g: &OccupancyGridDoc) -> String {
    let swept = g.cells.iter().filter(|&&c| c == 100).count();
    let unswept = g.cells.iter().filter(|&&c| c == 0).count();
    let share = if swept + unswept == 0 {
        0.0
    } else {
        100.0 * swept as f64 / (swept + unswept) as f64
    };
    let cell_m2 = g.resolution * g.resolution;
    pairs(&[
        ("site", site.to_owned()),
        (
            "size",
            format!(
                "{} × {} cells ({:.1} m × {:.1} m)",
                g.width,
                g.height,
                g.width as f64 * g.resolution,
                g.height as f64 * g.resolution
            ),
        ),
        ("swept", format!("{swept} cells ({:.1} m²)", swept as f64 * cell_m2)),
        (
            "not swept",
            format!("{unswept} free cells ({:.1} m²)", unswept as f64 * cell_m2),
        ),
        ("swept share", format!("{share:.1} %")),
    ])
}

/// `site show`.
pub fn site(s: &SiteSummary) -> String {
    let mut rows = vec![
        ("site", s.site.clone()),
        (
            "size",
            format!(
                "{} × {} cells ({:.1} m × {:.1} m)",
                s.width,
                s.height,
                s.width as f64 * s.resolution,
                s.height as f64 * s.resolution
            ),
        ),
        ("resolution", format!("{} m", s.resolution)),
        ("origin", format!("{}, {}", s.origin[0], s.origin[1])),
        ("free cells", s.free_cells.to_string()),
        ("live points", s.points_in_tree.to_string()),
        ("updates/s", format!("{:.1}", s.updates_per_s)),
        ("dropped clouds", s.dropped_clouds.to_string()),
        ("updated", ago_ms(s.updated_ms)),
    ];
    for w in &s.warnings {
        rows.push(("warning", w.clone()));
    }
    pairs(&rows)
}

/// `sites`.
pub fn sites(items: &[SiteSummary]) -> String {
    let rows: Vec<Vec<String>> = items
        .iter()
        .map(|s| {
            vec![
                s.site.clone(),
                format!("{}x{}", s.width, s.height),
                format!("{}", s.resolution),
                s.free_cells.to_string(),
                s.points_in_tree.to_string(),
                ago_ms(s.updated_ms),
            ]
        })
        .collect();
    table(&["SITE", "CELLS", "RES_M", "FREE", "LIVE_POINTS", "UPDATED"], &rows)
}

/// `plans`.
pub fn plans(items: &[PlanStatusResponse]) -> String {
    let rows: Vec<Vec<String>> = items
        .iter()
        .map(|p| {
            let m = p.metrics.as_ref();
            vec![
                p.plan_id.clone(),
                p.site.clone(),
                p.status.as_str().to_owned(),
                format!("{:.0}%", p.progress * 100.0),
                p.robot.clone().unwrap_or_else(|| "-".into()),
                m.map_or("-".into(), |m| format!("{:.1}", m.coverage_pct)),
                m.map_or("-".into(), |m| format!("{:.1}", m.length_m)),
                m.map_or("-".into(), |m| format!("{:.0}", m.duration_s)),
                ago_ms(p.created_ms),
            ]
        })
        .collect();
    table(
        &[
            "PLAN", "SITE", "STATUS", "PROGRESS", "ROBOT", "COVER_%", "LENGTH_M", "TIME_S", "CREATED",
        ],
        &rows,
    )
}

/// `robots`.
pub fn robots(items: &[RobotView]) -> String {
    let rows: Vec<Vec<String>> = items
        .iter()
        .map(|r| {
            vec![
                r.robot.clone(),
                if r.alive { "alive" } else { "lost" }.to_owned(),
                r.pose
                    .map_or("-".into(), |p| format!("{:.2},{:.2},{:.2}", p.x, p.y, p.yaw)),
                r.plan_id.clone().unwrap_or_else(|| "-".into()),
                r.driven_fraction.map_or("-".into(), |f| format!("{:.0}%", f * 100.0)),
                r.site.clone().unwrap_or_else(|| "-".into()),
                r.last_correction
                    .as_ref()
                    .map_or("-".into(), |c| format!("v{} {}", c.version, c.reason.as_str())),
                ago_ms(r.last_seen_ms),
            ]
        })
        .collect();
    table(
        &[
            "ROBOT",
            "STATE",
            "POSE_X,Y,YAW",
            "PLAN",
            "DRIVEN",
            "SITE",
            "LAST_CORRECTION",
            "SEEN",
        ],
        &rows,
    )
}

/// How long ago a Unix-epoch millisecond time was, roughly.
pub fn ago_ms(ms: u64) -> String {
    if ms == 0 {
        return "never".into();
    }
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    let s = now.saturating_sub(ms) / 1000;
    match s {
        0..60 => format!("{s}s ago"),
        60..3600 => format!("{}m ago", s / 60),
        3600..86_400 => format!("{}h ago", s / 3600),
        _ => format!("{}d ago", s / 86_400),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_align() {
        let t = table(
            &["A", "NUM"],
            &[vec!["long-name".into(), "7".into()], vec!["x".into(), "123".into()]],
        );
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[0], "A          NUM");
        assert_eq!(lines[1], "long-name    7");
        assert_eq!(lines[2], "x          123");
    }
}
