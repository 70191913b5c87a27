//! Baseline samplers that brdf-lab's adaptive-partition sampler is compared with.
//!
//! Direction samplers (pdf w.r.t. solid angle, the [`brdf_sampling::DirectionSampler`] shape):
//! [`UniformHemisphere`] and [`CosineHemisphere`].
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

pub mod hemisphere;
pub mod options;
pub mod srbf;

pub use hemisphere::{CosineHemisphere, UniformHemisphere};
pub use options::{BaselineOptions, CdfOptions, FactoredOptions, LobeOptions, SrbfOptions};
pub use srbf::{SrbfError, SrbfSampler};
