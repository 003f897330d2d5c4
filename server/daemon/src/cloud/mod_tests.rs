//! Module-level tests: format detection, limits, empty and garbage input, and a never-panics proptest.

use super::*;
use proptest::prelude::*;

#[test]
fn format_from_path_and_sniff() {
    assert_eq!(CloudFormat::from_path(Path::new("a/B.LAZ")), Some(CloudFormat::Laz));
    assert_eq!(CloudFormat::from_path(Path::new("x.Ply")), Some(CloudFormat::Ply));
    assert_eq!(CloudFormat::from_path(Path::new("x.pcd")), Some(CloudFormat::Pcd));
    assert_eq!(CloudFormat::from_path(Path::new("x.las")), Some(CloudFormat::Las));
    assert_eq!(CloudFormat::from_path(Path::new("x.xyz")), None);
    assert_eq!(CloudFormat::sniff(b"FIELDS x y z\n"), Some(CloudFormat::Pcd));
    assert_eq!(CloudFormat::sniff(b"\x00garbage"), None);
    assert_eq!(LengthUnit::UsSurveyFoot.metres_per_unit(), 1200.0 / 3937.0);
}

#[test]
fn garbage_is_a_format_error() {
    let err = load_cloud(b"\x13\x37 not a cloud", &LoadOptions::default()).expect_err("garbage");
    assert!(
        matches!(
            err,
            CloudError::Format {
                format: "point cloud",
                ..
            }
        ),
        "{err}"
    );
    let opts = LoadOptions {
        format: Some(CloudFormat::Las),
        ..LoadOptions::default()
    };
    let err = load_cloud(b"PK\x03\x04 zip", &opts).expect_err("not LASF");
    assert!(err.to_string().starts_with("LAS: file signature"), "{err}");
}

#[test]
fn max_bytes_is_enforced_for_bytes_and_files() {
    let opts = LoadOptions {
        limits: CloudLimits {
            max_bytes: 10,
            max_points: 10,
        },
        ..LoadOptions::default()
    };
    let bytes = ply::tests::ply("ascii", 3);
    let err = load_cloud(&bytes, &opts).expect_err("over max_bytes");
    assert!(
        matches!(
            err,
            CloudError::TooLarge {
                what: "the file size in bytes",
                ..
            }
        ),
        "{err}"
    );
    let path = std::env::temp_dir().join(format!("cloudio-{}.ply", std::process::id()));
    std::fs::write(&path, &bytes).expect("write temp");
    let err = load_cloud_file(&path, &opts).expect_err("file over max_bytes");
    assert!(matches!(err, CloudError::TooLarge { format: "PLY", .. }), "{err}");
    let cloud = load_cloud_file(&path, &LoadOptions::default()).expect("loads from file");
    assert_eq!(cloud.format, CloudFormat::Ply);
    std::fs::remove_file(&path).ok();
    let err = load_cloud_file(Path::new("/nonexistent/x.laz"), &LoadOptions::default()).expect_err("io");
    assert!(
        matches!(err, CloudError::Io { .. }) && err.to_string().contains("/nonexistent/x.laz"),
        "{err}"
    );
}

#[test]
fn max_points_is_enforced_from_the_header() {
    let opts = LoadOptions {
        limits: CloudLimits {
            max_points: 2,
            ..CloudLimits::default()
        },
        ..LoadOptions::default()
    };
    for bytes in [ply::tests::ply("binary_little_endian", 3), pcd::tests::pcd("binary")] {
        let err = load_cloud(&bytes, &opts).expect_err("3 > 2");
        assert!(
            matches!(
                err,
                CloudError::TooLarge {
                    what: "the point count",
                    actual: 3,
                    limit: 2,
                    ..
                }
            ),
            "{err}"
        );
    }
}

fn valid_files() -> Vec<Vec<u8>> {
    vec![
        ply::tests::ply("ascii", 3),
        ply::tests::ply("binary_little_endian", 3),
        ply::tests::ply("binary_big_endian", 3),
        pcd::tests::pcd("ascii"),
        pcd::tests::pcd("binary"),
        pcd::tests::pcd("binary_compressed"),
        las::tests::write_las(false, vec![], (1, 2)),
        las::tests::write_las(true, vec![], (1, 2)),
        las::tests::write_las(true, vec![], (1, 4)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        let _ = load_cloud(&bytes, &LoadOptions::default());
        for f in [CloudFormat::Las, CloudFormat::Laz, CloudFormat::Ply, CloudFormat::Pcd] {
            let _ = load_cloud(&bytes, &LoadOptions { format: Some(f), ..LoadOptions::default() });
        }
    }

    #[test]
    fn prefixes_and_flips_of_valid_files_never_panic(which in 0usize..9, cut in any::<prop::sample::Index>(),
                                                     flips in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..4)) {
        let mut bytes = valid_files().swap_remove(which);
        let len = cut.index(bytes.len() + 1);
        bytes.truncate(len);
        if !bytes.is_empty() {
            for (at, v) in flips {
                let i = at.index(bytes.len());
                bytes[i] = v;
            }
        }
        let _ = load_cloud(&bytes, &LoadOptions::default());
    }
}

#[test]
fn every_prefix_of_small_files_is_an_error_or_a_cloud() {
    for file in valid_files() {
        for cut in 0..file.len() {
            let _ = load_cloud(&file[..cut], &LoadOptions::default());
        }
        assert!(load_cloud(&file, &LoadOptions::default()).is_ok());
    }
}
