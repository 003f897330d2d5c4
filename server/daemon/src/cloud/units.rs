//! The linear units a cloud's coordinates can be in, and their size in metres.

use std::fmt;

/// A linear unit of the coordinates in a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// The metre (EPSG 9001).
    Metre,
    /// The international foot, exactly 0.3048 m (EPSG 9002).
    Foot,
    /// The US survey foot, 1200/3937 m (EPSG 9003).
    UsSurveyFoot,
}

impl LengthUnit {
    /// Metres in one of this unit.
    pub fn metres_per_unit(self) -> f64 {
        match self {
            Self::Metre => 1.0,
            Self::Foot => 0.3048,
            Self::UsSurveyFoot => 1200.0 / 3937.0,
        }
    }

    /// The unit's name as used in messages ("metre", "foot", "US survey foot").
    pub fn name(self) -> &'static str {
        match self {
            Self::Metre => "metre",
            Self::Foot => "foot",
            Self::UsSurveyFoot => "US survey foot",
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
