//! Tsai, Chang, Jiang, Weng 2008: spherical radial basis functions (Gaussian SRBFs) fitted to
//! BRDF slices and environment maps, the `srbf` BRDF sampler and SRBF product importance
//! sampling (baselines.md §C, §D).
//!
//! * [`vmf`] — the closed forms (SG integral and product) and the stable vMF sampler.
//! * [`fit`] — non-negative SRBF fitting: greedy guess, NNLS, bound-free L-BFGS.
//! * [`sampler`] — [`SrbfSampler`], the BRDF-only mixture sampler (pdf w.r.t. solid angle on
//!   the whole sphere).
//! * [`envfit`] — the fit of an environment map's luminance.
//! * [`product`] — estimators of reflected radiance under an environment map: SRBF product
//!   sampling, BRDF sampling, light sampling and MIS.

// Validation is written `if !(x > 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod envfit;
mod error;
pub mod fit;
mod lbfgs;
pub mod product;
pub mod sampler;
pub mod vmf;

pub use envfit::{EnvSrbf, fit_envmap};
pub use error::SrbfError;
pub use fit::{FitReport, FitSettings, FitTarget, SrbfFit, fit};
pub use product::{
    Estimate, LocalFrame, MisHeuristic, ProductScene, ProductSettings, ProductStats, estimate_brdf,
    estimate_light, estimate_mis, estimate_srbf_product,
};
pub use sampler::{SrbfReport, SrbfSampler};
pub use vmf::SgLobe;
