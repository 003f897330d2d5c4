//! The odometry payload of DESIGN §5.4: nav_msgs/Odometry CDR or JSON `{x, y, yaw, vx, vy, wz, stamp}`, reduced
//! to the planar pose the fleet needs.

use serde::{Deserialize, Serialize};

use super::{Odometry, decode_odometry};
use crate::error::CodecError;
use crate::ros::cdr::cdr_header_endianness;

/// JSON odometry of DESIGN §5.4, for robots without ROS. Unknown fields are ignored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OdomJson {
    /// x of the robot, metres, in `frame_id` (the fleet's map frame when absent).
    pub x: f64,
    /// y of the robot, metres.
    pub y: f64,
    /// Heading, radians, counter-clockwise from +x.
    pub yaw: f64,
    /// Forward velocity in the robot body frame, m/s (0 when absent).
    #[serde(default)]
    pub vx: f64,
    /// Leftward velocity in the robot body frame, m/s (0 when absent).
    #[serde(default)]
    pub vy: f64,
    /// Yaw rate, rad/s, counter-clockwise (0 when absent).
    #[serde(default)]
    pub wz: f64,
    /// Time of the measurement, seconds (Unix time, or the robot's clock).
    pub stamp: f64,
    /// Frame of x, y, yaw; absent means the fleet's map frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_id: Option<String>,
}

/// A robot's planar pose and velocity at one instant: what ingest keeps from either odometry form.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose2Stamped {
    /// x, metres, in `frame_id`.
    pub x: f64,
    /// y, metres, in `frame_id`.
    pub y: f64,
    /// Heading, radians in (−π, π], counter-clockwise from +x of `frame_id`.
    pub yaw: f64,
    /// Forward velocity in the robot body frame, m/s.
    pub vx: f64,
    /// Leftward velocity in the robot body frame, m/s.
    pub vy: f64,
    /// Yaw rate, rad/s.
    pub wz: f64,
    /// Measurement time, nanoseconds (sender's clock).
    pub stamp_ns: i64,
    /// Frame of the pose (`header.frame_id` of the Odometry; empty for JSON without `frame_id`, meaning the
    /// fleet's map frame).
    pub frame_id: String,
}

impl Pose2Stamped {
    /// The planar part of a nav_msgs/Odometry (yaw from its quaternion).
    pub fn from_odometry(odom: &Odometry) -> Self {
        let p = &odom.pose.pose;
        let v = &odom.twist.twist;
        Self {
            x: p.position.x,
            y: p.position.y,
            yaw: p.orientation.yaw(),
            vx: v.linear.x,
            vy: v.linear.y,
            wz: v.angular.z,
            stamp_ns: odom.header.stamp.to_ns(),
            frame_id: odom.header.frame_id.clone(),
        }
    }

    fn check_finite(self) -> Result<Self, CodecError> {
        let checks = [
            (self.x, "odometry x"),
            (self.y, "odometry y"),
            (self.yaw, "odometry yaw"),
        ];
        let checks = checks
            .into_iter()
            .chain([(self.vx, "odometry vx"), (self.vy, "odometry vy")]);
        for (v, what) in checks.chain([(self.wz, "odometry wz")]) {
            if !v.is_finite() {
                return Err(CodecError::NonFinite { what });
            }
        }
        Ok(self)
    }
}

impl TryFrom<OdomJson> for Pose2Stamped {
    type Error = CodecError;

    fn try_from(j: OdomJson) -> Result<Self, CodecError> {
        // ±9.2e9 s is the i64 nanosecond range.
        if !j.stamp.is_finite() || j.stamp.abs() >= 9.2e9 {
            return Err(CodecError::NonFinite { what: "odometry stamp" });
        }
        Self {
            x: j.x,
            y: j.y,
            yaw: j.yaw,
            vx: j.vx,
            vy: j.vy,
            wz: j.wz,
            stamp_ns: (j.stamp * 1e9).round() as i64,
            frame_id: j.frame_id.unwrap_or_default(),
        }
        .check_finite()
    }
}

/// Decodes an odometry sample of DESIGN §5.4 into a planar pose.
///
/// JSON when `encoding` starts with `application/json` or `text/json`, or (any other or no encoding) when the
/// first non-blank byte is `{`; CDR nav_msgs/Odometry when the encoding mentions `cdr`, or the payload starts
/// with a CDR encapsulation header (`00 01 00 00` little-endian, `00 00 00 00` big-endian). Non-finite
/// positions, headings or velocities are errors.
pub fn decode_odom_payload(bytes: &[u8], encoding: Option<&str>) -> Result<Pose2Stamped, CodecError> {
    let enc = encoding.map(|e| e.trim().to_ascii_lowercase());
    let enc = enc.as_deref().unwrap_or("");
    let is_json_enc = enc.starts_with("application/json") || enc.starts_with("text/json");
    let is_cdr_enc = enc.contains("cdr");
    let looks_json = bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
    if is_json_enc || (!is_cdr_enc && looks_json) {
        let j: OdomJson = serde_json::from_slice(bytes).map_err(|e| CodecError::Json { reason: e.to_string() })?;
        return Pose2Stamped::try_from(j);
    }
    if is_cdr_enc || cdr_header_endianness(bytes).is_some() {
        return Pose2Stamped::from_odometry(&decode_odometry(bytes)?).check_finite();
    }
    Err(CodecError::UnknownEncoding {
        encoding: encoding.map(str::to_owned),
        first: bytes.iter().take(4).copied().collect(),
    })
}

