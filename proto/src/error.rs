//! The one error type of the wire codecs: what is wrong with a payload, and where.
//!
//! Offsets are byte offsets into the whole payload, the 4-byte CDR encapsulation header included.

/// Why a payload (CDR or JSON) could not be decoded. Decoders return this and never panic.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CodecError {
    /// The payload ends before a field does.
    #[error("truncated payload: {what} needs {need} bytes at offset {offset}, but the payload has {len} bytes")]
    Truncated {
        /// The field being read, e.g. `PointCloud2.data`.
        what: &'static str,
        /// Byte offset where the field starts.
        offset: usize,
        /// Bytes the field needs from `offset`.
        need: usize,
        /// Length of the whole payload in bytes.
        len: usize,
    },
    /// The first four bytes are not a CDR encapsulation header this decoder reads.
    #[error(
        "bad CDR header: expected 00 01 00 00 (CDR little-endian) or 00 00 00 00 (CDR big-endian), found {found:02x?}"
    )]
    BadCdrHeader {
        /// The first (up to four) bytes of the payload.
        found: Vec<u8>,
    },
    /// A point cloud lacks one of the fields x, y, z.
    #[error("point cloud has no field named `{name}`")]
    MissingField {
        /// `x`, `y` or `z`.
        name: &'static str,
    },
    /// A coordinate field has a datatype other than FLOAT32 (7) or FLOAT64 (8).
    #[error("point field `{name}` has datatype {datatype}; only FLOAT32 (7) and FLOAT64 (8) are supported")]
    UnsupportedDatatype {
        /// Field name.
        name: String,
        /// sensor_msgs/PointField datatype code.
        datatype: u8,
    },
    /// A coordinate field does not fit inside one point.
    #[error("point_step {point_step} is smaller than field `{name}` (offset {offset} + {size} bytes)")]
    PointStepTooSmall {
        /// Field name.
        name: String,
        /// Field offset inside the point, bytes.
        offset: u32,
        /// Field size, bytes.
        size: u32,
        /// Bytes per point.
        point_step: u32,
    },
    /// Declared sizes disagree with each other or with the data.
    #[error("size mismatch: {what} (need {expected} bytes, have {found})")]
    SizeMismatch {
        /// Which sizes disagree, e.g. `PointCloud2.data is shorter than height × row_step`.
        what: &'static str,
        /// Bytes needed.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// A declared size is beyond what any real sensor sends (> 20 M points or > 512 MiB).
    #[error("absurd size: {what} is {value}, the limit is {limit}")]
    TooLarge {
        /// What was counted, e.g. `PointCloud2 points (height × width)`.
        what: &'static str,
        /// The declared value.
        value: u64,
        /// The largest accepted value.
        limit: u64,
    },
    /// A CDR string is not UTF-8.
    #[error("invalid UTF-8 in {what} at offset {offset}")]
    InvalidUtf8 {
        /// The string field, e.g. `Header.frame_id`.
        what: &'static str,
        /// Byte offset of the string's first byte.
        offset: usize,
    },
    /// A JSON payload does not parse or lacks a required field.
    #[error("invalid JSON odometry: {reason}")]
    Json {
        /// The parser's explanation, with line and column.
        reason: String,
    },
    /// A decoded value that must be finite is NaN or infinite (or out of range).
    #[error("{what} is not finite or out of range")]
    NonFinite {
        /// The value, e.g. `odometry x`.
        what: &'static str,
    },
    /// Neither the encoding nor the first bytes say JSON or CDR.
    #[error("payload is neither JSON nor CDR (encoding {encoding:?}, first bytes {first:02x?})")]
    UnknownEncoding {
        /// The Zenoh encoding given with the sample, if any.
        encoding: Option<String>,
        /// The first (up to four) bytes of the payload.
        first: Vec<u8>,
    },
}

impl CodecError {
    /// A short stable label for metrics and rate-limited logs, e.g. `truncated`, `bad_cdr_header`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Truncated { .. } => "truncated",
            Self::BadCdrHeader { .. } => "bad_cdr_header",
            Self::MissingField { .. } => "missing_field",
            Self::UnsupportedDatatype { .. } => "unsupported_datatype",
            Self::PointStepTooSmall { .. } => "point_step_too_small",
            Self::SizeMismatch { .. } => "size_mismatch",
            Self::TooLarge { .. } => "too_large",
            Self::InvalidUtf8 { .. } => "invalid_utf8",
            Self::Json { .. } => "invalid_json",
            Self::NonFinite { .. } => "non_finite",
            Self::UnknownEncoding { .. } => "unknown_encoding",
        }
    }
}
