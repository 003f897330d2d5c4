//! PCD (Point Cloud Library) loading: the VERSION/FIELDS/SIZE/TYPE/COUNT/WIDTH/HEIGHT/VIEWPOINT/POINTS/DATA
//! header, then `ascii` rows, `binary` little-endian rows (array of structures) or `binary_compressed` (LZF,
//! structure of arrays). The `x`, `y`, `z` fields may be of any PCD type; NaN points (the holes of an
//! organised cloud) are kept here and dropped and counted by [`super::finish`]. VIEWPOINT is not applied:
//! points stay in the sensor frame the file stores. PCD states no units: metres unless overridden.

use super::ply::Scalar;
use super::{
    CloudError, GroundFilter, LengthUnit, LoadOptions, RawCloud, bounded_capacity, check_points, format_err, header_err,
};

const NAME: &str = "PCD";
/// The header must end within this many bytes.
const MAX_HEADER: usize = 1 << 20;
/// LZF never expands more than this much (a 3-byte back-reference yields at most 264 bytes).
const MAX_LZF_RATIO: u64 = 100;

struct Field {
    name: String,
    ty: Scalar,
    count: usize,
    /// Byte offset within a binary row.
    offset: usize,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

struct Header {
    fields: Vec<Field>,
    points: u64,
    data: Data,
    row: usize,
    body: usize,
    xyz: [usize; 3],
}

fn parse_header(b: &[u8]) -> Result<Header, CloudError> {
    let mut pos = 0;
    let mut kv: Vec<(String, Vec<String>)> = Vec::new();
    let data = loop {
        let rest = b.get(pos..).unwrap_or_default();
        let Some(nl) = rest.iter().position(|&c| c == b'\n') else {
            return Err(CloudError::Truncated {
                format: NAME,
                part: "header",
                detail: "no DATA line".into(),
            });
        };
        let line = String::from_utf8_lossy(&rest[..nl]);
        pos += nl + 1;
        if pos > MAX_HEADER {
            return Err(format_err(NAME, "no DATA line within the first 1 MiB"));
        }
        let line = line.split('#').next().unwrap_or_default().trim();
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let values: Vec<String> = words.map(str::to_string).collect();
        if key.eq_ignore_ascii_case("DATA") {
            break match values.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                Some("ascii") => Data::Ascii,
                Some("binary") => Data::Binary,
                Some("binary_compressed") => Data::Compressed,
                other => {
                    return Err(header_err(
                        NAME,
                        "DATA",
                        format!("{other:?} is not ascii, binary or binary_compressed"),
                    ));
                }
            };
        }
        kv.push((key.to_ascii_uppercase(), values));
    };
    let get = |k: &str| kv.iter().rev().find(|(key, _)| key == k).map(|(_, v)| v.as_slice());
    let names = get("FIELDS").ok_or_else(|| header_err(NAME, "FIELDS", "missing"))?;
    let n = names.len();
    let list = |k: &'static str, default: Option<&str>| -> Result<Vec<String>, CloudError> {
        match (get(k), default) {
            (Some(v), _) if v.len() == n => Ok(v.to_vec()),
            (Some(v), _) => Err(header_err(NAME, k, format!("{} entries for {n} FIELDS", v.len()))),
            (None, Some(d)) => Ok(vec![d.to_string(); n]),
            (None, None) => Err(header_err(NAME, k, "missing")),
        }
    };
    let (sizes, types, counts) = (list("SIZE", None)?, list("TYPE", None)?, list("COUNT", Some("1"))?);
    let mut fields = Vec::with_capacity(n);
    let mut row = 0usize;
    for i in 0..n {
        let size: usize = sizes[i]
            .parse()
            .map_err(|_| header_err(NAME, "SIZE", format!("`{}` is not a number", sizes[i])))?;
        let ty = Scalar::from_pcd(&types[i].to_ascii_uppercase(), size).ok_or_else(|| {
            header_err(
                NAME,
                "TYPE",
                format!("{} of SIZE {size} (field {}) is not a PCD type", types[i], names[i]),
            )
        })?;
        let count: usize = counts[i]
            .parse()
            .ok()
            .filter(|c| (1..=1 << 20).contains(c))
            .ok_or_else(|| {
                header_err(
                    NAME,
                    "COUNT",
                    format!("`{}` (field {}) is not a count", counts[i], names[i]),
                )
            })?;
        fields.push(Field {
            name: names[i].clone(),
            ty,
            count,
            offset: row,
        });
        row += size * count;
    }
    let num = |k: &'static str| -> Result<Option<u64>, CloudError> {
        get(k)
            .map(|v| {
                v.first()
                    .and_then(|s| s.parse().ok())
                    .ok_or_else(|| header_err(NAME, k, "is not a number"))
            })
            .transpose()
    };
    let wh = match (num("WIDTH")?, num("HEIGHT")?) {
        (Some(w), h) => Some(
            w.checked_mul(h.unwrap_or(1))
                .ok_or_else(|| header_err(NAME, "WIDTH", "WIDTH x HEIGHT overflows"))?,
        ),
        (None, _) => None,
    };
    let points = match (num("POINTS")?, wh) {
        (Some(p), Some(wh)) if p != wh => {
            return Err(header_err(NAME, "POINTS", format!("{p}, but WIDTH x HEIGHT is {wh}")));
        }
        (Some(p), _) | (None, Some(p)) => p,
        (None, None) => return Err(header_err(NAME, "POINTS", "missing (and no WIDTH)")),
    };
    let mut xyz = [0; 3];
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        xyz[k] = fields
            .iter()
            .position(|f| f.name == axis)
            .ok_or_else(|| header_err(NAME, "FIELDS", format!("no `{axis}` field")))?;
    }
    Ok(Header {
        fields,
        points,
        data,
        row,
        body: pos,
        xyz,
    })
}

