//! General planar sampling machinery, below every sampler of the workspace: the 2D sampler
//! contract ([`Sampler2D`], [`InvertibleSampler2D`], [`UniformSource`]), rectangles and the
//! unit disc ([`Rect`], [`Domain`]), Walker/Vose alias tables ([`alias`]), saturating index
//! helpers ([`index`]), reproducible parallel sampling ([`sample_par`], [`chunk_seed`],
//! [`Shard`]) and the 1D/2D piecewise-constant tables with their CDF kernels
//! ([`PiecewiseConstant1D`], [`PiecewiseConstant2D`], [`find_cell`], …).
//!
//! It knows nothing of quadtrees, BRDFs or images: the adaptive quadtree sampler
//! (`partition-sampler`), the environment-map samplers (`envmap`) and the BRDF samplers build
//! on it. Same seed, same samples, whatever the thread count.

// `!(x > 0.0)` is the house style for checks that must also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod alias;
pub mod contract;
pub mod index;
pub mod parallel;
pub mod piecewise_constant;
pub mod rect;

pub use contract::{
    AsDistribution, InvertibleSampler2D, Point2, Sample2, Sampler2D, UniformSequence, UniformSource,
};
pub use parallel::{
    PAR_CHUNK, Shard, ShardError, chunk_rng, chunk_seed, on_threads, sample_par, thread_cpu_seconds,
};
pub use piecewise_constant::{
    ONE_MINUS_EPSILON, PiecewiseConstant1D, PiecewiseConstant2D, PiecewiseConstantError, Sample1,
    clamp_unit, fill_cdf, fill_guide, find_cell, find_cell_guided,
};
pub use rect::{Domain, Rect};
