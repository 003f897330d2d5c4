//! Tests of the ikd-tree against a brute-force oracle (a `Vec` of valid points), plus shape, memory and
//! background-rebuild checks. Long fuzz runs are `#[ignore]`d: `cargo test -p shift-planner -- --ignored`.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn key(p: &Point3) -> [u32; 3] {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

fn sorted(mut v: Vec<Point3>) -> Vec<Point3> {
    v.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)).then(a.z.total_cmp(&b.z)));
    v
}

/// Removes one instance of each of `sub` from `set` (multisets); false if some is missing.
fn remove_multiset(set: &mut Vec<Point3>, sub: &[Point3]) -> bool {
    for p in sub {
        match set.iter().position(|q| key(q) == key(p)) {
            Some(i) => {
                set.swap_remove(i);
            }
            None => return false,
        }
    }
    true
}

/// The brute-force model: the valid points (with the call that added them) and every point ever deleted.
struct Oracle {
    live: Vec<(Point3, u64)>,
    tombs: Vec<Point3>,
    vs: f32,
}

impl Oracle {
    fn new(vs: f32) -> Self {
        Oracle {
            live: Vec::new(),
            tombs: Vec::new(),
            vs,
        }
    }

    fn points(&self) -> Vec<Point3> {
        self.live.iter().map(|e| e.0).collect()
    }

    fn build(&mut self, pts: &[Point3]) -> usize {
        self.live = pts.iter().filter(|p| p.is_finite()).map(|p| (*p, 0)).collect();
        self.tombs.clear();
        self.live.len()
    }

    /// Sequential model of the voxel rule, one point after the other.
    fn add(&mut self, pts: &[Point3], downsample: bool, tag: u64) -> usize {
        for p in pts.iter().filter(|p| p.is_finite()) {
            if !downsample {
                self.live.push((*p, tag));
                continue;
            }
            let k = voxel_key(p, self.vs);
            let d = voxel_centre_dist2(p, &k, self.vs);
            let best = self
                .live
                .iter()
                .filter(|e| voxel_key(&e.0, self.vs) == k)
                .map(|e| voxel_centre_dist2(&e.0, &k, self.vs))
                .fold(f32::INFINITY, f32::min);
            if d < best {
                let vs = self.vs;
                let (gone, keep): (Vec<_>, Vec<_>) = self.live.drain(..).partition(|e| voxel_key(&e.0, vs) == k);
                self.live = keep;
                self.tombs.extend(gone.into_iter().map(|e| e.0));
                self.live.push((*p, tag));
            }
        }
        self.live.iter().filter(|e| e.1 == tag).count()
    }

    fn delete_where(&mut self, f: impl Fn(&Point3) -> bool) -> usize {
        let (gone, keep): (Vec<_>, Vec<_>) = self.live.drain(..).partition(|e| f(&e.0));
        self.live = keep;
        let n = gone.len();
        self.tombs.extend(gone.into_iter().map(|e| e.0));
        n
    }

    fn dists(&self, q: &Point3) -> Vec<f32> {
        let mut d: Vec<f32> = self.live.iter().map(|e| e.0.dist2(q)).collect();
        d.sort_by(f32::total_cmp);
        d
    }
}

/// Compares every query of `t` with the oracle at `q`.
fn check_queries(t: &IkdTree, o: &Oracle, q: &Point3, k: usize, r: f32, b: &Aabb) -> Result<(), TestCaseError> {
    let all = o.dists(q);
    let live_keys: std::collections::HashSet<[u32; 3]> = o.live.iter().map(|e| key(&e.0)).collect();
    let got = t.nearest(q, k);
    let want: Vec<f32> = all.iter().copied().take(k).collect();
    prop_assert_eq!(got.iter().map(|g| g.1).collect::<Vec<_>>(), want.clone());
    for (p, d) in &got {
        prop_assert!(
            live_keys.contains(&key(p)),
            "nearest returned a point not in the map: {:?}",
            p
        );
        prop_assert_eq!(p.dist2(q), *d);
    }
    let got = t.nearest_within(q, k, r);
    let want: Vec<f32> = all.iter().copied().filter(|d| *d <= r * r).take(k).collect();
    prop_assert_eq!(got.iter().map(|g| g.1).collect::<Vec<_>>(), want);
    let got: Vec<Point3> = t.within_radius(q, r).into_iter().map(|g| g.0).collect();
    let want: Vec<Point3> = o.points().into_iter().filter(|p| p.dist2(q) <= r * r).collect();
    prop_assert_eq!(sorted(got), sorted(want));
    let got = t.within_box(b);
    let want: Vec<Point3> = o.points().into_iter().filter(|p| b.contains(p)).collect();
    prop_assert_eq!(sorted(got), sorted(want));
    prop_assert_eq!(t.nearest_distance(q), all.first().map(|d| d.sqrt()));
    prop_assert_eq!(t.nearest_point(q).map(|g| g.1), all.first().copied());
    if let Some((p, d)) = t.nearest_point(q) {
        prop_assert!(live_keys.contains(&key(&p)));
        prop_assert_eq!(p.dist2(q), d);
    }
    Ok(())
}

