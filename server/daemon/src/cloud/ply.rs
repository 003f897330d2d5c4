//! PLY loading (ascii, binary_little_endian, binary_big_endian), hand-written: the header's elements are
//! walked in order, elements before `vertex` are skipped row by row (list properties included), the
//! vertex element's scalar `x`, `y`, `z` are read in any scalar type, its other properties (lists too) are
//! skipped, and everything after the vertex element (faces, trailing bytes) is ignored. A header count larger
//! than the body is an error; a smaller one reads that many vertices and ignores the rest (PLY has no row
//! delimiter in binary, so surplus bytes cannot be told from later elements). PLY states no units:
//! coordinates are taken as metres unless the caller overrides.

use super::{
    CloudError, GroundFilter, LengthUnit, LoadOptions, RawCloud, bounded_capacity, check_points, format_err, header_err,
};

const NAME: &str = "PLY";
/// The header must end within this many bytes.
const MAX_HEADER: usize = 1 << 20;

/// A PLY (or PCD) scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    /// The type a PLY header names (`char`…`double` and the `int8`…`float64` aliases).
    fn from_ply(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// The type a PCD TYPE letter (`I`, `U`, `F`) and SIZE name.
    pub(crate) fn from_pcd(kind: &str, size: usize) -> Option<Self> {
        Some(match (kind, size) {
            ("I", 1) => Self::I8,
            ("U", 1) => Self::U8,
            ("I", 2) => Self::I16,
            ("U", 2) => Self::U16,
            ("I", 4) => Self::I32,
            ("U", 4) => Self::U32,
            ("I", 8) => Self::I64,
            ("U", 8) => Self::U64,
            ("F", 4) => Self::F32,
            ("F", 8) => Self::F64,
            _ => return None,
        })
    }

    /// Bytes per value.
    pub(crate) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// Decodes one value from the start of `b` (at least `size()` bytes, else `None`).
    pub(crate) fn read(self, b: &[u8], big_endian: bool) -> Option<f64> {
        let mut a = [0u8; 8];
        let n = self.size();
        a[..n].copy_from_slice(b.get(..n)?);
        if big_endian {
            a[..n].reverse();
        }
        let [b0, b1, b2, b3, ..] = a;
        Some(match self {
            Self::I8 => f64::from(b0 as i8),
            Self::U8 => f64::from(b0),
            Self::I16 => f64::from(i16::from_le_bytes([b0, b1])),
            Self::U16 => f64::from(u16::from_le_bytes([b0, b1])),
            Self::I32 => f64::from(i32::from_le_bytes([b0, b1, b2, b3])),
            Self::U32 => f64::from(u32::from_le_bytes([b0, b1, b2, b3])),
            Self::I64 => i64::from_le_bytes(a) as f64,
            Self::U64 => u64::from_le_bytes(a) as f64,
            Self::F32 => f64::from(f32::from_le_bytes([b0, b1, b2, b3])),
            Self::F64 => f64::from_le_bytes(a),
        })
    }
}

#[derive(Debug)]
enum Prop {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Prop>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

/// Parses the header; returns the encoding, the elements and the offset of the body.
fn header(b: &[u8]) -> Result<(Encoding, Vec<Element>, usize), CloudError> {
    let window = &b[..b.len().min(MAX_HEADER)];
    let end = window
        .windows(11)
        .position(|w| w == b"end_header\n" || w == b"end_header\r");
    let end = end.ok_or_else(|| format_err(NAME, "no `end_header` line within the first 1 MiB"))?;
    let body = end
        + if b.get(end + 10..end + 12) == Some(b"\r\n") {
            12
        } else {
            11
        };
    let text = std::str::from_utf8(&b[..end]).map_err(|e| format_err(NAME, format!("header is not text: {e}")))?;
    let mut lines = text.lines().enumerate();
    if lines.next().map(|(_, l)| l.trim()) != Some("ply") {
        return Err(format_err(NAME, "line 1 is not `ply`"));
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in lines {
        let line_no = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |field: &str, what: String| header_err(NAME, format!("{field} (line {line_no})"), what);
        match words.as_slice() {
            [] | ["comment" | "obj_info", ..] => {}
            ["format", f, _version] => {
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    _ => {
                        return Err(bad(
                            "format",
                            format!("`{f}` is not ascii or binary_(little|big)_endian"),
                        ));
                    }
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| bad("element", format!("count `{count}` is not a number")))?;
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property", "comes before any element".into()))?;
                let ty = |t: &str| Scalar::from_ply(t).ok_or_else(|| bad("property", format!("unknown type `{t}`")));
                let prop = match rest {
                    ["list", c, t, name] => Prop::List((*name).to_string(), ty(c)?, ty(t)?),
                    [t, name] => Prop::Scalar((*name).to_string(), ty(t)?),
                    _ => return Err(bad("property", format!("`{line}` is not `property <type> <name>`"))),
                };
                el.props.push(prop);
            }
            _ => return Err(bad("header line", format!("`{line}` is not a PLY header line"))),
        }
    }
    let encoding = encoding.ok_or_else(|| header_err(NAME, "format", "missing"))?;
    Ok((encoding, elements, body))
}

/// The body reader: ascii tokens or binary values, either way with a position for messages.
struct Body<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
    encoding: Encoding,
}