/// Loads PCD bytes.
pub(crate) fn load(b: &[u8], opts: &LoadOptions) -> Result<RawCloud, CloudError> {
    if let GroundFilter::Classes(c) = &opts.ground_only {
        return Err(format_err(
            NAME,
            format!("has no classification to keep classes {c:?} by"),
        ));
    }
    let h = parse_header(b)?;
    check_points(NAME, h.points, &opts.limits)?;
    let body = b.get(h.body..).unwrap_or_default();
    let points = match h.data {
        Data::Ascii => ascii(&h, body, opts)?,
        Data::Binary => binary(&h, body, h.points)?,
        Data::Compressed => compressed(&h, body)?,
    };
    Ok(RawCloud {
        read_points: points.len() as u64,
        points,
        horizontal_unit: LengthUnit::Metre,
        vertical_unit: LengthUnit::Metre,
        unit_source: "assumed metres (PCD has no units)".to_string(),
        crs: None,
        ground_filter: "all points (PCD has no classification)".to_string(),
    })
}

fn truncated(h: &Header, got: usize) -> CloudError {
    let detail = format!("header says {} points but the body ends after {got}", h.points);
    CloudError::Truncated {
        format: NAME,
        part: "point data",
        detail,
    }
}

fn ascii(h: &Header, body: &[u8], opts: &LoadOptions) -> Result<Vec<[f64; 3]>, CloudError> {
    // Token index of x, y, z within a row.
    let starts: Vec<usize> = h
        .fields
        .iter()
        .scan(0, |at, f| Some(std::mem::replace(at, *at + f.count)))
        .collect();
    let tokens_per_row: usize = h.fields.iter().map(|f| f.count).sum();
    let idx = h.xyz.map(|i| starts[i]);
    let cap = bounded_capacity(h.points, 2 * tokens_per_row as u64, body.len(), opts.limits.max_points);
    let mut out = Vec::with_capacity(cap);
    let mut lines = body
        .split(|&c| c == b'\n')
        .enumerate()
        .filter(|(_, l)| !l.trim_ascii().is_empty());
    while (out.len() as u64) < h.points {
        let Some((line_no, line)) = lines.next() else {
            return Err(truncated(h, out.len()));
        };
        let text = String::from_utf8_lossy(line);
        let toks: Vec<&str> = text.split_whitespace().collect();
        if toks.len() != tokens_per_row {
            let detail = format!(
                "data line {}: {} values, the FIELDS/COUNT need {tokens_per_row}",
                line_no + 1,
                toks.len()
            );
            return Err(format_err(NAME, detail));
        }
        let mut p = [0.0; 3];
        for (k, &i) in idx.iter().enumerate() {
            p[k] = toks[i].parse().map_err(|_| {
                format_err(
                    NAME,
                    format!("data line {}: `{}` is not a number", line_no + 1, toks[i]),
                )
            })?;
        }
        out.push(p);
    }
    Ok(out)
}