#[derive(Debug, Clone)]
enum Op {
    Build(Vec<Point3>),
    Add(Vec<Point3>, bool),
    DeleteBox(Aabb),
    /// Indices into the valid points (modulo their number) and extra points that may not exist.
    DeletePoints(Vec<usize>, Vec<Point3>),
    Restore(Aabb),
    Wait,
    Query(Point3, usize, f32, Aabb),
}

/// Coordinates on a coarse lattice (many duplicates, several points per voxel) or anywhere in a range.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![(0i32..24).prop_map(|i| i as f32 * 0.07), -0.5f32..2.0]
}

fn point(flat: bool) -> impl Strategy<Value = Point3> {
    (coord(), coord(), coord()).prop_map(move |(x, y, z)| Point3::new(if flat { 0.5 } else { x }, y, z))
}

fn aabb() -> impl Strategy<Value = Aabb> {
    (coord(), coord(), coord(), 0.0f32..1.5, 0.0f32..1.5, 0.0f32..2.5)
        .prop_map(|(x, y, z, a, b, c)| Aabb::new(Point3::new(x - a, y - b, z - c), Point3::new(x + a, y + b, z + c)))
}

fn op(flat: bool) -> impl Strategy<Value = Op> {
    prop_oneof![
        1 => prop::collection::vec(point(flat), 0..300).prop_map(Op::Build),
        6 => (prop::collection::vec(point(flat), 0..200), any::<bool>()).prop_map(|(v, d)| Op::Add(v, d)),
        3 => aabb().prop_map(Op::DeleteBox),
        2 => (prop::collection::vec(any::<usize>(), 0..20), prop::collection::vec(point(flat), 0..3))
            .prop_map(|(i, p)| Op::DeletePoints(i, p)),
        2 => aabb().prop_map(Op::Restore),
        1 => Just(Op::Wait),
        5 => (point(flat), 1usize..12, 0.0f32..1.2, aabb()).prop_map(|(q, k, r, b)| Op::Query(q, k, r, b)),
    ]
}

fn params() -> impl Strategy<Value = IkdParams> {
    (
        prop_oneof![Just(0.6f32), Just(0.5), Just(0.9)],
        prop_oneof![Just(0.5f32), Just(0.3), Just(1.0)],
        prop_oneof![Just(0.2f32), Just(0.07), Just(0.5)],
        prop_oneof![Just(1500usize), Just(40), Just(usize::MAX)],
    )
        .prop_map(|(alpha_bal, alpha_del, voxel_size, background_rebuild_min)| IkdParams {
            alpha_bal,
            alpha_del,
            voxel_size,
            background_rebuild_min,
        })
}

