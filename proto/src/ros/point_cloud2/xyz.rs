//! x, y, z of every valid point of a PointCloud2, whatever its layout.

use super::{PointCloud2, PointCloud2Ref, PointField};
use crate::error::CodecError;
use crate::ros::MAX_POINTS;
use crate::ros::header::Header;

/// The valid points of a cloud, as f64 metres in `header.frame_id`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CloudXyz {
    /// The cloud's stamp and frame.
    pub header: Header,
    /// x, y, z of each point whose three coordinates are finite, in row-major order.
    pub points: Vec<[f64; 3]>,
    /// Points dropped because a coordinate was NaN or infinite.
    pub skipped: usize,
}

/// How one coordinate is stored.
#[derive(Debug, Clone, Copy)]
enum Coord {
    F32Le(usize),
    F32Be(usize),
    F64Le(usize),
    F64Be(usize),
}

impl Coord {
    fn find(fields: &[PointField], name: &'static str, big: bool, point_step: u32) -> Result<Self, CodecError> {
        let f = fields
            .iter()
            .find(|f| f.name == name)
            .ok_or(CodecError::MissingField { name })?;
        let size = match f.datatype {
            PointField::FLOAT32 => 4,
            PointField::FLOAT64 => 8,
            datatype => {
                return Err(CodecError::UnsupportedDatatype {
                    name: f.name.clone(),
                    datatype,
                });
            }
        };
        if u64::from(f.offset) + u64::from(size) > u64::from(point_step) {
            return Err(CodecError::PointStepTooSmall {
                name: f.name.clone(),
                offset: f.offset,
                size,
                point_step,
            });
        }
        let off = f.offset as usize;
        Ok(match (size, big) {
            (4, false) => Self::F32Le(off),
            (4, true) => Self::F32Be(off),
            (_, false) => Self::F64Le(off),
            (_, true) => Self::F64Be(off),
        })
    }

    /// The value in `point` (one point's bytes); `None` only if the point is shorter than the layout said.
    #[inline]
    fn read(self, point: &[u8]) -> Option<f64> {
        fn arr<const N: usize>(p: &[u8], off: usize) -> Option<[u8; N]> {
            p.get(off..off + N).and_then(|s| s.try_into().ok())
        }
        Some(match self {
            Self::F32Le(o) => f64::from(f32::from_le_bytes(arr(point, o)?)),
            Self::F32Be(o) => f64::from(f32::from_be_bytes(arr(point, o)?)),
            Self::F64Le(o) => f64::from_le_bytes(arr(point, o)?),
            Self::F64Be(o) => f64::from_be_bytes(arr(point, o)?),
        })
    }
}

/// The layout fields of a PointCloud2, borrowed from either the owned or the borrowed form.
struct Layout<'a> {
    height: u32,
    width: u32,
    fields: &'a [PointField],
    is_bigendian: bool,
    point_step: u32,
    row_step: u32,
    data: &'a [u8],
}

fn extract(header: &Header, l: &Layout<'_>) -> Result<CloudXyz, CodecError> {
    let n = u64::from(l.height) * u64::from(l.width);
    if n > MAX_POINTS as u64 {
        return Err(CodecError::TooLarge {
            what: "PointCloud2 points (height × width)",
            value: n,
            limit: MAX_POINTS as u64,
        });
    }
    let x = Coord::find(l.fields, "x", l.is_bigendian, l.point_step)?;
    let y = Coord::find(l.fields, "y", l.is_bigendian, l.point_step)?;
    let z = Coord::find(l.fields, "z", l.is_bigendian, l.point_step)?;
    let mut out = CloudXyz {
        header: header.clone(),
        points: Vec::new(),
        skipped: 0,
    };
    if n == 0 {
        return Ok(out);
    }
    let row_bytes = u64::from(l.width) * u64::from(l.point_step);
    if u64::from(l.row_step) < row_bytes {
        return Err(CodecError::SizeMismatch {
            what: "PointCloud2.row_step is smaller than width × point_step",
            expected: row_bytes,
            found: u64::from(l.row_step),
        });
    }
    // The last row may omit its padding.
    let needed = u64::from(l.height - 1) * u64::from(l.row_step) + row_bytes;
    if (l.data.len() as u64) < needed {
        return Err(CodecError::SizeMismatch {
            what: "PointCloud2.data is shorter than height × row_step",
            expected: needed,
            found: l.data.len() as u64,
        });
    }
    // n ≤ data.len() / 4 here (point_step ≥ 4), so this allocation is bounded by the payload.
    out.points.reserve_exact(n as usize);
    let (row_step, row_bytes, point_step) = (l.row_step as usize, row_bytes as usize, l.point_step as usize);
    for row in 0..l.height as usize {
        let start = row * row_step;
        let Some(row_data) = l.data.get(start..start + row_bytes) else {
            return Err(CodecError::SizeMismatch {
                what: "PointCloud2.data is shorter than height × row_step",
                expected: needed,
                found: l.data.len() as u64,
            });
        };
        for point in row_data.chunks_exact(point_step) {
            match (x.read(point), y.read(point), z.read(point)) {
                (Some(px), Some(py), Some(pz)) if px.is_finite() && py.is_finite() && pz.is_finite() => {
                    out.points.push([px, py, pz]);
                }
                _ => out.skipped += 1,
            }
        }
    }
    Ok(out)
}

