//! sensor_msgs/LaserScan (CDR): a planar range scan, and its points in the sensor frame.

use super::MAX_POINTS;
use super::cdr::{CdrReader, CdrWriter};
use super::header::Header;
use crate::error::CodecError;

/// sensor_msgs/LaserScan: ranges measured counter-clockwise about +z of `header.frame_id` (the laser frame),
/// beam i at angle `angle_min + i × angle_increment` from +x.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaserScan {
    /// Stamp (of the first beam) and the laser frame.
    pub header: Header,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians (negative for clockwise scanners).
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres (values outside [range_min, range_max], NaN or inf are no return).
    pub ranges: Vec<f32>,
    /// Intensities, device units (may be empty).
    pub intensities: Vec<f32>,
}

/// Decodes a sensor_msgs/LaserScan CDR payload (either byte order; at most 20 M ranges).
pub fn decode_laser_scan(bytes: &[u8]) -> Result<LaserScan, CodecError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(LaserScan {
        header: Header::read(&mut r)?,
        angle_min: r.f32("LaserScan.angle_min")?,
        angle_max: r.f32("LaserScan.angle_max")?,
        angle_increment: r.f32("LaserScan.angle_increment")?,
        time_increment: r.f32("LaserScan.time_increment")?,
        scan_time: r.f32("LaserScan.scan_time")?,
        range_min: r.f32("LaserScan.range_min")?,
        range_max: r.f32("LaserScan.range_max")?,
        ranges: r.f32_seq("LaserScan.ranges", MAX_POINTS)?,
        intensities: r.f32_seq("LaserScan.intensities", MAX_POINTS)?,
    })
}

/// Encodes a sensor_msgs/LaserScan as little-endian CDR (byte-identical to rosbags).
pub fn encode_laser_scan(msg: &LaserScan) -> Vec<u8> {
    encode_laser_scan_with(msg, false)
}

/// Encodes a sensor_msgs/LaserScan in the given CDR byte order.
pub fn encode_laser_scan_with(msg: &LaserScan, big_endian: bool) -> Vec<u8> {
    let mut w = CdrWriter::with_endianness(big_endian);
    msg.header.write(&mut w);
    for v in [
        msg.angle_min,
        msg.angle_max,
        msg.angle_increment,
        msg.time_increment,
        msg.scan_time,
        msg.range_min,
        msg.range_max,
    ] {
        w.f32(v);
    }
    w.f32_seq(&msg.ranges);
    w.f32_seq(&msg.intensities);
    w.finish()
}

/// The returns of a scan as (x, y) metres in the laser frame (`scan.header.frame_id`), in beam order. Beams
/// whose range is NaN, infinite or outside [range_min, range_max], or whose angle is not finite, are skipped.
pub fn scan_points(scan: &LaserScan) -> Vec<[f64; 2]> {
    let (a0, da) = (f64::from(scan.angle_min), f64::from(scan.angle_increment));
    let (lo, hi) = (f64::from(scan.range_min), f64::from(scan.range_max));
    scan.ranges
        .iter()
        .enumerate()
        .filter_map(|(i, &r)| {
            let r = f64::from(r);
            let a = a0 + i as f64 * da;
            (r.is_finite() && r >= lo && r <= hi && a.is_finite()).then(|| [r * a.cos(), r * a.sin()])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_skip_invalid_ranges() {
        let scan = LaserScan {
            angle_min: 0.0,
            angle_increment: std::f32::consts::FRAC_PI_2,
            range_min: 0.5,
            range_max: 5.0,
            ranges: vec![1.0, f32::NAN, 2.0, 0.1, f32::INFINITY, 9.0, 5.0],
            ..LaserScan::default()
        };
        let pts = scan_points(&scan);
        assert_eq!(pts.len(), 3);
        assert!((pts[0][0] - 1.0).abs() < 1e-9 && pts[0][1].abs() < 1e-9);
        assert!((pts[1][0] + 2.0).abs() < 1e-6 && pts[1][1].abs() < 1e-6);
        assert!((pts[2][0] + 5.0).abs() < 1e-5 && pts[2][1].abs() < 1e-5, "{:?}", pts[2]);
    }
}
