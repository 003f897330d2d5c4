//! Every site's live map, shared between threads: the pure [`LiveMap`] behind a lock (one writer: the daemon's
//! ingest thread; many readers: path checks, plan jobs' overlays, the API), plus the rates and drop counters the
//! API shows. Created at the first points routed to a site, for the extent of the site's map.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};

use shift_planner::map::DistanceField;
use shift_planner::terrain::TerrainSurface;
use shift_proto::SiteSummary;

use crate::live_map::{LiveMap, LiveMapParams};

/// One site's live map.
#[derive(Debug)]
pub struct SiteLive {
    /// The map.
    pub map: RwLock<LiveMap>,
    recent_ms: Mutex<VecDeque<u64>>,
    /// Clouds and scans dropped for this site (queue overflow, malformed, no map, no pose at their stamp).
    pub dropped: AtomicU64,
    /// Last horizon pass, milliseconds since the Unix epoch.
    pub last_expire_ms: AtomicU64,
}

/// Window over which updates/s is measured, milliseconds.
const RATE_WINDOW_MS: u64 = 10_000;

impl SiteLive {
    /// Records one ingested cloud at `now_ms`.
    pub fn mark_update(&self, now_ms: u64) {
        if let Ok(mut q) = self.recent_ms.lock() {
            q.push_back(now_ms);
            while q.front().is_some_and(|&t| now_ms.saturating_sub(t) > RATE_WINDOW_MS) {
                q.pop_front();
            }
        }
    }

    /// Clouds per second over the last window.
    pub fn updates_per_s(&self, now_ms: u64) -> f64 {
        self.recent_ms.lock().map_or(0.0, |q| {
            let n = q
                .iter()
                .filter(|&&t| now_ms.saturating_sub(t) <= RATE_WINDOW_MS)
                .count();
            n as f64 / (RATE_WINDOW_MS as f64 / 1e3)
        })
    }
}

/// Every site's live map, created at the first cloud for the site (its box comes from the site's map).
#[derive(Debug, Default)]
pub struct LiveMaps {
    sites: RwLock<HashMap<String, Arc<SiteLive>>>,
    /// Each site's static map as live maps use it.
    statics: RwLock<HashMap<String, SiteStatic>>,
}

/// What a live map takes from its site's static map.
#[derive(Debug, Clone)]
struct SiteStatic {
    /// Distance to the static map's obstacles: points it explains are not new.
    clearance: Arc<DistanceField>,
    /// A terrain site's ground: the obstacle height band is measured over it.
    ground: Option<Arc<TerrainSurface>>,
}

impl SiteStatic {
    fn apply(&self, map: &mut LiveMap) {
        map.set_static(Some(self.clearance.clone()));
        map.set_ground(self.ground.clone());
    }
}

impl LiveMaps {
    /// The site's live map, if it has one.
    pub fn get(&self, site: &str) -> Option<Arc<SiteLive>> {
        self.sites.read().ok()?.get(site).cloned()
    }

    /// Sets a site's static map (at upload and restore): its clearance field and, on a terrain site, its ground.
    /// Its live map, if any, uses them from now on.
    pub fn set_static(&self, site: &str, clearance: Arc<DistanceField>, ground: Option<Arc<TerrainSurface>>) {
        let stat = SiteStatic { clearance, ground };
        if let Some(live) = self.get(site)
            && let Ok(mut map) = live.map.write()
        {
            stat.apply(&mut map);
        }
        if let Ok(mut statics) = self.statics.write() {
            statics.insert(site.to_owned(), stat);
        }
    }

    /// The site's live map, created for `summary`'s extent when missing.
    pub fn get_or_create(&self, summary: &SiteSummary, params: LiveMapParams) -> Option<Arc<SiteLive>> {
        if let Some(s) = self.get(&summary.site) {
            return Some(s);
        }
        let (x0, y0) = (summary.origin[0], summary.origin[1]);
        let x1 = x0 + summary.width as f64 * summary.resolution;
        let y1 = y0 + summary.height as f64 * summary.resolution;
        let mut map = LiveMap::new(params, x0, y0, x1, y1).ok()?;
        if let Some(stat) = self.statics.read().ok()?.get(&summary.site) {
            stat.apply(&mut map);
        }
        let live = Arc::new(SiteLive {
            map: RwLock::new(map),
            recent_ms: Mutex::new(VecDeque::new()),
            dropped: AtomicU64::new(0),
            last_expire_ms: AtomicU64::new(0),
        });
        let mut sites = self.sites.write().ok()?;
        Some(sites.entry(summary.site.clone()).or_insert(live).clone())
    }

    /// Heap bytes held by every site's live map ([`LiveMap::memory_bytes`]) and by the static clearance fields
    /// they filter with (one per site, shared with the site's map), in that order.
    pub fn memory_bytes(&self) -> (usize, usize) {
        let live = self.sites.read().map_or(0, |sites| {
            sites
                .values()
                .filter_map(|s| s.map.read().ok().map(|m| m.memory_bytes()))
                .sum()
        });
        let statics = self
            .statics
            .read()
            .map_or(0, |f| f.values().map(|d| d.clearance.memory_bytes()).sum());
        (live, statics)
    }

    /// Fills the live fields of a site summary.
    pub fn annotate(&self, summary: &mut SiteSummary, now_ms: u64) {
        if let Some(live) = self.get(&summary.site)
            && let Ok(map) = live.map.read()
        {
            let st = map.stats();
            summary.points_in_tree = st.points as u64;
            summary.updated_ms = summary.updated_ms.max(st.last_update_ms);
            summary.updates_per_s = live.updates_per_s(now_ms);
            summary.dropped_clouds = live.dropped.load(Ordering::Relaxed);
        }
    }
}