/// The x, y, z (metres, in `cloud.header.frame_id`) of every point whose coordinates are all finite.
///
/// Fields are found by name at any offset; FLOAT32 or FLOAT64 each; byte order from `is_bigendian`; organised
/// (height > 1) and unorganised clouds, rows `row_step` apart (padding skipped). NaN and infinite points are
/// skipped and counted, whatever `is_dense` says. Errors: a missing x/y/z, another datatype, a field that does
/// not fit in `point_step`, `row_step < width × point_step`, data shorter than the layout, > 20 M points.
pub fn cloud_xyz(cloud: &PointCloud2) -> Result<CloudXyz, CodecError> {
    extract(
        &cloud.header,
        &Layout {
            height: cloud.height,
            width: cloud.width,
            fields: &cloud.fields,
            is_bigendian: cloud.is_bigendian,
            point_step: cloud.point_step,
            row_step: cloud.row_step,
            data: &cloud.data,
        },
    )
}

/// [`decode_point_cloud2`](super::decode_point_cloud2) then [`cloud_xyz`], without copying the point data:
/// the ingest path.
pub fn decode_cloud_xyz(bytes: &[u8]) -> Result<CloudXyz, CodecError> {
    let c = PointCloud2Ref::decode(bytes)?;
    extract(
        &c.header,
        &Layout {
            height: c.height,
            width: c.width,
            fields: &c.fields,
            is_bigendian: c.is_bigendian,
            point_step: c.point_step,
            row_step: c.row_step,
            data: c.data,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::point_cloud2::xyz32_fields;

    fn cloud(points: &[[f32; 3]]) -> PointCloud2 {
        PointCloud2 {
            header: Header::new(7, "map"),
            height: 1,
            width: points.len() as u32,
            fields: xyz32_fields(),
            point_step: 12,
            row_step: 12 * points.len() as u32,
            data: points.iter().flatten().flat_map(|v| v.to_le_bytes()).collect(),
            ..PointCloud2::default()
        }
    }

    #[test]
    fn layout_errors_are_specific() {
        let good = cloud(&[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert_eq!(
            cloud_xyz(&good).expect("good").points,
            vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
        );

        let mut c = good.clone();
        c.point_step = 8;
        c.row_step = 16;
        let err = cloud_xyz(&c).expect_err("z does not fit");
        assert!(
            matches!(err, CodecError::PointStepTooSmall { ref name, offset: 8, size: 4, point_step: 8 } if name == "z")
        );

        let mut c = good.clone();
        c.fields.retain(|f| f.name != "y");
        assert_eq!(cloud_xyz(&c), Err(CodecError::MissingField { name: "y" }));

        let mut c = good.clone();
        c.fields[0].datatype = PointField::UINT16;
        assert!(matches!(
            cloud_xyz(&c),
            Err(CodecError::UnsupportedDatatype { datatype: 4, .. })
        ));

        let mut c = good.clone();
        c.row_step = 20;
        assert_eq!(cloud_xyz(&c).map_err(|e| e.kind()), Err("size_mismatch"));

        let mut c = good.clone();
        c.width = 3;
        c.row_step = 36;
        assert_eq!(cloud_xyz(&c).map_err(|e| e.kind()), Err("size_mismatch"));

        let mut c = good;
        c.height = 100_000;
        c.width = 100_000;
        assert_eq!(cloud_xyz(&c).map_err(|e| e.kind()), Err("too_large"));
    }

    #[test]
    fn point_step_zero_with_points_is_an_error_not_a_loop() {
        let mut c = cloud(&[[1.0, 2.0, 3.0]]);
        c.point_step = 0;
        assert_eq!(cloud_xyz(&c).map_err(|e| e.kind()), Err("point_step_too_small"));
    }
}