fn run_ops(params: IkdParams, ops: &[Op]) -> Result<(), TestCaseError> {
    let mut t = IkdTree::new(params).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let mut o = Oracle::new(params.voxel_size);
    for (step, op) in ops.iter().enumerate() {
        let tag = step as u64 + 1;
        match op {
            Op::Build(v) => prop_assert_eq!(t.build(v), o.build(v)),
            Op::Add(v, d) => {
                prop_assert_eq!(t.add_points(v, *d), o.add(v, *d, tag), "add #{}", step)
            }
            Op::DeleteBox(b) => prop_assert_eq!(t.delete_box(b), o.delete_where(|p| b.contains(p))),
            Op::DeletePoints(idx, extra) => {
                let live = o.points();
                let mut pts: Vec<Point3> = extra.clone();
                if !live.is_empty() {
                    pts.extend(idx.iter().map(|i| live[i % live.len()]));
                }
                let keys: std::collections::HashSet<[u32; 3]> = pts.iter().map(key).collect();
                let want = o.delete_where(|p| keys.contains(&key(p)));
                prop_assert_eq!(t.delete_points(&pts), want);
            }
            Op::Restore(b) => {
                let before = o.points();
                let restored = t.restore_box(b);
                let mut now = t.flatten();
                prop_assert!(remove_multiset(&mut now, &before), "restore lost valid points");
                prop_assert_eq!(now.len(), restored, "restore count");
                prop_assert!(now.iter().all(|p| b.contains(p)), "restored a point outside the box");
                prop_assert!(remove_multiset(&mut o.tombs, &now), "restored a point never deleted");
                o.live.extend(now.into_iter().map(|p| (p, 0)));
            }
            Op::Wait => t.wait_rebuild(),
            Op::Query(q, k, r, b) => check_queries(&t, &o, q, *k, *r, b)?,
        }
        prop_assert_eq!(t.len(), o.live.len(), "len after #{} {:?}", step, op);
        prop_assert!(t.tree_size() >= t.len());
    }
    prop_assert_eq!(sorted(t.flatten()), sorted(o.points()));
    t.wait_rebuild();
    prop_assert_eq!(sorted(t.flatten()), sorted(o.points()));
    prop_assert!(!t.rebuild_in_flight());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn matches_oracle(params in params(), ops in prop::collection::vec(op(false), 1..40)) {
        run_ops(params, &ops)?;
    }

    #[test]
    fn matches_oracle_all_on_one_x(params in params(), ops in prop::collection::vec(op(true), 1..40)) {
        run_ops(params, &ops)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    #[ignore = "long fuzz run"]
    fn fuzz_matches_oracle(params in params(), flat in any::<bool>(), ops in prop::collection::vec(op(false), 1..120)) {
        let _ = flat;
        run_ops(params, &ops)?;
    }
}

fn random_points(rng: &mut ChaCha8Rng, n: usize, side: f32) -> Vec<Point3> {
    (0..n)
        .map(|_| {
            Point3::new(
                rng.random::<f32>() * side,
                rng.random::<f32>() * side,
                rng.random::<f32>() * side,
            )
        })
        .collect()
}

fn brute_nearest(pts: &[Point3], q: &Point3, k: usize) -> Vec<f32> {
    let mut d: Vec<f32> = pts.iter().map(|p| p.dist2(q)).collect();
    d.sort_by(f32::total_cmp);
    d.truncate(k);
    d
}

fn depth_after_random_inserts(n: usize, batch: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    let pts = random_points(&mut rng, n, 100.0);
    for c in pts.chunks(batch) {
        t.add_points(c, false);
    }
    t.wait_rebuild();
    assert_eq!(t.len(), n);
    let bound = 3.0 * (n as f64).log2();
    assert!((t.depth() as f64) <= bound, "depth {} > 3 log2 n = {bound}", t.depth());
    for q in random_points(&mut rng, 50, 100.0) {
        let got: Vec<f32> = t.nearest(&q, 5).iter().map(|g| g.1).collect();
        assert_eq!(got, brute_nearest(&pts, &q, 5));
    }
}

#[test]
fn depth_bounded_after_200k_single_inserts() {
    depth_after_random_inserts(200_000, 1);
}

#[test]
fn depth_bounded_after_1m_inserts() {
    depth_after_random_inserts(1_000_000, 10);
}

#[test]
fn sorted_inserts_stay_balanced() {
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    let n = 50_000;
    for i in 0..n {
        t.add_points(&[Point3::new(i as f32 * 0.01, 0.0, 0.0)], false);
    }
    t.wait_rebuild();
    assert_eq!(t.len(), n);
    assert!((t.depth() as f64) <= 3.0 * (n as f64).log2(), "depth {}", t.depth());
    assert!(t.stats().rebuilds_in_place + t.stats().rebuilds_background > 0);
}

#[test]
fn duplicates_and_one_axis_value() {
    // Every point identical, then every point on z = 0 (the case that defeats kiddo's mutable tree).
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    let p = Point3::new(1.0, 2.0, 3.0);
    for _ in 0..5000 {
        t.add_points(&[p], false);
    }
    assert_eq!(t.len(), 5000);
    assert!(t.depth() <= 3 * 13, "depth {}", t.depth());
    assert_eq!(
        t.nearest(&Point3::new(1.0, 2.0, 4.0), 3)
            .iter()
            .map(|g| g.1)
            .collect::<Vec<_>>(),
        vec![1.0; 3]
    );
    assert_eq!(
        t.add_points(&[p], true),
        0,
        "an equally near point does not replace the voxel's points"
    );
    assert_eq!(t.delete_points(&[p]), 5000);
    assert!(t.is_empty());
    assert_eq!(t.nearest_distance(&p), None);

    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let flat: Vec<Point3> = (0..20_000)
        .map(|_| Point3::new(rng.random::<f32>() * 10.0, rng.random::<f32>() * 10.0, 0.0))
        .collect();
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    for c in flat.chunks(7) {
        t.add_points(c, false);
    }
    t.wait_rebuild();
    assert!((t.depth() as f64) <= 3.0 * 20_000f64.log2());
    for q in random_points(&mut rng, 50, 10.0) {
        let got: Vec<f32> = t.nearest(&q, 5).iter().map(|g| g.1).collect();
        assert_eq!(got, brute_nearest(&flat, &q, 5));
    }
}

#[test]
fn box_deletes_reclaim_memory() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let n = 200_000;
    let pts = random_points(&mut rng, n, 100.0);
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    t.build(&pts);
    let full = t.memory_bytes();
    assert!(full / n <= 64, "{} bytes per point after build", full / n);
    // Delete 90 % with nine slabs of 10 m along x.
    let mut deleted = 0;
    for i in 0..9 {
        let x0 = i as f32 * 10.0;
        let b = Aabb::new(Point3::new(x0, -1.0, -1.0), Point3::new(x0 + 10.0, 101.0, 101.0));
        deleted += t.delete_box(&b);
        assert_eq!(t.len(), n - deleted);
    }
    let want = pts.iter().filter(|p| p.x < 90.0).count();
    assert_eq!(deleted, want);
    t.wait_rebuild();
    assert_eq!(t.len(), n - want);
    assert_eq!(t.tree_size(), t.len(), "every tombstone is reclaimed by the rebuilds");
    let after = t.memory_bytes();
    assert!(after * 4 < full, "memory not reclaimed: {full} -> {after} bytes");
    assert!(
        after / t.len() <= 64,
        "{} bytes per point after deleting",
        after / t.len()
    );
    assert!(t.stats().compactions > 0);
    let rest: Vec<Point3> = pts.iter().filter(|p| p.x > 90.0).copied().collect();
    for q in random_points(&mut rng, 50, 100.0) {
        let got: Vec<f32> = t.nearest(&q, 5).iter().map(|g| g.1).collect();
        assert_eq!(got, brute_nearest(&rest, &q, 5));
    }
}

