//! Helpers of the bench examples: /metrics scrapes with histogram quantiles, a seeded generator, wall-clock
//! stamps and synthetic clouds of a building of square rooms.

use std::collections::HashMap;
use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::Result;
use shift_proto::ros::Time;

use crate::TestServer;

/// xorshift64*: a seeded, dependency-free generator for the synthetic clouds.
pub struct Rng(pub u64);

impl Rng {
    /// The next value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A building of square rooms: walls every `room_m` metres on a `site_m` × `site_m` site from the origin.
#[derive(Debug, Clone, Copy)]
pub struct Rooms {
    /// Side of the site, metres.
    pub site_m: f64,
    /// Side of a room (the walls' spacing), metres.
    pub room_m: f64,
}

impl Rooms {
    /// Where a ray from (x, y) at angle `a` meets the next wall of the room grid (walls every `room_m`, the
    /// site's border included), with `noise` metres added to its range.
    pub fn ray_hit(&self, x: f64, y: f64, a: f64, noise: f64) -> (f64, f64) {
        let room = self.room_m;
        let (dx, dy) = (a.cos(), a.sin());
        let next = |p: f64, d: f64| {
            if d > 1e-9 {
                (((p / room).floor() + 1.0) * room - p) / d
            } else if d < -1e-9 {
                (((p / room).ceil() - 1.0) * room - p) / d
            } else {
                f64::INFINITY
            }
        };
        let t = next(x, dx).min(next(y, dy)) + noise;
        (x + t * dx, y + t * dy)
    }

    /// A 3-D cloud of `n` wall points seen from (x, y), map frame: rays in random directions with 1 cm of
    /// range noise, 0.1–1.9 m high.
    pub fn cloud(&self, rng: &mut Rng, x: f64, y: f64, n: usize) -> Vec<[f32; 3]> {
        (0..n)
            .map(|_| {
                let a = rng.next_f64() * std::f64::consts::TAU;
                let (hx, hy) = self.ray_hit(x, y, a, (rng.next_f64() - 0.5) * 0.02);
                let z = 0.1 + rng.next_f64() * 1.8;
                [
                    hx.clamp(0.0, self.site_m - 1e-3) as f32,
                    hy.clamp(0.0, self.site_m - 1e-3) as f32,
                    z as f32,
                ]
            })
            .collect()
    }
}

/// The wall clock, nanoseconds since the Unix epoch (0 before it).
pub fn wall_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i64)
}

/// Overwrites the header stamp of a little-endian PointCloud2 CDR payload (bytes 4–11) with `ns`.
pub fn restamp(cdr: &mut [u8], ns: i64) {
    let t = Time::from_ns(ns);
    cdr[4..8].copy_from_slice(&t.sec.to_le_bytes());
    cdr[8..12].copy_from_slice(&t.nanosec.to_le_bytes());
}

/// One scrape of /metrics: plain samples by their full name with labels, plus histogram buckets.
#[derive(Default)]
pub struct Scrape {
    /// Every sample: `name{labels}` → value.
    pub values: HashMap<String, f64>,
}

impl Scrape {
    /// Reads the server's /metrics.
    pub async fn take(server: &TestServer) -> Result<Self> {
        Self::fetch(&server.http, &server.base).await
    }

    /// Reads /metrics of the daemon at `base` (`http://127.0.0.1:PORT`).
    pub async fn fetch(http: &reqwest::Client, base: &str) -> Result<Self> {
        let text = http.get(format!("{base}/metrics")).send().await?.text().await?;
        Ok(Self::parse(&text))
    }

    /// Parses the Prometheus text format.
    pub fn parse(text: &str) -> Self {
        let mut values = HashMap::new();
        for line in text.lines().filter(|l| !l.starts_with('#')) {
            if let Some((k, v)) = line.rsplit_once(' ')
                && let Ok(v) = v.parse::<f64>()
            {
                values.insert(k.to_owned(), v);
            }
        }
        Self { values }
    }

    /// A sample's value; 0 when absent.
    pub fn get(&self, key: &str) -> f64 {
        self.values.get(key).copied().unwrap_or(0.0)
    }

    /// `(le, cumulative count)` of a histogram without labels, ascending, `+Inf` last.
    pub fn buckets(&self, name: &str) -> Vec<(f64, f64)> {
        let prefix = format!("{name}_bucket{{le=\"");
        let mut b: Vec<(f64, f64)> = self
            .values
            .iter()
            .filter_map(|(k, &v)| {
                let le = k.strip_prefix(&prefix)?.strip_suffix("\"}")?;
                let le = if le == "+Inf" { f64::INFINITY } else { le.parse().ok()? };
                Some((le, v))
            })
            .collect();
        b.sort_by(|x, y| x.0.total_cmp(&y.0));
        b
    }
}

/// The `q` quantile of the observations between two scrapes, interpolated inside its bucket (seconds).
pub fn quantile(before: &Scrape, after: &Scrape, name: &str, q: f64) -> Option<f64> {
    let a = after.buckets(name);
    let b = before.buckets(name);
    let diff: Vec<(f64, f64)> = a
        .iter()
        .map(|&(le, n)| (le, n - b.iter().find(|x| x.0 == le).map_or(0.0, |x| x.1)))
        .collect();
    let total = diff.last()?.1;
    if total <= 0.0 {
        return None;
    }
    let rank = q * total;
    let mut prev = (0.0, 0.0);
    for &(le, n) in &diff {
        if n >= rank {
            if le.is_infinite() {
                return Some(prev.0);
            }
            let f = if n > prev.1 {
                (rank - prev.1) / (n - prev.1)
            } else {
                1.0
            };
            return Some(prev.0 + f * (le - prev.0));
        }
        prev = (le, n);
    }
    None
}

/// The `q` quantile of ascending `sorted` (nearest rank); NaN when empty.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}
