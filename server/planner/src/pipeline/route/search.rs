//! The local search over a region's tasks ([`SearchProblem`]): a generalised TSP on straight-line
//! connections, built once per region and solved from each entry with the 2-opt orderer.

use super::{Leg, MAX_SEARCH_POINTS, RegionRoute, RouteSearch, euclidean, task_options};
use crate::geom::Point2;
use crate::order::{DistanceMatrix, OrderMethod, SolveBudget, TourOption, TourProblem};
use crate::pattern::Task;

/// Local search over the tasks (generalised TSP, open tour from an entry): the problem is built once per
/// region; only the entry (point 0) changes from one entry to the next.
pub(super) struct SearchProblem {
    problem: TourProblem,
    points: Vec<Point2>,
    legs_of: Vec<Vec<Leg>>,
}

impl SearchProblem {
    /// The problem of `tasks`, or `None` when their options have more than [`MAX_SEARCH_POINTS`] points.
    pub(super) fn new(tasks: &[Task]) -> Option<Self> {
        let count: usize = (0..tasks.len()).map(|k| 2 * task_options(tasks, k).len()).sum();
        if count > MAX_SEARCH_POINTS {
            return None;
        }
        let mut points = vec![Point2::origin()];
        let mut legs_of: Vec<Vec<Leg>> = Vec::with_capacity(tasks.len());
        let mut nodes = Vec::with_capacity(tasks.len());
        for k in 0..tasks.len() {
            let opts = task_options(tasks, k);
            let len = tasks[k].length();
            let mut node = Vec::new();
            let mut legs = Vec::new();
            for (entry_p, exit_p, leg) in &opts {
                let e = points.len();
                points.push(*entry_p);
                points.push(*exit_p);
                node.push(TourOption {
                    entry: e,
                    exit: e + 1,
                    cost: len,
                    reverse: 0,
                });
                legs.push(*leg);
            }
            // Reverse pairs: options come in (forward, backward) pairs.
            for (j, o) in node.iter_mut().enumerate() {
                o.reverse = j ^ 1;
            }
            nodes.push(node);
            legs_of.push(legs);
        }
        let dist = DistanceMatrix::from_fn(points.len(), |i, j| euclidean(points[i], points[j]));
        Some(Self {
            problem: TourProblem {
                dist,
                depot: 0,
                nodes,
                closed: false,
            },
            points,
            legs_of,
        })
    }

    /// The searched route from `entry`.
    pub(super) fn route(&mut self, tasks: &[Task], entry: Point2, search: &RouteSearch<'_>) -> RegionRoute {
        self.points[0] = entry;
        for j in 1..self.points.len() {
            self.problem.dist.set(0, j, euclidean(entry, self.points[j]));
        }
        let tour = OrderMethod::TwoOpt.orderer().solve(
            &self.problem,
            search.seed,
            &SolveBudget {
                max_iterations: search.iterations,
                stop: search.stop,
            },
        );
        let legs: Vec<Leg> = tour
            .order
            .iter()
            .zip(&tour.options)
            .map(|(&n, &o)| self.legs_of[n][o])
            .collect();
        let exit = legs.last().map_or(entry, |l| l.ends(tasks).1);
        RegionRoute {
            legs,
            entry,
            exit,
            cost: tour.cost,
        }
    }
}
