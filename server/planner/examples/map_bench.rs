//! Side-by-side benchmark of the live map (ikd-tree) against kiddo, printing ONE JSON line.
//!
//! `cargo run --release -p shift-planner --example map_bench [-- POINTS]` (default 1 000 000 points).
//! With `MAP_BENCH_IKD_ONLY=1` in the environment only the ikd-tree part runs (a profiling aid).
//!
//! Scene: a 100 m × 100 m site, 3 m high, in the map frame (metres): the ground (z ≈ 0) and walls (a
//! perimeter and a grid of 8 m room walls), every point with 1 cm of sensor noise along the surface
//! normal. The map holds POINTS points on these surfaces; a scan is 10 000 points seen from a sensor that
//! moves along a circle, 70 % ground within 12 m and 30 % on nearby walls. Queries are surface points
//! moved by up to 0.5 m (where a robot asks for obstacle distances). Everything comes from a seeded RNG.
//!
//! Steps, on the same data for every tree:
//! 1. build from the map points (`build_ms`);
//! 2. insert 100 scans (`insert_scan_us`, mean per scan): the ikd-tree down-samples on the tree (0.2 m
//!    voxels); kiddo's mutable tree adds the raw scan (it has no down-sampling); `kiddo_rebuild` rebuilds
//!    kiddo's immutable tree from the map plus the scan (mean over 10 scans);
//! 3. delete a box holding 5 % of the points (`delete_box_ms`; kiddo: `remove` of each point in it);
//! 4. 100 000 5-nearest queries (`knn5_ns`, mean per query); `kiddo_immutable` is built from exactly the
//!    ikd-tree's valid points at that moment;
//! 5. bytes per point after the build: the ikd-tree's own accounting (`memory_bytes / len`, capacities),
//!    and for kiddo's mutable tree the growth of the process's resident memory (Linux `/proc/self/statm`).
//!
//! Times are wall-clock; `cpu_time` repeats the main ones as the main thread's CPU time
//! (`/proc/thread-self/schedstat`), and `load_avg_1m` tells how busy the machine was.
//!
//! Then the randomized protocol of the ikd-Tree paper on a fresh tree: 20 000 initial points uniform in a
//! 10 m cube; 1000 operations of 200 inserts (raw, uniform in the cube) and 200 5-NN queries; every 50
//! operations 4 box deletes of 1.5 m side. `ikd_protocol_update_us` is the mean time of an operation's
//! updates (inserts and, when due, deletes), queries excluded (`ikd_protocol_query_us` is theirs).

use std::hint::black_box;
use std::num::NonZeroUsize;
use std::time::Instant;

use kiddo::{ImmutableKdTree, MutableKdTree, SquaredEuclidean};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shift_planner::map::ikd_tree::{Aabb, IkdParams, IkdTree, Point3};

const SIDE_M: f32 = 100.0;
const HEIGHT_M: f32 = 3.0;
const NOISE_M: f32 = 0.01;

/// A vertical wall segment from (x0, y0) to (x1, y1), 0..3 m high.
#[derive(Clone, Copy)]
struct Wall {
    x0: f32,
    y0: f32,
    x1: f32,
    y1: f32,
}

impl Wall {
    fn len(&self) -> f32 {
        ((self.x1 - self.x0).powi(2) + (self.y1 - self.y0).powi(2)).sqrt()
    }
}

struct Scene {
    walls: Vec<Wall>,
    /// Cumulative wall lengths, for sampling by length.
    cum: Vec<f32>,
}

