//! LAS/LAZ tests: the real Autzen sample, written round trips, truncation and lying headers.

use super::super::{CloudError, GroundFilter, LengthUnit, LoadOptions, load_cloud};
use las::point::{Classification, Format};
use las::{Builder, Point, Transform, Vector, Vlr, Writer};
use std::io::Cursor;
use std::path::PathBuf;

/// `shared/terrain/<name>`: `$SHIFT_SHARED_DIR`, else beside the repository (from the daemon crate's
/// manifest directory), else from this source file's absolute path. Fails loudly when absent.
pub(crate) fn shared_terrain(name: &str) -> PathBuf {
    let mut tried = Vec::new();
    if let Ok(dir) = std::env::var("SHIFT_SHARED_DIR") {
        tried.push(PathBuf::from(dir));
    }
    tried.push(PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared")));
    let src = std::path::Path::new(file!());
    if src.is_absolute()
        && let Some(repo_parent) = src.ancestors().nth(6)
    {
        tried.push(repo_parent.join("shared"));
    }
    for dir in &tried {
        let p = dir.join("terrain").join(name);
        if p.is_file() {
            return p;
        }
    }
    panic!("test data terrain/{name} not found; tried {tried:?} (set SHIFT_SHARED_DIR to the shared/ folder)");
}

fn autzen() -> Vec<u8> {
    std::fs::read(shared_terrain("autzen_trim.laz")).expect("read autzen_trim.laz")
}

fn all() -> LoadOptions {
    LoadOptions {
        ground_only: GroundFilter::All,
        ..LoadOptions::default()
    }
}

#[test]
fn autzen_header_units_crs_and_bounds() {
    let bytes = autzen();
    let cloud = load_cloud(&bytes, &all()).expect("autzen loads");
    assert_eq!(cloud.format, super::super::CloudFormat::Laz);
    assert_eq!(cloud.read_points, 110_000);
    assert_eq!(cloud.kept_points, 110_000);
    assert_eq!(cloud.dropped_non_finite, 0);
    // The header truly says international feet: ProjLinearUnitsGeoKey=9002, and the WKT UNIT["foot",0.3048].
    assert_eq!(cloud.horizontal_unit, LengthUnit::Foot, "{}", cloud.unit_source);
    assert_eq!(cloud.vertical_unit, LengthUnit::Foot);
    assert!(
        cloud.unit_source.contains("ProjLinearUnitsGeoKey=9002"),
        "{}",
        cloud.unit_source
    );
    assert!(
        cloud.unit_source.contains("vertical unit not stated"),
        "{}",
        cloud.unit_source
    );
    assert_eq!(cloud.crs.as_deref(), Some("NAD_1983_HARN_Lambert_Conformal_Conic"));
    // Header bounds (feet) x 0.3048, to the 0.01 ft quantum.
    let header = las::Reader::new(Cursor::new(bytes)).expect("reader").header().bounds();
    let ft = 0.3048;
    let want = [
        [header.min.x, header.min.y, header.min.z],
        [header.max.x, header.max.y, header.max.z],
    ];
    for (got, want) in cloud.bounds.iter().flatten().zip(want.iter().flatten()) {
        assert!((got - want * ft).abs() < 0.01 * ft, "bound {got} vs {}", want * ft);
    }
    assert!((cloud.bounds[0][0] - 636_001.76 * ft).abs() < 1e-6);
    assert!((cloud.bounds[1][2] - 520.51 * ft).abs() < 1e-6);
}

#[test]
fn autzen_auto_keeps_ground() {
    let bytes = autzen();
    let pd = las::Reader::new(Cursor::new(bytes.clone()))
        .expect("reader")
        .read_all()
        .expect("points");
    let mut counts = [0u64; 256];
    for c in pd.classification() {
        counts[usize::from(c)] += 1;
    }
    let listed: Vec<(usize, u64)> = counts.iter().copied().enumerate().filter(|(_, n)| *n > 0).collect();
    println!("autzen class counts: {listed:?}");
    let ground = counts[2];
    assert!(ground > 0, "autzen has ground points");
    let cloud = load_cloud(&bytes, &LoadOptions::default()).expect("loads");
    assert_eq!(cloud.read_points, 110_000);
    assert_eq!(cloud.kept_points, ground);
    assert!(cloud.ground_filter.contains("ground only"), "{}", cloud.ground_filter);
    let classes = LoadOptions {
        ground_only: GroundFilter::Classes(vec![1, 2]),
        ..LoadOptions::default()
    };
    assert_eq!(
        load_cloud(&bytes, &classes).expect("loads").kept_points,
        counts[1] + counts[2]
    );
}

#[test]
fn autzen_units_override_wins() {
    let opts = LoadOptions {
        units: Some(LengthUnit::Metre),
        ..all()
    };
    let cloud = load_cloud(&autzen(), &opts).expect("loads");
    assert_eq!(cloud.horizontal_unit, LengthUnit::Metre);
    assert!(
        cloud.unit_source.starts_with("--units override"),
        "{}",
        cloud.unit_source
    );
    assert!((cloud.bounds[0][0] - 636_001.76).abs() < 1e-6);
}

#[test]
fn autzen_truncated_is_an_error_not_a_panic() {
    let bytes = autzen();
    let n = bytes.len();
    for cut in [100, 227, 2144, 2200, n / 10, n / 2, n * 9 / 10, n - 30, n - 1] {
        match load_cloud(&bytes[..cut], &all()) {
            Err(e @ (CloudError::Truncated { .. } | CloudError::Format { .. })) => {
                let msg = e.to_string();
                // Below byte 105 the point format (and its compression bit) is cut off: sniffing says LAS.
                assert!(
                    msg.starts_with(if cut > 104 { "LAZ" } else { "LAS" }),
                    "cut {cut}: {msg}"
                );
                println!("cut at {cut}: {msg}");
            }
            other => panic!("cut at {cut}: expected Truncated/Format, got {other:?}"),
        }
    }
}

/// A GeoKeyDirectoryTag: projected model, ProjectedCSTypeGeoKey `pcs`, then `(key, value)` short keys.
fn geokeys(pcs: u16, keys: &[(u16, u16)]) -> Vec<u8> {
    let mut w: Vec<u16> = vec![1, 1, 0, 2 + keys.len() as u16, 1024, 0, 1, 1, 3072, 0, 1, pcs];
    for &(k, v) in keys {
        w.extend([k, 0, 1, v]);
    }
    w.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn projection_vlr(record_id: u16, data: Vec<u8>) -> Vlr {
    Vlr {
        user_id: "LASF_Projection".into(),
        record_id,
        description: String::new(),
        data,
    }
}

/// Writes three points (two ground) in file units, compressed or not, with the given VLRs.
pub(crate) fn write_las(compressed: bool, vlrs: Vec<Vlr>, version: (u8, u8)) -> Vec<u8> {
    let mut b = Builder::from(version);
    b.point_format = Format::new(1).expect("format 1");
    b.point_format.is_compressed = compressed;
    let t = Transform {
        scale: 0.001,
        offset: 0.0,
    };
    b.transforms = Vector { x: t, y: t, z: t };
    b.vlrs = vlrs;
    let mut w = Writer::new(Cursor::new(Vec::new()), b.into_header().expect("header")).expect("writer");
    for (x, y, z, class) in [
        (1000.0, 2000.0, 10.0, 2),
        (1001.0, 2001.0, 11.0, 2),
        (1002.0, 2002.0, 50.0, 5),
    ] {
        let classification = Classification::new(class).expect("class");
        w.write_point(Point {
            x,
            y,
            z,
            classification,
            gps_time: Some(0.0),
            ..Point::default()
        })
        .expect("write");
    }
    w.into_inner().expect("finish").into_inner()
}

#[test]
fn roundtrip_las_and_laz_with_geokeys_in_us_feet() {
    for compressed in [false, true] {
        let vlrs = vec![projection_vlr(34735, geokeys(2992, &[(3076, 9003), (4099, 9001)]))];
        let bytes = write_las(compressed, vlrs, (1, 2));
        let sniffed = super::super::CloudFormat::sniff(&bytes);
        assert_eq!(sniffed.map(|f| f.name()), Some(if compressed { "LAZ" } else { "LAS" }));
        let cloud = load_cloud(&bytes, &all()).expect("round trip");
        assert_eq!(cloud.read_points, 3);
        assert_eq!(cloud.horizontal_unit, LengthUnit::UsSurveyFoot);
        assert_eq!(cloud.vertical_unit, LengthUnit::Metre);
        assert_eq!(cloud.crs.as_deref(), Some("EPSG:2992"));
        let f = 1200.0 / 3937.0;
        let want = [
            [1000.0 * f, 2000.0 * f, 10.0],
            [1001.0 * f, 2001.0 * f, 11.0],
            [1002.0 * f, 2002.0 * f, 50.0],
        ];
        for (p, w) in cloud.points.iter().zip(want) {
            for i in 0..3 {
                assert!((p[i] - w[i]).abs() < 1e-6, "{p:?} vs {w:?}");
            }
        }
        let ground = load_cloud(&bytes, &LoadOptions::default()).expect("auto");
        assert_eq!((ground.read_points, ground.kept_points), (3, 2));
    }
}

#[test]
fn wkt_only_compound_cs_units() {
    let wkt = br#"COMPD_CS["x",PROJCS["NAD83 / Oregon GIC Lambert (ft)",GEOGCS["NAD83",UNIT["degree",0.0174532925199433]],UNIT["foot",0.3048],AUTHORITY["EPSG","2992"]],VERT_CS["NAVD88 height (ftUS)",UNIT["US survey foot",0.304800609601219]]]"#;
    let bytes = write_las(true, vec![projection_vlr(2112, wkt.to_vec())], (1, 2));
    let cloud = load_cloud(&bytes, &all()).expect("loads");
    assert_eq!(
        (cloud.horizontal_unit, cloud.vertical_unit),
        (LengthUnit::Foot, LengthUnit::UsSurveyFoot)
    );
    assert_eq!(cloud.crs.as_deref(), Some("EPSG:2992"));
    assert!(cloud.unit_source.contains("WKT PROJCS UNIT"), "{}", cloud.unit_source);
}

#[test]
fn no_crs_is_assumed_metres_and_conflicts_are_errors() {
    let cloud = load_cloud(&write_las(false, vec![], (1, 2)), &all()).expect("loads");
    assert_eq!(cloud.horizontal_unit, LengthUnit::Metre);
    assert!(cloud.unit_source.contains("assumed metres"), "{}", cloud.unit_source);
    assert_eq!(cloud.crs, None);

    let wkt = br#"PROJCS["p",UNIT["metre",1]]"#.to_vec();
    let vlrs = vec![
        projection_vlr(34735, geokeys(32767, &[(3076, 9002)])),
        projection_vlr(2112, wkt),
    ];
    let bytes = write_las(false, vlrs, (1, 2));
    let err = load_cloud(&bytes, &all()).expect_err("conflicting units");
    assert!(
        err.to_string().contains("9002") && err.to_string().contains("metre"),
        "{err}"
    );
    let opts = LoadOptions {
        units: Some(LengthUnit::Foot),
        ..all()
    };
    assert_eq!(
        load_cloud(&bytes, &opts).expect("override resolves").horizontal_unit,
        LengthUnit::Foot
    );

    let bytes = write_las(
        false,
        vec![projection_vlr(34735, geokeys(32767, &[(3076, 9036)]))],
        (1, 2),
    );
    let err = load_cloud(&bytes, &all()).expect_err("kilometres unsupported");
    assert!(
        matches!(err, CloudError::Header { .. }) && err.to_string().contains("9036"),
        "{err}"
    );
}

#[test]
fn lying_point_counts() {
    let mut bytes = write_las(false, vec![], (1, 2));
    bytes[107..111].copy_from_slice(&1000u32.to_le_bytes());
    let err = load_cloud(&bytes, &all()).expect_err("count too big");
    assert!(matches!(err, CloudError::Truncated { .. }), "{err}");
    assert!(err.to_string().contains("says 1000 points"), "{err}");

    bytes[107..111].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = load_cloud(&bytes, &all()).expect_err("over max_points");
    assert!(matches!(err, CloudError::TooLarge { .. }), "{err}");

    let mut laz = write_las(true, vec![], (1, 2));
    laz[107..111].copy_from_slice(&40_000_000u32.to_le_bytes());
    let err = load_cloud(&laz, &all()).expect_err("LAZ count too big");
    assert!(
        matches!(err, CloudError::Truncated { .. } | CloudError::Format { .. }),
        "{err}"
    );
}

#[test]
fn geographic_crs_is_refused() {
    let mut w: Vec<u16> = vec![1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326];
    w.truncate(12);
    let data = w.iter().flat_map(|v| v.to_le_bytes()).collect();
    let bytes = write_las(false, vec![projection_vlr(34735, data)], (1, 2));
    let err = load_cloud(&bytes, &all()).expect_err("degrees");
    assert!(
        err.to_string().contains("geographic") && err.to_string().contains("EPSG:4326"),
        "{err}"
    );
}

#[test]
fn autzen_cut_mid_points_without_chunk_table_names_the_chunk() {
    // A stream-written LAZ (chunk table offset -1, no table at the end) cut half-way: the decoder runs
    // out of bytes inside the point data.
    let mut bytes = autzen();
    let start = 2144;
    bytes[start..start + 8].copy_from_slice(&(-1i64).to_le_bytes());
    bytes.truncate(bytes.len() / 2);
    bytes.extend([0u8; 8]);
    let err = load_cloud(&bytes, &all()).expect_err("cut");
    let msg = err.to_string();
    println!("{msg}");
    assert!(msg.starts_with("LAZ"), "{msg}");
    assert!(
        matches!(err, CloudError::Truncated { .. } | CloudError::Format { .. }),
        "{msg}"
    );
}