#[test]
fn background_rebuild_replays_the_log() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let pts = random_points(&mut rng, 100_000, 50.0);
    let mut t = IkdTree::new(IkdParams::default()).expect("params");
    t.build(&pts);
    let mut o = Oracle::new(0.2);
    o.build(&pts);
    // A big delete makes large subtrees dirty: they go to the background thread; keep writing meanwhile.
    let b = Aabb::new(Point3::new(0.0, 0.0, 0.0), Point3::new(30.0, 50.0, 50.0));
    assert_eq!(t.delete_box(&b), o.delete_where(|p| b.contains(p)));
    let mut saw_flight = t.rebuild_in_flight();
    for i in 0..200u64 {
        let add = random_points(&mut rng, 50, 50.0);
        assert_eq!(t.add_points(&add, i % 2 == 0), o.add(&add, i % 2 == 0, i + 1));
        let c = random_points(&mut rng, 1, 50.0)[0];
        let b = Aabb::around(c, 1.0);
        assert_eq!(t.delete_box(&b), o.delete_where(|p| b.contains(p)));
        saw_flight |= t.rebuild_in_flight();
        let q = random_points(&mut rng, 1, 50.0)[0];
        let got: Vec<f32> = t.nearest(&q, 5).iter().map(|g| g.1).collect();
        assert_eq!(got, o.dists(&q).into_iter().take(5).collect::<Vec<_>>());
    }
    t.wait_rebuild();
    assert!(saw_flight, "no background rebuild was started");
    assert!(t.stats().rebuilds_background > 0);
    assert_eq!(sorted(t.flatten()), sorted(o.points()));
}

