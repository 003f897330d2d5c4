//! Move deltas against exact costs, neighbour lists, and the 2-opt orderer's guarantees.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::super::testutil::{euclid, random_matrix};
use super::super::{DistanceMatrix, Orderer, SolveBudget, TourOption, TwoOpt, construct};
use super::neighbours::neighbour_lists;
use super::*;

/// A random order with random options of `p`.
fn random_state(inst: &Inst<'_>, rng: &mut ChaCha8Rng) -> State {
    let mut order: Vec<usize> = (0..inst.n).collect();
    for i in (1..order.len()).rev() {
        order.swap(i, rng.random_range(0..=i));
    }
    let opt = order.iter().map(|&v| rng.random_range(0..inst.k(v))).collect();
    State::new(inst, order, opt)
}

/// Every 2-opt, Or-opt and re-option move of a state with n nodes.
fn all_moves(inst: &Inst<'_>, st: &State) -> Vec<Move> {
    let n = inst.n;
    let mut moves = Vec::new();
    for i in 0..n {
        for j in i + 1..=n {
            moves.push(Move::TwoOpt { i, j });
        }
    }
    for a in 1..=n {
        for b in a..=(a + 2).min(n) {
            for t in (0..=n).filter(|&t| t + 1 < a || t > b) {
                if a == b {
                    for o in 0..inst.k(st.order[a - 1]) {
                        moves.push(Move::OrOpt {
                            a,
                            b,
                            t,
                            reversed: false,
                            o,
                        });
                    }
                } else {
                    for reversed in [false, true] {
                        moves.push(Move::OrOpt {
                            a,
                            b,
                            t,
                            reversed,
                            o: 0,
                        });
                    }
                }
            }
        }
        for o in 0..inst.k(st.order[a - 1]) {
            moves.push(Move::Reopt { s: a, o });
        }
    }
    moves
}

fn full(p: &TourProblem) -> TwoOptParams {
    TwoOptParams {
        neighbours: p.nodes.len() + 1,
        ..TwoOptParams::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The O(1) delta of every move equals the change of the exact cost, and `apply` keeps the cached
    /// points, slots and tracked cost consistent.
    #[test]
    fn deltas_match_exact_costs(n in 1usize..9, k in 1usize..=4, closed: bool, metric: bool, seed: u64) {
        let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
        let inst = Inst::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let st = random_state(&inst, &mut rng);
        let budget = SolveBudget::unlimited();
        let search = Search::new(Inst::new(&p), &full(&p), Meter::new(&budget));
        let mut queue = WorkQueue::new(n);
        for mv in all_moves(&inst, &st) {
            let mut after = st.clone();
            let delta = search.delta(&st, mv);
            search.apply(&mut after, mv, delta, &mut queue);
            let exact = inst.eval(&after.order, &after.opt);
            let tracked = after.cost;
            prop_assert!((tracked - exact).abs() <= 1e-9 * exact.max(1.0), "{mv:?}: {tracked} vs {exact}");
            let fresh = State::new(&inst, after.order.clone(), after.opt.clone());
            prop_assert_eq!(&fresh.pos, &after.pos);
            prop_assert_eq!((&fresh.ent, &fresh.ext), (&after.ent, &after.ext));
            let mut seen = after.order.clone();
            seen.sort_unstable();
            prop_assert_eq!(seen, (0..n).collect::<Vec<_>>());
        }
    }

    /// 2-opt never returns a tour longer than its construction, for any neighbour-list size.
    #[test]
    fn never_lengthens_the_initial_tour(
        n in 0usize..60, k in 1usize..=4, closed: bool, metric: bool, seed: u64,
        neighbours in prop::sample::select(vec![1usize, 3, 8, 16, 100]), insertion: bool,
    ) {
        let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
        let construction =
            if insertion { Construction::CheapestInsertion } else { Construction::NearestNeighbour };
        let params = TwoOptParams { construction, neighbours, max_chain: 3 };
        let initial = construct(&p, construction);
        let budgets = [0, 97, 2_000, u64::MAX].map(SolveBudget::new);
        for budget in budgets {
            let t = TwoOpt { params }.solve(&p, seed, &budget);
            prop_assert_eq!(t.check(&p), Ok(()));
            prop_assert!(t.cost <= initial.cost, "{} > {}", t.cost, initial.cost);
        }
    }
}

#[test]
fn neighbour_lists_are_sorted_and_bounded() {
    let p = euclid(40, 4, true, 3);
    let inst = Inst::new(&p);
    let (nb, nbd, kn) = neighbour_lists(&inst, 8);
    assert_eq!((kn, nb.len(), nbd.len()), (8, 41 * 8, 41 * 8));
    for v in 0..=40 {
        let row = &nb[v * kn..(v + 1) * kn];
        assert!(!row.contains(&v));
        assert!(nbd[v * kn..(v + 1) * kn].windows(2).all(|w| w[0] <= w[1]));
    }
    // With k ≥ n every other pseudo node is listed.
    let (nb, _, kn) = neighbour_lists(&inst, 100);
    assert_eq!(kn, 40);
    let mut row = nb[..kn].to_vec();
    row.sort_unstable();
    assert_eq!(row, (1..=40).collect::<Vec<_>>());
}

#[test]
fn one_way_options_skip_reversals_but_still_improve() {
    // Lanes that may only be driven one way (reverse = itself, entry ≠ exit) fail validation; the solver
    // still returns a valid tour no worse than its construction, without reversing any of them.
    let mut p = euclid(30, 2, true, 17);
    for node in &mut p.nodes {
        let first = node[0];
        *node = vec![TourOption { reverse: 0, ..first }];
    }
    let inst = Inst::new(&p);
    assert!(!inst.reversible, "the instance has one-way lanes");
    let initial = construct(&p, Construction::NearestNeighbour);
    let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
    assert_eq!(t.check(&p), Ok(()));
    assert!(t.cost <= initial.cost);
}

#[test]
fn complete_lists_reach_a_two_opt_optimum_on_a_circle() {
    // Points on a circle, visited in a scrambled order: the optimum is the circle itself.
    let n = 24;
    let pts: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let a = (i * 7 % (n + 1)) as f64 / (n + 1) as f64 * std::f64::consts::TAU;
            (10.0 * a.cos(), 10.0 * a.sin())
        })
        .collect();
    let dist = DistanceMatrix::from_fn(n + 1, |i, j| (pts[i].0 - pts[j].0).hypot(pts[i].1 - pts[j].1));
    let nodes = (1..=n)
        .map(|q| {
            vec![TourOption {
                entry: q,
                exit: q,
                cost: 0.0,
                reverse: 0,
            }]
        })
        .collect();
    let p = TourProblem {
        dist,
        depot: 0,
        nodes,
        closed: true,
    };
    let perimeter = 2.0 * (n + 1) as f64 * 10.0 * (std::f64::consts::PI / (n + 1) as f64).sin();
    let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
    assert!((t.cost - perimeter).abs() < 1e-6, "{} vs {perimeter}", t.cost);
}
