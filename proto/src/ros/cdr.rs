//! Plain CDR (OMG XCDR1, what ROS 2 rmw layers put on the wire) with its 4-byte encapsulation header.
//!
//! Hand-written rather than the `cdr` crate: that crate allocates a string's or byte sequence's declared length
//! before checking the payload holds it, so a 16-byte hostile payload costs ~4 GiB of memory; and these readers
//! name the field and offset in every error. Layout rules (byte-identical to the Python `rosbags` serializer):
//! a primitive of size n is aligned to n (at most 8) counted from the end of the 4-byte header; strings are a
//! u32 length including the NUL, the bytes, and the NUL; sequences are a u32 count then the elements; fixed
//! arrays have no count. Trailing bytes after the last field (padding some DDS vendors add) are ignored.

use crate::error::CodecError;

/// Bytes of the encapsulation header before the CDR body; alignment counts from here.
const ORIGIN: usize = 4;

/// Encapsulation header of a little-endian CDR payload.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];
/// Encapsulation header of a big-endian CDR payload.
pub const CDR_BE_HEADER: [u8; 4] = [0x00, 0x00, 0x00, 0x00];

/// Whether `payload` starts with a plain-CDR encapsulation header; `Some(true)` for big-endian. The two option
/// bytes (2 and 3) are not checked: some vendors store the end padding there.
pub fn cdr_header_endianness(payload: &[u8]) -> Option<bool> {
    match payload {
        [0x00, 0x01, _, _, ..] => Some(false),
        [0x00, 0x00, _, _, ..] => Some(true),
        _ => None,
    }
}

/// A cursor over one CDR payload. Every read checks the bounds and names the field in its error.
#[derive(Debug, Clone)]
pub struct CdrReader<'a> {
    buf: &'a [u8],
    pos: usize,
    big_endian: bool,
}

macro_rules! read_prim {
    ($name:ident, $t:ty, $n:expr) => {
        #[doc = concat!("Reads an aligned `", stringify!($t), "`; `what` names the field for errors.")]
        pub fn $name(&mut self, what: &'static str) -> Result<$t, CodecError> {
            self.align($n, what)?;
            let b: [u8; $n] = self.array(what)?;
            Ok(if self.big_endian {
                <$t>::from_be_bytes(b)
            } else {
                <$t>::from_le_bytes(b)
            })
        }
    };
}

impl<'a> CdrReader<'a> {
    /// Checks the encapsulation header (CDR LE `00 01` or CDR BE `00 00`) and positions at the body.
    pub fn new(payload: &'a [u8]) -> Result<Self, CodecError> {
        if payload.len() < ORIGIN {
            return Err(CodecError::Truncated {
                what: "CDR header",
                offset: 0,
                need: ORIGIN,
                len: payload.len(),
            });
        }
        let big_endian = cdr_header_endianness(payload).ok_or_else(|| CodecError::BadCdrHeader {
            found: payload.iter().take(ORIGIN).copied().collect(),
        })?;
        Ok(Self {
            buf: payload,
            pos: ORIGIN,
            big_endian,
        })
    }

    /// True when the body is big-endian.
    pub fn is_big_endian(&self) -> bool {
        self.big_endian
    }

    /// Current byte offset in the payload (header included).
    pub fn position(&self) -> usize {
        self.pos
    }

    /// Bytes left after the cursor.
    pub fn remaining(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }

    fn truncated(&self, what: &'static str, need: usize) -> CodecError {
        CodecError::Truncated {
            what,
            offset: self.pos,
            need,
            len: self.buf.len(),
        }
    }

    /// Takes `n` raw bytes.
    pub fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CodecError> {
        let end = self.pos.checked_add(n).ok_or_else(|| self.truncated(what, n))?;
        let bytes = self.buf.get(self.pos..end).ok_or_else(|| self.truncated(what, n))?;
        self.pos = end;
        Ok(bytes)
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], CodecError> {
        let bytes = self.take(N, what)?;
        <[u8; N]>::try_from(bytes).map_err(|_| self.truncated(what, N))
    }

    /// Skips the padding that aligns the next `n`-byte primitive.
    pub fn align(&mut self, n: usize, what: &'static str) -> Result<(), CodecError> {
        let pad = (n - (self.pos - ORIGIN) % n) % n;
        if pad > 0 {
            self.take(pad, what)?;
        }
        Ok(())
    }

