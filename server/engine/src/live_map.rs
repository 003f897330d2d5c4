//! A site's live obstacle map: the ikd-tree of obstacle points robots report, down-sampled into voxels,
//! bounded in space (the site box), in size (a point cap) and in time (voxels not re-observed within the
//! horizon are deleted). Pure: the daemon decides when to call it and with what clock.
//!
//! Points inside the obstacle height band are projected to the ground plane and stored relative to the site's
//! corner ([`LivePoints`]): obstacles are 2-D for coverage and corrections, a column of points is one
//! obstacle, and `f32` keeps millimetres even on georeferenced sites (UTM, state-plane feet).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;

use shift_planner::geom::Point2;
use shift_planner::map::ikd_tree::{Aabb, IkdError, IkdParams, IkdTree, Point3};
use shift_planner::map::{DistanceField, LivePoints};
use shift_planner::terrain::TerrainSurface;

use crate::sensors::geometry::Heights;
use crate::sensors::sweep::Sweep;

/// Knobs of a live map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveMapParams {
    /// Down-sampling voxel side, metres.
    pub voxel_m: f32,
    /// Points below this height are floor, not obstacles (3-D clouds only), metres: over the map frame's z = 0,
    /// or over the ground on a terrain site ([`LiveMap::set_ground`]).
    pub z_min_m: f32,
    /// Points above this height are overhead, not obstacles (3-D clouds only), metres, measured as `z_min_m`.
    pub z_max_m: f32,
    /// Most points the tree may hold; clouds beyond it are dropped and counted.
    pub max_points: usize,
    /// Voxels not re-observed for this long are deleted, milliseconds.
    pub horizon_ms: u64,
    /// Points within this distance of a non-free cell of the site's static map are that obstacle seen
    /// again (walls, known furniture; the slack absorbs localisation error), not new obstacles: they are
    /// not stored, metres. 0 keeps everything.
    pub known_tolerance_m: f32,
    /// A scan clears the scan points its rays saw through by more than this, metres (range noise and pose
    /// error; see [`crate::sensors::sweep`]). 0 turns clearing off: points then leave only by the horizon.
    pub clear_margin_m: f32,
}

impl Default for LiveMapParams {
    fn default() -> Self {
        Self {
            voxel_m: 0.05,
            z_min_m: 0.05,
            z_max_m: 2.0,
            max_points: 2_000_000,
            horizon_ms: 600_000,
            known_tolerance_m: 0.1,
            clear_margin_m: 0.1,
        }
    }
}

/// What one cloud did to the map.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IngestReport {
    /// Points offered.
    pub offered: usize,
    /// Points outside the site box or the height band.
    pub filtered: usize,
    /// Points on obstacles the static map already has (within `known_tolerance_m`).
    pub known: usize,
    /// Points new to the tree after down-sampling.
    pub inserted: usize,
    /// Points refused because the tree is at its cap.
    pub over_cap: usize,
    /// Ground-plane box `[min, max]` (metres) of the points kept, when any were.
    pub extent: Option<([f64; 2], [f64; 2])>,
}

/// Running totals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LiveMapStats {
    /// Points in the tree.
    pub points: usize,
    /// Clouds ingested.
    pub clouds: u64,
    /// Points offered in total.
    pub points_offered: u64,
    /// Points refused at the cap in total.
    pub points_over_cap: u64,
    /// Points deleted by the horizon in total.
    pub points_expired: u64,
    /// Points deleted because a scan saw through them, in total.
    pub points_cleared: u64,
    /// Last ingest, milliseconds since the Unix epoch (0 = never).
    pub last_update_ms: u64,
}

/// A ground-plane voxel (column) of the tree's frame.
type VoxelKey = (i32, i32);

/// When a voxel was last seen, and whether a 3-D cloud saw it (a planar laser sweeping under a table top must
/// not clear what a cloud saw on it).
#[derive(Debug, Clone, Copy)]
struct Seen {
    ms: u64,
    by_cloud: bool,
}

/// A multiply-rotate hasher for voxel keys (two i32s). The default SipHash cost about 15 % of cloud ingest
/// (one look-up per point); keys are map coordinates, not attacker-chosen strings, so a fast hash is fine.
#[derive(Debug, Default, Clone, Copy)]
struct VoxelHasher(u64);

