//! A site's occupancy as a `foxglove.Grid` (JSON): the static map's cells and the live map's obstacle points
//! rasterised onto them, so Foxglove shows what the daemon believes. Two fields per cell: `occupancy` (int8:
//! -1 unknown, 0 free, 100 occupied, as nav_msgs/OccupancyGrid) and `live` (uint8: 100 where the live map holds
//! an obstacle point, else 0). Large maps are coarsened to at most [`MAX_CELLS`] cells (occupied wins, then
//! free, then unknown).

use serde_json::{Value, json};
use shift_engine::CoverageRecord;
use shift_planner::map::grid::{CellState, OccupancyGrid};

/// Most cells one grid message holds.
pub const MAX_CELLS: usize = 1 << 20;

/// foxglove.NumericType codes.
const UINT8: u8 = 1;
const INT8: u8 = 2;

/// The grid message for `grid` plus `live` obstacle points `(x, y)` (map frame, metres) at `stamp_ns`.
pub fn occupancy_grid(grid: &OccupancyGrid, live: &[(f64, f64)], frame: &str, stamp_ns: u64) -> Value {
    let g = grid.geometry;
    let mut k = 1usize;
    while g.width.div_ceil(k) * g.height.div_ceil(k) > MAX_CELLS {
        k += 1;
    }
    let (w, h) = (g.width.div_ceil(k), g.height.div_ceil(k));
    let mut data = vec![0u8; w * h * 2];
    // Rank: unknown 0 < free 1 < occupied 2; a coarse cell takes its highest-ranked fine cell.
    let mut rank = vec![0u8; w * h];
    for (i, c) in grid.cells.iter().enumerate() {
        let (x, y) = (i % g.width / k, i / g.width / k);
        let r = match c {
            CellState::Unknown => 0,
            CellState::Free => 1,
            CellState::Occupied => 2,
        };
        let slot = &mut rank[y * w + x];
        *slot = (*slot).max(r);
    }
    for (i, r) in rank.iter().enumerate() {
        let v: i8 = match r {
            0 => -1,
            1 => 0,
            _ => 100,
        };
        data[i * 2] = v.to_le_bytes()[0];
    }
    let cell = g.resolution * k as f64;
    for &(px, py) in live {
        let fx = (px - g.origin.x) / cell;
        let fy = (py - g.origin.y) / cell;
        if fx >= 0.0 && fy >= 0.0 && (fx as usize) < w && (fy as usize) < h {
            data[(fy as usize * w + fx as usize) * 2 + 1] = 100;
        }
    }
    json!({
        "timestamp": {"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000},
        "frame_id": frame,
        "pose": {
            "position": {"x": g.origin.x, "y": g.origin.y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
        },
        "column_count": w,
        "cell_size": {"x": cell, "y": cell},
        "row_stride": w * 2,
        "cell_stride": 2,
        "fields": [
            {"name": "occupancy", "offset": 0, "type": INT8},
            {"name": "live", "offset": 1, "type": UINT8}
        ],
        "data": base64(&data),
    })
}

/// The grid message of a measured coverage raster at `stamp_ns`: one uint8 field `swept` (100 where the
/// robots' tools swept, else 0), coarsened as [`occupancy_grid`] is (a coarse cell is swept when any of its
/// cells is).
pub fn coverage_grid(record: &CoverageRecord, frame: &str, stamp_ns: u64) -> Value {
    let (gw, gh) = (record.width, record.height);
    let mut k = 1usize;
    while gw.div_ceil(k) * gh.div_ceil(k) > MAX_CELLS {
        k += 1;
    }
    let (w, h) = (gw.div_ceil(k), gh.div_ceil(k));
    let mut data = vec![0u8; w * h];
    let swept = record.covered.decode(gw * gh).unwrap_or_default();
    for (i, _) in swept.iter().enumerate().filter(|(_, s)| **s) {
        data[(i / gw / k) * w + i % gw / k] = 100;
    }
    let cell = record.resolution * k as f64;
    json!({
        "timestamp": {"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000},
        "frame_id": frame,
        "pose": {
            "position": {"x": record.origin[0], "y": record.origin[1], "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
        },
        "column_count": w,
        "cell_size": {"x": cell, "y": cell},
        "row_stride": w,
        "cell_stride": 1,
        "fields": [{"name": "swept", "offset": 0, "type": UINT8}],
        "data": base64(&data),
    })
}

/// Standard base64 with padding (RFC 4648), as JSON Schema's `contentEncoding: base64` means.
pub fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(c.get(1).copied().unwrap_or(0)) << 8)
            | u32::from(c.get(2).copied().unwrap_or(0));
        for (j, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if j <= c.len() {
                out.push(char::from(ABC[(n >> shift) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use shift_planner::geom::Point2;
    use shift_planner::map::grid::GridGeometry;

    use super::*;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(raw.as_bytes()), enc);
        }
    }

    #[test]
    fn cells_and_live_points_land_where_they_are() {
        let g = GridGeometry::new(4, 3, 0.5, Point2::new(-1.0, 2.0)).expect("geometry");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.set(shift_planner::map::grid::Cell::new(3, 2), CellState::Occupied);
        grid.set(shift_planner::map::grid::Cell::new(0, 1), CellState::Unknown);
        let v = occupancy_grid(&grid, &[(-0.9, 2.1), (50.0, 50.0)], "map", 1_500_000_000);
        assert_eq!(v["column_count"], 4);
        assert_eq!(v["row_stride"], 8);
        assert_eq!(v["timestamp"]["sec"], 1);
        assert_eq!(v["timestamp"]["nsec"], 500_000_000);
        let mut expect = vec![0u8; 24];
        expect[1] = 100; // live point in cell (0, 0)
        expect[(4) * 2] = 0xff; // unknown (0, 1)
        expect[(2 * 4 + 3) * 2] = 100; // occupied (3, 2)
        assert_eq!(v["data"], base64(&expect));
    }

    #[test]
    fn swept_cells_land_where_they_are() {
        let rec = CoverageRecord {
            key: shift_engine::CoverageKey::Site("s".into()),
            width: 3,
            height: 2,
            resolution: 0.5,
            origin: [1.0, 2.0],
            covered: shift_engine::cell_mask::CellMask::encode(&[false, true, false, false, false, true]),
            updated_ms: 0,
        };
        let v = coverage_grid(&rec, "map", 0);
        assert_eq!(v["column_count"], 3);
        assert_eq!(v["fields"][0]["name"], "swept");
        assert_eq!(v["pose"]["position"]["x"], 1.0);
        assert_eq!(v["data"], base64(&[0, 100, 0, 0, 0, 100]));
    }

    #[test]
    fn large_maps_are_coarsened() {
        let g = GridGeometry::new(3000, 1000, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let grid = OccupancyGrid::filled(g, CellState::Free);
        let v = occupancy_grid(&grid, &[], "map", 0);
        let cols = v["column_count"].as_u64().expect("cols") as usize;
        let rows = 1000usize.div_ceil(3000 / cols);
        assert!(cols * rows <= MAX_CELLS, "{cols} x {rows}");
        assert!((v["cell_size"]["x"].as_f64().expect("x") - 0.1 * (3000 / cols) as f64).abs() < 1e-9);
    }
}
