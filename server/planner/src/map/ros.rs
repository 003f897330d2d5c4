//! ROS map_server maps: the YAML description plus a PGM or PNG image.
//!
//! The planner does no I/O: the caller passes the YAML text and a function that returns the bytes of the
//! image the YAML names (relative names are the caller's to resolve, as map_server resolves them against
//! the YAML's directory).
//!
//! Pixel interpretation follows map_server: the grey value `c` (mean of the colour channels) gives an
//! occupancy probability `p = (255 − c) / 255`, or `c / 255` when `negate` is set. In `trinary` and `scale`
//! modes `p` is compared with `occupied_thresh` and `free_thresh` (in `scale` mode the values between are
//! graded probabilities, which for coverage are simply "not free"). In `raw` mode the pixel value is the
//! occupancy in percent (0–100) and larger values mean unknown.

use serde::Deserialize;

use super::grid::{CellState, GridGeometry, OccupancyGrid, Thresholds};
use crate::error::{PlannerError, Result, finite};
use crate::geom::Point2;

/// How pixel values become occupancy, as map_server's `mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapMode {
    /// Free, occupied or unknown by the thresholds (map_server's default).
    #[default]
    Trinary,
    /// Thresholds for free/occupied, graded values between.
    Scale,
    /// Pixel value is the occupancy in percent.
    Raw,
}

/// The parsed map_server YAML.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// Image file name as written in the YAML.
    pub image: String,
    /// Metres per pixel.
    pub resolution: f64,
    /// Map-frame pose of the lower-left pixel's outer corner: x, y (metres) and yaw (radians).
    pub origin: [f64; 3],
    /// White is occupied when true.
    pub negate: bool,
    /// Free/occupied thresholds.
    pub thresholds: Thresholds,
    /// Pixel interpretation.
    pub mode: MapMode,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Flag {
    Int(i64),
    Bool(bool),
}

#[derive(Deserialize)]
struct RawYaml {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<Vec<f64>>,
    negate: Option<Flag>,
    occupied_thresh: Option<f64>,
    free_thresh: Option<f64>,
    mode: Option<MapMode>,
}

impl MapYaml {
    /// Parses and validates map_server YAML text.
    pub fn parse(text: &str) -> Result<Self> {
        let raw: RawYaml = serde_yaml_ng::from_str(text).map_err(|e| PlannerError::MapYaml(e.to_string()))?;
        let image = raw
            .image
            .filter(|s| !s.trim().is_empty())
            .ok_or_else(|| PlannerError::MapYaml("missing key `image`".into()))?;
        let resolution = raw
            .resolution
            .ok_or_else(|| PlannerError::MapYaml("missing key `resolution`".into()))?;
        if !resolution.is_finite() || resolution <= 0.0 {
            return Err(PlannerError::InvalidResolution(resolution));
        }
        let origin = raw
            .origin
            .ok_or_else(|| PlannerError::MapYaml("missing key `origin`".into()))?;
        if origin.len() != 3 && origin.len() != 2 {
            return Err(PlannerError::MapYaml(format!(
                "`origin` must be [x, y, yaw], got {} numbers",
                origin.len()
            )));
        }
        let origin = [
            finite("origin x", origin[0])?,
            finite("origin y", origin[1])?,
            finite("origin yaw", origin.get(2).copied().unwrap_or(0.0))?,
        ];
        let negate = match raw.negate {
            None => false,
            Some(Flag::Bool(b)) => b,
            Some(Flag::Int(0)) => false,
            Some(Flag::Int(1)) => true,
            Some(Flag::Int(n)) => return Err(PlannerError::MapYaml(format!("`negate` must be 0 or 1, got {n}"))),
        };
        let defaults = Thresholds::default();
        let thresholds = Thresholds {
            free: raw.free_thresh.unwrap_or(defaults.free),
            occupied: raw.occupied_thresh.unwrap_or(defaults.occupied),
        };
        thresholds.validate()?;
        Ok(Self {
            image,
            resolution,
            origin,
            negate,
            thresholds,
            mode: raw.mode.unwrap_or_default(),
        })
    }
}

/// A loaded map plus anything the user should know about how it was read.
#[derive(Debug, Clone)]
pub struct LoadedMap {
    /// The thresholded grid.
    pub grid: OccupancyGrid,
    /// Non-fatal remarks (e.g. an ignored yaw).
    pub warnings: Vec<String>,
}

