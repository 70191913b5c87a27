//! The study's typed error.

/// A study could not be configured, run or merged.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A sampler name that is not a registered direction sampler.
    #[error(transparent)]
    Sampler(Box<samplers::RegistryError>),
    /// A BRDF spec that does not parse.
    #[error("--brdf {spec}: {source}")]
    Brdf {
        /// The spec given.
        spec: String,
        /// Why it does not parse.
        source: brdf::SpecError,
    },
    /// A light spec that does not parse, or names a map that cannot be read.
    #[error("--light {spec}: {reason}")]
    Light {
        /// The spec given.
        spec: String,
        /// Why it is refused.
        reason: String,
    },
    /// The sample-count grid is empty, contains 0 or is not strictly increasing.
    #[error("sample counts must be positive and strictly increasing, got {0:?}")]
    SampleGridNotIncreasing(Vec<usize>),
    /// An outgoing angle outside `[0°, 90°)` (or NaN).
    #[error("outgoing angle θo = {0}° is not in [0°, 90°)")]
    ThetaOutOfRange(f64),
    /// A count that must be positive is not (`repetitions`, `variance samples`, …).
    #[error("{what} must be at least {min}, got {got}")]
    TooFew {
        /// Which setting.
        what: &'static str,
        /// The least allowed value.
        min: usize,
        /// The value given.
        got: usize,
    },
    /// A study with no sampler, BRDF, angle or light.
    #[error("the study has no {0}")]
    EmptyGrid(&'static str),
    /// A name that is not one of the study's (e.g. a sphere-sheet BRDF).
    #[error("{name} is not one of the study's {what}")]
    NotInStudy {
        /// `BRDFs`, …
        what: &'static str,
        /// The name given.
        name: String,
    },
    /// An estimator the study does not know, or a MIS sampler outside the study's samplers.
    #[error("unknown estimator setting: {0} (estimators: light, mis-balance, mis-power)")]
    UnknownEstimator(String),
    /// Shards given to `merge` that do not form one study.
    #[error("cannot merge: {0}")]
    Merge(String),
    /// A results file that cannot be read back.
    #[error("results file {path}: {reason}")]
    ResultsFile {
        /// The file.
        path: String,
        /// Why it cannot be read.
        reason: String,
    },
    /// Drawing a plot or encoding an image failed.
    #[error("plot {name}: {reason}")]
    Plot {
        /// The plot's file stem.
        name: String,
        /// The backend's message.
        reason: String,
    },
}

impl From<samplers::RegistryError> for StudyError {
    /// Boxed: the registry's error carries every sampler's error and would make every
    /// `Result<_, StudyError>` large.
    fn from(e: samplers::RegistryError) -> Self {
        StudyError::Sampler(Box::new(e))
    }
}
