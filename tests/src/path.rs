//! Geometry of plan documents for end-to-end tests: straight stretches, points along them, clearance to
//! obstacle points, and the checks every correction must pass.

use anyhow::{Result, anyhow};
use shift_proto::{CorrectionDoc, PlanDocument, WaypointDoc};

/// A cluster of obstacle points: a 0.2 m post centred at `(x, y)`, 0.1–0.5 m high (5 × 5 × 3 points).
pub fn post(x: f64, y: f64) -> Vec<[f32; 3]> {
    let mut pts = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..3 {
                pts.push([
                    (x - 0.1 + 0.05 * f64::from(i)) as f32,
                    (y - 0.1 + 0.05 * f64::from(j)) as f32,
                    0.1 + 0.2 * k as f32,
                ]);
            }
        }
    }
    pts
}

/// Index of the first waypoint at or beyond `s` metres along the path.
pub fn index_at(w: &[WaypointDoc], s: f64) -> usize {
    let mut acc = 0.0;
    for i in 1..w.len() {
        acc += (w[i].x - w[i - 1].x).hypot(w[i].y - w[i - 1].y);
        if acc >= s {
            return i;
        }
    }
    w.len().saturating_sub(1)
}

/// The path's length, metres.
pub fn length(w: &[WaypointDoc]) -> f64 {
    w.windows(2).map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y)).sum()
}

/// The longest straight stretch of the plan, as waypoint indices `(i, j)`: every waypoint between lies on
/// the line from `i` to `j` (the document samples lanes densely for its speed profile).
pub fn longest_straight(w: &[WaypointDoc]) -> (usize, usize) {
    let mut best = (0, 1);
    let mut i = 0;
    while i + 1 < w.len() {
        let mut j = i + 1;
        while j + 1 < w.len()
            && (i + 1..=j).all(|k| seg_dist((w[k].x, w[k].y), (w[i].x, w[i].y), (w[j + 1].x, w[j + 1].y)) < 1e-6)
        {
            j += 1;
        }
        if dist(w, i, j) > dist(w, best.0, best.1) {
            best = (i, j);
        }
        i = j;
    }
    best
}

/// Straight distance between waypoints `i` and `j`, metres.
pub fn dist(w: &[WaypointDoc], i: usize, j: usize) -> f64 {
    (w[j].x - w[i].x).hypot(w[j].y - w[i].y)
}

/// The point `s` metres from waypoint `i` towards waypoint `j`, and the heading.
pub fn along(w: &[WaypointDoc], (i, j): (usize, usize), s: f64) -> (f64, f64, f64) {
    let (a, b) = (&w[i], &w[j]);
    let l = dist(w, i, j);
    let (ux, uy) = ((b.x - a.x) / l, (b.y - a.y) / l);
    (a.x + ux * s, a.y + uy * s, uy.atan2(ux))
}

/// Distance from p to segment ab.
pub fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

/// Smallest distance between the path's segments in `range` (waypoint indices, inclusive ends) and the points.
pub fn clearance(w: &[WaypointDoc], range: std::ops::Range<usize>, pts: &[[f32; 3]]) -> f64 {
    let mut best = f64::INFINITY;
    for i in range.start..range.end.min(w.len() - 1) {
        for p in pts {
            let d = seg_dist(
                (f64::from(p[0]), f64::from(p[1])),
                (w[i].x, w[i].y),
                (w[i + 1].x, w[i + 1].y),
            );
            best = best.min(d);
        }
    }
    best
}

/// Checks a correction against the document it patches: it applies, the stretches before `from` and from
/// `to` on are the old ones, and the patch with its two joins keeps ≥ radius from every obstacle point (with
/// `whole`, the entire new path does). Returns the corrected document.
pub fn check_correction(
    old: &PlanDocument,
    c: &CorrectionDoc,
    obstacle: &[[f32; 3]],
    whole: bool,
    radius: f64,
) -> Result<PlanDocument> {
    let new = c.apply(old).map_err(|e| anyhow!("{e}"))?;
    assert_eq!(new.version, old.version + 1);
    assert_eq!(
        &new.waypoints[..c.from],
        &old.waypoints[..c.from],
        "kept before the patch"
    );
    let tail = new.waypoints.len() - (old.waypoints.len() - c.to);
    for (a, b) in new.waypoints[tail..].iter().zip(&old.waypoints[c.to..]) {
        assert_eq!((a.x, a.y), (b.x, b.y), "kept after the patch");
    }
    let range = if whole {
        0..new.waypoints.len()
    } else {
        c.from.saturating_sub(1)..(c.from + c.waypoints.len() + 1)
    };
    let d = clearance(&new.waypoints, range, obstacle);
    assert!(
        d >= radius - 1e-6,
        "corrected path comes {d:.3} m from an obstacle point (radius {radius})"
    );
    for w in &c.waypoints {
        assert!(
            w.v.is_finite() && w.v > 0.0 && w.t.is_finite(),
            "re-profiled speeds and times: {w:?}"
        );
    }
    Ok(new)
}

/// The first straight stretch at least `min_m` long that starts at or after waypoint `from`: `(i, j)`.
pub fn straight_from(w: &[WaypointDoc], from: usize, min_m: f64) -> Option<(usize, usize)> {
    let mut i = from;
    while i + 1 < w.len() {
        let mut j = i + 1;
        while j + 1 < w.len()
            && (i + 1..=j).all(|k| seg_dist((w[k].x, w[k].y), (w[i].x, w[i].y), (w[j + 1].x, w[j + 1].y)) < 1e-6)
        {
            j += 1;
        }
        if (w[j].x - w[i].x).hypot(w[j].y - w[i].y) >= min_m {
            return Some((i, j));
        }
        i = j;
    }
    None
}
