//! Tsai, Chang, Jiang, Weng 2008: spherical radial basis functions (Gaussian SRBFs) fitted to
//! BRDF slices and environment maps, the `srbf` BRDF sampler and SRBF product importance
//! sampling (baselines.md §C, §D).
//!
//! * [`vmf`] — the closed forms (SG integral and product) and the stable vMF sampler.
//! * [`fit`] — non-negative SRBF fitting: greedy guess, NNLS, then Levenberg–Marquardt (BRDF
//!   slices) or bound-free L-BFGS (the map).
//! * [`sampler`] — [`SrbfSampler`], the BRDF-only mixture sampler (pdf w.r.t. solid angle on
//!   the whole sphere).
//! * [`envfit`] — the fit of an environment map's luminance.
//! * [`product`] — the settings of the SRBF product estimator (the estimator itself, with the
//!   BRDF, light and MIS estimators, is in the `estimators` crate).
//!
//! ```
//! use baselines::{SrbfOptions, SrbfSampler};
//! use brdf_sampling::DirectionSampler;
//! use rand::SeedableRng;
//!
//! let brdf = brdf::parse_spec("phong:n=30")?;
//! let options = SrbfOptions { slices: 4, fit_rows: 12, brdf_lobes: 4, map_lobes: 8, map_fit_width: 32, ..SrbfOptions::default() };
//! let sampler = SrbfSampler::build(brdf.as_ref(), &options)?;
//! let wo = brdf::direction_from_angles(30.0, 0.0);
//! let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
//! let s = sampler.sample(&wo, &mut rng); // pdf w.r.t. solid angle, on the whole sphere
//! assert!((sampler.pdf(&wo, &s.wi) - s.pdf).abs() <= 1e-9 * s.pdf);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// Validation is written `if !(x > 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod envfit;
mod error;
pub mod fit;
mod lbfgs;
mod lm;
pub mod product;
pub mod sampler;
mod target;
pub mod vmf;

pub use envfit::{EnvSrbf, fit_envmap};
pub use error::SrbfError;
pub use fit::{FitReport, FitSettings, FitTarget, SrbfFit, fit, fit_from, fit_lbfgs};
pub use product::ProductSettings;
pub use sampler::{SrbfReport, SrbfSampler};
pub use vmf::SgLobe;
