//! builtin_interfaces/Time and std_msgs/Header.

use super::cdr::{CdrReader, CdrWriter};
use crate::error::CodecError;

/// builtin_interfaces/Time: a ROS time stamp, seconds plus nanoseconds (of the sender's clock, usually Unix
/// time or simulation time).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds past `sec`, normally below 10⁹.
    pub nanosec: u32,
}

impl Time {
    /// The stamp in nanoseconds (cannot overflow for any field values).
    pub fn to_ns(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The stamp of `ns` nanoseconds; seconds saturate at the i32 range (years 1901 to 2038 as Unix time).
    pub fn from_ns(ns: i64) -> Self {
        let sec = ns.div_euclid(1_000_000_000);
        let nanosec = ns.rem_euclid(1_000_000_000) as u32;
        match i32::try_from(sec) {
            Ok(sec) => Self { sec, nanosec },
            Err(_) if sec < 0 => Self {
                sec: i32::MIN,
                nanosec: 0,
            },
            Err(_) => Self {
                sec: i32::MAX,
                nanosec: 999_999_999,
            },
        }
    }

    /// The stamp in seconds.
    pub fn to_secs_f64(self) -> f64 {
        f64::from(self.sec) + f64::from(self.nanosec) * 1e-9
    }

    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            sec: r.i32("Time.sec")?,
            nanosec: r.u32("Time.nanosec")?,
        })
    }

    pub(crate) fn write(&self, w: &mut CdrWriter) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
}

/// std_msgs/Header: when a message was measured and in which coordinate frame its geometry is expressed.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// The coordinate frame of the message's geometry (e.g. `map`, `odom`, `base_link`, `laser`).
    pub frame_id: String,
}

impl Header {
    /// A header with this stamp (ns) and frame.
    pub fn new(stamp_ns: i64, frame_id: impl Into<String>) -> Self {
        Self {
            stamp: Time::from_ns(stamp_ns),
            frame_id: frame_id.into(),
        }
    }

    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            stamp: Time::read(r)?,
            frame_id: r.string("Header.frame_id")?,
        })
    }

    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nanoseconds_round_trip_including_negative_stamps() {
        for ns in [0, 1, 999_999_999, 1_700_000_123_456_789_000, -1, -1_500_000_000] {
            assert_eq!(Time::from_ns(ns).to_ns(), ns, "{ns}");
        }
        assert_eq!(
            Time::from_ns(-1),
            Time {
                sec: -1,
                nanosec: 999_999_999
            }
        );
        assert_eq!(Time::from_ns(i64::MAX).sec, i32::MAX);
        assert_eq!(
            Time {
                sec: i32::MAX,
                nanosec: u32::MAX
            }
            .to_ns(),
            2_147_483_647_000_000_000 + 4_294_967_295
        );
    }
}
