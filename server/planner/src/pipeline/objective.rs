//! What a plan is ranked by. Fleet operators pay for time, so the default is the time the plan takes to
//! drive (DESIGN §6 `duration_s`): a spiral with three times the turns of a lane plan can have less overlap
//! and still take longer, because every sharp corner pulls the speed down. A request may name another
//! objective (Fields2Cover passes its objective as an argument too). Every objective is subject to the
//! coverage bar first: a plan that meets it beats one that does not.

use super::prepare::Estimate;

/// The quantity the portfolio minimises among plans that meet the coverage bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Objective {
    /// Estimated driving time under the robot's speed and acceleration limits, with corner slow-downs.
    #[default]
    Time,
    /// Path length.
    Length,
    /// Overlap (DESIGN §6): length × tool width against the covered area.
    Overlap,
    /// Heading changes of 30° or more.
    Turns,
}

impl Objective {
    /// Every objective, default first.
    pub const ALL: [Objective; 4] = [Objective::Time, Objective::Length, Objective::Overlap, Objective::Turns];

    /// The name used in requests and tables.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Time => "time",
            Objective::Length => "length",
            Objective::Overlap => "overlap",
            Objective::Turns => "turns",
        }
    }

    /// Parses [`Objective::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|o| o.name() == name)
    }

    /// The value this objective minimises for `e`.
    pub fn value(self, e: &Estimate) -> f64 {
        match self {
            Objective::Time => e.duration_s,
            Objective::Length => e.length_m,
            Objective::Overlap => e.overlap_pct,
            Objective::Turns => e.turns as f64,
        }
    }
}

impl std::str::FromStr for Objective {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::from_name(s)
            .ok_or_else(|| format!("unknown objective {s:?}; expected one of time, length, overlap, turns"))
    }
}

/// How close, relative, two estimated driving times must be to count as equal: the estimate drives a sketch
/// of the path with every corner rounded as smoothing may round it, and the final profile differs by up to
/// about 2 % (one measured pair: the undivided fitted lanes on four-rooms-cluttered, 594 s estimated against
/// 605 s driven; more pairs are still to be measured). Within it the least overlap wins: the same time with
/// less double sweeping (wear, water, energy).
pub const TIME_TIE: f64 = 0.02;

/// Sort keys of `estimates`, best first when sorted ascending: plans that meet the coverage bar
/// `target_pct` first, then by `objective`; below the bar, more coverage first. Under the time objective
/// the plans within [`TIME_TIE`] of the fastest come first, least overlap first among them. Keys compare
/// with [`f64::total_cmp`] element-wise, so the order is total (ties keep member order in a stable sort).
pub fn rank_keys(estimates: &[Estimate], target_pct: f64, objective: Objective) -> Vec<[f64; 3]> {
    let fastest = estimates
        .iter()
        .filter(|e| e.good(target_pct))
        .map(|e| e.duration_s)
        .fold(f64::INFINITY, f64::min);
    estimates
        .iter()
        .map(|e| {
            if !e.good(target_pct) {
                return [1.0, 0.0, -e.coverage_pct];
            }
            match objective {
                Objective::Time if e.duration_s <= fastest * (1.0 + TIME_TIE) => [0.0, 0.0, e.overlap_pct],
                o => [0.0, 1.0, o.value(e)],
            }
        })
        .collect()
}

/// Compares two keys of [`rank_keys`].
pub fn compare_keys(a: &[f64; 3], b: &[f64; 3]) -> std::cmp::Ordering {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(std::cmp::Ordering::Equal)
}

/// True when `a` ranks strictly above `b` when they are the only two candidates.
pub fn better(a: &Estimate, b: &Estimate, target_pct: f64, objective: Objective) -> bool {
    let keys = rank_keys(&[*a, *b], target_pct, objective);
    compare_keys(&keys[0], &keys[1]).is_lt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(coverage_pct: f64, overlap_pct: f64, duration_s: f64, turns: usize) -> Estimate {
        Estimate {
            coverage_pct,
            length_m: 100.0 + overlap_pct,
            overlap_pct,
            duration_s,
            turns,
        }
    }

    #[test]
    fn the_coverage_bar_comes_before_the_objective() {
        for o in Objective::ALL {
            assert!(better(&e(99.5, 30.0, 900.0, 90), &e(98.0, 5.0, 100.0, 9), 99.0, o));
            assert!(!better(&e(98.0, 5.0, 100.0, 9), &e(99.5, 30.0, 900.0, 90), 99.0, o));
            assert!(
                better(&e(97.0, 50.0, 900.0, 90), &e(96.0, 5.0, 100.0, 9), 99.0, o),
                "below the bar: more coverage first"
            );
            let a = e(99.2, 10.0, 500.0, 40);
            assert!(!better(&a, &a, 99.0, o), "ties keep the earlier member");
        }
    }

    #[test]
    fn each_objective_ranks_by_its_own_value() {
        // A spiral: less overlap, more turns, more time; lanes: the opposite.
        let spiral = e(99.6, 3.1, 4334.0, 240);
        let lanes = e(99.6, 5.0, 3300.0, 35);
        assert!(better(&lanes, &spiral, 99.0, Objective::Time));
        assert!(better(&lanes, &spiral, 99.0, Objective::Turns));
        assert!(better(&spiral, &lanes, 99.0, Objective::Overlap));
        assert!(better(&spiral, &lanes, 99.0, Objective::Length));
    }

    #[test]
    fn times_within_the_estimates_precision_fall_back_to_overlap() {
        let fit = e(99.4, 55.0, 594.0, 242);
        let framed = e(99.9, 36.5, 602.5, 291);
        let spiral = e(99.4, 13.6, 913.0, 1318);
        assert!(
            better(&framed, &fit, 99.0, Objective::Time),
            "1.4 % slower, 19 points less overlap"
        );
        assert!(better(&fit, &spiral, 99.0, Objective::Time));
        let keys = rank_keys(&[fit, spiral, framed], 99.0, Objective::Time);
        let mut order = vec![0, 1, 2];
        order.sort_by(|&a, &b| compare_keys(&keys[a], &keys[b]));
        assert_eq!(order, vec![2, 0, 1]);
    }

    #[test]
    fn names_round_trip() {
        for o in Objective::ALL {
            assert_eq!(Objective::from_name(o.name()), Some(o));
        }
        assert_eq!(Objective::from_name("fast"), None);
        assert_eq!(Objective::default(), Objective::Time);
    }
}