impl Hasher for VoxelHasher {
    fn finish(&self) -> u64 {
        // Spread the high bits down: hashbrown takes its bucket from the low bits and its tag from the top 7.
        let h = self.0.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        h ^ (h >> 29)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_i32(&mut self, v: i32) {
        self.write_u64(u64::from(v as u32));
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(21) ^ v).wrapping_mul(0x517C_C1B7_2722_0A95);
    }
}

type VoxelMap = HashMap<VoxelKey, Seen, BuildHasherDefault<VoxelHasher>>;

/// The live map of one site.
#[derive(Debug)]
pub struct LiveMap {
    params: LiveMapParams,
    /// Map-frame position of the tree's (0, 0): the site's lower-left corner.
    origin: Point2,
    /// The site box in the tree's frame.
    bounds: Aabb,
    known: Option<Arc<DistanceField>>,
    ground: Option<Arc<TerrainSurface>>,
    tree: IkdTree,
    seen: VoxelMap,
    stats: LiveMapStats,
}

impl LiveMap {
    /// An empty map for a site whose map covers `[x0, x1] × [y0, y1]` metres (map frame).
    pub fn new(params: LiveMapParams, x0: f64, y0: f64, x1: f64, y1: f64) -> Result<Self, IkdError> {
        let tree = IkdTree::new(IkdParams {
            voxel_size: params.voxel_m,
            ..IkdParams::default()
        })?;
        let origin = Point2::new(x0, y0);
        let bounds = Aabb::new(
            Point3::new(0.0, 0.0, f32::NEG_INFINITY),
            Point3::new((x1 - x0) as f32, (y1 - y0) as f32, f32::INFINITY),
        );
        Ok(Self {
            params,
            origin,
            bounds,
            known: None,
            ground: None,
            tree,
            seen: VoxelMap::default(),
            stats: LiveMapStats::default(),
        })
    }

    /// The voxel of a point of the tree.
    fn key(&self, p: &Point3) -> VoxelKey {
        let v = self.params.voxel_m;
        ((p.x / v).floor() as i32, (p.y / v).floor() as i32)
    }

    /// Sets the static map's clearance field (distance to its non-free cells): points it explains are not
    /// stored from now on (see [`LiveMapParams::known_tolerance_m`]). `None` stores every point.
    pub fn set_static(&mut self, clearance: Option<Arc<DistanceField>>) {
        self.known = clearance;
    }

    /// Sets the site's ground (a terrain site's elevation map): the height band of 3-D clouds is then measured
    /// over the ground under each point, not over z = 0, so a robot on a hill 130 m above the datum still sees
    /// the post in front of it. Points beyond the map's domain take the height of its nearest edge. `None`
    /// measures over z = 0 (flat sites).
    pub fn set_ground(&mut self, ground: Option<Arc<TerrainSurface>>) {
        self.ground = ground;
    }

    /// Height of the ground under map-frame (x, y), metres (0 without a ground).
    fn ground_at(&self, x: f64, y: f64) -> f64 {
        self.ground.as_ref().and_then(|s| s.height_clamped(x, y)).unwrap_or(0.0)
    }

