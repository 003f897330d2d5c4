//! sensor_msgs/PointCloud2 (CDR): the message, its codec, and x, y, z extraction for any point layout.

mod xyz;

pub use xyz::{CloudXyz, cloud_xyz, decode_cloud_xyz};

use super::cdr::{CdrReader, CdrWriter};
use super::header::Header;
use super::{MAX_CLOUD_BYTES, MAX_POINTS};
use crate::error::CodecError;

/// sensor_msgs/PointField: one named field inside each point.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct PointField {
    /// Field name, e.g. `x`, `intensity`, `rgb`.
    pub name: String,
    /// Byte offset of the field inside a point.
    pub offset: u32,
    /// Type code: one of the `PointField::INT8` … `FLOAT64` constants.
    pub datatype: u8,
    /// Number of elements of `datatype` (1 for scalars).
    pub count: u32,
}

impl PointField {
    /// Datatype code of a signed 8-bit integer.
    pub const INT8: u8 = 1;
    /// Datatype code of an unsigned 8-bit integer.
    pub const UINT8: u8 = 2;
    /// Datatype code of a signed 16-bit integer.
    pub const INT16: u8 = 3;
    /// Datatype code of an unsigned 16-bit integer.
    pub const UINT16: u8 = 4;
    /// Datatype code of a signed 32-bit integer.
    pub const INT32: u8 = 5;
    /// Datatype code of an unsigned 32-bit integer.
    pub const UINT32: u8 = 6;
    /// Datatype code of a 32-bit float.
    pub const FLOAT32: u8 = 7;
    /// Datatype code of a 64-bit float.
    pub const FLOAT64: u8 = 8;

    /// A scalar field.
    pub fn new(name: impl Into<String>, offset: u32, datatype: u8) -> Self {
        Self {
            name: name.into(),
            offset,
            datatype,
            count: 1,
        }
    }

    /// Bytes of one element of `datatype`, or `None` for an unknown code.
    pub fn datatype_size(datatype: u8) -> Option<u32> {
        match datatype {
            1 | 2 => Some(1),
            3 | 4 => Some(2),
            5..=7 => Some(4),
            8 => Some(8),
            _ => None,
        }
    }

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            name: r.string("PointField.name")?,
            offset: r.u32("PointField.offset")?,
            datatype: r.u8("PointField.datatype")?,
            count: r.u32("PointField.count")?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        w.string(&self.name);
        w.u32(self.offset);
        w.u8(self.datatype);
        w.u32(self.count);
    }
}

/// sensor_msgs/PointCloud2, decoded: `height` rows of `width` points; point (row, col) starts at byte
/// `row × row_step + col × point_step` of `data`. Coordinates are in `header.frame_id`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct PointCloud2 {
    /// Stamp and the frame of the points.
    pub header: Header,
    /// Rows (1 for an unorganised cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// The layout of one point.
    pub fields: Vec<PointField>,
    /// Byte order of the values in `data` (independent of the CDR body's byte order).
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row (at least `width × point_step`; more means row padding).
    pub row_step: u32,
    /// The points.
    pub data: Vec<u8>,
    /// The sender's claim that no point is invalid (NaN); not trusted by [`cloud_xyz`].
    pub is_dense: bool,
}

/// A decoded PointCloud2 whose data still borrows the payload (what [`decode_cloud_xyz`] reads without a copy).
#[derive(Debug, Clone)]
pub(crate) struct PointCloud2Ref<'a> {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointField>,
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    pub data: &'a [u8],
    pub is_dense: bool,
}

