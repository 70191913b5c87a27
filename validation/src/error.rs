//! Errors of a validation run: bad input (the CLI exits with code 2 on any of them).
//! A sampler that fails a test is not an error: it is a failed test in the report.

use thiserror::Error;

/// Why a validation run could not start.
#[derive(Debug, Error)]
pub enum ValidationError {
    /// No registered sampler has this name.
    #[error(transparent)]
    Sampler(#[from] samplers::RegistryError),
    /// A BRDF spec did not parse or the model could not be built.
    #[error("bad BRDF spec `{spec}`: {source}")]
    Brdf {
        /// The spec given.
        spec: String,
        /// Why.
        #[source]
        source: brdf::SpecError,
    },
    /// A saved set could not be read or re-attached to its BRDF.
    #[error("set {path}: {reason}")]
    Set {
        /// The file.
        path: std::path::PathBuf,
        /// Why (I/O or the registry's reason).
        reason: String,
    },
    /// An outgoing angle is not a finite number in `[0, 90)` degrees.
    #[error("outgoing angle {0} deg is invalid: theta_o must be finite and in [0, 90)")]
    BadAngle(f64),
    /// Too few samples per case for the tests to mean anything.
    #[error("{got} samples per case is too few; need at least {min}")]
    TooFewSamples {
        /// The count given.
        got: usize,
        /// The minimum.
        min: usize,
    },
    /// The significance level is not in `(0, 1)`.
    #[error("significance level must lie in (0, 1), got {0}")]
    BadAlpha(f64),
    /// The selection contains nothing to test.
    #[error("nothing to validate: {0}")]
    Empty(String),
}
