//! A site's live obstacle map: the ikd-tree of obstacle points robots report, down-sampled into voxels,
//! bounded in space (the site box), in size (a point cap) and in time (voxels not re-observed within the
//! horizon are deleted). Pure: the daemon decides when to call it and with what clock.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use shift_planner::map::ikd_tree::{Aabb, IkdError, IkdParams, IkdTree, Point3};

/// Knobs of a live map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveMapParams {
    /// Down-sampling voxel side, metres.
    pub voxel_m: f32,
    /// Points below this height (map frame, metres) are floor, not obstacles (3-D clouds only).
    pub z_min_m: f32,
    /// Points above this height are overhead, not obstacles (3-D clouds only).
    pub z_max_m: f32,
    /// Most points the tree may hold; clouds beyond it are dropped and counted.
    pub max_points: usize,
    /// Voxels not re-observed for this long are deleted, milliseconds.
    pub horizon_ms: u64,
}

impl Default for LiveMapParams {
    fn default() -> Self {
        Self {
            voxel_m: 0.05,
            z_min_m: 0.05,
            z_max_m: 2.0,
            max_points: 2_000_000,
            horizon_ms: 600_000,
        }
    }
}

/// What one cloud did to the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IngestReport {
    /// Points offered.
    pub offered: usize,
    /// Points outside the site box or the height band.
    pub filtered: usize,
    /// Points new to the tree after down-sampling.
    pub inserted: usize,
    /// Points refused because the tree is at its cap.
    pub over_cap: usize,
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
    /// Last ingest, milliseconds since the Unix epoch (0 = never).
    pub last_update_ms: u64,
}

type VoxelKey = (i32, i32, i32);

/// A multiply-rotate hasher for voxel keys (three i32s). The default SipHash cost about 15 % of cloud ingest
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

type VoxelMap = HashMap<VoxelKey, u64, BuildHasherDefault<VoxelHasher>>;

/// The live map of one site.
#[derive(Debug)]
pub struct LiveMap {
    params: LiveMapParams,
    bounds: Aabb,
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
        let bounds = Aabb::new(
            Point3::new(x0 as f32, y0 as f32, f32::NEG_INFINITY),
            Point3::new(x1 as f32, y1 as f32, f32::INFINITY),
        );
        Ok(Self {
            params,
            bounds,
            tree,
            seen: VoxelMap::default(),
            stats: LiveMapStats::default(),
        })
    }

    fn key(&self, p: &Point3) -> VoxelKey {
        let v = self.params.voxel_m;
        (
            (p.x / v).floor() as i32,
            (p.y / v).floor() as i32,
            (p.z / v).floor() as i32,
        )
    }

    /// Adds obstacle points given in the map frame, metres. `planar` (2-D scans) skips the height band.
    pub fn ingest(&mut self, points: &[[f64; 3]], planar: bool, now_ms: u64) -> IngestReport {
        let mut report = IngestReport {
            offered: points.len(),
            ..IngestReport::default()
        };
        let mut keep = Vec::with_capacity(points.len());
        for p in points {
            let q = Point3::new(p[0] as f32, p[1] as f32, p[2] as f32);
            let in_band = planar || (q.z >= self.params.z_min_m && q.z <= self.params.z_max_m);
            if q.is_finite() && in_band && self.bounds.contains(&q) {
                keep.push(q);
            } else {
                report.filtered += 1;
            }
        }
        let room = self.params.max_points.saturating_sub(self.tree.len());
        if keep.len() > room {
            report.over_cap = keep.len() - room;
            keep.truncate(room);
        }
        for q in &keep {
            let k = self.key(q);
            self.seen.insert(k, now_ms);
        }
        report.inserted = self.tree.add_points(&keep, true);
        self.stats.clouds += 1;
        self.stats.points_offered += points.len() as u64;
        self.stats.points_over_cap += report.over_cap as u64;
        self.stats.last_update_ms = now_ms;
        self.stats.points = self.tree.len();
        report
    }

    /// Deletes voxels not re-observed within the horizon; returns how many points went.
    pub fn expire(&mut self, now_ms: u64) -> usize {
        let horizon = self.params.horizon_ms;
        let stale: Vec<VoxelKey> = self
            .seen
            .iter()
            .filter(|&(_, &t)| now_ms.saturating_sub(t) > horizon)
            .map(|(&k, _)| k)
            .collect();
        let v = self.params.voxel_m;
        let mut removed = 0;
        for k in stale {
            self.seen.remove(&k);
            let min = Point3::new(k.0 as f32 * v, k.1 as f32 * v, k.2 as f32 * v);
            let max = Point3::new(min.x + v, min.y + v, min.z + v);
            removed += self.tree.delete_box(&Aabb::new(min, max));
        }
        self.stats.points_expired += removed as u64;
        self.stats.points = self.tree.len();
        removed
    }

    /// The tree, for distance queries (IKD-SWOpt, the occupancy overlay).
    pub fn tree(&self) -> &IkdTree {
        &self.tree
    }

    /// Running totals.
    pub fn stats(&self) -> LiveMapStats {
        self.stats
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
        let r = m.ingest(&pts, false, 10);
        assert_eq!(r.filtered, 4);
        assert_eq!(m.tree().len(), 1);
        // A 2-D scan ignores the band.
        m.ingest(&[[2.0, 2.0, 0.0]], true, 11);
        assert_eq!(m.tree().len(), 2);
        assert_eq!(m.stats().clouds, 2);
    }

    #[test]
    fn cap_drops_and_counts() {
        let mut m = map();
        let pts: Vec<[f64; 3]> = (0..150)
            .map(|i| [0.1 + (i % 15) as f64 * 0.5, 0.1 + (i / 15) as f64 * 0.5, 0.5])
            .collect();
        let r = m.ingest(&pts, false, 1);
        assert_eq!(r.over_cap, 50);
        assert_eq!(m.tree().len(), 100);
    }

    #[test]
    fn horizon_expires_only_stale_voxels() {
        let mut m = map();
        m.ingest(&[[1.0, 1.0, 0.5]], false, 0);
        m.ingest(&[[5.0, 5.0, 0.5]], false, 900);
        assert_eq!(m.expire(1500), 1);
        assert_eq!(m.tree().len(), 1);
        let near = m.tree().nearest(&Point3::new(5.0, 5.0, 0.5), 1);
        assert_eq!(near.len(), 1);
    }
}
