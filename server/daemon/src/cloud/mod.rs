//! Point-cloud file loaders for outdoor terrain: LAS/LAZ, PLY and PCD.
//!
//! Each loader turns the bytes of a file into points in metres, `[x, y, z]`, on the file's own axes: x and y
//! are the file's horizontal axes (easting and northing for a projected CRS) scaled to metres with the origin
//! kept (no recentring), z is the file's vertical axis scaled to metres. Units come from the file where it
//! states them (LAS: GeoTIFF keys or the OGC WKT VLR), from the caller's override ([`LoadOptions::units`]),
//! or are assumed metres, and [`Cloud::unit_source`] says which. Nothing here panics on any input, and no
//! allocation is sized by a header count beyond what the bytes can hold and [`CloudLimits::max_points`].

mod geokeys;
mod las;
mod pcd;
mod ply;
pub mod source;
mod units;

pub use units::LengthUnit;

use std::fmt;
use std::path::{Path, PathBuf};

/// The file formats the loaders read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudFormat {
    /// ASPRS LAS, uncompressed point records.
    Las,
    /// LAS compressed with LASzip.
    Laz,
    /// Stanford PLY (ascii, binary little- or big-endian).
    Ply,
    /// Point Cloud Library PCD (ascii, binary, binary_compressed).
    Pcd,
}

impl CloudFormat {
    /// The format named by the path's extension (`.las`, `.laz`, `.ply`, `.pcd`, any case), if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "las" => Some(Self::Las),
            "laz" => Some(Self::Laz),
            "ply" => Some(Self::Ply),
            "pcd" => Some(Self::Pcd),
            _ => None,
        }
    }

    /// The format the leading bytes announce: `LASF` (LAZ when the point format's compression bits are set
    /// or a `laszip encoded` VLR is present), `ply` + newline, or a PCD header line (`# .PCD`, `VERSION`,
    /// `FIELDS`).
    pub fn sniff(bytes: &[u8]) -> Option<Self> {
        if bytes.starts_with(b"LASF") {
            return Some(if las::looks_compressed(bytes) {
                Self::Laz
            } else {
                Self::Las
            });
        }
        if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
            return Some(Self::Ply);
        }
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(bytes.len());
        let head = &bytes[start..];
        if head.starts_with(b"# .PCD") || head.starts_with(b"VERSION") || head.starts_with(b"FIELDS") {
            return Some(Self::Pcd);
        }
        None
    }

    /// The format's name as used in messages ("LAS", "LAZ", "PLY", "PCD").
    pub fn name(self) -> &'static str {
        match self {
            Self::Las => "LAS",
            Self::Laz => "LAZ",
            Self::Ply => "PLY",
            Self::Pcd => "PCD",
        }
    }
}

impl fmt::Display for CloudFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Caps on what a load may take in: file bytes and point records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CloudLimits {
    /// The largest file accepted, in bytes (default 512 MiB).
    pub max_bytes: u64,
    /// The most point records a header may announce or a body may hold (default 50 000 000).
    pub max_points: u64,
}

impl Default for CloudLimits {
    fn default() -> Self {
        Self {
            max_bytes: 512 * 1024 * 1024,
            max_points: 50_000_000,
        }
    }
}

/// Which points of a classified cloud (LAS) to keep.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum GroundFilter {
    /// LAS: keep ground (class 2) when any point is class 2, else every point. PLY/PCD: every point.
    #[default]
    Auto,
    /// Every point.
    All,
    /// Only points whose LAS classification is one of these (an error for formats without classes).
    Classes(Vec<u8>),
}

/// How to load a cloud.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// The format; `None` takes it from the path's extension, else sniffs the bytes.
    pub format: Option<CloudFormat>,
    /// The unit of all three axes, overriding whatever the file says; `None` uses the file's own.
    pub units: Option<LengthUnit>,
    /// Which points to keep.
    pub ground_only: GroundFilter,
    /// Size caps.
    pub limits: CloudLimits,
}