impl<'a> PointCloud2Ref<'a> {
    pub(crate) fn decode(bytes: &'a [u8]) -> Result<Self, CodecError> {
        let mut r = CdrReader::new(bytes)?;
        let header = Header::read(&mut r)?;
        let height = r.u32("PointCloud2.height")?;
        let width = r.u32("PointCloud2.width")?;
        let points = u64::from(height) * u64::from(width);
        if points > MAX_POINTS as u64 {
            return Err(CodecError::TooLarge {
                what: "PointCloud2 points (height × width)",
                value: points,
                limit: MAX_POINTS as u64,
            });
        }
        // A PointField takes at least 13 bytes (string length, offset, datatype, count).
        let n_fields = r.seq_len(13, "PointCloud2.fields")?;
        let fields = (0..n_fields)
            .map(|_| PointField::read(&mut r))
            .collect::<Result<Vec<_>, _>>()?;
        let is_bigendian = r.bool("PointCloud2.is_bigendian")?;
        let point_step = r.u32("PointCloud2.point_step")?;
        let row_step = r.u32("PointCloud2.row_step")?;
        let data = r.byte_seq("PointCloud2.data", MAX_CLOUD_BYTES)?;
        let is_dense = r.bool("PointCloud2.is_dense")?;
        Ok(Self {
            header,
            height,
            width,
            fields,
            is_bigendian,
            point_step,
            row_step,
            data,
            is_dense,
        })
    }

    fn into_owned(self) -> PointCloud2 {
        PointCloud2 {
            header: self.header,
            height: self.height,
            width: self.width,
            fields: self.fields,
            is_bigendian: self.is_bigendian,
            point_step: self.point_step,
            row_step: self.row_step,
            data: self.data.to_vec(),
            is_dense: self.is_dense,
        }
    }
}

/// Decodes a sensor_msgs/PointCloud2 CDR payload (either byte order). Checks the structure and the absurd-size
/// limits (> 20 M points, > 512 MiB of data); the point layout is checked by [`cloud_xyz`].
pub fn decode_point_cloud2(bytes: &[u8]) -> Result<PointCloud2, CodecError> {
    PointCloud2Ref::decode(bytes).map(PointCloud2Ref::into_owned)
}

/// Encodes any PointCloud2 as little-endian CDR (the message is written as given, consistent or not).
pub fn encode_point_cloud2(msg: &PointCloud2) -> Vec<u8> {
    encode_point_cloud2_with(msg, false)
}

/// Encodes any PointCloud2 in the given CDR byte order (the point data is copied as is).
pub fn encode_point_cloud2_with(msg: &PointCloud2, big_endian: bool) -> Vec<u8> {
    let mut w = CdrWriter::with_endianness(big_endian);
    msg.header.write(&mut w);
    w.u32(msg.height);
    w.u32(msg.width);
    w.seq_len(msg.fields.len());
    for f in &msg.fields {
        f.write(&mut w);
    }
    w.bool(msg.is_bigendian);
    w.u32(msg.point_step);
    w.u32(msg.row_step);
    w.byte_seq(&msg.data);
    w.bool(msg.is_dense);
    w.finish()
}

/// The x, y, z fields (FLOAT32 at offsets 0, 4, 8) of the clouds this crate writes.
pub fn xyz32_fields() -> Vec<PointField> {
    vec![
        PointField::new("x", 0, PointField::FLOAT32),
        PointField::new("y", 4, PointField::FLOAT32),
        PointField::new("z", 8, PointField::FLOAT32),
    ]
}

/// Encodes points (metres, in `header.frame_id`) as an unorganised little-endian PointCloud2 with FLOAT32 x, y,
/// z and point_step 12; `is_dense` is true when every coordinate is finite. Byte-identical to rosbags. Clouds
/// beyond u32::MAX / 12 points are not representable and are cut there.
pub fn encode_point_cloud2_xyz(header: &Header, points: &[[f32; 3]]) -> Vec<u8> {
    let points = &points[..points.len().min(u32::MAX as usize / 12)];
    let mut w = CdrWriter::new();
    header.write(&mut w);
    w.u32(1);
    w.seq_len(points.len());
    let fields = xyz32_fields();
    w.seq_len(fields.len());
    for f in &fields {
        f.write(&mut w);
    }
    w.bool(false);
    w.u32(12);
    w.seq_len(points.len() * 12); // row_step
    // data: a uint8[] whose elements are the little-endian floats; 4-aligned after its count, so no padding.
    w.seq_len(points.len() * 12);
    for v in points.iter().flatten() {
        w.f32(*v);
    }
    w.bool(points.iter().flatten().all(|v| v.is_finite()));
    w.finish()
}