    /// Adds obstacle points given in the map frame, metres, whose z measures `heights` (2-D scans skip the
    /// height band). Kept points are stored in the ground plane.
    pub fn ingest(&mut self, points: &[[f64; 3]], heights: Heights, now_ms: u64) -> IngestReport {
        let mut report = IngestReport {
            offered: points.len(),
            ..IngestReport::default()
        };
        let mut keep = Vec::with_capacity(points.len());
        for p in points {
            let over = match heights {
                Heights::Planar => None,
                Heights::MapFrame => Some(p[2] - self.ground_at(p[0], p[1])),
                Heights::OverGround => Some(p[2]),
            };
            let q = LivePoints::to_local(self.origin, Point2::new(p[0], p[1]));
            let in_band = over.is_none_or(|h| {
                let h = h as f32;
                h >= self.params.z_min_m && h <= self.params.z_max_m
            });
            if !(q.is_finite() && in_band && self.bounds.contains(&q)) {
                report.filtered += 1;
            } else if self
                .known
                .as_ref()
                .is_some_and(|f| f.at_point(Point2::new(p[0], p[1])) <= f64::from(self.params.known_tolerance_m))
            {
                report.known += 1;
            } else {
                keep.push(q);
            }
        }
        let room = self.params.max_points.saturating_sub(self.tree.len());
        if keep.len() > room {
            report.over_cap = keep.len() - room;
            keep.truncate(room);
        }
        let by_cloud = heights != Heights::Planar;
        for q in &keep {
            let k = self.key(q);
            let seen = self.seen.entry(k).or_insert(Seen { ms: now_ms, by_cloud });
            seen.ms = now_ms;
            seen.by_cloud |= by_cloud;
            let (x, y) = (self.origin.x + f64::from(q.x), self.origin.y + f64::from(q.y));
            let e = report.extent.get_or_insert(([x, y], [x, y]));
            e.0 = [e.0[0].min(x), e.0[1].min(y)];
            e.1 = [e.1[0].max(x), e.1[1].max(y)];
        }
        report.inserted = self.tree.add_points(&keep, true);
        self.stats.clouds += 1;
        self.stats.points_offered += points.len() as u64;
        self.stats.points_over_cap += report.over_cap as u64;
        self.stats.last_update_ms = now_ms;
        self.stats.points = self.tree.len();
        report
    }

    /// Deletes the scan points that `sweep`'s rays saw through by more than `clear_margin_m`: an obstacle that
    /// moved away (a person, a trolley) or was never there (a reflection). Voxels a 3-D cloud saw are left to the
    /// horizon: a planar laser does not see their heights. Returns how many points went.
    pub fn clear_through(&mut self, sweep: &Sweep) -> usize {
        let margin = f64::from(self.params.clear_margin_m);
        let reach = sweep.max_reach();
        if margin <= 0.0 || reach <= margin || self.tree.is_empty() {
            return 0;
        }
        let c = LivePoints::to_local(self.origin, Point2::new(sweep.origin[0], sweep.origin[1]));
        let r = reach as f32;
        let near = Aabb::new(
            Point3::new(c.x - r, c.y - r, f32::NEG_INFINITY),
            Point3::new(c.x + r, c.y + r, f32::INFINITY),
        );
        let mut gone = self.tree.within_box(&near);
        gone.retain(|p| {
            let by_cloud = self.seen.get(&self.key(p)).is_some_and(|s| s.by_cloud);
            let at = [self.origin.x + f64::from(p.x), self.origin.y + f64::from(p.y)];
            !by_cloud && sweep.sees_past(at, margin)
        });
        for p in &gone {
            let k = self.key(p);
            self.seen.remove(&k);
        }
        let removed = self.tree.delete_points(&gone);
        self.stats.points_cleared += removed as u64;
        self.stats.points = self.tree.len();
        removed
    }

    /// Deletes voxel `k`'s points. The box is widened by two ulps each way: a point's key is `floor(p / v)` in
    /// f32, and `k * v` rounded may land a hair past a point on the voxel's edge (3.6 m at 5 cm: key 71, box
    /// up to 3.5999998), which would then never expire.
    fn delete_voxel(&mut self, k: VoxelKey) -> usize {
        self.seen.remove(&k);
        let v = f64::from(self.params.voxel_m);
        let lo = |i: i32| ((f64::from(i) * v) as f32).next_down().next_down();
        let hi = |i: i32| ((f64::from(i + 1) * v) as f32).next_up().next_up();
        let min = Point3::new(lo(k.0), lo(k.1), f32::NEG_INFINITY);
        let max = Point3::new(hi(k.0), hi(k.1), f32::INFINITY);
        self.tree.delete_box(&Aabb::new(min, max))
    }

    /// Deletes voxels not re-observed within the horizon; returns how many points went.
    pub fn expire(&mut self, now_ms: u64) -> usize {
        let horizon = self.params.horizon_ms;
        let stale: Vec<VoxelKey> = self
            .seen
            .iter()
            .filter(|&(_, s)| now_ms.saturating_sub(s.ms) > horizon)
            .map(|(&k, _)| k)
            .collect();
        let mut removed = 0;
        for k in stale {
            removed += self.delete_voxel(k);
        }
        self.stats.points_expired += removed as u64;
        self.stats.points = self.tree.len();
        removed
    }

