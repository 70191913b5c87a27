//! The estimators' typed error.

use baselines::SrbfError;

/// Why an estimator (or the product experiment) could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// A shading normal of zero length or with a non-finite component (or a non-finite
    /// rotation).
    #[error("the normal ({x}, {y}, {z}) must be finite with non-zero length")]
    BadNormal {
        /// x.
        x: f64,
        /// y.
        y: f64,
        /// z.
        z: f64,
    },
    /// Frame axes that are not an orthonormal right-handed triple.
    #[error("the frame's axes must be orthonormal and right-handed (t × b = n)")]
    NotOrthonormal,
    /// The outgoing direction is not above the local horizon.
    #[error("the outgoing direction must be above the horizon (cos θo = {cos_theta})")]
    BelowHorizon {
        /// `cos θo` in the local frame.
        cos_theta: f64,
    },
    /// Fewer samples than the estimator needs.
    #[error("{estimator} needs at least {min} samples (got {got})")]
    TooFewSamples {
        /// The estimator.
        estimator: &'static str,
        /// Its minimum.
        min: usize,
        /// Samples asked for.
        got: usize,
    },
    /// An SRBF fit or product setting was refused.
    #[error(transparent)]
    Srbf(#[from] SrbfError),
    /// A sampler name, or a sampler that could not be built (the registry's message).
    #[error("{0}")]
    Sampler(String),
    /// An environment map that could not be read or made.
    #[error("{0}")]
    Map(String),
    /// The product experiment was given no BRDF sampler or no light sampler.
    #[error("the product experiment needs at least one {0} sampler")]
    NoSampler(&'static str),
}