/// Loads a map_server map: parses `yaml_text`, asks `read_image` for the bytes of the image it names, and
/// thresholds the pixels. `read_image` receives the image name exactly as written in the YAML.
pub fn load_ros_map(
    yaml_text: &str,
    read_image: impl FnOnce(&str) -> std::result::Result<Vec<u8>, String>,
) -> Result<LoadedMap> {
    let yaml = MapYaml::parse(yaml_text)?;
    let bytes = read_image(&yaml.image).map_err(|reason| PlannerError::MissingImage {
        path: yaml.image.clone(),
        reason,
    })?;
    grid_from_image(&yaml, &bytes)
}

/// Thresholds decoded image bytes (PGM or PNG) with the YAML's settings.
pub fn grid_from_image(yaml: &MapYaml, bytes: &[u8]) -> Result<LoadedMap> {
    // The header's size first: a few bytes may declare an image far too large to decode.
    let (w, h) = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| PlannerError::ImageDecode(e.to_string()))?
        .into_dimensions()
        .map_err(|e| PlannerError::ImageDecode(e.to_string()))?;
    GridGeometry::check_size(w as usize, h as usize)?;
    let img = image::load_from_memory(bytes).map_err(|e| PlannerError::ImageDecode(e.to_string()))?;
    let rgba = img.to_rgba8();
    let (w, h) = (rgba.width() as usize, rgba.height() as usize);
    let geometry = GridGeometry::new(w, h, yaml.resolution, Point2::new(yaml.origin[0], yaml.origin[1]))?;
    let channels = img.color().channel_count();
    let has_alpha = img.color().has_alpha();
    let mut cells = vec![CellState::Unknown; w * h];
    for (px, py, pixel) in rgba.enumerate_pixels() {
        let [r, g, b, a] = pixel.0;
        let grey = if channels >= 3 {
            (f64::from(r) + f64::from(g) + f64::from(b)) / 3.0
        } else {
            f64::from(r)
        };
        let state = match yaml.mode {
            MapMode::Raw => {
                if grey <= 100.0 {
                    yaml.thresholds.classify(grey / 100.0)
                } else {
                    CellState::Unknown
                }
            }
            MapMode::Trinary | MapMode::Scale => {
                let p = if yaml.negate {
                    grey / 255.0
                } else {
                    (255.0 - grey) / 255.0
                };
                let s = yaml.thresholds.classify(p);
                if yaml.mode == MapMode::Scale && has_alpha && a < 255 && s == CellState::Free {
                    CellState::Unknown
                } else {
                    s
                }
            }
        };
        // Image row 0 is the top of the map; grid row 0 is at the origin (bottom).
        let y = h - 1 - py as usize;
        cells[y * w + px as usize] = state;
    }
    let mut warnings = Vec::new();
    if yaml.origin[2].abs() > 1e-9 {
        warnings.push(format!(
            "map origin yaw {} rad ignored: the grid is taken as axis-aligned, as map_server consumers do",
            yaml.origin[2]
        ));
    }
    Ok(LoadedMap {
        grid: OccupancyGrid::new(geometry, cells)?,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pgm(w: usize, h: usize, pixels: &[u8]) -> Vec<u8> {
        let mut v = format!("P5\n{w} {h}\n255\n").into_bytes();
        v.extend_from_slice(pixels);
        v
    }

    const YAML: &str = "image: m.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

    #[test]
    fn trinary_thresholds_and_row_flip() {
        // top row: black (occupied), white (free); bottom row: grey (unknown), white.
        let img = pgm(2, 2, &[0, 254, 205, 255]);
        let m = load_ros_map(YAML, |name| {
            assert_eq!(name, "m.pgm");
            Ok(img.clone())
        })
        .expect("loads");
        let g = &m.grid;
        assert_eq!(g.geometry.width, 2);
        assert_eq!(g.geometry.origin, Point2::new(1.0, -2.0));
        use super::super::grid::Cell;
        assert_eq!(g.state(Cell::new(0, 1)), CellState::Occupied);
        assert_eq!(g.state(Cell::new(1, 1)), CellState::Free);
        assert_eq!(g.state(Cell::new(0, 0)), CellState::Unknown);
        assert_eq!(g.state(Cell::new(1, 0)), CellState::Free);
        assert!(m.warnings.is_empty());
    }

    #[test]
    fn an_image_header_declaring_an_absurd_size_is_refused_before_decoding() {
        // 20 bytes that declare a 10^6 × 10^6 image.
        let img = pgm(1_000_000, 1_000_000, &[0; 4]);
        let e = load_ros_map(YAML, |_| Ok(img.clone())).expect_err("too large");
        assert!(matches!(e, PlannerError::MapTooLarge { .. }), "{e}");
    }

    #[test]
    fn negate_and_raw() {
        let img = pgm(3, 1, &[0, 255, 50]);
        let neg = YAML.replace("negate: 0", "negate: 1");
        let m = load_ros_map(&neg, |_| Ok(img.clone())).expect("loads");
        assert_eq!(
            m.grid.cells,
            vec![CellState::Free, CellState::Occupied, CellState::Unknown]
        );
        let raw = format!("{YAML}mode: raw\n");
        let m = load_ros_map(&raw, |_| Ok(img.clone())).expect("loads");
        assert_eq!(
            m.grid.cells,
            vec![CellState::Free, CellState::Unknown, CellState::Unknown]
        );
    }

    #[test]
    fn png_colour_is_averaged() {
        let mut buf = Vec::new();
        let img = image::RgbImage::from_fn(2, 1, |x, _| {
            if x == 0 {
                image::Rgb([255, 255, 255])
            } else {
                image::Rgb([0, 0, 0])
            }
        });
        image::DynamicImage::ImageRgb8(img)
            .write_to(&mut std::io::Cursor::new(&mut buf), image::ImageFormat::Png)
            .expect("encode");
        let m = load_ros_map(&YAML.replace("m.pgm", "m.png"), |_| Ok(buf.clone())).expect("loads");
        assert_eq!(m.grid.cells, vec![CellState::Free, CellState::Occupied]);
    }

    #[test]
    fn errors_are_typed() {
        let img = pgm(1, 1, &[255]);
        assert!(matches!(
            load_ros_map("image: [", |_| Ok(img.clone())),
            Err(PlannerError::MapYaml(_))
        ));
        assert!(matches!(
            load_ros_map(YAML, |_| Err("no such file".into())),
            Err(PlannerError::MissingImage { .. })
        ));
        assert!(matches!(
            load_ros_map(&YAML.replace("0.5", "0"), |_| Ok(img.clone())),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            load_ros_map(&YAML.replace("0.5", "-0.1"), |_| Ok(img.clone())),
            Err(PlannerError::InvalidResolution(_))
        ));
        assert!(matches!(
            load_ros_map(&YAML.replace("1.0, -2.0", ".nan, -2.0"), |_| Ok(img.clone())),
            Err(PlannerError::NonFinite { .. })
        ));
        assert!(matches!(
            load_ros_map(YAML, |_| Ok(b"P5\n2 2\n255\n\x00".to_vec())),
            Err(PlannerError::ImageDecode(_))
        ));
        assert!(matches!(
            load_ros_map(YAML, |_| Ok(vec![1, 2, 3])),
            Err(PlannerError::ImageDecode(_))
        ));
        assert!(matches!(
            load_ros_map(&YAML.replace("free_thresh: 0.196", "free_thresh: 0.9"), |_| Ok(
                img.clone()
            )),
            Err(PlannerError::InvalidParam { .. })
        ));
        assert!(matches!(
            load_ros_map("resolution: 0.1\norigin: [0,0,0]\n", |_| Ok(img.clone())),
            Err(PlannerError::MapYaml(_))
        ));
    }

    #[test]
    fn yaw_is_reported() {
        let img = pgm(1, 1, &[255]);
        let m = load_ros_map(&YAML.replace("0.0]", "0.5]"), |_| Ok(img.clone())).expect("loads");
        assert_eq!(m.warnings.len(), 1);
    }
}

#[cfg(test)]
mod fuzz {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Whatever the YAML text and image bytes, loading returns a map or an error, never a panic.
        #[test]
        fn malformed_maps_never_panic(yaml in ".{0,200}", bytes in proptest::collection::vec(any::<u8>(), 0..300),
                                       w in 0usize..5, h in 0usize..5, res in prop_oneof![Just(0.05), Just(0.0), Just(-1.0), Just(f64::NAN)]) {
            let _ = load_ros_map(&yaml, |_| Ok(bytes.clone()));
            let text = format!("image: m.pgm\nresolution: {res}\norigin: [0, 0, 0]\n");
            let mut img = format!("P5\n{w} {h}\n255\n").into_bytes();
            img.extend_from_slice(&bytes);
            let _ = load_ros_map(&text, |_| Ok(img.clone()));
        }

        #[test]
        fn malformed_json_grids_never_panic(text in ".{0,200}", w in 0usize..4, h in 0usize..4, cells in proptest::collection::vec(-3i16..120, 0..20)) {
            let _ = crate::map::JsonGrid::parse(&text).and_then(crate::map::JsonGrid::into_grid);
            let doc = serde_json::json!({"resolution": 0.1, "origin": [0.0, 0.0], "width": w, "height": h, "cells": cells});
            let _ = crate::map::JsonGrid::parse(&doc.to_string()).and_then(crate::map::JsonGrid::into_grid);
        }
    }
}
