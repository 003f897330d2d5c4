//! The time a robot is expected to spend on a cell: what division balances.

use super::FleetRobot;
use crate::speed::attribute::AttributeMap;
use crate::speed::dwell::DwellLaw;

/// Expected seconds per coverable cell, per robot: lanes one tool width apart driven at the speed the
/// attribute asks for there (RFICP's law, [`DwellLaw`], over the attribute's range on the fleet's coverable
/// area; full speed without an attribute map), times the place's calibration.
pub(super) struct Work<'a> {
    /// Per robot: cell area / tool width, m (divide by a speed for seconds).
    per_speed: Vec<f64>,
    /// Per cell: planned over expected time learned there (see [`super::divide`]).
    calibration: Option<&'a [f64]>,
    /// Per robot: its speed law, with the attribute map.
    laws: Vec<DwellLaw>,
    attribute: Option<&'a AttributeMap>,
    v_max: Vec<f64>,
}

impl<'a> Work<'a> {
    /// `coverable`: the fleet's coverable cells (for the attribute's range).
    pub fn new(
        robots: &[FleetRobot],
        calibration: Option<&'a [f64]>,
        cell_area_m2: f64,
        attribute: Option<&'a AttributeMap>,
        coverable: &[bool],
    ) -> Self {
        let (a_lo, a_hi) = attribute.and_then(|a| a.range_over(coverable)).unwrap_or((1.0, 1.0));
        let per_speed = robots.iter().map(|r| cell_area_m2 / r.shape.tool_width_m).collect();
        let laws = robots
            .iter()
            .map(|r| DwellLaw::for_range(a_lo, a_hi, r.shape.tool_width_m, &r.limits))
            .collect();
        Self {
            per_speed,
            calibration,
            laws,
            attribute,
            v_max: robots.iter().map(|r| r.limits.v_max_mps).collect(),
        }
    }

    /// Robot `r`'s expected seconds on cell `i`.
    pub fn at(&self, r: usize, i: usize) -> f64 {
        let v = match self.attribute {
            Some(a) => self.laws[r].speed(a.at(i)),
            None => self.v_max[r],
        };
        let c = self
            .calibration
            .and_then(|c| c.get(i))
            .copied()
            .filter(|c| c.is_finite() && *c > 0.0)
            .unwrap_or(1.0);
        c * self.per_speed[r] / v
    }
}