impl Scene {
    fn new() -> Self {
        let mut walls = vec![
            Wall {
                x0: 0.0,
                y0: 0.0,
                x1: SIDE_M,
                y1: 0.0,
            },
            Wall {
                x0: SIDE_M,
                y0: 0.0,
                x1: SIDE_M,
                y1: SIDE_M,
            },
            Wall {
                x0: SIDE_M,
                y0: SIDE_M,
                x1: 0.0,
                y1: SIDE_M,
            },
            Wall {
                x0: 0.0,
                y0: SIDE_M,
                x1: 0.0,
                y1: 0.0,
            },
        ];
        // Rooms: every 10 m, walls of 8 m leaving 2 m doorways.
        for i in 1..10 {
            let c = i as f32 * 10.0;
            for j in 0..10 {
                let s = j as f32 * 10.0 + 1.0;
                walls.push(Wall {
                    x0: c,
                    y0: s,
                    x1: c,
                    y1: s + 8.0,
                });
                walls.push(Wall {
                    x0: s,
                    y0: c,
                    x1: s + 8.0,
                    y1: c,
                });
            }
        }
        let mut cum = Vec::with_capacity(walls.len());
        let mut acc = 0.0;
        for w in &walls {
            acc += w.len();
            cum.push(acc);
        }
        Scene { walls, cum }
    }

    fn noise(rng: &mut ChaCha8Rng) -> f32 {
        (rng.random::<f32>() - 0.5) * 2.0 * NOISE_M
    }

    fn wall_point(&self, rng: &mut ChaCha8Rng, w: &Wall, t: f32) -> Point3 {
        let (dx, dy) = (w.x1 - w.x0, w.y1 - w.y0);
        let l = w.len().max(1e-6);
        let n = Self::noise(rng);
        Point3::new(
            w.x0 + dx * t - dy / l * n,
            w.y0 + dy * t + dx / l * n,
            rng.random::<f32>() * HEIGHT_M,
        )
    }

    /// A point anywhere on the site's surfaces: 60 % ground, 40 % walls (by length).
    fn point(&self, rng: &mut ChaCha8Rng) -> Point3 {
        if rng.random::<f32>() < 0.6 {
            Point3::new(
                rng.random::<f32>() * SIDE_M,
                rng.random::<f32>() * SIDE_M,
                Self::noise(rng),
            )
        } else {
            let total = self.cum.last().copied().unwrap_or(1.0);
            let u = rng.random::<f32>() * total;
            let i = self.cum.partition_point(|c| *c < u).min(self.walls.len() - 1);
            let w = self.walls[i];
            let t = rng.random::<f32>();
            self.wall_point(rng, &w, t)
        }
    }

    /// A scan of `n` points seen from (sx, sy): 70 % ground within 12 m (denser near the sensor), 30 % on
    /// walls within 12 m.
    fn scan(&self, rng: &mut ChaCha8Rng, sx: f32, sy: f32, n: usize) -> Vec<Point3> {
        let r = 12.0f32;
        let near: Vec<Wall> = self
            .walls
            .iter()
            .filter(|w| {
                let (mx, my) = (
                    sx.clamp(w.x0.min(w.x1), w.x0.max(w.x1)),
                    sy.clamp(w.y0.min(w.y1), w.y0.max(w.y1)),
                );
                (mx - sx).powi(2) + (my - sy).powi(2) < r * r
            })
            .copied()
            .collect();
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            if near.is_empty() || rng.random::<f32>() < 0.7 {
                let d = r * rng.random::<f32>();
                let a = rng.random::<f32>() * std::f32::consts::TAU;
                out.push(Point3::new(sx + d * a.cos(), sy + d * a.sin(), Self::noise(rng)));
            } else {
                let w = near[rng.random_range(0..near.len())];
                let t = rng.random::<f32>();
                let p = self.wall_point(rng, &w, t);
                if (p.x - sx).powi(2) + (p.y - sy).powi(2) < r * r {
                    out.push(p);
                }
            }
        }
        out
    }
}

/// CPU time of the calling thread in nanoseconds (Linux `/proc/thread-self/schedstat`), 0 elsewhere.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse::<u64>().ok()))
        .unwrap_or(0)
}

fn rss_bytes() -> usize {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1).and_then(|v| v.parse::<usize>().ok()))
        .map_or(0, |pages| pages * 4096)
}

