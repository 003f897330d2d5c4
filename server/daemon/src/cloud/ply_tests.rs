//! PLY tests: the three encodings with extra properties and faces, lying headers, bad types.

use super::super::{CloudError, CloudFormat, GroundFilter, LengthUnit, LoadOptions, load_cloud};

const PTS: [[f64; 3]; 3] = [[1.0, 2.0, 3.0], [4.5, -5.0, 6.25], [7.0, 8.0, f64::NAN]];

/// A PLY with a leading `camera` element (a list), vertex x (float) y (double) z (short*0.25-able float),
/// extra scalar and list properties, and a face element after.
pub(crate) fn ply(encoding: &str, count: usize) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {encoding} 1.0\ncomment test\nelement camera 1\nproperty list uchar int ids\n\
         element vertex {count}\nproperty uchar red\nproperty float x\nproperty list uint8 float32 extra\n\
         property double y\nproperty float32 z\nproperty int16 label\nelement face 1\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    let big = encoding == "binary_big_endian";
    let put = |out: &mut Vec<u8>, bytes: &[u8]| {
        if big {
            out.extend(bytes.iter().rev());
        } else {
            out.extend(bytes);
        }
    };
    if encoding == "ascii" {
        out.extend(b"2 10 20\n");
        for p in &PTS[..count.min(3)] {
            out.extend(format!("255 {} 2 0.5 0.25 {} {} -7\n", p[0], p[1], p[2]).bytes());
        }
        out.extend(b"3 0 1 2\n");
    } else {
        out.push(2);
        put(&mut out, &10i32.to_le_bytes());
        put(&mut out, &20i32.to_le_bytes());
        for p in &PTS[..count.min(3)] {
            out.push(255);
            put(&mut out, &(p[0] as f32).to_le_bytes());
            out.push(2);
            put(&mut out, &0.5f32.to_le_bytes());
            put(&mut out, &0.25f32.to_le_bytes());
            put(&mut out, &p[1].to_le_bytes());
            put(&mut out, &(p[2] as f32).to_le_bytes());
            put(&mut out, &(-7i16).to_le_bytes());
        }
        out.push(3);
        for i in 0..3i32 {
            put(&mut out, &i.to_le_bytes());
        }
    }
    out
}

#[test]
fn three_encodings_read_the_same_points() {
    for enc in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let bytes = ply(enc, 3);
        assert_eq!(CloudFormat::sniff(&bytes), Some(CloudFormat::Ply));
        let cloud = load_cloud(&bytes, &LoadOptions::default()).unwrap_or_else(|e| panic!("{enc}: {e}"));
        assert_eq!(
            (cloud.read_points, cloud.kept_points, cloud.dropped_non_finite),
            (3, 2, 1),
            "{enc}"
        );
        assert_eq!(cloud.points, vec![PTS[0], PTS[1]], "{enc}");
        assert_eq!(cloud.horizontal_unit, LengthUnit::Metre);
        assert_eq!(cloud.unit_source, "assumed metres (PLY has no units)");
        assert_eq!(cloud.bounds, [[1.0, -5.0, 3.0], [4.5, 2.0, 6.25]]);
    }
}

#[test]
fn units_override_scales_ply() {
    let opts = LoadOptions {
        units: Some(LengthUnit::Foot),
        ..LoadOptions::default()
    };
    let cloud = load_cloud(&ply("ascii", 3), &opts).expect("loads");
    assert!((cloud.points[0][0] - 0.3048).abs() < 1e-12);
    assert!((cloud.points[1][2] - 6.25 * 0.3048).abs() < 1e-12);
}

#[test]
fn lying_header_count_too_big_is_truncated() {
    for enc in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let mut bytes = ply(enc, 3);
        // Patch the count in place (the binary body is not text).
        let at = bytes
            .windows(16)
            .position(|w| w == b"element vertex 3")
            .expect("header");
        bytes.splice(at..at + 16, b"element vertex 1000".iter().copied());
        let err = load_cloud(&bytes, &LoadOptions::default()).expect_err("lying header");
        let msg = err.to_string();
        assert!(
            matches!(err, CloudError::Truncated { .. } | CloudError::Format { .. }),
            "{enc}: {msg}"
        );
        if enc != "ascii" {
            // The face element's bytes are read as vertices until they run out.
            assert!(
                msg.contains("header says 1000 vertices but the body ends after"),
                "{enc}: {msg}"
            );
        }
    }
}

#[test]
fn count_smaller_than_body_reads_the_count_and_ignores_the_rest() {
    // Documented choice: rows past the header's count (and any later elements) are not read.
    let bytes = ply("ascii", 3);
    let at = bytes
        .windows(16)
        .position(|w| w == b"element vertex 3")
        .expect("header");
    let mut fewer = bytes.clone();
    fewer[at + 15] = b'1';
    let err = load_cloud(&fewer, &LoadOptions::default());
    // The second row is now read as a face; nothing after the vertex element is parsed, so this loads.
    assert_eq!(err.expect("loads").points, vec![PTS[0]]);
}

#[test]
fn bad_types_tokens_and_shapes_are_clear_errors() {
    let cases: [(&str, &str); 7] = [
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n1\n",
            "unknown type `flaot`",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n",
            "property z",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n1 1 2 3\n",
            "is a list",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 five 6\n",
            "token `five` is not a number",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
            "end_header",
        ),
        ("ply\nformat utf8 1.0\nend_header\n", "`utf8`"),
        ("ply\nformat ascii 1.0\nend_header\n", "element vertex"),
    ];
    for (text, want) in cases {
        let err = load_cloud(text.as_bytes(), &LoadOptions::default()).expect_err(text);
        assert!(err.to_string().starts_with("PLY"), "{err}");
        assert!(err.to_string().contains(want), "{text:?}: {err}");
    }
}

#[test]
fn zero_vertices_and_classes_filter() {
    let text =
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let err = load_cloud(text.as_bytes(), &LoadOptions::default()).expect_err("empty");
    assert!(matches!(err, CloudError::Empty { format: "PLY", .. }), "{err}");
    let opts = LoadOptions {
        ground_only: GroundFilter::Classes(vec![2]),
        ..LoadOptions::default()
    };
    let err = load_cloud(&ply("ascii", 3), &opts).expect_err("no classes");
    assert!(err.to_string().contains("no classification"), "{err}");
}

#[test]
fn over_max_points_is_too_large() {
    let text = "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let err = load_cloud(text.as_bytes(), &LoadOptions::default()).expect_err("huge");
    assert!(matches!(err, CloudError::TooLarge { format: "PLY", .. }), "{err}");
}