    /// The points, for distance queries (IKD-SWOpt, the occupancy overlay, the API), each standing for its
    /// voxel (see [`LivePoints::voxels`]).
    pub fn points(&self) -> LivePoints<'_> {
        LivePoints::voxels(&self.tree, self.origin)
    }

    /// Points held.
    pub fn len(&self) -> usize {
        self.tree.len()
    }

    /// True when no point is held.
    pub fn is_empty(&self) -> bool {
        self.tree.is_empty()
    }

    /// Running totals.
    pub fn stats(&self) -> LiveMapStats {
        self.stats
    }

    /// Heap bytes held: the tree's ([`IkdTree::memory_bytes`]) and the voxels' last-seen times (buckets of key,
    /// time and hashbrown's control byte, by capacity: what the allocator holds). The static map's distance field
    /// is shared with the site and not counted.
    pub fn memory_bytes(&self) -> usize {
        let bucket = size_of::<VoxelKey>() + size_of::<Seen>() + 1;
        self.tree.memory_bytes() + self.seen.capacity() * bucket
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> LiveMap {
        LiveMap::new(
            LiveMapParams {
                max_points: 100,
                horizon_ms: 1000,
                ..LiveMapParams::default()
            },
            0.0,
            0.0,
            10.0,
            10.0,
        )
        .expect("valid params")
    }

    #[test]
    fn memory_follows_the_points_held_and_counts_the_voxel_times() {
        let mut m = map();
        let empty = m.memory_bytes();
        assert!(empty >= m.tree.memory_bytes());
        let points: Vec<[f64; 3]> = (0..80)
            .map(|i| [0.5 + 0.1 * f64::from(i % 9), 0.5 + 0.1 * f64::from(i / 9), 0.5])
            .collect();
        m.ingest(&points, Heights::MapFrame, 0);
        let full = m.memory_bytes();
        let voxels = m.seen.len() * (size_of::<VoxelKey>() + size_of::<Seen>());
        assert!(
            full >= m.tree.memory_bytes() + voxels,
            "{full} bytes for {} voxels",
            m.seen.len()
        );
        assert!(full > empty, "{empty} → {full}");
    }

    #[test]
    fn filters_band_and_box_and_downsamples() {
        let mut m = map();
        let pts = [
            [1.02, 1.02, 0.52], // kept
            [1.03, 1.03, 0.53], // same 5 cm voxel: down-sampled away
            [1.0, 1.0, 0.01],   // floor
            [1.0, 1.0, 3.0],    // overhead
            [20.0, 1.0, 0.5],   // outside the site
            [f64::NAN, 1.0, 0.5],
        ];
        let r = m.ingest(&pts, Heights::MapFrame, 10);
        assert_eq!(r.filtered, 4);
        let e = r.extent.expect("two points kept");
        assert!((e.0[0] - 1.02).abs() < 1e-6 && (e.1[1] - 1.03).abs() < 1e-6, "{e:?}");
        assert_eq!(m.tree.len(), 1);
        // A 2-D scan ignores the band.
        m.ingest(&[[2.0, 2.0, 0.0]], Heights::Planar, 11);
        assert_eq!(m.tree.len(), 2);
        assert_eq!(m.stats().clouds, 2);
    }

    #[test]
    fn on_a_terrain_site_the_band_is_over_the_ground() {
        use shift_planner::map::GridGeometry;
        // A slope 130 m above the datum: z = 130 + 0.2 x over [0, 10] m.
        let g = GridGeometry::new(20, 20, 0.5, Point2::new(0.0, 0.0)).expect("geometry");
        let hill = TerrainSurface::from_fn(g, |x, _| 130.0 + 0.2 * x).expect("surface");
        let mut m = map();
        let post = [5.0, 5.0, 131.0 + 0.3]; // 0.3 m over the ground at x = 5
        assert_eq!(
            m.ingest(&[post], Heights::MapFrame, 0).filtered,
            1,
            "over z = 0 it is overhead"
        );
        m.set_ground(Some(Arc::new(hill)));
        let pts = [
            post,
            [5.0, 7.0, 131.02],       // the ground itself
            [5.0, 3.0, 131.0 + 2.5],  // a branch overhead
            [9.9, 1.0, 131.95 + 0.5], // beyond the last cell centre (9.75 m): that edge's ground, 0.5 m up
            [0.1, 1.0, 130.05 + 0.5], // before the first (0.25 m): likewise
        ];
        let r = m.ingest(&pts, Heights::MapFrame, 1);
        assert_eq!((r.filtered, r.inserted), (2, 3), "{r:?}");
        // A robot-frame cloud's z is over the ground already: 0.3 m up is an obstacle, 0.01 m up is the ground.
        let r = m.ingest(&[[2.0, 5.0, 0.3], [2.0, 6.0, 0.01]], Heights::OverGround, 2);
        assert_eq!((r.filtered, r.inserted), (1, 1), "{r:?}");
        // Scans (planar) are obstacles at any height, as before.
        assert_eq!(m.ingest(&[[2.0, 2.0, 0.0]], Heights::Planar, 3).inserted, 1);
    }

    #[test]
    fn a_georeferenced_site_keeps_its_points_to_the_millimetre() {
        // A UTM-sized site: f32 map-frame coordinates would be 0.5 m apart at this northing.
        let (x0, y0) = (512_000.0, 5_123_000.0);
        let mut m = LiveMap::new(LiveMapParams::default(), x0, y0, x0 + 100.0, y0 + 100.0).expect("valid");
        let p = [x0 + 40.012, y0 + 60.037, 0.4];
        assert_eq!(m.ingest(&[p], Heights::MapFrame, 0).inserted, 1);
        let got = m.points().all();
        assert!((got[0] - Point2::new(p[0], p[1])).norm() < 1e-3, "{got:?} for {p:?}");
        let q = Point2::new(p[0] + 0.3, p[1]);
        let (near, d) = LivePoints::new(&m.tree, m.origin).nearest(q).expect("a point");
        assert!(
            (d - 0.3).abs() < 1e-3 && (near.x - p[0]).abs() < 1e-3,
            "{near:?} at {d}"
        );
        // Read as voxels (what corrections read), the distance is to the point's 5 cm square: 40.012 lies in
        // [40.00, 40.05], so the square's near edge is 0.262 m away.
        let (near, d) = m.points().nearest(q).expect("a point");
        assert!(
            (d - 0.262).abs() < 1e-3 && (near.x - (x0 + 40.05)).abs() < 1e-3,
            "{near:?} at {d}"
        );
        // Outside the site box: refused, wherever it is.
        assert_eq!(m.ingest(&[[x0 - 1.0, y0 + 1.0, 0.4]], Heights::MapFrame, 0).filtered, 1);
    }

    #[test]
    fn points_on_static_obstacles_are_not_new() {
        use shift_planner::map::{CellState, GridGeometry, OccupancyGrid};
        let g = GridGeometry::new(100, 100, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(5.0, 0.0, 5.1, 10.0, CellState::Occupied); // a wall at x ∈ [5, 5.1]
        let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
        let mut m = map();
        m.set_static(Some(Arc::new(field)));
        // On the wall, 5 cm off it (localisation error), and a new box 1 m away.
        let r = m.ingest(
            &[[5.05, 3.0, 0.5], [4.97, 4.0, 0.5], [4.0, 3.0, 0.5]],
            Heights::MapFrame,
            1,
        );
        assert_eq!((r.known, r.inserted), (2, 1), "{r:?}");
        assert_eq!(m.tree.len(), 1);
    }

    #[test]
    fn cap_drops_and_counts() {
        let mut m = map();
        let pts: Vec<[f64; 3]> = (0..150)
            .map(|i| [0.1 + (i % 15) as f64 * 0.5, 0.1 + (i / 15) as f64 * 0.5, 0.5])
            .collect();
        let r = m.ingest(&pts, Heights::MapFrame, 1);
        assert_eq!(r.over_cap, 50);
        assert_eq!(m.tree.len(), 100);
    }

    #[test]
    fn horizon_expires_only_stale_voxels() {
        let mut m = map();
        m.ingest(&[[1.0, 1.0, 0.5]], Heights::MapFrame, 0);
        m.ingest(&[[5.0, 5.0, 0.5]], Heights::MapFrame, 900);
        assert_eq!(m.expire(1500), 1);
        assert_eq!(m.tree.len(), 1);
        let near = m.tree.nearest(&Point3::new(5.0, 5.0, 0.5), 1);
        assert_eq!(near.len(), 1);
    }

    /// The sweep of a laser at (2, 3) facing +x whose rays start at `angle_min`, `increment` apart.
    fn sweep_from_2_3(ranges: Vec<f32>, angle_min: f32, increment: f32) -> Sweep {
        let scan = crate::sensors::sweep::test_scan(ranges, angle_min, increment);
        let pose = crate::robots::Pose2 {
            x: 2.0,
            y: 3.0,
            yaw: 0.0,
            stamp_ns: 0,
        };
        Sweep::of_scan(&scan, pose, crate::sensors::geometry::SensorOffset::default()).expect("usable")
    }

    #[test]
    fn a_scan_clears_the_trail_it_sees_through_and_keeps_what_it_hits() {
        let mut m = map();
        // A walker's trail across an aisle at x = 5 (scan points), and a table top beside it seen by a 3-D cloud
        // (0.5 m up, where the laser's rays pass under it).
        let trail: Vec<[f64; 3]> = (0..20).map(|i| [5.0, 2.0 + f64::from(i) * 0.1, 0.0]).collect();
        m.ingest(&trail, Heights::Planar, 1);
        m.ingest(&[[5.3, 2.45, 0.5]], Heights::MapFrame, 1);
        let before = m.tree.len();
        assert_eq!(before, 21);
        // A laser at (2, 3) looking along +x over ±30°, every ray returning at 6 m (the far wall at x = 8),
        // except the one along +x, which returns at 3 m: the walker standing at (5, 3) now.
        let rays = 61;
        let mut ranges = vec![6.0_f32; rays];
        ranges[30] = 3.0;
        let sweep = sweep_from_2_3(ranges, -30f32.to_radians(), 1f32.to_radians());
        let cleared = m.clear_through(&sweep);
        // Kept: the 3-D point, the walker's own return (its ray stopped there) and the trail points next to it
        // whose neighbouring ray is the short one.
        let kept = m.points().all();
        let table = |p: &Point2| (p.x - 5.3).abs() < 0.01 && (p.y - 2.45).abs() < 0.01;
        assert!(kept.iter().any(table), "what a cloud saw is left to the horizon");
        assert!(
            kept.iter().any(|p| (p.y - 3.0).abs() < 0.01),
            "the walker now: {kept:?}"
        );
        assert!(
            kept.iter().all(|p| table(p) || (p.y - 3.0).abs() < 0.1),
            "the trail went: {kept:?}"
        );
        assert_eq!(cleared, before - kept.len());
        assert_eq!(m.stats().points_cleared, cleared as u64);
        // The horizon does not count what was cleared, and a cleared voxel can come back.
        assert_eq!(m.expire(5000), kept.len());
        assert_eq!(m.ingest(&trail[..1], Heights::Planar, 6000).inserted, 1);
    }

    #[test]
    fn points_on_a_voxel_edge_expire() {
        let mut m = map();
        // 3.6 / 0.05 is 71.99999 in f32: the point's voxel is 71, whose far edge rounds to 3.5999998.
        m.ingest(
            &[[5.0, 3.6, 0.0], [1.0, 0.15, 0.0], [2.0, 2.0, 0.0]],
            Heights::Planar,
            0,
        );
        assert_eq!(m.tree.len(), 3);
        assert_eq!(m.expire(5000), 3);
        assert!(m.tree.is_empty());
    }

    #[test]
    fn no_clearing_with_a_zero_margin() {
        let mut m = LiveMap::new(
            LiveMapParams {
                clear_margin_m: 0.0,
                ..LiveMapParams::default()
            },
            0.0,
            0.0,
            10.0,
            10.0,
        )
        .expect("valid params");
        m.ingest(&[[5.0, 3.0, 0.0]], Heights::Planar, 1);
        let sweep = sweep_from_2_3(vec![6.0; 3], -0.1, 0.1);
        assert_eq!(m.clear_through(&sweep), 0);
        assert_eq!(m.tree.len(), 1);
    }
}
