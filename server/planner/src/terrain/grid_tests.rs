use super::*;
use proptest::prelude::*;

#[test]
fn median_and_gaps_on_a_small_cloud() {
    let pts = [
        [0.1, 0.1, 1.0],
        [0.2, 0.3, 5.0],
        [0.4, 0.2, 2.0],
        [1.6, 0.1, 7.0],
        [f64::NAN, 0.0, 0.0],
        [0.0, f64::INFINITY, 0.0],
        [0.0, 1.2, 3.0],
    ];
    let raw = GridParams {
        slope_correction: false,
        ..GridParams::default()
    };
    let g = ElevationGrid::from_points(&pts, &raw).expect("grid");
    assert_eq!((g.geometry.width, g.geometry.height), (4, 3));
    assert_eq!(g.skipped_non_finite, 2);
    assert_eq!(g.height(Cell::new(0, 0)), Some(2.0));
    assert_eq!(g.counts[0], 3);
    assert_eq!(g.height(Cell::new(3, 0)), Some(7.0));
    assert_eq!(g.height(Cell::new(0, 2)), Some(3.0));
    assert_eq!(g.gap_count(), 12 - 3);
    let low = GridParams {
        height_quantile: 0.0,
        ..raw
    };
    let g = ElevationGrid::from_points(&pts, &low).expect("grid");
    assert_eq!(g.height(Cell::new(0, 0)), Some(1.0));
}

#[test]
fn slope_correction_takes_a_sloping_cell_to_its_centre() {
    // A 40° plane, 5 points at random spots in each 0.25 m cell.
    let (g, tilt) = (0.25, 40f64.to_radians().tan());
    let mut pts = Vec::new();
    let mut seed = 1u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for j in 0..20 {
        for i in 0..20 {
            for _ in 0..5 {
                let (x, y) = ((i as f64 + next()) * g, (j as f64 + next()) * g);
                pts.push([x, y, tilt * (0.6 * x + 0.8 * y)]);
            }
        }
    }
    let error = |p: &GridParams| {
        let grid = ElevationGrid::from_points(&pts, p).expect("grid");
        (0..grid.geometry.len())
            .map(|i| {
                let c = grid.geometry.center_of(i);
                (grid.heights[i] - tilt * (0.6 * c.x + 0.8 * c.y)).abs()
            })
            .fold(0.0, f64::max)
    };
    let raw = error(&GridParams {
        cell_m: g,
        slope_correction: false,
        ..GridParams::default()
    });
    let corrected = error(&GridParams {
        cell_m: g,
        ..GridParams::default()
    });
    eprintln!("40° plane at 0.25 m: raw median error {raw:.3} m, slope-corrected {corrected:.2e} m");
    assert!(raw > 0.05, "raw {raw}");
    assert!(corrected < 0.01, "corrected {corrected}");
}

#[test]
fn bad_clouds_and_params_are_refused() {
    assert!(matches!(
        ElevationGrid::from_points(&[], &GridParams::default()),
        Err(PlannerError::EmptyCloud { total: 0, skipped: 0 })
    ));
    assert!(matches!(
        ElevationGrid::from_points(&[[f64::NAN, 0.0, 0.0]], &GridParams::default()),
        Err(PlannerError::EmptyCloud { total: 1, skipped: 1 })
    ));
    let far = [[0.0, 0.0, 0.0], [1e9, 1e9, 0.0]];
    assert!(matches!(
        ElevationGrid::from_points(&far, &GridParams::default()),
        Err(PlannerError::MapTooLarge { .. })
    ));
    for bad in [0.0, -1.0, f64::NAN] {
        let p = GridParams {
            cell_m: bad,
            ..GridParams::default()
        };
        assert!(matches!(
            ElevationGrid::from_points(&far, &p),
            Err(PlannerError::InvalidParam { name: "grid_m", .. })
        ));
    }
    let geometry = GridGeometry::new(2, 2, 1.0, Point2::origin()).expect("geometry");
    assert!(matches!(
        ElevationGrid::from_heights(geometry, vec![0.0; 3]),
        Err(PlannerError::SizeMismatch { .. })
    ));
    assert!(matches!(
        ElevationGrid::from_heights(geometry, vec![0.0, f64::INFINITY, 0.0, f64::NAN]),
        Err(PlannerError::NonFinite { field: "heights", .. })
    ));
}

proptest! {
    /// Gridding against a naive oracle: for every cell, scan every point, keep those inside the cell's
    /// bounds, sort their z and take the quantile (the lower value between two).
    #[test]
    fn gridding_matches_a_per_cell_scan(
        raw in prop::collection::vec((0usize..7, 0usize..5, 0.05f64..0.95, 0.05f64..0.95, -5.0f64..5.0), 1..120),
        q in 0.0f64..=1.0,
    ) {
        let g = 0.25;
        // The anchor at (0, 0) fixes the origin, so the other points sit well inside their cells.
        let mut pts = vec![[0.0, 0.0, 0.0]];
        pts.extend(raw.iter().map(|&(i, j, fx, fy, z)| [(i as f64 + fx) * g, (j as f64 + fy) * g, z]));
        let params = GridParams { cell_m: g, height_quantile: q, min_points: 1, slope_correction: false };
        let grid = ElevationGrid::from_points(&pts, &params).expect("grid");
        let w = raw.iter().map(|r| r.0).max().unwrap_or(0) + 1;
        let h = raw.iter().map(|r| r.1).max().unwrap_or(0) + 1;
        prop_assert_eq!((grid.geometry.width, grid.geometry.height), (w, h));
        for cy in 0..h {
            for cx in 0..w {
                let (x0, y0) = (cx as f64 * g, cy as f64 * g);
                let mut zs: Vec<f64> = pts
                    .iter()
                    .filter(|p| p[0] >= x0 && p[0] < x0 + g && p[1] >= y0 && p[1] < y0 + g)
                    .map(|p| p[2])
                    .collect();
                zs.sort_by(f64::total_cmp);
                let i = cy * w + cx;
                prop_assert_eq!(grid.counts[i] as usize, zs.len());
                if zs.is_empty() {
                    prop_assert!(grid.heights[i].is_nan());
                } else {
                    let want = zs[((zs.len() - 1) as f64 * q).floor() as usize];
                    prop_assert_eq!(grid.heights[i], want);
                }
            }
        }
    }
}