/// Encodes a planar pose as the JSON odometry of DESIGN §5.4 (stamp in seconds; `frame_id` omitted when empty).
pub fn encode_odom_json(pose: &Pose2Stamped) -> Vec<u8> {
    let j = OdomJson {
        x: pose.x,
        y: pose.y,
        yaw: pose.yaw,
        vx: pose.vx,
        vy: pose.vy,
        wz: pose.wz,
        stamp: pose.stamp_ns as f64 * 1e-9,
        frame_id: (!pose.frame_id.is_empty()).then(|| pose.frame_id.clone()),
    };
    // Serialising a struct of numbers and a string cannot fail; fall back to an empty object regardless.
    serde_json::to_vec(&j).unwrap_or_else(|_| b"{}".to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::geometry::Quaternion;
    use crate::ros::header::Header;
    use crate::ros::odometry::encode_odometry;

    fn sample() -> Odometry {
        let mut o = Odometry {
            header: Header::new(1_500_000_000, "odom"),
            ..Odometry::default()
        };
        o.pose.pose.position.x = 1.0;
        o.pose.pose.position.y = 2.0;
        o.pose.pose.orientation = Quaternion::from_yaw(0.5);
        o.twist.twist.linear.x = 0.3;
        o.twist.twist.angular.z = -0.1;
        o
    }

    #[test]
    fn json_by_encoding_or_by_first_byte() {
        let body = br#" {"x": 1.5, "y": -2, "yaw": 0.25, "vx": 0.5, "stamp": 12.000000001, "extra": true}"#;
        for enc in [Some("application/json"), None, Some("zenoh/bytes")] {
            let p = decode_odom_payload(body, enc).expect("json");
            assert_eq!((p.x, p.y, p.yaw, p.vx, p.vy, p.wz), (1.5, -2.0, 0.25, 0.5, 0.0, 0.0));
            assert_eq!(p.stamp_ns, 12_000_000_001);
            assert_eq!(p.frame_id, "");
        }
    }

    #[test]
    fn cdr_by_encoding_or_by_header() {
        let bytes = encode_odometry(&sample());
        for enc in [Some("application/cdr"), None, Some("zenoh/bytes")] {
            let p = decode_odom_payload(&bytes, enc).expect("cdr");
            assert_eq!((p.x, p.y, p.vx, p.wz), (1.0, 2.0, 0.3, -0.1));
            assert!((p.yaw - 0.5).abs() < 1e-12);
            assert_eq!(p.stamp_ns, 1_500_000_000);
            assert_eq!(p.frame_id, "odom");
        }
    }

    #[test]
    fn json_round_trip() {
        let p = decode_odom_payload(&encode_odometry(&sample()), None).expect("cdr");
        let back = decode_odom_payload(&encode_odom_json(&p), Some("application/json")).expect("json");
        assert_eq!(back, p);
    }

    #[test]
    fn bad_payloads_are_named() {
        let missing = decode_odom_payload(br#"{"x": 1, "y": 2, "stamp": 1}"#, None).expect_err("no yaw");
        assert!(
            matches!(&missing, CodecError::Json { reason } if reason.contains("yaw")),
            "{missing}"
        );
        let huge = decode_odom_payload(br#"{"x": 1e400, "y": 2, "yaw": 0, "stamp": 1}"#, None);
        assert!(huge.is_err(), "{huge:?}");
        let stamp = decode_odom_payload(br#"{"x": 1, "y": 2, "yaw": 0, "stamp": 1e300}"#, None);
        assert_eq!(stamp, Err(CodecError::NonFinite { what: "odometry stamp" }));
        let unknown = decode_odom_payload(b"hello", None).expect_err("text");
        assert_eq!(unknown.kind(), "unknown_encoding");
        let json_as_cdr = decode_odom_payload(br#"{"x": 1}"#, Some("application/cdr")).expect_err("not cdr");
        assert_eq!(json_as_cdr.kind(), "bad_cdr_header");
        let mut nan = sample();
        nan.pose.pose.position.x = f64::NAN;
        let err = decode_odom_payload(&encode_odometry(&nan), None);
        assert_eq!(err, Err(CodecError::NonFinite { what: "odometry x" }));
    }
}
