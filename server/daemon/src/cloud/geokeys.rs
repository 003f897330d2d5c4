//! Linear units and CRS names from a LAS file's CRS records: the GeoTIFF GeoKeyDirectoryTag (with its
//! double and ASCII parameter records) and OGC WKT (WKT1 `PROJCS`/`VERT_CS`/`COMPD_CS`, WKT2 `PROJCRS`/
//! `VERTCRS`/`COMPOUNDCRS`). Nothing here converts coordinates; it only says what unit the file states.

use super::{CloudError, LengthUnit, header_err};

/// A unit the file states, and how it says so (for [`super::Cloud::unit_source`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Stated {
    pub unit: LengthUnit,
    pub how: String,
}

/// What a CRS record says.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct CrsInfo {
    /// The horizontal (x, y) unit, when stated.
    pub horizontal: Option<Stated>,
    /// The vertical (z) unit, when stated.
    pub vertical: Option<Stated>,
    /// "EPSG:n", or the name of a user-defined CRS.
    pub crs: Option<String>,
    /// The horizontal coordinates are geographic (degrees), not lengths.
    pub geographic: bool,
}

/// The unit whose metres-per-unit is `factor` (1, 0.3048 or 1200/3937, to 1e-9 relative), if one of ours.
pub(crate) fn unit_from_factor(factor: f64) -> Option<LengthUnit> {
    [LengthUnit::Metre, LengthUnit::Foot, LengthUnit::UsSurveyFoot]
        .into_iter()
        .find(|u| ((factor - u.metres_per_unit()) / u.metres_per_unit()).abs() < 1e-9)
}

/// The unit an EPSG unit-of-measure code names, if one of ours.
fn unit_from_epsg(code: u16) -> Option<LengthUnit> {
    match code {
        9001 => Some(LengthUnit::Metre),
        9002 => Some(LengthUnit::Foot),
        9003 => Some(LengthUnit::UsSurveyFoot),
        _ => None,
    }
}

/// Projected CRS codes whose unit is the metre without a database: WGS 84 / UTM (326xx, 327xx), NAD83 / UTM
/// (269xx), ETRS89 / UTM (258xx) and Web Mercator (3857).
fn epsg_projected_is_metre(code: u16) -> bool {
    matches!(code, 32601..=32660 | 32701..=32760 | 26901..=26923 | 25828..=25838 | 3857)
}

struct GeoKey {
    id: u16,
    location: u16,
    count: u16,
    value: u16,
}

/// Reads the GeoKeyDirectoryTag (`dir`, u16 little-endian) with its GeoDoubleParamsTag and GeoAsciiParamsTag.
/// `format` names the file format in errors.
pub(crate) fn from_geokeys(
    format: &'static str,
    dir: &[u8],
    doubles: Option<&[u8]>,
    ascii: Option<&[u8]>,
) -> Result<CrsInfo, CloudError> {
    let words: Vec<u16> = dir.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
    let [version, _, _, n, ..] = words[..] else {
        return Err(header_err(
            format,
            "GeoKeyDirectoryTag",
            format!("{} bytes, shorter than its 8-byte header", dir.len()),
        ));
    };
    if version != 1 {
        return Err(header_err(
            format,
            "GeoKeyDirectoryTag",
            format!("KeyDirectoryVersion {version}, expected 1"),
        ));
    }
    let keys: Vec<GeoKey> = words[4..]
        .chunks_exact(4)
        .take(usize::from(n))
        .map(|k| GeoKey {
            id: k[0],
            location: k[1],
            count: k[2],
            value: k[3],
        })
        .collect();
    if keys.len() < usize::from(n) {
        return Err(header_err(
            format,
            "GeoKeyDirectoryTag",
            format!("says {n} keys but holds {}", keys.len()),
        ));
    }
    let short = |id: u16| keys.iter().find(|k| k.id == id && k.location == 0).map(|k| k.value);
    let double = |id: u16| {
        let k = keys
            .iter()
            .find(|k| k.id == id && k.location == 34736 && k.count >= 1)?;
        let at = usize::from(k.value) * 8;
        let b = doubles?.get(at..at + 8)?;
        Some(f64::from_le_bytes(b.try_into().ok()?))
    };
    let text = |id: u16| {
        let k = keys.iter().find(|k| k.id == id && k.location == 34737)?;
        let at = usize::from(k.value);
        let b = ascii?.get(at..at + usize::from(k.count))?;
        let s = String::from_utf8_lossy(b);
        Some(s.trim_end_matches(['|', '\0']).trim().to_string())
    };

    let mut info = CrsInfo {
        geographic: short(1024) == Some(2),
        ..CrsInfo::default()
    };
    let projected = short(3072);
    info.crs = match projected {
        Some(code @ 1024..=32766) => Some(format!("EPSG:{code}")),
        _ => text(3073).or_else(|| text(1026)).filter(|s| !s.is_empty()),
    };
    if info.geographic && info.crs.is_none() {
        info.crs = short(2048)
            .filter(|c| (1024..=32766).contains(c))
            .map(|c| format!("EPSG:{c}"));
    }

    if let Some(code) = short(3076) {
        info.horizontal = Some(linear_key(format, "ProjLinearUnitsGeoKey", 3076, code, double(3077))?);
    } else if let Some(code) = projected.filter(|c| epsg_projected_is_metre(*c)) {
        let how = format!("GeoTIFF keys: ProjectedCSTypeGeoKey=EPSG:{code} (a metre UTM/Web Mercator CRS)");
        info.horizontal = Some(Stated {
            unit: LengthUnit::Metre,
            how,
        });
    }
    if let Some(code) = short(4099) {
        info.vertical = Some(linear_key(format, "VerticalUnitsGeoKey", 4099, code, None)?);
    }
    Ok(info)
}

