//! Attribute maps on the wire (DESIGN §5.3 `POST /v1/plans` `attribute`, and `shiftd plan --attribute
//! FILE.json`): a list of Gaussian blobs. Grey images travel as files or multipart parts instead.

use serde::{Deserialize, Serialize};

/// `{"blobs": [{"x", "y", "sigma", "amplitude"}, …]}`: A(x, y) = Σ amplitude · exp(−d² / (2 sigma²)), clamped
/// to [0, 1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct AttributeDoc {
    /// The blobs.
    pub blobs: Vec<AttributeBlobDoc>,
}

impl AttributeDoc {
    /// Most blobs a plan request may carry (the attribute map sums every blob at every cell).
    pub const MAX_BLOBS: usize = 256;
}

/// One Gaussian blob of attribute.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct AttributeBlobDoc {
    /// Centre x, metres, map frame.
    pub x: f64,
    /// Centre y, metres, map frame.
    pub y: f64,
    /// Standard deviation, metres.
    pub sigma: f64,
    /// Peak value (A is clamped to [0, 1] after summing).
    pub amplitude: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_blobs_and_rejects_unknown_fields() {
        let a: AttributeDoc =
            serde_json::from_str(r#"{"blobs": [{"x": 1.0, "y": 2.0, "sigma": 0.5, "amplitude": 0.8}]}"#).expect("ok");
        assert_eq!(a.blobs[0].sigma, 0.5);
        assert!(
            serde_json::from_str::<AttributeDoc>(r#"{"blobs": [{"x": 1, "y": 2, "s": 1, "amplitude": 1}]}"#).is_err()
        );
    }
}
