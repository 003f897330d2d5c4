//! A loaded cloud's provenance as the plan JSON and the terrain site record state it
//! ([`shift_proto::CloudSourceDoc`]): format, CRS, units and where they were read, and the conversion to metres
//! in words.

use shift_proto::CloudSourceDoc;

use super::{Cloud, LengthUnit};

/// The cloud's provenance for the plan JSON, with the conversion in words.
pub fn source_doc(cloud: &Cloud, name: &str) -> CloudSourceDoc {
    let (h, v) = (cloud.horizontal_unit, cloud.vertical_unit);
    let conversion = if h == LengthUnit::Metre && v == LengthUnit::Metre {
        "none: the file is in metres; origin kept".to_owned()
    } else {
        format!(
            "x and y × {} ({} → metre), z × {} ({} → metre); origin kept (no recentring)",
            h.metres_per_unit(),
            h.name(),
            v.metres_per_unit(),
            v.name()
        )
    };
    CloudSourceDoc {
        name: name.to_owned(),
        format: cloud.format.name().to_ascii_lowercase(),
        crs: cloud.crs.clone(),
        horizontal_unit: unit_slug(h).to_owned(),
        vertical_unit: unit_slug(v).to_owned(),
        unit_source: cloud.unit_source.clone(),
        conversion,
        points_read: cloud.read_points,
        points_used: cloud.kept_points,
        ground_filter: cloud.ground_filter.clone(),
    }
}

/// A unit as the plan JSON names it (`metre`, `foot`, `us-survey-foot`).
fn unit_slug(u: LengthUnit) -> &'static str {
    match u {
        LengthUnit::Metre => "metre",
        LengthUnit::Foot => "foot",
        LengthUnit::UsSurveyFoot => "us-survey-foot",
    }
}