fn linear_key(format: &'static str, name: &str, id: u16, code: u16, size: Option<f64>) -> Result<Stated, CloudError> {
    if let Some(unit) = unit_from_epsg(code) {
        return Ok(Stated {
            unit,
            how: format!("GeoTIFF keys: {name}={code} ({unit})"),
        });
    }
    if code == 32767
        && let Some(unit) = size.and_then(unit_from_factor)
    {
        let how = format!(
            "GeoTIFF keys: {name}=32767 (user-defined) with ProjLinearUnitSizeGeoKey={:?} m ({unit})",
            size
        );
        return Ok(Stated { unit, how });
    }
    Err(header_err(
        format,
        format!("{name} ({id})"),
        format!("unit code {code} is not metre (9001), foot (9002) or US survey foot (9003); pass a units override"),
    ))
}

/// A WKT node: keyword and children (quoted strings and bare tokens are leaves).
#[derive(Debug)]
enum Wkt {
    Leaf(String),
    Node(String, Vec<Wkt>),
}

const MAX_WKT_DEPTH: usize = 48;

fn parse_wkt(s: &[u8], pos: &mut usize, depth: usize) -> Option<Wkt> {
    if depth > MAX_WKT_DEPTH {
        return None;
    }
    while s.get(*pos).is_some_and(u8::is_ascii_whitespace) {
        *pos += 1;
    }
    if s.get(*pos) == Some(&b'"') {
        let start = *pos + 1;
        let end = start + s.get(start..)?.iter().position(|&b| b == b'"')?;
        *pos = end + 1;
        return Some(Wkt::Leaf(String::from_utf8_lossy(&s[start..end]).into_owned()));
    }
    let start = *pos;
    while s
        .get(*pos)
        .is_some_and(|b| !matches!(b, b'[' | b']' | b'(' | b')' | b','))
    {
        *pos += 1;
    }
    let word = String::from_utf8_lossy(&s[start..*pos]).trim().to_string();
    if !matches!(s.get(*pos), Some(b'[' | b'(')) {
        return Some(Wkt::Leaf(word));
    }
    *pos += 1;
    let mut children = Vec::new();
    loop {
        children.push(parse_wkt(s, pos, depth + 1)?);
        while s.get(*pos).is_some_and(u8::is_ascii_whitespace) {
            *pos += 1;
        }
        match s.get(*pos)? {
            b',' => *pos += 1,
            b']' | b')' => {
                *pos += 1;
                return Some(Wkt::Node(word.to_ascii_uppercase(), children));
            }
            _ => return None,
        }
    }
}

