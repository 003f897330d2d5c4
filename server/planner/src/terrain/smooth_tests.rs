use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::geom::Point2;

/// Rolling hills: amplitude 0.6 m, wavelengths of 19 m and 25 m; |H| stays under 0.07 1/m.
fn hills(x: f64, y: f64) -> f64 {
    0.6 * (x / 3.0).sin() * (y / 4.0).cos() + 0.05 * x
}

struct Field {
    geometry: GridGeometry,
    clean: Vec<f64>,
    noisy: Vec<f64>,
    spikes: Vec<usize>,
}

/// `n × n` cells of 0.2 m over the hills, with `share` of the cells raised or sunk by 0.3–1.5 m.
fn spike_field(n: usize, share: f64, seed: u64) -> Field {
    let geometry = GridGeometry::new(n, n, 0.2, Point2::new(-10.0, -10.0)).expect("geometry");
    let clean: Vec<f64> = (0..geometry.len())
        .map(|i| {
            let c = geometry.center_of(i);
            hills(c.x, c.y)
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut noisy = clean.clone();
    let mut spikes = Vec::new();
    for (i, z) in noisy.iter_mut().enumerate() {
        if rng.random::<f64>() < share {
            let size = rng.random_range(0.3..1.5);
            *z += if rng.random::<bool>() { size } else { -size };
            spikes.push(i);
        }
    }
    Field {
        geometry,
        clean,
        noisy,
        spikes,
    }
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn spikes_are_found_and_removed_and_nothing_else_moves() {
    let f = spike_field(120, 0.01, 7);
    let measured = vec![true; f.geometry.len()];
    let mut h = f.noisy.clone();
    let report = smooth_outliers(&mut h, &measured, &f.geometry, &SmoothParams::default()).expect("smooth");
    let before = rms(&f.noisy, &f.clean);
    let after = rms(&h, &f.clean);
    let worst = h.iter().zip(&f.clean).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!(
        "spike field: {} spikes, {} outliers, {} smoothed, {} iterations; RMS {before:.4} -> {after:.6} m \
         (x{:.0}), worst {worst:.4} m; thresholds {:?} then {:?}",
        f.spikes.len(),
        report.outlier.iter().filter(|&&o| o).count(),
        report.smoothed_cells,
        report.iterations,
        before / after,
        report.thresholds,
        report.final_thresholds
    );
    assert!(f.spikes.len() > 100);
    assert!(f.spikes.iter().all(|&i| report.outlier[i]), "every spike is an outlier");
    // Measured: RMS 0.099 → 0.00043 m (×229); a spike is brought down until ρ < release, under
    // release · min_spike_cells · g = 0.5 cm plus the hills' own curvature.
    assert!(before / after > 100.0, "RMS {before} -> {after}");
    assert!(worst < 0.02, "worst remaining error {worst}");
    for (i, (now, was)) in h.iter().zip(&f.noisy).enumerate() {
        if !report.outlier[i] {
            assert_eq!(now.to_bits(), was.to_bits(), "cell {i} is no outlier yet moved");
        }
    }
    // Outliers that are not spikes (their neighbours, curved one way) barely move.
    let spike_set: std::collections::HashSet<usize> = f.spikes.iter().copied().collect();
    let moved_other = (0..h.len())
        .filter(|i| !spike_set.contains(i))
        .map(|i| (h[i] - f.noisy[i]).abs())
        .fold(0.0, f64::max);
    assert!(moved_other < 0.01, "a spike's neighbour moved {moved_other} m");
}

#[test]
fn smooth_hills_and_a_sphere_cap_have_no_outliers() {
    let f = spike_field(80, 0.0, 1);
    let measured = vec![true; f.geometry.len()];
    let mut h = f.clean.clone();
    let report = smooth_outliers(&mut h, &measured, &f.geometry, &SmoothParams::default()).expect("smooth");
    assert_eq!(report.smoothed_cells, 0);
    assert!(report.outlier.iter().all(|&o| !o));
    let geometry = GridGeometry::new(60, 60, 0.1, Point2::new(-3.0, -3.0)).expect("geometry");
    let mut cap: Vec<f64> = (0..geometry.len())
        .map(|i| {
            let c = geometry.center_of(i);
            (25.0 - c.x * c.x - c.y * c.y).sqrt()
        })
        .collect();
    let report = smooth_outliers(&mut cap, &vec![true; 3600], &geometry, &SmoothParams::default()).expect("smooth");
    assert_eq!(report.smoothed_cells, 0, "a sphere cap of R = 5 m is not an outlier");
}

#[test]
fn a_kerb_keeps_its_step() {
    let geometry = GridGeometry::new(40, 40, 0.05, Point2::origin()).expect("geometry");
    let kerb = |i: usize| if geometry.center_of(i).x > 1.0 { 0.2 } else { 0.0 };
    let clean: Vec<f64> = (0..geometry.len()).map(kerb).collect();
    let mut h = clean.clone();
    let report = smooth_outliers(&mut h, &vec![true; 1600], &geometry, &SmoothParams::default()).expect("smooth");
    assert!(
        report.outlier.iter().all(|&o| !o),
        "a kerb bends less than a 2.5 cm spike on 5 cm cells"
    );
    // With a floor low enough to flag its edge, the kerb is an outlier but one-directional: λ = 0.
    let touchy = SmoothParams {
        min_spike_cells: 0.02,
        ..SmoothParams::default()
    };
    let report = smooth_outliers(&mut h, &vec![true; 1600], &geometry, &touchy).expect("smooth");
    assert!(
        report.outlier.iter().filter(|&&o| o).count() >= 80,
        "both kerb columns are outliers"
    );
    assert_eq!(report.smoothed_cells, 0);
    assert_eq!(h, clean);
}

#[test]
fn unmeasured_cells_are_neither_judged_nor_used() {
    let f = spike_field(40, 0.0, 3);
    let mut measured = vec![true; f.geometry.len()];
    let mut h = f.clean.clone();
    // A spike in a provisional fill is not data: it is left for the gap filling to redo.
    let gap = f.geometry.len() / 2 + 20;
    measured[gap] = false;
    h[gap] += 3.0;
    let report = smooth_outliers(&mut h, &measured, &f.geometry, &SmoothParams::default()).expect("smooth");
    assert!(!report.outlier[gap]);
    assert_eq!(report.smoothed_cells, 0);
}

#[test]
fn bad_params_are_named() {
    let geometry = GridGeometry::new(4, 4, 1.0, Point2::origin()).expect("geometry");
    let mut h = vec![0.0; 16];
    let m = vec![true; 16];
    for (p, name) in [
        (
            SmoothParams {
                lambda: 0.0,
                ..SmoothParams::default()
            },
            "lambda",
        ),
        (
            SmoothParams {
                alpha: -1.0,
                ..SmoothParams::default()
            },
            "alpha",
        ),
        (
            SmoothParams {
                tolerance_m: 0.0,
                ..SmoothParams::default()
            },
            "tolerance_m",
        ),
    ] {
        match smooth_outliers(&mut h, &m, &geometry, &p) {
            Err(PlannerError::InvalidParam { name: got, .. }) => assert_eq!(got, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    let p = SmoothParams {
        beta: f64::NAN,
        ..SmoothParams::default()
    };
    assert!(matches!(
        smooth_outliers(&mut h, &m, &geometry, &p),
        Err(PlannerError::NonFinite { field: "beta", .. })
    ));
}