fn binary(h: &Header, body: &[u8], n: u64) -> Result<Vec<[f64; 3]>, CloudError> {
    let have = body.len() / h.row.max(1);
    if (have as u64) < n {
        return Err(truncated(h, have));
    }
    let n = n as usize; // <= have, which is a usize
    let mut out = Vec::with_capacity(n);
    for row in body.chunks_exact(h.row).take(n) {
        let mut p = [0.0; 3];
        for (k, &i) in h.xyz.iter().enumerate() {
            let f = &h.fields[i];
            p[k] = row
                .get(f.offset..)
                .and_then(|b| f.ty.read(b, false))
                .unwrap_or(f64::NAN);
        }
        out.push(p);
    }
    Ok(out)
}

fn compressed(h: &Header, body: &[u8]) -> Result<Vec<[f64; 3]>, CloudError> {
    let word = |at: usize| {
        body.get(at..at + 4)
            .map(|w| u64::from(u32::from_le_bytes([w[0], w[1], w[2], w[3]])))
    };
    let (Some(packed), Some(unpacked)) = (word(0), word(4)) else {
        return Err(CloudError::Truncated {
            format: NAME,
            part: "compressed data",
            detail: "no size words".into(),
        });
    };
    let expect = h.points.saturating_mul(h.row as u64);
    if unpacked != expect {
        return Err(header_err(
            NAME,
            "binary_compressed sizes",
            format!("unpacked {unpacked} bytes, POINTS x row is {expect}"),
        ));
    }
    let data = body.get(8..).unwrap_or_default();
    if (data.len() as u64) < packed {
        let detail = format!("{packed} compressed bytes announced, {} present", data.len());
        return Err(CloudError::Truncated {
            format: NAME,
            part: "compressed data",
            detail,
        });
    }
    if unpacked > packed.saturating_mul(MAX_LZF_RATIO) {
        return Err(format_err(
            NAME,
            format!("{packed} LZF bytes cannot unpack to {unpacked}"),
        ));
    }
    if unpacked == 0 {
        return Ok(Vec::new());
    }
    let raw = lzf::decompress(&data[..packed as usize], unpacked as usize)
        .map_err(|e| format_err(NAME, format!("LZF data does not decompress: {e:?}")))?;
    if raw.len() as u64 != unpacked {
        return Err(format_err(
            NAME,
            format!("LZF data unpacked to {} bytes, not {unpacked}", raw.len()),
        ));
    }
    // Structure of arrays: field i's values for all points start at points x (sum of earlier field widths).
    let n = h.points as usize;
    let mut out = vec![[0.0; 3]; n];
    for (k, &i) in h.xyz.iter().enumerate() {
        let f = &h.fields[i];
        let start = f.offset * n;
        let width = f.ty.size() * f.count;
        for (j, p) in out.iter_mut().enumerate() {
            p[k] = raw
                .get(start + j * width..)
                .and_then(|b| f.ty.read(b, false))
                .unwrap_or(f64::NAN);
        }
    }
    Ok(out)
}

#[cfg(test)]
#[path = "pcd_tests.rs"]
pub(crate) mod tests;