    /// Reads a `uint8`.
    pub fn u8(&mut self, what: &'static str) -> Result<u8, CodecError> {
        Ok(self.array::<1>(what)?[0])
    }

    /// Reads a `bool` (any non-zero byte is true).
    pub fn bool(&mut self, what: &'static str) -> Result<bool, CodecError> {
        Ok(self.u8(what)? != 0)
    }

    read_prim!(u32, u32, 4);
    read_prim!(i32, i32, 4);
    read_prim!(f32, f32, 4);
    read_prim!(f64, f64, 8);

    /// Reads a `string`: u32 length including the NUL, the bytes, the NUL (a length of 0 reads as "").
    pub fn string(&mut self, what: &'static str) -> Result<String, CodecError> {
        let len = self.u32(what)? as usize;
        let offset = self.pos;
        let bytes = self.take(len, what)?;
        let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        std::str::from_utf8(text)
            .map(str::to_owned)
            .map_err(|_| CodecError::InvalidUtf8 { what, offset })
    }

    /// Reads a sequence's u32 count and checks that `count × min_elem_bytes` bytes can still follow, so no
    /// hostile count makes the caller allocate more than the payload could hold.
    pub fn seq_len(&mut self, min_elem_bytes: usize, what: &'static str) -> Result<usize, CodecError> {
        let count = self.u32(what)? as usize;
        let need = count.saturating_mul(min_elem_bytes.max(1));
        if need > self.remaining() {
            return Err(self.truncated(what, need));
        }
        Ok(count)
    }

    /// Reads a `uint8[]` sequence as a borrowed slice.
    pub fn byte_seq(&mut self, what: &'static str, limit: usize) -> Result<&'a [u8], CodecError> {
        let count = self.u32(what)? as usize;
        if count > limit {
            return Err(CodecError::TooLarge {
                what,
                value: count as u64,
                limit: limit as u64,
            });
        }
        self.take(count, what)
    }

    /// Reads a `float32[]` sequence of at most `limit` elements.
    pub fn f32_seq(&mut self, what: &'static str, limit: usize) -> Result<Vec<f32>, CodecError> {
        let count = self.u32(what)? as usize;
        if count > limit {
            return Err(CodecError::TooLarge {
                what,
                value: count as u64,
                limit: limit as u64,
            });
        }
        self.align(4, what)?;
        let bytes = self.take(count.saturating_mul(4), what)?;
        let be = self.big_endian;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| {
                let b = [c[0], c[1], c[2], c[3]];
                if be {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                }
            })
            .collect())
    }

    /// Reads a fixed `float64[N]` array.
    pub fn f64_array<const N: usize>(&mut self, what: &'static str) -> Result<[f64; N], CodecError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(what)?;
        }
        Ok(out)
    }
}

/// Builds one CDR payload, header included. Little-endian unless asked otherwise (ROS 2 sends little-endian).
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
    big_endian: bool,
}

