//! Statistical validation of every sampler in brdf-lab (docs/validation.md): chi-square and
//! Kolmogorov–Smirnov goodness of fit, pdf consistency, normalisation, support coverage,
//! unbiasedness z-tests (one-sample and batch), and the bound audit, judged together with a
//! Šidák correction; plus mutant samplers that the suite must reject.
//!
//! * [`SamplerUnderTest`] is what the tests run on: `sample(u) → (x, pdf)`, `pdf(x)`,
//!   `sample_batch`. Adapters cover any `DirectionSampler` at a fixed `ωo` (directions, pdf
//!   w.r.t. solid angle, on the [`Domain::Hemisphere`] or [`Domain::Sphere`]) and any planar
//!   `Sampler2D` (pdf w.r.t. area on the [`Domain::Disc`] or [`Domain::UnitSquare`]).
//! * the `samplers` crate is the registry (one entry per sampler; [`builds`] maps each kind to
//!   a subject under test); [`mutants()`] are the broken ones.
//! * [`run`] executes a [`ValidateConfig`] (quick or full tier) and returns a
//!   [`ValidationReport`] ([`ValidationReport::to_json`], [`ValidationReport::to_markdown`]);
//!   [`run_shard`] runs one [`Shard`] of it and [`merge`] recombines the shards' reports into
//!   the single run's.
//!
//! Tests per case (sampler, target, `θo`): `chi-square` and `batch-chi-square` (expected counts
//! by adaptive quadrature with accuracy tied to N, pooling below 5), `ks-cos-theta`/`ks-phi`
//! (or `ks-x`/`ks-y`), `pdf-consistency`, `normalisation`, `support-coverage`,
//! `unbiasedness` (albedo or the subject's integral), `batch-size`, `batch-unbiasedness`
//! (per-batch estimates of a non-proportional integrand), and `bound-audit` for samplers with
//! bounds. Every p-value is judged at `1 − (1 − α)^{1/m}` over the `m` p-valued tests of the run.
//!
//! # Example
//!
//! ```
//! use validation::{ValidateConfig, run};
//!
//! let config = ValidateConfig {
//!     samplers: vec!["grid-cdf".into()],
//!     samples: Some(20_000),
//!     ..ValidateConfig::quick()
//! };
//! let report = run(&config, &|_| {})?;
//! assert!(report.passed());
//! assert!(report.tests.iter().any(|t| t.test == "chi-square"));
//! let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
//! assert_eq!(json["passed"], true);
//! # Ok::<(), validation::ValidationError>(())
//! ```

// `!(x >= 0.0)`-style checks are deliberate: they reject NaN along with out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod adapters;
mod builds;
mod case;
pub mod cells;
mod domain;
mod error;
mod merge;
pub mod mutants;
mod outcomes;
mod plan;
pub mod references;
mod report;
pub mod seeding;
mod subject;
mod suite;
pub mod targets;

pub use builds::{
    StandaloneCase, build_direction, build_disc, direction_domain, quadtree_disc_sampler,
    standalone_cases, test_maps, uses_brdf,
};
pub use case::{DECLARED_ERROR_FACTOR, DRAW_CHUNK, draw, draw_batches, names, run_case, z_test};
pub use domain::{Domain, Resolution};
pub use error::{MergeError, ValidationError};
pub use merge::merge;
pub use mutants::{Mutant, mutants};
pub use plan::{
    DEFAULT_MEASURED_DIR, DEFAULT_MERL_DIR, FULL_PRESET_MODELS, FULL_SAMPLES, FULL_THETA_O,
    MIN_SAMPLES, PRESET_THETA_O, Plan, QUICK_BRDFS, QUICK_CORNELL, QUICK_RGL, QUICK_SAMPLES,
    QUICK_THETA_O, Shard, Tier, ValidateConfig,
};
pub use report::{BuildWarning, MutantRecord, ShardInfo, TestRecord, ValidationReport};
pub use subject::{
    AnySubject, Dir3, Estimand, Point2, Reference, SamplerUnderTest, ScalarFn, Subject,
};
pub use suite::{ProgressEvent, run, run_shard, run_shard_with, run_with, run_with_brdfs};
