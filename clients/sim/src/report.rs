//! The report other programs read (issue 19's fields, kept exactly; extra fields are additions) and the
//! per-robot ground-truth trace (`ROBOT.csv`: `t,x,y,yaw,v` every step of simulated time).

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::measure::Coverage;
use crate::robot::SimRobot;

/// One robot's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotReport {
    /// Robot id.
    pub id: String,
    /// Distance driven, metres.
    pub driven_m: f64,
    /// Simulated time it took to finish its plan (or the whole run when it did not), seconds.
    pub time_s: f64,
    /// Safety stops.
    pub stops: u64,
    /// Contacts with the static world.
    pub collisions: u64,
    /// Corrections applied.
    pub corrections_applied: u64,
    /// The plan version it ended on.
    pub final_version: Option<u64>,
    /// Its swept share of its coverable area, percent.
    pub covered_pct: f64,
    /// True when it reached the end of its plan.
    pub finished: bool,
    /// The plan it followed.
    pub plan_id: Option<String>,
    /// Contacts with movers.
    pub mover_contacts: u64,
    /// Touches of the static world within the tracking tolerance (not collisions).
    pub grazes: u64,
    /// Plan fetches on a version gap.
    pub gaps: u64,
    /// Waypoints given up after standing blocked too long.
    #[serde(default)]
    pub skipped_waypoints: u64,
}

/// The fleet's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FleetReport {
    /// Union of swept cells over union of coverable cells, percent.
    pub covered_pct: f64,
    /// The most the plans can cover when each robot keeps inside its region, percent of the same coverable
    /// cells (100 without regions; see [`crate::measure::Coverage::fleet_within_regions`]).
    #[serde(default = "hundred")]
    pub within_regions_pct: f64,
    /// Simulated time until the last robot finished (or the run ended), seconds.
    pub time_s: f64,
    /// Contacts with the static world, all robots.
    pub collisions: u64,
    /// Simulated seconds per wall-clock second achieved.
    pub speedup_achieved: f64,
}

fn hundred() -> f64 {
    100.0
}

/// The report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Per robot.
    pub robots: Vec<RobotReport>,
    /// The fleet.
    pub fleet: FleetReport,
    /// What the robots sent and how fast corrections answered what they saw.
    #[serde(default)]
    pub traffic: Traffic,
}

/// The robots' traffic, on the wall clock: messages sent, and correction latency as the robots lived it (see
/// [`crate::sight`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Traffic {
    /// Wall-clock seconds the robots drove.
    pub wall_s: f64,
    /// Odometry messages published, all robots.
    pub odom_sent: u64,
    /// Scans published, all robots.
    pub scans_sent: u64,
    /// First sight of something new across a path → the correction applied next, milliseconds.
    pub correction_latency_ms: Option<Quantiles>,
    /// Sights no correction followed in time.
    pub sights_unanswered: u64,
    /// Sights the daemon answered by holding the plan's end at a blockage (status `blocked`), milliseconds to
    /// that answer.
    #[serde(default)]
    pub held_latency_ms: Option<Quantiles>,
}

/// A few order statistics of a sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quantiles {
    /// Sample size.
    pub n: usize,
    /// Median.
    pub p50: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

impl Quantiles {
    /// The statistics of `sample` (`None` when it is empty).
    pub fn of(sample: &[f64]) -> Option<Self> {
        let mut s: Vec<f64> = sample.iter().copied().filter(|v| v.is_finite()).collect();
        if s.is_empty() {
            return None;
        }
        s.sort_by(f64::total_cmp);
        let rank = |q: f64| s[((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1];
        Some(Self {
            n: s.len(),
            p50: rank(0.5),
            p99: rank(0.99),
            max: s[s.len() - 1],
        })
    }
}

impl Report {
    /// The report of `robots` after `t` simulated seconds and `wall_s` real ones.
    pub fn new(robots: &[SimRobot], coverage: &Coverage, t: f64, wall_s: f64) -> Self {
        let robots: Vec<RobotReport> = robots
            .iter()
            .zip(&coverage.robots)
            .map(|(r, &covered_pct)| RobotReport {
                id: r.spec.id.clone(),
                driven_m: r.stats.driven_m,
                time_s: r.stats.finished_at_s.unwrap_or(t),
                stops: r.stats.stops,
                collisions: r.stats.collisions,
                corrections_applied: r.stats.corrections_applied,
                final_version: r.followed.version(),
                covered_pct,
                finished: r.finished(),
                plan_id: r.followed.doc().map(|d| d.plan_id.clone()),
                mover_contacts: r.stats.mover_contacts,
                grazes: r.stats.grazes,
                gaps: r.stats.gaps,
                skipped_waypoints: r.stats.skipped_waypoints,
            })
            .collect();
        let fleet = FleetReport {
            covered_pct: coverage.fleet,
            within_regions_pct: coverage.fleet_within_regions,
            time_s: robots.iter().map(|r| r.time_s).fold(0.0, f64::max),
            collisions: robots.iter().map(|r| r.collisions).sum(),
            speedup_achieved: if wall_s > 0.0 { t / wall_s } else { 0.0 },
        };
        Self {
            robots,
            fleet,
            traffic: Traffic::default(),
        }
    }

    /// True when every robot finished.
    pub fn all_finished(&self) -> bool {
        self.robots.iter().all(|r| r.finished)
    }
}

/// Writes `t,x,y,yaw,v` rows to `DIR/ROBOT.csv`, one file per robot.
#[derive(Debug)]
pub struct TraceWriter {
    files: Vec<(std::io::BufWriter<std::fs::File>, String)>,
}

impl TraceWriter {
    /// Creates `dir` and one CSV per robot id, with its header.
    pub fn create(dir: &Path, ids: &[String]) -> Result<Self, SimError> {
        let io = |p: &Path, e| SimError::Io {
            path: p.display().to_string(),
            source: e,
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        let mut files = Vec::new();
        for id in ids {
            let path = dir.join(format!("{id}.csv"));
            let f = std::fs::File::create(&path).map_err(|e| io(&path, e))?;
            let mut w = std::io::BufWriter::new(f);
            writeln!(w, "t,x,y,yaw,v").map_err(|e| io(&path, e))?;
            files.push((w, path.display().to_string()));
        }
        Ok(Self { files })
    }

    /// One row per robot at time `t`.
    pub fn row(&mut self, t: f64, robots: &[SimRobot]) -> Result<(), SimError> {
        for ((w, path), r) in self.files.iter_mut().zip(robots) {
            let b = &r.body;
            writeln!(w, "{t:.3},{:.4},{:.4},{:.4},{:.4}", b.x, b.y, b.yaw, b.v).map_err(|e| SimError::Io {
                path: path.clone(),
                source: e,
            })?;
        }
        Ok(())
    }

    /// Flushes every file.
    pub fn finish(mut self) -> Result<(), SimError> {
        for (w, path) in &mut self.files {
            w.flush().map_err(|e| SimError::Io {
                path: path.clone(),
                source: e,
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_nearest_rank() {
        let sample: Vec<f64> = (1..=200).map(f64::from).collect();
        let q = Quantiles::of(&sample).expect("non-empty");
        assert_eq!((q.n, q.p50, q.p99, q.max), (200, 100.0, 198.0, 200.0));
        assert_eq!(Quantiles::of(&[f64::NAN]), None);
        assert_eq!(Quantiles::of(&[7.0]).map(|q| (q.p50, q.p99)), Some((7.0, 7.0)));
    }
}
