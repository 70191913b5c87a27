//! Baseline samplers that brdf-lab's adaptive-partition sampler is compared with.
//!
//! Direction samplers (pdf w.r.t. solid angle, the [`brdf_sampling::DirectionSampler`] shape):
//! [`UniformHemisphere`] and [`CosineHemisphere`]; per-slice tabulated CDFs, uncompressed
//! ([`TabulatedCdf`]) and Douglas–Peucker-compressed ([`CascadeCdf`], Lawrence 2005), in [`cdf`];
//! the cosine lobe about the mirror direction with a fitted exponent per outgoing slice
//! ([`LobeSampler`]: `lobe-sphere`, `lobe-hemisphere`); the models' own analytic samplers
//! ([`AnalyticSampler`]: `analytic`); [`FactoredSampler`] (Lawrence et al. 2004, NMF-factored
//! `f_r cos θ`, options [`FactoredOptions`]); [`RglNative`], the RGL format's own sampler;
//! [`SrbfSampler`] (Tsai et al. 2008 SRBF mixtures) and the product estimators in [`srbf`].
//!
//! The planar baseline, the classic piecewise-constant CDF sampler, lives in `partition_sampler`
//! (`partition_sampler::PiecewiseConstant2D`) next to the adaptive sampler it is compared with.
//!
//! ```
//! use baselines::CosineHemisphere;
//! use brdf::Vec3;
//! use brdf_sampling::DirectionSampler;
//! use partition_sampler::UniformSequence;
//!
//! let wo = Vec3::new(0.0, 0.0, 1.0);
//! let mut u = UniformSequence::new(&[0.25, 0.5]);
//! let s = CosineHemisphere.sample(&wo, &mut u);
//! assert!((s.pdf - CosineHemisphere.pdf(&wo, &s.wi)).abs() < 1e-12);
//!
//! // The cosine lobe about the mirror direction, exponent fitted per θo slice, and the
//! // model's own sampler.
//! use baselines::{AnalyticSampler, LobeOptions, LobeSampler, LobeSupport};
//! use std::sync::Arc;
//! let phong: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec("phong:n=50")?);
//! let options = LobeOptions { slices: 4, ..LobeOptions::default() };
//! let lobe = LobeSampler::new(&phong, LobeSupport::Hemisphere, &options)?;
//! assert_eq!(lobe.exponents().len(), 4);
//! let analytic = AnalyticSampler::new(phong.as_ref())?;
//! let wo = brdf::direction_from_angles(30.0, 0.0);
//! for s in [&lobe as &dyn DirectionSampler, &analytic] {
//!     let d = s.sample(&wo, &mut UniformSequence::new(&[0.5, 0.25, 0.75]));
//!     assert!((d.pdf - s.pdf(&wo, &d.wi)).abs() <= 1e-12 * d.pdf);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// `!(x > 0.0)` is the project's NaN-rejecting check (NaN fails it).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cdf;
pub mod factored;
pub mod hemisphere;
pub mod lobe;
pub mod options;
pub mod rgl_native;
pub mod srbf;

pub use cdf::{CascadeCdf, CdfReport, TabulatedCdf};
pub use factored::{FactoredError, FactoredReport, FactoredSampler};
pub use hemisphere::{CosineHemisphere, UniformHemisphere};
pub use lobe::{AnalyticSampler, LobeError, LobeFit, LobeSampler, LobeSupport};
pub use options::{
    BaselineOptions, CdfOptions, CdfOptionsError, FactoredOptions, FactoredOptionsError,
    LobeOptions, NmfCost, Reparam, SrbfOptions,
};
pub use rgl_native::{NotRglError, RglNative};
pub use srbf::{SrbfError, SrbfSampler};
