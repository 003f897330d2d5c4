//! Criterion benches of the ikd-tree beside kiddo, at sizes small enough for `cargo bench` to finish in a
//! few minutes. The same cases as `examples/map_bench.rs` (which runs them at 1 M points and prints JSON):
//! build, a 10 k-point scan insert with down-sampling (kiddo: mutable add, immutable rebuild), a box delete
//! of 5 % of the points, 5-nearest queries. Points lie on the ground and walls of a 30 m × 30 m × 3 m scene
//! (metres, seeded RNG).

use std::hint::black_box;
use std::num::NonZeroUsize;
use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use kiddo::{ImmutableKdTree, MutableKdTree, SquaredEuclidean};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shift_planner::map::ikd_tree::{Aabb, IkdParams, IkdTree, Point3};

const N: usize = 100_000;
const SIDE_M: f32 = 30.0;

/// A point on the ground (60 %) or on one of the walls x = 0, 10, 20, 30 (40 %), with 1 cm noise.
fn scene_point(rng: &mut ChaCha8Rng) -> Point3 {
    let noise = (rng.random::<f32>() - 0.5) * 0.02;
    if rng.random::<f32>() < 0.6 {
        Point3::new(rng.random::<f32>() * SIDE_M, rng.random::<f32>() * SIDE_M, noise)
    } else {
        let x = rng.random_range(0..4) as f32 * 10.0 + noise;
        Point3::new(x, rng.random::<f32>() * SIDE_M, rng.random::<f32>() * 3.0)
    }
}

/// 10 k points within 8 m of (cx, cy).
fn scan(rng: &mut ChaCha8Rng, cx: f32, cy: f32) -> Vec<Point3> {
    let mut out = Vec::with_capacity(10_000);
    while out.len() < 10_000 {
        let p = scene_point(rng);
        let q = Point3::new(cx + (p.x - SIDE_M / 2.0) * 0.5, cy + (p.y - SIDE_M / 2.0) * 0.5, p.z);
        out.push(q);
    }
    out
}

fn arr(p: &Point3) -> [f32; 3] {
    [p.x, p.y, p.z]
}

fn benches(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let map: Vec<Point3> = (0..N).map(|_| scene_point(&mut rng)).collect();
    let map_arr: Vec<[f32; 3]> = map.iter().map(arr).collect();
    let scans: Vec<Vec<Point3>> = (0..8).map(|i| scan(&mut rng, 10.0 + i as f32, 15.0)).collect();
    let queries: Vec<Point3> = (0..1000).map(|_| scene_point(&mut rng)).collect();
    let params = IkdParams::default();
    let mut base = IkdTree::new(params).expect("valid params");
    base.build(&map);
    let k5 = NonZeroUsize::MIN.saturating_add(4);
    let slab = Aabb::new(Point3::new(-1.0, -1.0, -1.0), Point3::new(1.5, SIDE_M + 1.0, 4.0));

    let mut g = c.benchmark_group("ikd_tree");
    g.sample_size(10);
    g.warm_up_time(Duration::from_secs(1));
    g.measurement_time(Duration::from_secs(3));
    g.bench_function("build_100k", |b| {
        b.iter(|| {
            let mut t = IkdTree::new(params).expect("valid params");
            t.build(black_box(&map));
            t
        })
    });
    g.bench_function("kiddo_immutable_build_100k", |b| {
        b.iter(|| ImmutableKdTree::<f32, 3>::new_from_slice(black_box(&map_arr)).expect("kiddo build"))
    });
    g.bench_function("insert_scan_10k_downsampled_fresh_100k", |b| {
        b.iter_batched(
            || {
                let mut t = IkdTree::new(params).expect("valid params");
                t.build(&map);
                t
            },
            |mut t| black_box(t.add_points(&scans[0], true)),
            BatchSize::LargeInput,
        )
    });
    let mut warm = IkdTree::new(params).expect("valid params");
    warm.build(&map);
    let mut j = 0;
    g.bench_function("insert_scan_10k_downsampled_into_100k", |b| {
        b.iter(|| {
            j += 1;
            black_box(warm.add_points(&scans[j % scans.len()], true))
        })
    });
    let mut km: MutableKdTree<f32, 3> = MutableKdTree::default();
    for (i, p) in map_arr.iter().enumerate() {
        let _ = km.add(p, i as u32);
    }
    let mut next = N as u32;
    g.bench_function("kiddo_mutable_add_scan_10k", |b| {
        b.iter(|| {
            for p in &scans[next as usize % scans.len()] {
                let _ = km.add(&arr(p), next);
                next += 1;
            }
        })
    });
    g.bench_function("kiddo_immutable_rebuild_with_scan", |b| {
        b.iter(|| {
            let mut all = map_arr.clone();
            all.extend(scans[0].iter().map(arr));
            ImmutableKdTree::<f32, 3>::new_from_slice(&all).expect("kiddo build")
        })
    });
    g.bench_function("delete_box_5pct", |b| {
        b.iter_batched(
            || {
                let mut t = IkdTree::new(params).expect("valid params");
                t.build(&map);
                t
            },
            |mut t| black_box(t.delete_box(&slab)),
            BatchSize::LargeInput,
        )
    });
    g.bench_function("knn5_1k_queries", |b| {
        b.iter(|| {
            for q in &queries {
                black_box(base.nearest(q, 5));
            }
        })
    });
    let ki = ImmutableKdTree::<f32, 3>::new_from_slice(&map_arr).expect("kiddo build");
    g.bench_function("kiddo_immutable_knn5_1k_queries", |b| {
        b.iter(|| {
            for q in &queries {
                black_box(ki.query(&arr(q)).nearest_n::<SquaredEuclidean<f32>>(k5).execute());
            }
        })
    });
    g.bench_function("nearest_distance_1k_queries", |b| {
        b.iter(|| {
            for q in &queries {
                black_box(base.nearest_distance(q));
            }
        })
    });
    g.finish();
}

criterion_group!(ikd, benches);
criterion_main!(ikd);
