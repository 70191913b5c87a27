//! The SRBF baselines' typed error.

/// SRBF fitting, sampling or product estimation could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SrbfError {
    /// A lobe count of zero (per slice or for the map).
    #[error("the {what} lobe count must be at least 1 (got 0)")]
    ZeroLobes {
        /// Which count (`per-slice`, `map`, `kept product`).
        what: &'static str,
    },
    /// Bandwidth bounds that are not `0 < min < max < ∞`.
    #[error("{what} bandwidth bounds must satisfy 0 < min < max < ∞ (got min {min}, max {max})")]
    BadBandwidth {
        /// Which bounds (`BRDF`, `map`).
        what: &'static str,
        /// The lower bound given.
        min: f64,
        /// The upper bound given.
        max: f64,
    },
    /// A resolution (slices, fit grid) of zero or too large.
    #[error("{what} must be between 1 and {max} (got {got})")]
    BadResolution {
        /// Which resolution.
        what: &'static str,
        /// The largest accepted value.
        max: usize,
        /// The value given.
        got: usize,
    },
    /// Target samples, weights and directions of different lengths, or no samples at all.
    #[error(
        "fit target: {directions} directions, {weights} weights, {values} values (need equal, non-zero counts)"
    )]
    TargetShape {
        /// Number of directions.
        directions: usize,
        /// Number of weights.
        weights: usize,
        /// Number of values.
        values: usize,
    },
    /// A target value or weight that is NaN, infinite or negative.
    #[error("fit target sample {index}: value {value} and weight {weight} must be finite and ≥ 0")]
    BadTarget {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
        /// Its weight.
        weight: f64,
    },
    /// The target is zero everywhere (e.g. an all-black map): nothing to fit.
    #[error("the fit target is zero everywhere (e.g. an all-black map)")]
    BlackTarget,
    /// A defensive sample share outside `[0, 1)`.
    #[error("the defensive share must be in [0, 1) (got {value})")]
    BadDefensive {
        /// The value given.
        value: f64,
    },
    /// A cosine sample share outside `(0, 1)`, a light share outside `[0, 1)`, or shares that
    /// leave no room for the product lobes (`δ + γ + β ≥ 1`).
    #[error(
        "the cosine share must be in (0, 1), the light share in [0, 1), with defensive + cosine + light < 1 (got cosine {cosine}, light {light}, defensive {defensive})"
    )]
    BadCosineShare {
        /// The cosine share given.
        cosine: f64,
        /// The light share given.
        light: f64,
        /// The defensive share given.
        defensive: f64,
    },
}
