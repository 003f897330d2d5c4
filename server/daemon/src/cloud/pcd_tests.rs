//! PCD tests: ascii, binary and binary_compressed with NaN holes, lying and bad headers.

use super::super::{CloudError, CloudFormat, LoadOptions, load_cloud};

fn header(data: &str, points: usize) -> String {
    format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 8 4\nTYPE F F F U\n\
         COUNT 1 1 1 1\nWIDTH {points}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {data}\n"
    )
}

const PTS: [[f64; 3]; 3] = [[1.0, 2.0, 3.0], [f64::NAN, f64::NAN, f64::NAN], [-4.0, 5.5, 6.0]];

/// Array-of-structures bytes for PTS (x, y f32, z f64, rgb u32).
fn rows() -> Vec<u8> {
    let mut out = Vec::new();
    for p in PTS {
        out.extend((p[0] as f32).to_le_bytes());
        out.extend((p[1] as f32).to_le_bytes());
        out.extend(p[2].to_le_bytes());
        out.extend(0xff00ffu32.to_le_bytes());
    }
    out
}

pub(crate) fn pcd(data: &str) -> Vec<u8> {
    let mut out = header(data, 3).into_bytes();
    match data {
        "ascii" => out.extend(b"1 2 3 4278190335\nnan nan nan 0\n-4 5.5 6 1\n"),
        "binary" => out.extend(rows()),
        _ => {
            // Structure of arrays: all x, all y, all z, all rgb.
            let aos = rows();
            let mut soa = Vec::new();
            for (off, w) in [(0, 4), (4, 4), (8, 8), (16, 4)] {
                for r in aos.chunks_exact(20) {
                    soa.extend(&r[off..off + w]);
                }
            }
            let packed = lzf::compress(&soa).unwrap_or_else(|_| {
                // Incompressible input: LZF literal runs of up to 32 bytes.
                soa.chunks(32)
                    .flat_map(|c| std::iter::once(c.len() as u8 - 1).chain(c.iter().copied()))
                    .collect()
            });
            out.extend((packed.len() as u32).to_le_bytes());
            out.extend((soa.len() as u32).to_le_bytes());
            out.extend(packed);
        }
    }
    out
}

#[test]
fn ascii_binary_and_compressed_drop_nans() {
    for data in ["ascii", "binary", "binary_compressed"] {
        let bytes = pcd(data);
        assert_eq!(CloudFormat::sniff(&bytes), Some(CloudFormat::Pcd));
        let cloud = load_cloud(&bytes, &LoadOptions::default()).unwrap_or_else(|e| panic!("{data}: {e}"));
        assert_eq!(
            (cloud.read_points, cloud.kept_points, cloud.dropped_non_finite),
            (3, 2, 1),
            "{data}"
        );
        assert_eq!(cloud.points, vec![PTS[0], PTS[2]], "{data}");
        assert_eq!(cloud.unit_source, "assumed metres (PCD has no units)");
    }
}

#[test]
fn all_nan_is_empty() {
    let mut bytes = header("ascii", 2).into_bytes();
    bytes.extend(b"nan nan nan 0\nnan 1 2 0\n");
    let err = load_cloud(&bytes, &LoadOptions::default()).expect_err("all NaN");
    assert!(matches!(err, CloudError::Empty { format: "PCD", .. }), "{err}");
    assert!(err.to_string().contains("2 dropped as non-finite"), "{err}");
}

#[test]
fn lying_and_bad_headers() {
    let mut short = header("binary", 5).into_bytes();
    short.extend(rows());
    let err = load_cloud(&short, &LoadOptions::default()).expect_err("short");
    assert!(
        err.to_string()
            .contains("header says 5 points but the body ends after 3"),
        "{err}"
    );

    let mut ascii = header("ascii", 4).into_bytes();
    ascii.extend(b"1 2 3 0\n1 2 3\n");
    let err = load_cloud(&ascii, &LoadOptions::default()).expect_err("short row");
    assert!(err.to_string().contains("data line 2: 3 values"), "{err}");

    let bad = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n";
    let err = load_cloud(bad.as_bytes(), &LoadOptions::default()).expect_err("type");
    assert!(
        matches!(err, CloudError::Header { .. }) && err.to_string().contains("TYPE"),
        "{err}"
    );

    let mismatch = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 3\nDATA ascii\n";
    let err = load_cloud(mismatch.as_bytes(), &LoadOptions::default()).expect_err("mismatch");
    assert!(err.to_string().contains("WIDTH x HEIGHT is 2"), "{err}");

    let huge = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 4000000000\nDATA binary\n";
    let err = load_cloud(huge.as_bytes(), &LoadOptions::default()).expect_err("huge");
    assert!(matches!(err, CloudError::TooLarge { format: "PCD", .. }), "{err}");

    let mut lzf = pcd("binary_compressed");
    let n = lzf.len();
    lzf.truncate(n - 5);
    let err = load_cloud(&lzf, &LoadOptions::default()).expect_err("cut lzf");
    assert!(matches!(err, CloudError::Truncated { .. }), "{err}");
}