/// A loaded cloud, in metres on the file's axes.
#[derive(Debug, Clone)]
pub struct Cloud {
    /// Points in metres: x, y on the file's horizontal axes (origin kept, no recentring), z on its vertical.
    pub points: Vec<[f64; 3]>,
    /// The format read.
    pub format: CloudFormat,
    /// The unit the file's horizontal coordinates were in (converted to metres in `points`).
    pub horizontal_unit: LengthUnit,
    /// The unit the file's vertical coordinates were in (converted to metres in `points`).
    pub vertical_unit: LengthUnit,
    /// Where the units came from, for a person: header keys, WKT, override or an assumption.
    pub unit_source: String,
    /// The CRS the file names: "EPSG:n", or the WKT/GeoTIFF citation name of a user-defined one.
    pub crs: Option<String>,
    /// Point records read from the file.
    pub read_points: u64,
    /// Points kept in `points` (finite and passing the ground filter).
    pub kept_points: u64,
    /// Records (of those the ground filter kept) dropped because a coordinate was NaN or infinite, in the file
    /// or after scaling to metres.
    pub dropped_non_finite: u64,
    /// The filter applied, for a person.
    pub ground_filter: String,
    /// `[min, max]` of `points`, metres.
    pub bounds: [[f64; 3]; 2],
}

/// Why a cloud could not be loaded. Each message names the format and the field or offset at fault.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    /// The bytes are not a well-formed file of the format.
    #[error("{format}: {detail}")]
    Format {
        /// The format name ("LAS", "PLY", … or "point cloud" when unknown).
        format: &'static str,
        /// What is wrong, and where.
        detail: String,
    },
    /// The file ends before the data its header announces.
    #[error("{format}: the {part} is truncated: {detail}")]
    Truncated {
        /// The format name.
        format: &'static str,
        /// Which part ("header", "point data", "vertex data", …).
        part: &'static str,
        /// How far it got.
        detail: String,
    },
    /// A header field is missing, malformed or unsupported.
    #[error("{format}: header field `{field}`: {detail}")]
    Header {
        /// The format name.
        format: &'static str,
        /// The field.
        field: String,
        /// What is wrong with it.
        detail: String,
    },
    /// The file or its point count is over a [`CloudLimits`] cap.
    #[error("{format}: {what} is {actual}, over the limit of {limit}")]
    TooLarge {
        /// The format name.
        format: &'static str,
        /// What is over ("the file size in bytes", "the point count").
        what: &'static str,
        /// The size found.
        actual: u64,
        /// The cap.
        limit: u64,
    },
    /// No point is left with finite coordinates (after the ground filter).
    #[error("{format}: the cloud has no points with finite coordinates ({detail})")]
    Empty {
        /// The format name.
        format: &'static str,
        /// Counts read, dropped and filtered.
        detail: String,
    },
    /// The file could not be read.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// Shorthand for a [`CloudError::Format`].
pub(crate) fn format_err(format: &'static str, detail: impl Into<String>) -> CloudError {
    CloudError::Format {
        format,
        detail: detail.into(),
    }
}

/// Shorthand for a [`CloudError::Header`].
pub(crate) fn header_err(format: &'static str, field: impl Into<String>, detail: impl Into<String>) -> CloudError {
    CloudError::Header {
        format,
        field: field.into(),
        detail: detail.into(),
    }
}

/// Shorthand for the point-count [`CloudError::TooLarge`] check.
pub(crate) fn check_points(format: &'static str, count: u64, limits: &CloudLimits) -> Result<(), CloudError> {
    if count > limits.max_points {
        return Err(CloudError::TooLarge {
            format,
            what: "the point count",
            actual: count,
            limit: limits.max_points,
        });
    }
    Ok(())
}

/// What a format loader hands back before unit scaling and the finite check.
pub(crate) struct RawCloud {
    /// Points in file units, already filtered by class where the format has classes.
    pub points: Vec<[f64; 3]>,
    pub horizontal_unit: LengthUnit,
    pub vertical_unit: LengthUnit,
    pub unit_source: String,
    pub crs: Option<String>,
    pub read_points: u64,
    pub ground_filter: String,
}

/// Loads a cloud from the bytes of a file. The format is `opts.format`, else sniffed from the bytes.
pub fn load_cloud(bytes: &[u8], opts: &LoadOptions) -> Result<Cloud, CloudError> {
    load_owned(std::borrow::Cow::Borrowed(bytes), opts.format, opts)
}

