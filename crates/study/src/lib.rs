//! Variance-versus-cost studies of brdf-lab's direction samplers (docs/studies.md).
//!
//! A study is a grid of independent **cells** — sampler × mode (one-sample, and batch for
//! batch-mode samplers) × BRDF × outgoing angle θo × light — each seeded from
//! `(seed, cell index)`. For each cell it measures the estimator of reflected radiance
//! `L_r(ωo) = ∫_Ω f_r(ωo, ωi) L(ωi) cos θi dσ(ωi)` built on the sampler (pdf w.r.t. solid
//! angle): the per-sample variance, the per-sample mean squared error at the budget N against
//! the reference (module [`dispersion`]: heavy tails and bias are not mistaken for low
//! variance), time per sample, BRDF evaluations per sample, efficiency `1 / (MSE × time)`,
//! and relative error against a deterministic-quadrature reference at
//! every N of a grid, with 95 % confidence intervals. Samplers come from the `samplers`
//! registry and BRDFs from `brdf::parse_spec`, so new ones join without code changes.
//!
//! ```
//! use study::{StudyConfig, StudyPlan};
//!
//! let mut config = StudyConfig::new(
//!     vec!["uniform".into(), "cosine".into()],
//!     vec!["lambert".into()],
//!     vec![30.0],
//!     vec!["constant".into()],
//! );
//! config.n_grid = vec![1, 16];
//! config.repetitions = 4;
//! config.variance_samples = 100;
//! config.timing_samples = 10;
//! let plan = StudyPlan::new(config, Vec::new())?;
//! let results = plan.run(None, &|_| {});
//! // Under constant light, cosine sampling of a Lambertian BRDF is exact: zero variance.
//! let cosine = results.cells.iter().find(|c| c.sampler == "cosine").unwrap();
//! assert!(cosine.zero_variance);
//! assert!(cosine.warnings.is_empty() && cosine.timing.unwrap().efficiency.is_none());
//! let uniform = results.cells.iter().find(|c| c.sampler == "uniform").unwrap();
//! assert!(!uniform.zero_variance);
//! # Ok::<(), study::StudyError>(())
//! ```

// Validation is written `if !(x > 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod answers;
mod config;
mod counting;
pub mod dispersion;
mod error;
mod groups;
mod harness;
mod light;
mod machine;
mod merge;
mod names;
mod paper;
mod plot;
pub mod ranking;
mod reference;
mod render;
mod report;
mod results;
mod sheet;
mod verdict;

pub use config::{
    BATCH_REPETITIONS, CellSpec, DEFAULT_MERL_FITS, EXTRA_ESTIMATORS, FULL_THETA_O_DEG,
    LIGHT_SAMPLERS, MAP_CANDIDATES, MEASURED_CANDIDATES, MEASURED_DIRS, Mode, PAPER_N_GRID,
    PREFERRED_SAMPLERS, QUICK_BRDFS, QUICK_MIS_SAMPLERS, Shard, StudyConfig, all_merl_fits,
    analytic_models, registered_preferred, shared_measured,
};
pub use counting::{CountingBrdf, thread_evaluations};
pub use dispersion::BudgetMse;
pub use error::StudyError;
pub use groups::{
    Family, Group, SHEET_MAX_BRDFS, groups, is_adaptive, sheet_brdfs, short_brdf, short_light,
};
pub use harness::{ProgressFn, StudyPlan};
pub use light::{AREA_PHI_DEG, AREA_RADIANCE, AREA_RADIUS_DEG, AREA_THETA_DEG, Light, SKY_WIDTH};
pub use machine::{COMMIT, PhaseCpu, RunInfo, process_cpu_seconds};
pub use paper::{
    Claim, ClaimVerdict, MERL_SAMPLES, PAPER_SPHERE_PX, PaperRow, PaperTable, SEED_003_MODELS,
    TIME_MARGIN, paper_markdown, paper_tables,
};
pub use plot::{
    Bar, Figure, Marker, PLOT_SIZE, PlotFile, SamplerStyle, Series, group_figures, sampler_style,
    study_plots, summary_figures,
};
pub use ranking::{Ranking, RankingComparison, compare_rankings, rankings};
pub use reference::{Reference, reference};
pub use render::{
    AdaptiveVerdict, IMAGE_KINDS, Image, PRODUCT_DEFENSIVE, PRODUCT_KINDS, PRODUCT_NAME,
    ProductCost, Render, RenderConfig, SampleCost, SphereError, TIMING_REPEATS, encode_png,
    equal_time_spp, product_equal_time_spp, rank_pixel_errors, relative_error, stack,
};
pub use report::{ReportAssets, report_markdown};
pub use results::{CellResult, Clock, ErrorAtN, LightInfo, SCHEMA, StudyResults, Timing, WithCi};
pub use sheet::labelled_sheet;