impl Body<'_> {
    /// The next value of type `ty`; `Ok(None)` at the end of the body.
    fn value(&mut self, ty: Scalar) -> Result<Option<f64>, CloudError> {
        match self.encoding {
            Encoding::Binary { big_endian } => {
                let v = self.b.get(self.pos..).and_then(|rest| ty.read(rest, big_endian));
                if v.is_some() {
                    self.pos += ty.size();
                }
                Ok(v)
            }
            Encoding::Ascii => {
                while let Some(&c) = self.b.get(self.pos).filter(|c| c.is_ascii_whitespace()) {
                    self.line += usize::from(c == b'\n');
                    self.pos += 1;
                }
                let start = self.pos;
                while self.b.get(self.pos).is_some_and(|c| !c.is_ascii_whitespace()) {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Ok(None);
                }
                let tok = String::from_utf8_lossy(&self.b[start..self.pos]);
                let v: f64 = tok
                    .parse()
                    .map_err(|_| format_err(NAME, format!("body line {}: token `{tok}` is not a number", self.line)))?;
                Ok(Some(v))
            }
        }
    }

    /// The next list length (a non-negative integer).
    fn list_len(&mut self, ty: Scalar) -> Result<Option<u64>, CloudError> {
        let Some(v) = self.value(ty)? else { return Ok(None) };
        if v < 0.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
            return Err(format_err(
                NAME,
                format!("list length {v} at byte {} is not a count", self.pos),
            ));
        }
        Ok(Some(v as u64))
    }

    /// Reads one row of `el`; fills `xyz` for the properties at `want`. `Ok(false)` when the body ends.
    fn row(&mut self, el: &Element, want: [usize; 3], xyz: &mut [f64; 3]) -> Result<bool, CloudError> {
        for (i, p) in el.props.iter().enumerate() {
            match p {
                Prop::Scalar(_, ty) => {
                    let Some(v) = self.value(*ty)? else { return Ok(false) };
                    if let Some(k) = want.iter().position(|&w| w == i) {
                        xyz[k] = v;
                    }
                }
                Prop::List(_, count, item) => {
                    let Some(n) = self.list_len(*count)? else {
                        return Ok(false);
                    };
                    if let Encoding::Binary { .. } = self.encoding {
                        let skip = (n as usize).saturating_mul(item.size());
                        if self.b.len() - self.pos.min(self.b.len()) < skip {
                            return Ok(false);
                        }
                        self.pos += skip;
                    } else {
                        for _ in 0..n {
                            if self.value(*item)?.is_none() {
                                return Ok(false);
                            }
                        }
                    }
                }
            }
        }
        Ok(true)
    }
}

/// Loads PLY bytes.
pub(crate) fn load(b: &[u8], opts: &LoadOptions) -> Result<RawCloud, CloudError> {
    let ground_filter = match &opts.ground_only {
        GroundFilter::Classes(c) => {
            return Err(format_err(
                NAME,
                format!("has no classification to keep classes {c:?} by"),
            ));
        }
        _ => "all points (PLY has no classification)".to_string(),
    };
    let (encoding, elements, start) = header(b)?;
    let vi = elements.iter().position(|e| e.name == "vertex");
    let vi = vi.ok_or_else(|| header_err(NAME, "element vertex", "missing"))?;
    let vertex = &elements[vi];
    check_points(NAME, vertex.count, &opts.limits)?;
    let mut want = [usize::MAX; 3];
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        want[k] = match vertex
            .props
            .iter()
            .position(|p| matches!(p, Prop::Scalar(n, _) | Prop::List(n, ..) if n == axis))
        {
            Some(i) if matches!(vertex.props[i], Prop::List(..)) => {
                return Err(header_err(
                    NAME,
                    format!("property {axis}"),
                    "is a list; x, y, z must be scalars",
                ));
            }
            Some(i) => i,
            None => {
                return Err(header_err(
                    NAME,
                    format!("property {axis}"),
                    "missing from element vertex",
                ));
            }
        };
    }
    let mut body = Body {
        b,
        pos: start,
        line: 1,
        encoding,
    };
    let mut scratch = [0.0; 3];
    for el in &elements[..vi] {
        if el.props.is_empty() {
            continue;
        }
        for row in 0..el.count {
            if !body.row(el, [usize::MAX; 3], &mut scratch)? {
                let detail = format!(
                    "header says {} {} elements but the body ends after {row}",
                    el.count, el.name
                );
                return Err(CloudError::Truncated {
                    format: NAME,
                    part: "element data",
                    detail,
                });
            }
        }
    }
    let min_row = match encoding {
        Encoding::Binary { .. } => vertex.props.iter().map(|p| match p {
            Prop::Scalar(_, t) | Prop::List(_, t, _) => t.size() as u64,
        }),
        Encoding::Ascii => return read_vertices(&mut body, vertex, want, opts, 6, ground_filter),
    };
    read_vertices(&mut body, vertex, want, opts, min_row.sum(), ground_filter)
}

fn read_vertices(
    body: &mut Body<'_>,
    vertex: &Element,
    want: [usize; 3],
    opts: &LoadOptions,
    min_row: u64,
    ground_filter: String,
) -> Result<RawCloud, CloudError> {
    let remaining = body.b.len().saturating_sub(body.pos);
    let mut points = Vec::with_capacity(bounded_capacity(
        vertex.count,
        min_row,
        remaining,
        opts.limits.max_points,
    ));
    let mut xyz = [0.0; 3];
    for row in 0..vertex.count {
        if !body.row(vertex, want, &mut xyz)? {
            let detail = format!("header says {} vertices but the body ends after {row}", vertex.count);
            return Err(CloudError::Truncated {
                format: NAME,
                part: "vertex data",
                detail,
            });
        }
        points.push(xyz);
    }
    Ok(RawCloud {
        read_points: points.len() as u64,
        points,
        horizontal_unit: LengthUnit::Metre,
        vertical_unit: LengthUnit::Metre,
        unit_source: "assumed metres (PLY has no units)".to_string(),
        crs: None,
        ground_filter,
    })
}

#[cfg(test)]
#[path = "ply_tests.rs"]
pub(crate) mod tests;