/// Reads a file (refusing it before reading when it is over `opts.limits.max_bytes`) and loads it. The
/// format is `opts.format`, else the extension's, else sniffed from the bytes.
pub fn load_cloud_file(path: &Path, opts: &LoadOptions) -> Result<Cloud, CloudError> {
    let io = |source| CloudError::Io {
        path: path.to_path_buf(),
        source,
    };
    let format = opts.format.or_else(|| CloudFormat::from_path(path));
    let name = format.map_or("point cloud", CloudFormat::name);
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > opts.limits.max_bytes {
        return Err(CloudError::TooLarge {
            format: name,
            what: "the file size in bytes",
            actual: len,
            limit: opts.limits.max_bytes,
        });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    load_owned(std::borrow::Cow::Owned(bytes), format, opts)
}

fn load_owned(
    bytes: std::borrow::Cow<'_, [u8]>,
    format: Option<CloudFormat>,
    opts: &LoadOptions,
) -> Result<Cloud, CloudError> {
    let format = match format {
        Some(f) => f,
        None => CloudFormat::sniff(&bytes).ok_or_else(|| {
            format_err(
                "point cloud",
                "the bytes are not LAS/LAZ (`LASF`), PLY (`ply`) or PCD (`# .PCD`/`VERSION`/`FIELDS`)",
            )
        })?,
    };
    let name = format.name();
    if bytes.len() as u64 > opts.limits.max_bytes {
        return Err(CloudError::TooLarge {
            format: name,
            what: "the file size in bytes",
            actual: bytes.len() as u64,
            limit: opts.limits.max_bytes,
        });
    }
    let raw = match format {
        CloudFormat::Las | CloudFormat::Laz => las::load(bytes.into_owned(), format, opts)?,
        CloudFormat::Ply => ply::load(&bytes, opts)?,
        CloudFormat::Pcd => pcd::load(&bytes, opts)?,
    };
    finish(raw, format, opts.units)
}

/// Applies the unit override or the file's units, drops non-finite points, computes bounds.
fn finish(raw: RawCloud, format: CloudFormat, units: Option<LengthUnit>) -> Result<Cloud, CloudError> {
    let (horizontal_unit, vertical_unit, unit_source) = match units {
        Some(u) => (
            u,
            u,
            format!("--units override ({u}); the file said: {}", raw.unit_source),
        ),
        None => (raw.horizontal_unit, raw.vertical_unit, raw.unit_source),
    };
    let (h, v) = (horizontal_unit.metres_per_unit(), vertical_unit.metres_per_unit());
    let mut points = raw.points;
    let before = points.len() as u64;
    // Scale first: a finite coordinate near f64::MAX can overflow to infinity in metres, and is dropped too.
    for p in &mut points {
        *p = [p[0] * h, p[1] * h, p[2] * v];
    }
    points.retain(|p| p.iter().all(|c| c.is_finite()));
    let dropped_non_finite = before - points.len() as u64;
    let mut bounds = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for p in &points {
        for i in 0..3 {
            bounds[0][i] = bounds[0][i].min(p[i]);
            bounds[1][i] = bounds[1][i].max(p[i]);
        }
    }
    if points.is_empty() {
        return Err(CloudError::Empty {
            format: format.name(),
            detail: format!(
                "{} records read, {} kept by the filter ({}), {} dropped as non-finite",
                raw.read_points, before, raw.ground_filter, dropped_non_finite
            ),
        });
    }
    Ok(Cloud {
        kept_points: points.len() as u64,
        points,
        format,
        horizontal_unit,
        vertical_unit,
        unit_source,
        crs: raw.crs,
        read_points: raw.read_points,
        dropped_non_finite,
        ground_filter: raw.ground_filter,
        bounds,
    })
}

/// The capacity to reserve for `count` records of at least `min_record_bytes` each in `available` bytes,
/// capped by `max_points`: header counts never size an allocation beyond what the bytes can hold.
pub(crate) fn bounded_capacity(count: u64, min_record_bytes: u64, available: usize, max_points: u64) -> usize {
    let by_bytes = available as u64 / min_record_bytes.max(1);
    usize::try_from(count.min(by_bytes).min(max_points)).unwrap_or(0)
}

#[cfg(test)]
#[path = "mod_tests.rs"]
mod tests;
