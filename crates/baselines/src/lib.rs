//! Baseline samplers that brdf-lab's adaptive-partition sampler is compared with.
//!
//! Direction samplers (pdf w.r.t. solid angle, the [`brdf_sampling::DirectionSampler`] shape):
//! [`UniformHemisphere`] and [`CosineHemisphere`].
//!
//! Planar samplers: the classic marginal/conditional piecewise-constant CDF sampler
//! ([`PiecewiseConstant2D`], with its 1D building block [`PiecewiseConstant1D`]), as used by
//! pbrt for environment maps. It implements the shared [`partition_sampler::Sampler2D`] and
//! [`partition_sampler::InvertibleSampler2D`] contract: pdfs are **with respect to area on the
//! domain rectangle**, exactly two uniforms per sample.
//!
//! ```
//! use baselines::PiecewiseConstant2D;
//! use partition_sampler::{Rect, Sampler2D};
//! use rand::SeedableRng;
//!
//! // A 4×2 grid on [0,2]×[0,1]; row 0 lies at y = 0.
//! let values = vec![0.0, 1.0, 2.0, 1.0, 4.0, 0.0, 0.0, 0.0];
//! let domain = Rect { x0: 0.0, y0: 0.0, x1: 2.0, y1: 1.0 };
//! let table = PiecewiseConstant2D::new(4, 2, values, domain).unwrap();
//!
//! let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(7);
//! let s = table.sample(&mut rng);
//! assert!(s.pdf > 0.0 && s.pdf == table.pdf(s.point));
//!
//! // Reproducible parallel batches: the result depends only on (n, seed).
//! let batch = table.sample_par(10_000, 42);
//! assert_eq!(batch, table.sample_par(10_000, 42));
//! ```

// Validation is written `if !(x >= 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod hemisphere;
pub mod parallel;
pub mod piecewise_constant;

pub use hemisphere::{CosineHemisphere, UniformHemisphere};
pub use parallel::sample_par;
pub use partition_sampler::Rect;
pub use piecewise_constant::{PiecewiseConstant1D, PiecewiseConstant2D, Sample1, TabulatedError};