fn arr(p: &Point3) -> [f32; 3] {
    [p.x, p.y, p.z]
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn round(x: f64, digits: i32) -> f64 {
    let f = 10f64.powi(digits);
    (x * f).round() / f
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let scene = Scene::new();
    let mut rng = ChaCha8Rng::seed_from_u64(2021);
    let map: Vec<Point3> = (0..n).map(|_| scene.point(&mut rng)).collect();
    let map_arr: Vec<[f32; 3]> = map.iter().map(arr).collect();
    let scans: Vec<Vec<Point3>> = (0..100)
        .map(|i| {
            let a = i as f32 / 100.0 * std::f32::consts::TAU;
            scene.scan(&mut rng, 50.0 + 30.0 * a.cos(), 50.0 + 30.0 * a.sin(), 10_000)
        })
        .collect();
    let queries: Vec<Point3> = (0..100_000)
        .map(|_| {
            let p = scene.point(&mut rng);
            let mut o = || (rng.random::<f32>() - 0.5) * 1.0;
            Point3::new(p.x + o(), p.y + o(), p.z + o())
        })
        .collect();
    let k5 = NonZeroUsize::MIN.saturating_add(4);

    // ---- ikd-tree ----
    let mut ikd = IkdTree::new(IkdParams::default()).expect("default parameters are valid");
    let t = Instant::now();
    ikd.build(&map);
    let ikd_build_ms = ms(t);
    let ikd_bpp = ikd.memory_bytes() as f64 / ikd.len() as f64;
    let t = Instant::now();
    let c = thread_cpu_ns();
    let mut kept = 0;
    for s in &scans {
        kept += ikd.add_points(s, true);
    }
    let ikd_scan_us = t.elapsed().as_secs_f64() * 1e6 / scans.len() as f64;
    let ikd_scan_cpu_us = (thread_cpu_ns() - c) as f64 / 1e3 / scans.len() as f64;
    ikd.wait_rebuild();
    // The box: a slab along x holding 5 % of the current points.
    let mut xs: Vec<f32> = ikd.flatten().iter().map(|p| p.x).collect();
    xs.sort_by(f32::total_cmp);
    let x5 = xs[xs.len() / 20];
    let del_box = Aabb::new(
        Point3::new(-1.0, -1.0, -1.0),
        Point3::new(x5, SIDE_M + 1.0, HEIGHT_M + 1.0),
    );
    let t = Instant::now();
    let deleted = ikd.delete_box(&del_box);
    let ikd_delete_ms = ms(t);
    ikd.wait_rebuild();
    let ikd_delete_settled_ms = ms(t);
    let t = Instant::now();
    let c = thread_cpu_ns();
    let mut acc = 0.0f32;
    for q in &queries {
        let r = ikd.nearest(q, 5);
        acc += r.last().map_or(0.0, |x| x.1);
    }
    let ikd_knn_ns = t.elapsed().as_secs_f64() * 1e9 / queries.len() as f64;
    let ikd_knn_cpu_ns = (thread_cpu_ns() - c) as f64 / queries.len() as f64;
    black_box(acc);
    let t = Instant::now();
    let mut acc = 0.0f32;
    for q in &queries {
        acc += ikd.nearest_distance(q).unwrap_or(0.0);
    }
    let ikd_nn1_ns = t.elapsed().as_secs_f64() * 1e9 / queries.len() as f64;
    black_box(acc);
    let ikd_bpp_after = ikd.memory_bytes() as f64 / ikd.len() as f64;
    let final_points = ikd.flatten();

    if std::env::var_os("MAP_BENCH_IKD_ONLY").is_some() {
        // Profiling aid: the ikd-tree figures alone, without the slow kiddo runs.
        let out = serde_json::json!({"points": n, "ikd": {
            "build_ms": round(ikd_build_ms, 2), "insert_scan_us": round(ikd_scan_us, 1),
            "insert_scan_cpu_us": round(ikd_scan_cpu_us, 1), "delete_box_ms": round(ikd_delete_ms, 3),
            "knn5_ns": round(ikd_knn_ns, 1), "knn5_cpu_ns": round(ikd_knn_cpu_ns, 1),
            "nearest_distance_ns": round(ikd_nn1_ns, 1),
            "bytes_per_point": round(ikd_bpp, 2), "bytes_per_point_after_updates": round(ikd_bpp_after, 2),
            "rebuilds_in_place": ikd.stats().rebuilds_in_place, "rebuilds_background": ikd.stats().rebuilds_background}});
        println!("{out}");
        return;
    }
    // ---- kiddo mutable ----
    let rss0 = rss_bytes();
    let t = Instant::now();
    let mut km: MutableKdTree<f32, 3> = MutableKdTree::default();
    let mut km_fail = 0usize;
    for (i, p) in map_arr.iter().enumerate() {
        if km.add(p, i as u32).is_err() {
            km_fail += 1;
        }
    }
    let km_build_ms = ms(t);
    let km_bpp = rss_bytes().saturating_sub(rss0) as f64 / n as f64;
    let mut km_points: Vec<([f32; 3], u32)> = map_arr.iter().enumerate().map(|(i, p)| (*p, i as u32)).collect();
    let t = Instant::now();
    for s in &scans {
        for p in s {
            let id = km_points.len() as u32;
            if km.add(&arr(p), id).is_err() {
                km_fail += 1;
            }
        }
    }
    let km_scan_us = t.elapsed().as_secs_f64() * 1e6 / scans.len() as f64;
    for s in &scans {
        for p in s {
            let id = km_points.len() as u32;
            km_points.push((arr(p), id));
        }
    }
    let in_box: Vec<([f32; 3], u32)> = km_points
        .iter()
        .filter(|(p, _)| del_box.contains(&Point3::from(*p)))
        .copied()
        .collect();
    let t = Instant::now();
    for (p, i) in &in_box {
        km.remove(p, *i);
    }
    let km_delete_ms = ms(t);
    let t = Instant::now();
    let mut acc = 0.0f32;
    for q in &queries {
        let r = km.query(&arr(q)).nearest_n::<SquaredEuclidean<f32>>(k5).execute();
        acc += r.last().map_or(0.0, |x| x.distance);
    }
    let km_knn_ns = t.elapsed().as_secs_f64() * 1e9 / queries.len() as f64;
    black_box(acc);
    drop(km);
    drop(km_points);

    // ---- kiddo immutable: rebuild per scan, and queries on the ikd-tree's final points ----
    let rebuilds = 10;
    let mut kr_s = 0.0;
    for s in scans.iter().take(rebuilds) {
        let mut all = map_arr.clone();
        all.extend(s.iter().map(arr));
        let t = Instant::now();
        let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&all).expect("kiddo build");
        kr_s += t.elapsed().as_secs_f64();
        black_box(tree.size());
    }
    let kr_scan_us = kr_s * 1e6 / rebuilds as f64;
    let final_arr: Vec<[f32; 3]> = final_points.iter().map(arr).collect();
    let t = Instant::now();
    let ki: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&final_arr).expect("kiddo build");
    let ki_build_ms = ms(t);
    let t = Instant::now();
    let c = thread_cpu_ns();
    let mut acc = 0.0f32;
    for q in &queries {
        let r = ki.query(&arr(q)).nearest_n::<SquaredEuclidean<f32>>(k5).execute();
        acc += r.last().map_or(0.0, |x| x.distance);
    }
    let ki_knn_ns = t.elapsed().as_secs_f64() * 1e9 / queries.len() as f64;
    let ki_knn_cpu_ns = (thread_cpu_ns() - c) as f64 / queries.len() as f64;
    black_box(acc);
    // kiddo's fastest documented path: caller-owned scratch (alpha API), kept to be fair to it.
    let mut scratch = ki.create_scratch::<SquaredEuclidean<f32>>();
    let t = Instant::now();
    let mut acc = 0.0f32;
    for q in &queries {
        let r = ki
            .query(&arr(q))
            .nearest_n::<SquaredEuclidean<f32>>(k5)
            .with_scratch(&mut scratch)
            .execute();
        acc += r.last().map_or(0.0, |x| x.distance);
    }
    let ki_knn_scratch_ns = t.elapsed().as_secs_f64() * 1e9 / queries.len() as f64;
    black_box(acc);
    black_box(acc);

    // ---- the ikd-Tree paper's randomized protocol ----
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let cube = |rng: &mut ChaCha8Rng, m: usize| -> Vec<Point3> {
        (0..m)
            .map(|_| {
                Point3::new(
                    rng.random::<f32>() * 10.0,
                    rng.random::<f32>() * 10.0,
                    rng.random::<f32>() * 10.0,
                )
            })
            .collect()
    };
    let mut proto = IkdTree::new(IkdParams::default()).expect("default parameters are valid");
    proto.build(&cube(&mut rng, 20_000));
    let (mut upd_s, mut qry_s) = (0.0f64, 0.0f64);
    let ops = 1000;
    for op in 0..ops {
        let ins = cube(&mut rng, 200);
        let qs = cube(&mut rng, 200);
        let boxes: Vec<Aabb> = if op % 50 == 49 {
            cube(&mut rng, 4).into_iter().map(|c| Aabb::around(c, 0.75)).collect()
        } else {
            Vec::new()
        };
        let t = Instant::now();
        proto.add_points(&ins, false);
        for b in &boxes {
            proto.delete_box(b);
        }
        upd_s += t.elapsed().as_secs_f64();
        let t = Instant::now();
        for q in &qs {
            black_box(proto.nearest(q, 5));
        }
        qry_s += t.elapsed().as_secs_f64();
    }

    let out = serde_json::json!({
        "points": n,
        "ikd": {
            "build_ms": round(ikd_build_ms, 2),
            "insert_scan_us": round(ikd_scan_us, 1),
            "delete_box_ms": round(ikd_delete_ms, 3),
            "knn5_ns": round(ikd_knn_ns, 1),
            "nearest_distance_ns": round(ikd_nn1_ns, 1),
            "bytes_per_point": round(ikd_bpp, 2),
            "bytes_per_point_after_updates": round(ikd_bpp_after, 2),
            "delete_box_settled_ms": round(ikd_delete_settled_ms, 3),
            "scan_points_kept": kept,
            "rebuilds_in_place": ikd.stats().rebuilds_in_place,
            "rebuilds_background": ikd.stats().rebuilds_background,
            "deleted_points": deleted,
            "depth": ikd.depth(),
        },
        "kiddo_mutable": {
            "build_ms": round(km_build_ms, 2),
            "insert_scan_us": round(km_scan_us, 1),
            "delete_box_ms": round(km_delete_ms, 3),
            "knn5_ns": round(km_knn_ns, 1),
            "bytes_per_point": round(km_bpp, 2),
            "add_errors": km_fail,
        },
        "kiddo_rebuild": { "insert_scan_us": round(kr_scan_us, 1) },
        "kiddo_immutable": {
            "knn5_ns": round(ki_knn_ns, 1),
            "knn5_scratch_ns": round(ki_knn_scratch_ns, 1),
            "build_ms": round(ki_build_ms, 2),
        },
        "cpu_time": {
            "ikd_insert_scan_us": round(ikd_scan_cpu_us, 1),
            "ikd_knn5_ns": round(ikd_knn_cpu_ns, 1),
            "kiddo_immutable_knn5_ns": round(ki_knn_cpu_ns, 1),
        },
        "load_avg_1m": std::fs::read_to_string("/proc/loadavg").ok().and_then(|s| s.split_whitespace().next().and_then(|v| v.parse::<f64>().ok())),
        "ikd_protocol_update_us": round(upd_s * 1e6 / ops as f64, 1),
        "ikd_protocol_query_us": round(qry_s * 1e6 / ops as f64, 1),
    });
    println!("{out}");
}