impl Wkt {
    fn kids(&self) -> &[Wkt] {
        match self {
            Wkt::Node(_, k) => k,
            Wkt::Leaf(_) => &[],
        }
    }
    fn is(&self, names: &[&str]) -> bool {
        matches!(self, Wkt::Node(k, _) if names.contains(&k.as_str()))
    }
    fn leaf(&self, i: usize) -> Option<&str> {
        match self.kids().get(i)? {
            Wkt::Leaf(s) => Some(s),
            Wkt::Node(..) => None,
        }
    }
    fn child(&self, names: &[&str]) -> Option<&Wkt> {
        self.kids().iter().find(|k| k.is(names))
    }
    fn last_child(&self, names: &[&str]) -> Option<&Wkt> {
        self.kids().iter().rev().find(|k| k.is(names))
    }
    /// "EPSG:n" from a direct AUTHORITY["EPSG","n"] or ID["EPSG",n], else the node's name.
    fn crs_name(&self) -> Option<String> {
        if let Some(auth) = self.child(&["AUTHORITY", "ID"])
            && auth.leaf(0).is_some_and(|a| a.eq_ignore_ascii_case("EPSG"))
            && let Some(code) = auth.leaf(1)
        {
            return Some(format!("EPSG:{code}"));
        }
        self.leaf(0).filter(|s| !s.is_empty()).map(str::to_string)
    }
    /// The node's length unit: its last direct UNIT/LENGTHUNIT, else the first AXIS's LENGTHUNIT.
    fn length_unit(&self) -> Option<&Wkt> {
        const UNITS: &[&str] = &["UNIT", "LENGTHUNIT"];
        self.last_child(UNITS).or_else(|| {
            self.kids()
                .iter()
                .filter(|k| k.is(&["AXIS"]))
                .find_map(|a| a.child(UNITS))
        })
    }
}

fn wkt_unit(format: &'static str, node: &Wkt, part: &str) -> Result<Stated, CloudError> {
    let name = node.leaf(0).unwrap_or("");
    let factor = node.leaf(1).and_then(|f| f.trim().parse::<f64>().ok());
    let by_name = match name.to_ascii_lowercase().replace([' ', '_', '-'], "").as_str() {
        "metre" | "meter" | "metres" | "meters" | "m" => Some(LengthUnit::Metre),
        "foot" | "feet" | "ft" | "internationalfoot" | "footinternational" => Some(LengthUnit::Foot),
        "ussurveyfoot" | "footus" | "usfoot" | "ftus" | "ussurveyfeet" => Some(LengthUnit::UsSurveyFoot),
        _ => None,
    };
    // The conversion factor is what a WKT consumer multiplies by, so it decides when present.
    let unit = factor.map_or(by_name, unit_from_factor).ok_or_else(|| {
        header_err(
            format,
            format!("WKT {part} UNIT"),
            format!("UNIT[\"{name}\", {factor:?}] is not metre, foot or US survey foot; pass a units override"),
        )
    })?;
    let f = factor.map_or(String::new(), |f| format!(",{f}"));
    Ok(Stated {
        unit,
        how: format!("WKT {part} UNIT[\"{name}\"{f}] ({unit})"),
    })
}

/// Reads an OGC WKT CRS (WKT1 or WKT2, NUL-terminated or not). `format` names the file format in errors.
pub(crate) fn from_wkt(format: &'static str, wkt: &[u8]) -> Result<CrsInfo, CloudError> {
    let end = wkt.iter().position(|&b| b == 0).unwrap_or(wkt.len());
    let mut pos = 0;
    let root = parse_wkt(&wkt[..end], &mut pos, 0)
        .filter(|r| matches!(r, Wkt::Node(..)))
        .ok_or_else(|| header_err(format, "OGC WKT", format!("not well-formed WKT near byte {pos}")))?;
    const HORIZONTAL: &[&str] = &["PROJCS", "PROJCRS", "PROJECTEDCRS"];
    const GEOGRAPHIC: &[&str] = &["GEOGCS", "GEOGCRS", "GEOGRAPHICCRS", "GEODCRS", "GEOCCS", "BASEGEOGCRS"];
    const VERTICAL: &[&str] = &["VERT_CS", "VERTCRS", "VERTICALCRS"];
    let compound = root.is(&["COMPD_CS", "COMPOUNDCRS"]);
    let pick = |names: &[&str]| {
        if compound {
            root.child(names)
        } else {
            Some(&root).filter(|r| r.is(names))
        }
    };
    let mut info = CrsInfo::default();
    if let Some(p) = pick(HORIZONTAL) {
        info.crs = p.crs_name();
        if let Some(u) = p.length_unit() {
            info.horizontal = Some(wkt_unit(format, u, "PROJCS")?);
        }
    } else if let Some(g) = pick(GEOGRAPHIC) {
        info.geographic = true;
        info.crs = g.crs_name();
    }
    if let Some(v) = pick(VERTICAL)
        && let Some(u) = v.length_unit()
    {
        info.vertical = Some(wkt_unit(format, u, "VERT_CS")?);
    }
    if compound && info.crs.is_none() {
        info.crs = root.crs_name();
    }
    Ok(info)
}

#[cfg(test)]
#[path = "geokeys_tests.rs"]
mod tests;