macro_rules! write_prim {
    ($name:ident, $t:ty, $n:expr) => {
        #[doc = concat!("Writes an aligned `", stringify!($t), "`.")]
        pub fn $name(&mut self, v: $t) {
            self.align($n);
            if self.big_endian {
                self.buf.extend_from_slice(&v.to_be_bytes());
            } else {
                self.buf.extend_from_slice(&v.to_le_bytes());
            }
        }
    };
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A little-endian payload (header `00 01 00 00`).
    pub fn new() -> Self {
        Self::with_endianness(false)
    }

    /// A payload in the given byte order (header `00 00 00 00` when `big_endian`).
    pub fn with_endianness(big_endian: bool) -> Self {
        let mut buf = Vec::with_capacity(256);
        buf.extend_from_slice(if big_endian { &CDR_BE_HEADER } else { &CDR_LE_HEADER });
        Self { buf, big_endian }
    }

    /// True when writing big-endian.
    pub fn is_big_endian(&self) -> bool {
        self.big_endian
    }

    /// Pads with zeros so the next `n`-byte primitive is aligned.
    pub fn align(&mut self, n: usize) {
        let pad = (n - (self.buf.len() - ORIGIN) % n) % n;
        self.buf.resize(self.buf.len() + pad, 0);
    }

    /// Writes a `uint8`.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// Writes a `bool` as 0 or 1.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    write_prim!(u32, u32, 4);
    write_prim!(i32, i32, 4);
    write_prim!(f32, f32, 4);
    write_prim!(f64, f64, 8);

    /// Writes a sequence count (u32; lengths beyond u32 are not representable in CDR and saturate).
    pub fn seq_len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    /// Writes a `string` (length with the NUL, bytes, NUL).
    pub fn string(&mut self, s: &str) {
        self.seq_len(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// Writes a `uint8[]` sequence.
    pub fn byte_seq(&mut self, bytes: &[u8]) {
        self.seq_len(bytes.len());
        self.buf.extend_from_slice(bytes);
    }

    /// Writes a `float32[]` sequence.
    pub fn f32_seq(&mut self, values: &[f32]) {
        self.seq_len(values.len());
        for &v in values {
            self.f32(v);
        }
    }

    /// Writes a fixed `float64[N]` array.
    pub fn f64_array(&mut self, values: &[f64]) {
        for &v in values {
            self.f64(v);
        }
    }

    /// The finished payload.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alignment_counts_from_the_end_of_the_header() {
        let mut w = CdrWriter::new();
        w.u8(7);
        w.f64(1.5);
        w.string("ab");
        let bytes = w.finish();
        assert_eq!(&bytes[..4], &CDR_LE_HEADER);
        assert_eq!(bytes.len(), 4 + 8 + 8 + 4 + 3);
        let mut r = CdrReader::new(&bytes).expect("header");
        assert_eq!(r.u8("a").expect("u8"), 7);
        assert_eq!(r.f64("b").expect("f64"), 1.5);
        assert_eq!(r.string("c").expect("string"), "ab");
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn big_endian_round_trip() {
        let mut w = CdrWriter::with_endianness(true);
        w.i32(-5);
        w.f32_seq(&[1.0, -2.5]);
        let bytes = w.finish();
        assert_eq!(&bytes[..4], &CDR_BE_HEADER);
        assert_eq!(&bytes[4..8], &(-5i32).to_be_bytes());
        let mut r = CdrReader::new(&bytes).expect("header");
        assert!(r.is_big_endian());
        assert_eq!(r.i32("a").expect("i32"), -5);
        assert_eq!(r.f32_seq("b", 10).expect("seq"), vec![1.0, -2.5]);
    }

    #[test]
    fn hostile_lengths_fail_without_allocating() {
        let mut bytes = CDR_LE_HEADER.to_vec();
        bytes.extend_from_slice(&0xF000_0000u32.to_le_bytes());
        let err = CdrReader::new(&bytes).and_then(|mut r| r.string("Header.frame_id"));
        assert!(
            matches!(
                err,
                Err(CodecError::Truncated {
                    what: "Header.frame_id",
                    offset: 8,
                    ..
                })
            ),
            "{err:?}"
        );
        let err = CdrReader::new(&bytes).and_then(|mut r| r.seq_len(8, "poses"));
        assert!(matches!(err, Err(CodecError::Truncated { .. })), "{err:?}");
        let err = CdrReader::new(&bytes).and_then(|mut r| r.f32_seq("ranges", 1000));
        assert!(
            matches!(err, Err(CodecError::TooLarge { value: 0xF000_0000, .. })),
            "{err:?}"
        );
    }

    #[test]
    fn header_errors_name_what_was_found() {
        assert!(matches!(
            CdrReader::new(&[0, 1]),
            Err(CodecError::Truncated { what: "CDR header", .. })
        ));
        let err = CdrReader::new(&[0x7b, 0x22, 0, 0]).expect_err("JSON is not CDR");
        assert_eq!(
            err,
            CodecError::BadCdrHeader {
                found: vec![0x7b, 0x22, 0, 0]
            }
        );
        assert!(err.to_string().contains("7b"), "{err}");
        assert_eq!(
            cdr_header_endianness(&[0, 1, 0, 2]),
            Some(false),
            "option bytes are not checked"
        );
    }

    #[test]
    fn invalid_utf8_names_the_offset() {
        let mut bytes = CDR_LE_HEADER.to_vec();
        bytes.extend_from_slice(&3u32.to_le_bytes());
        bytes.extend_from_slice(&[0xff, 0xfe, 0]);
        let err = CdrReader::new(&bytes).and_then(|mut r| r.string("frame_id"));
        assert_eq!(
            err,
            Err(CodecError::InvalidUtf8 {
                what: "frame_id",
                offset: 8
            })
        );
    }
}
