//! LAS and LAZ (LASzip) loading through the `las` crate, with the checks it leaves to its callers: header
//! counts and offsets are validated against the byte length before the crate sizes anything by them (the
//! point count, an EVLR's 64-bit length, the LAZ chunk count), points are read in bounded batches, and
//! units come from the CRS VLRs ([`super::geokeys`]). Coordinates are the header's scale and offset applied
//! to the integer records, in the file's units; [`super::finish`] scales them to metres.

use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};

use super::geokeys::{self, CrsInfo, Stated};
use super::{
    CloudError, CloudFormat, GroundFilter, LengthUnit, LoadOptions, RawCloud, bounded_capacity, check_points,
    format_err, header_err,
};

/// Points decoded per `fill_points` call: bounds the crate's batch buffer whatever the header says.
const BATCH: u64 = 50_000;
/// The smallest LAS point record (format 0), bytes; also the smallest raw first point of a LAZ chunk.
const MIN_RECORD: u64 = 20;

fn le_u16(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn le_u64(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Whether a `LASF` file's points are LASzip-compressed: the point format's compression bits (0x80 or 0x40)
/// or a `laszip encoded` VLR.
pub(crate) fn looks_compressed(bytes: &[u8]) -> bool {
    if bytes.get(104).is_some_and(|pf| pf & 0xC0 != 0) {
        return true;
    }
    let (Some(header_size), Some(n_vlrs)) = (le_u16(bytes, 94), le_u32(bytes, 100)) else {
        return false;
    };
    let mut at = usize::from(header_size);
    for _ in 0..n_vlrs.min(1024) {
        let (Some(id), Some(len)) = (bytes.get(at + 2..at + 18), le_u16(bytes, at + 20)) else {
            return false;
        };
        if id.starts_with(b"laszip encoded") {
            return true;
        }
        at += 54 + usize::from(len);
    }
    false
}

/// The counts and offsets of a LAS header that the checks below need.
struct Fixed {
    minor: u8,
    header_size: u64,
    offset_to_points: u64,
    compressed: bool,
    record_len: u64,
    n_points: u64,
}

fn fixed(b: &[u8], name: &'static str) -> Result<Fixed, CloudError> {
    let truncated = |detail: String| CloudError::Truncated {
        format: name,
        part: "header",
        detail,
    };
    if b.len() < 227 {
        return Err(truncated(format!(
            "{} bytes, the LAS 1.0-1.2 header alone is 227",
            b.len()
        )));
    }
    let (major, minor) = (b[24], b[25]);
    if major != 1 || minor > 4 {
        return Err(header_err(
            name,
            "version",
            format!("{major}.{minor}; only LAS 1.0 to 1.4 are read"),
        ));
    }
    let header_size = u64::from(le_u16(b, 94).unwrap_or(0));
    let offset_to_points = u64::from(le_u32(b, 96).unwrap_or(0));
    let legacy = u64::from(le_u32(b, 107).unwrap_or(0));
    let n_points = if minor >= 4 {
        let n = le_u64(b, 247).ok_or_else(|| truncated(format!("{} bytes, the LAS 1.4 header is 375", b.len())))?;
        if n == 0 { legacy } else { n }
    } else {
        legacy
    };
    if (b.len() as u64) < header_size.max(offset_to_points) {
        return Err(truncated(format!(
            "the header and VLRs end at byte {} (offset to point data) but the file has {} bytes",
            header_size.max(offset_to_points),
            b.len()
        )));
    }
    Ok(Fixed {
        minor,
        header_size,
        offset_to_points,
        compressed: b[104] & 0xC0 != 0,
        record_len: u64::from(le_u16(b, 105).unwrap_or(0)),
        n_points,
    })
}

/// Checks the counts the `las`/`laz` crates would allocate by before handing them the bytes.
fn precheck(b: &[u8], f: &Fixed, name: &'static str, opts: &LoadOptions) -> Result<(), CloudError> {
    let len = b.len() as u64;
    check_points(name, f.n_points, &opts.limits)?;
    if f.record_len < MIN_RECORD {
        let detail = format!("{} bytes, below the smallest LAS record ({MIN_RECORD})", f.record_len);
        return Err(header_err(name, "point data record length", detail));
    }
    if !f.compressed {
        let have = (len - f.offset_to_points) / f.record_len;
        if have < f.n_points {
            return Err(CloudError::Truncated {
                format: name,
                part: "point data",
                detail: format!(
                    "the header says {} points of {} bytes from byte {} but the file holds {have}",
                    f.n_points, f.record_len, f.offset_to_points
                ),
            });
        }
    }
    // LAS 1.4 EVLRs: the crate reads the first one with a 64-bit length into a buffer of that size.
    if f.minor >= 4 && f.header_size >= 375 && le_u32(b, 243).is_some_and(|n| n > 0) {
        let start = le_u64(b, 235).unwrap_or(0);
        let fits = start
            .checked_add(60)
            .and_then(|end| end.checked_add(le_u64(b, usize::try_from(start.checked_add(20)?).ok()?)?))
            .is_some_and(|end| end <= len);
        if !fits {
            let detail = format!("the first EVLR at byte {start} does not fit in the file's {len} bytes");
            return Err(CloudError::Truncated {
                format: name,
                part: "extended VLRs",
                detail,
            });
        }
    }
    // LAZ: the chunk table's count sizes a Vec; every chunk starts with a raw point of >= 20 bytes.
    if f.compressed {
        let at = usize::try_from(f.offset_to_points).unwrap_or(usize::MAX);
        // As the laz crate finds it: the offset before the points, else (stream-written) the file's last 8 bytes.
        let pos = f.offset_to_points as i64;
        let mut table = le_u64(b, at).map_or(0, |t| t as i64);
        if table <= pos {
            table = le_u64(b, b.len().saturating_sub(8)).map_or(0, |t| t as i64);
        }
        let table = if table <= pos { 0 } else { table as u64 };
        if table > 0 && table.saturating_add(8) > len {
            let detail = format!("the file ends at byte {len}, before the chunk table at byte {table}");
            return Err(CloudError::Truncated {
                format: name,
                part: "compressed point data",
                detail,
            });
        }
        if table > 0
            && let Some(n_chunks) = usize::try_from(table).ok().and_then(|t| le_u32(b, t.checked_add(4)?))
            && u64::from(n_chunks) > len / MIN_RECORD
        {
            let detail = format!("the chunk table at byte {table} says {n_chunks} chunks, more than {len} bytes hold");
            return Err(format_err(name, detail));
        }
    }
    Ok(())
}

/// Whether an error from the crates is the input running out.
fn is_eof(e: &las::Error) -> bool {
    let io = match e {
        las::Error::Io(io) | las::Error::LasZipError(laz::LasZipError::IoError(io)) => io,
        _ => return false,
    };
    io.kind() == std::io::ErrorKind::UnexpectedEof
}

/// Loads LAS or LAZ bytes (`format` is the caller's or the sniffed one; the header's compression bit decides).
pub(crate) fn load(bytes: Vec<u8>, format: CloudFormat, opts: &LoadOptions) -> Result<RawCloud, CloudError> {
    if !bytes.starts_with(b"LASF") {
        let magic = bytes.get(..4).unwrap_or(&bytes);
        return Err(format_err(
            format.name(),
            format!("file signature {magic:?} at byte 0 is not \"LASF\""),
        ));
    }
    let name = if looks_compressed(&bytes) || format == CloudFormat::Laz {
        "LAZ"
    } else {
        "LAS"
    };
    let f = fixed(&bytes, name)?;
    precheck(&bytes, &f, name, opts)?;
    // The crates are trusted only after the checks above; a panic deep in a decoder on a crafted file is
    // still turned into an error here rather than taking the daemon down.
    match catch_unwind(AssertUnwindSafe(|| read(bytes, &f, name, opts))) {
        Ok(r) => r,
        Err(_) => Err(format_err(name, "the LAS/LAZ decoder failed on malformed point data")),
    }
}

fn read(bytes: Vec<u8>, f: &Fixed, name: &'static str, opts: &LoadOptions) -> Result<RawCloud, CloudError> {
    let len = bytes.len();
    let header = las::Header::new(Cursor::new(&bytes[..])).map_err(|e| {
        if is_eof(&e) {
            CloudError::Truncated {
                format: name,
                part: "header or VLRs",
                detail: e.to_string(),
            }
        } else {
            format_err(name, format!("reading the header and VLRs: {e}"))
        }
    })?;
    let n = header.number_of_points();
    check_points(name, n, &opts.limits)?;
    let chunk_size = if header.point_format().is_compressed {
        let vlr = header
            .laz_vlr()
            .map_err(|e| header_err(name, "laszip VLR", e.to_string()))?;
        let record = u64::from(header.point_format().len());
        if vlr.items_size() != record {
            let detail = format!(
                "its items are {} bytes but the point record is {record}",
                vlr.items_size()
            );
            return Err(header_err(name, "laszip VLR", detail));
        }
        u64::from(vlr.chunk_size()).max(1)
    } else {
        n.max(1)
    };
    let mut reader = las::Reader::new(Cursor::new(bytes)).map_err(|e| {
        if is_eof(&e) {
            CloudError::Truncated {
                format: name,
                part: "compressed point data",
                detail: e.to_string(),
            }
        } else {
            format_err(name, format!("opening the point data: {e}"))
        }
    })?;
    let units = units(&header, name, opts);
    let (h, v, unit_source, crs) = match (units, opts.units) {
        (Ok(u), _) => u,
        (Err(e), Some(_)) => (LengthUnit::Metre, LengthUnit::Metre, format!("unreadable: {e}"), None),
        (Err(e), None) => return Err(e),
    };

    let cap = bounded_capacity(
        n,
        if f.compressed { 1 } else { f.record_len },
        len,
        opts.limits.max_points,
    );
    let mut points = Vec::with_capacity(cap);
    let mut classes = Vec::with_capacity(cap);
    let mut pd = las::PointDataBuilder::new().for_header(&header).build();
    loop {
        let got = reader.fill_points(BATCH, &mut pd).map_err(|e| {
            let at = points.len() as u64;
            let detail = format!(
                "chunk {} of {} (after {at} of {n} points): {e}",
                at / chunk_size + 1,
                n.div_ceil(chunk_size).max(1)
            );
            if is_eof(&e) {
                CloudError::Truncated {
                    format: name,
                    part: "point data",
                    detail,
                }
            } else {
                format_err(name, format!("decoding the point data: {detail}"))
            }
        })?;
        if got == 0 {
            break;
        }
        points.extend(pd.x().zip(pd.y()).zip(pd.z()).map(|((x, y), z)| [x, y, z]));
        classes.extend(pd.classification());
    }
    let read_points = points.len() as u64;
    let ground_filter = filter(&mut points, &classes, &opts.ground_only);
    Ok(RawCloud {
        points,
        horizontal_unit: h,
        vertical_unit: v,
        unit_source,
        crs,
        read_points,
        ground_filter,
    })
}

/// Applies the ground filter in place; returns what it did, for a person.
fn filter(points: &mut Vec<[f64; 3]>, classes: &[u8], how: &GroundFilter) -> String {
    let n = points.len();
    let keep: Vec<u8> = match how {
        GroundFilter::All => return "all points".to_string(),
        GroundFilter::Auto if !classes.contains(&2) => {
            return "all points (no point is classified ground, class 2)".to_string();
        }
        GroundFilter::Auto => vec![2],
        GroundFilter::Classes(c) => c.clone(),
    };
    let mut i = 0;
    points.retain(|_| {
        let k = classes.get(i).is_some_and(|c| keep.contains(c));
        i += 1;
        k
    });
    let auto = if matches!(how, GroundFilter::Auto) {
        "ground only, "
    } else {
        ""
    };
    format!("{auto}classes {keep:?}: kept {} of {n}", points.len())
}

type Units = (LengthUnit, LengthUnit, String, Option<String>);

/// The file's horizontal and vertical units, where they came from, and its CRS name.
fn units(header: &las::Header, name: &'static str, opts: &LoadOptions) -> Result<Units, CloudError> {
    let find = |id: u16| {
        header
            .all_vlrs()
            .find(|v| v.user_id == "LASF_Projection" && v.record_id == id)
            .map(|v| v.data.as_slice())
    };
    let geo = find(34735)
        .map(|dir| geokeys::from_geokeys(name, dir, find(34736), find(34737)))
        .transpose()?;
    let wkt = find(2112).map(|w| geokeys::from_wkt(name, w)).transpose()?;
    // LAS 1.4's global-encoding WKT bit makes the WKT record the authoritative one.
    let sources: Vec<CrsInfo> = if header.has_wkt_crs() { [wkt, geo] } else { [geo, wkt] }
        .into_iter()
        .flatten()
        .collect();
    let horizontal: Vec<&Stated> = sources.iter().filter_map(|s| s.horizontal.as_ref()).collect();
    if let [a, b, ..] = horizontal[..]
        && a.unit != b.unit
        && opts.units.is_none()
    {
        let detail = format!("{} but {}; pass a units override", a.how, b.how);
        return Err(header_err(name, "CRS linear unit", detail));
    }
    let crs = sources.iter().find_map(|s| s.crs.clone());
    if sources.first().is_some_and(|s| s.geographic) && horizontal.is_empty() && opts.units.is_none() {
        let detail = format!(
            "the CRS ({}) is geographic: x and y are degrees, not lengths; reproject to a projected CRS",
            crs.as_deref().unwrap_or("unnamed")
        );
        return Err(header_err(name, "CRS", detail));
    }
    let vertical = sources.iter().find_map(|s| s.vertical.as_ref());
    Ok(match (horizontal.first(), vertical) {
        (Some(h), Some(v)) => (h.unit, v.unit, format!("{}; vertical: {}", h.how, v.how), crs),
        (Some(h), None) => {
            let how = format!("{}; vertical unit not stated, taken as the horizontal", h.how);
            (h.unit, h.unit, how, crs)
        }
        (None, Some(v)) => {
            let how = format!("horizontal unit not stated, assumed metres; vertical: {}", v.how);
            (LengthUnit::Metre, v.unit, how, crs)
        }
        (None, None) => {
            let how = if sources.is_empty() {
                "assumed metres (the file has no CRS records)"
            } else {
                "assumed metres (the CRS records state no linear unit)"
            };
            (LengthUnit::Metre, LengthUnit::Metre, how.to_string(), crs)
        }
    })
}

#[cfg(test)]
#[path = "las_tests.rs"]
pub(crate) mod tests;
