//! The one home of brdf-lab's estimators of reflected radiance
//! `L_r(ωo) = ∫_Ω L(ωi) f_r(ωo, ωi) cos θi dσ(ωi)`, used by the `product` command, the
//! study's cells and its sphere renderer:
//!
//! * [`estimate_brdf`] — a BRDF direction sampler alone; [`estimate_light`] — an
//!   environment-map sampler alone; [`estimate_mis`] — one of each, `N/2` samples each,
//!   balance or power heuristic ([`MisHeuristic`], Veach 1997); the per-sample terms
//!   ([`mis_brdf_term`], [`mis_light_term`]) and the one-value-per-call forms a renderer or
//!   the study averages itself ([`MisPair`], [`light_value`]);
//! * [`Batch`] — the batch path: many query points (a row of pixels) × `spp` samples in one
//!   [`brdf_sampling::DirectionSampler::sample_eval_batch`] call, BRDF sampling or MIS with any
//!   [`LightTechnique`], for luminance or RGB values ([`Radiance`]); the per-sample terms
//!   ([`brdf_value`], [`mis_term`]) are the ones every estimator here uses;
//! * [`estimate_srbf_product`] — SRBF product importance sampling (Tsai et al. 2008) of the
//!   fits of `baselines::srbf`;
//! * [`Estimate`] — the estimate, its standard error, and whether that standard error can be
//!   trusted (tail share, the variance's own interval: [`Estimate::heavy_tailed`]);
//! * [`quadrature_reference`] — a deterministic reference on the map's pixels;
//! * [`load_map`] — a map file or the built-in procedural sky; [`ProductExperiment`] — the
//!   `product` command's experiment.
//!
//! The shading point has an explicit [`LocalFrame`] (normal and a rotation about it); the map
//! is world-space, so a local direction `ω` sees the radiance `L(frame.to_world(ω))`.
//!
//! ```
//! use baselines::{CosineHemisphere, SrbfOptions, SrbfSampler};
//! use baselines::srbf::fit_envmap;
//! use estimators::{LocalFrame, MisHeuristic, ProductScene, estimate_mis, estimate_srbf_product};
//!
//! let brdf = brdf::parse_spec("phong:n=30")?;
//! let options = SrbfOptions { slices: 4, fit_rows: 12, brdf_lobes: 4, map_lobes: 8, map_fit_width: 32, ..SrbfOptions::default() };
//! let sampler = SrbfSampler::build(brdf.as_ref(), &options)?;
//! let wo = brdf::direction_from_angles(30.0, 0.0);
//! let sky = envmap::procedural_sky(64, 32)?;
//! let map_fit = fit_envmap(&sky, &options)?;
//! let light = envmap::EnvMapSampler::piecewise_constant(&sky)?;
//! let frame = LocalFrame::new([0.0, 0.3, 1.0], 0.0)?;
//! let scene = ProductScene::new(brdf.as_ref(), &sky, frame, wo)?;
//! let (product, stats) = estimate_srbf_product(&scene, &sampler, &map_fit, &light, &options.product_settings(), 10_000, 7)?;
//! assert!(product.estimate > 0.0 && product.std_err > 0.0 && stats.kept >= 1);
//! let mis = estimate_mis(&scene, &CosineHemisphere, &light, MisHeuristic::Balance, "mis", 10_000, 8)?;
//! assert!((mis.estimate - product.estimate).abs() < 5.0 * (mis.std_err + product.std_err));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// Validation is written `if !(x > 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod adaptive_product;
mod batch;
mod driver;
mod error;
mod estimate;
mod heuristic;
mod map;
mod mis;
mod product;
mod scene;

pub use adaptive_product::{ProductBatch, ProductCut, ProductOptions};
pub use baselines::srbf::ProductSettings;
pub use batch::{Batch, LightTechnique, Query, Radiance, brdf_value, mis_term};
pub use driver::{ProductExperiment, ProductOutcome};
pub use error::EstimatorError;
pub use estimate::{Estimate, HEAVY_TAIL_SHARE, UNCERTAIN_VARIANCE, tail_threshold};
pub use heuristic::MisHeuristic;
pub use map::{SKY_NAME, SKY_SIZE, load_map};
pub use mis::{
    MisPair, estimate_brdf, estimate_light, estimate_mis, light_value, mis_brdf_term,
    mis_light_term,
};
pub use product::{ProductStats, estimate_srbf_product};
pub use scene::{LocalFrame, ProductScene, quadrature_reference};