#[test]
fn restore_brings_back_unreclaimed_tombstones() {
    let params = IkdParams {
        alpha_bal: 1.0,
        alpha_del: 1.0,
        background_rebuild_min: usize::MAX,
        ..Default::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let pts = random_points(&mut rng, 5000, 10.0);
    let mut t = IkdTree::new(params).expect("params");
    t.build(&pts);
    let b1 = Aabb::new(Point3::new(0.0, 0.0, 0.0), Point3::new(5.0, 10.0, 10.0));
    let b2 = Aabb::around(Point3::new(7.0, 7.0, 7.0), 2.0);
    let d = t.delete_box(&b1) + t.delete_box(&b2);
    assert_eq!(t.len(), 5000 - d);
    assert_eq!(t.tree_size(), 5000);
    let all = Aabb::new(Point3::new(-1.0, -1.0, -1.0), Point3::new(11.0, 11.0, 11.0));
    assert_eq!(t.restore_box(&all), d);
    assert_eq!(sorted(t.flatten()), sorted(pts));
}

#[test]
fn rejects_bad_input() {
    assert!(
        IkdTree::new(IkdParams {
            alpha_bal: 0.4,
            ..Default::default()
        })
        .is_err()
    );
    assert!(
        IkdTree::new(IkdParams {
            alpha_del: 0.0,
            ..Default::default()
        })
        .is_err()
    );
    assert!(
        IkdTree::new(IkdParams {
            voxel_size: f32::NAN,
            ..Default::default()
        })
        .is_err()
    );
    let mut t = IkdTree::default();
    let bad = [
        Point3::new(f32::NAN, 0.0, 0.0),
        Point3::new(0.0, f32::INFINITY, 0.0),
        Point3::new(1.0, 1.0, 1.0),
    ];
    assert_eq!(t.add_points(&bad, true), 1);
    assert_eq!(t.add_points(&bad, false), 1);
    assert!(t.nearest(&bad[0], 3).is_empty());
    assert!(t.nearest(&bad[2], 0).is_empty());
    assert!(t.nearest_within(&bad[2], 3, -1.0).is_empty());
    assert!(t.within_radius(&bad[2], f32::NAN).is_empty());
    assert_eq!(t.delete_points(&bad[..2]), 0);
    assert_eq!(t.delete_box(&Aabb::empty()), 0);
    assert_eq!(t.len(), 2);
    assert_eq!(t.nearest_distance(&Point3::new(1.0, 1.0, 2.0)), Some(1.0));
}

#[test]
fn is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<IkdTree>();
}

#[test]
fn voxel_membership_matches_the_key() {
    // The inner/outer box shortcut must agree with floor(c / voxel_size) everywhere, voxel faces included.
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for &vs in &[0.2f32, 0.07, 0.5, 1.0 / 3.0] {
        for _ in 0..20_000 {
            let scale = [1.0f32, 100.0, 10_000.0][rng.random_range(0..3)];
            let mut c = || {
                let k = rng.random_range(-50i32..50) as f32;
                // On a face, a hair off it, or anywhere.
                match rng.random_range(0..3) {
                    0 => k * vs,
                    1 => f32::from_bits((k * vs).to_bits().wrapping_add(rng.random_range(0..3))),
                    _ => (rng.random::<f32>() - 0.5) * scale,
                }
            };
            let p = Point3::new(c(), c(), c());
            let q = Point3::new(c(), c(), c());
            let shape = VoxelShape::new(voxel_key(&p, vs), vs);
            assert!(shape.holds(&p, vs), "{p:?} not in its own voxel");
            assert_eq!(
                shape.holds(&q, vs),
                voxel_key(&q, vs) == shape.key,
                "{q:?} vs voxel of {p:?}"
            );
        }
    }
}
