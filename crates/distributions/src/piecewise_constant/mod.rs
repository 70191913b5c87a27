//! Piecewise-constant densities sampled by CDF inversion (the pbrt-style baseline): the planar
//! tabulated CDFs [`PiecewiseConstant1D`] and [`PiecewiseConstant2D`].
//!
//! Not to be confused with `partition_sampler::TabulatedDensity`, the quadtree's region-statistics
//! provider for gridded densities: these types are samplers in their own right (one CDF
//! inversion per coordinate, exactly two uniforms per 2D sample), the classic baseline the
//! adaptive sampler is compared with.

// Validation is written `if !(x >= 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod cdf;
mod error;
mod one_d;
mod two_d;

pub use cdf::{ONE_MINUS_EPSILON, clamp_unit, fill_cdf, fill_guide, find_cell, find_cell_guided};
pub use error::PiecewiseConstantError;
pub use one_d::{PiecewiseConstant1D, Sample1};
pub use two_d::PiecewiseConstant2D;
