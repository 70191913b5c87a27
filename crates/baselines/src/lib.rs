//! Baseline samplers that brdf-lab's adaptive-partition sampler is compared with.
//!
//! Direction samplers (pdf w.r.t. solid angle, the [`brdf_sampling::DirectionSampler`] shape):
//! [`UniformHemisphere`] and [`CosineHemisphere`]; [`FactoredSampler`] (Lawrence et al. 2004,
//! NMF-factored `f_r cos θ`, options [`FactoredOptions`]).
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
//! ```

// `!(x > 0.0)`-style checks are deliberate: they reject NaN along with out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod factored;
pub mod hemisphere;
pub mod options;

pub use factored::{FactoredError, FactoredReport, FactoredSampler};
pub use hemisphere::{CosineHemisphere, UniformHemisphere};
pub use options::{
    BaselineOptions, CdfOptions, FactoredOptions, FactoredOptionsError, LobeOptions, NmfCost,
    Reparam,
};
