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

/// Why shards' parts (`validate --shard K/N --json PART`) could not be merged.
#[derive(Debug, Error)]
pub enum MergeError {
    /// No part was given.
    #[error("no part to merge")]
    NoParts,
    /// A part was not written by a sharded run (no `shard` object).
    #[error(
        "part {0} is not a shard's report (no `shard` object: run `validate --shard K/N --json FILE`)"
    )]
    NotAShard(String),
    /// Two parts were run with different configurations (or found different cases).
    #[error(
        "part {part} was run with another configuration than part {first} (fingerprint {got} ≠ {expected}): shards of different runs cannot be merged"
    )]
    ConfigMismatch {
        /// The first part.
        first: String,
        /// The part that differs.
        part: String,
        /// The first part's fingerprint.
        expected: String,
        /// This part's fingerprint.
        got: String,
    },
    /// Two parts were run with different shard counts.
    #[error("part {part} is a shard of {got}, part {first} of {expected}")]
    CountMismatch {
        /// The first part.
        first: String,
        /// The part that differs.
        part: String,
        /// The first part's shard count.
        expected: usize,
        /// This part's shard count.
        got: usize,
    },
    /// The same shard was given twice.
    #[error("shard {index}/{count} given twice ({first} and {second})")]
    Duplicate {
        /// `K`.
        index: usize,
        /// `N`.
        count: usize,
        /// One part.
        first: String,
        /// The other.
        second: String,
    },
    /// Some shards are missing.
    #[error("missing shard(s): {}", missing.iter().map(|k| format!("{k}/{count}")).collect::<Vec<_>>().join(", "))]
    Missing {
        /// The missing `K`s.
        missing: Vec<usize>,
        /// `N`.
        count: usize,
    },
    /// The parts together do not hold every case of the plan exactly once.
    #[error("the parts hold {got} of the plan's {expected} cases (a part was truncated or edited)")]
    Incomplete {
        /// Distinct cases found.
        got: usize,
        /// Cases of the full plan.
        expected: usize,
    },
}
