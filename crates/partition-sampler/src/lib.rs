//! Generic 2D adaptive-partition sampler (Montes, Ureña et al., GRAPP 2008 / CEIG 2008).
//!
//! A density `f ≥ 0` on a rectangle or on the unit disc is partitioned by a quadtree whose
//! cells are split until rejection sampling inside each leaf needs at most `n_max` trials on
//! average. Samples are drawn by choosing a leaf and doing rejection in its (disc-clipped)
//! rectangle under the leaf bound `M_i`. The crate knows nothing about BRDFs or images: it
//! needs only a [`RegionStats`] provider giving an upper bound `M_i` and the integral `I_i` of
//! `f` on a rectangle:
//!
//! * [`TabulatedDensity`]: piecewise-constant grids (optionally times a smooth row factor such
//!   as [`SinPiRows`] for latitude–longitude maps), exact `M_i`, `I_i` from pyramids;
//! * [`SampledGridDensity`]: any [`Density`] evaluated on a dense grid (the papers' "image
//!   map"), bounds with a safety factor, audited while sampling;
//! * [`UserBoundDensity`]: caller-supplied bounds, integrals by quadrature.
//!
//! All pdfs are with respect to **area on the domain** ([`Sampler2D`]). The default
//! [`Scheme::Envelope`] is exact whenever the bounds hold; [`Scheme::Paper`] is the papers'
//! scheme. See [`QuadTreeSampler`] for what `pdf` returns.
//!
//! # Sampling verbs
//! A [`QuadTreeSampler`] draws through four verbs, each for one use:
//!
//! | verb | draws | for |
//! |---|---|---|
//! | [`Sampler2D::sample`] | one sample from the caller's uniforms | a renderer's inner loop, QMC streams |
//! | [`Sampler2D::sample_into`] | a slice of samples, the same as repeated `sample` (bit for bit) | filling a buffer with the one-sample law, faster |
//! | [`QuadTreeSampler::sample_batch`] | `n` samples stratified over the leaves (the papers' batch mode, seed 000 §3.6, on [`allocate()`]) | lower-variance estimates from one batch |
//! | [`QuadTreeSampler::sample_par`] | `n` one-sample draws in parallel, reproducible from a seed whatever the thread count ([`sample_par()`]) | large sample sets, tests |
//!
//! The draws with caller-held trial counts and rejection against another density under the
//! tree's bounds are diagnostics, behind [`diagnostics::AuditedDraws`] (import it to use
//! them); every verb also feeds the bound audit of [`SamplerStats::bound_violations`].
//!
//! Beyond sampling: versioned
//! persistence of the tree ([`QuadTree::to_bytes`], [`QuadTreeSampler::from_parts`]) and
//! memory reports ([`QuadTreeSampler::memory`]). Wrap a provider in [`SharedDensity`] to
//! build several trees over one copy of it.
//!
//! The crate also holds the planar tabulated CDFs the adaptive sampler is compared with: the
//! classic marginal/conditional piecewise-constant sampler [`PiecewiseConstant2D`] (an
//! [`InvertibleSampler2D`], as pbrt uses for environment maps) and its 1D building block
//! [`PiecewiseConstant1D`].
//!
//! ```
//! use partition_sampler::{QuadTreeBuilder, Rect, Sampler2D, SinPiRows, TabulatedDensity};
//! use rand::{SeedableRng, rngs::Xoshiro256PlusPlus};
//!
//! // A 8 × 4 latitude–longitude luminance map over (u, v) ∈ [0, 1]², one bright texel.
//! let mut lum = vec![1.0; 8 * 4];
//! lum[2 * 8 + 5] = 1000.0;
//! let density = TabulatedDensity::new(8, 4, lum, Rect::UNIT)?.with_row_factor(SinPiRows)?;
//! let sampler = QuadTreeBuilder::new().build(density)?;
//!
//! let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
//! let s = sampler.sample(&mut rng);
//! assert!(Rect::UNIT.contains(s.point) && s.pdf > 0.0);
//! assert!((sampler.pdf(s.point) - s.pdf).abs() <= 1e-12 * s.pdf);
//! let stats = sampler.stats();
//! assert!(stats.expected_mean_trials <= 2.0 && stats.bound_violations == 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod allocate;
mod audit;
pub mod diagnostics;
// The general planar machinery lives in the `distributions` crate: the sampler contract,
// alias tables, index helpers, rectangles and domains, parallel sampling and the
// piecewise-constant tables. Re-exported here so that `partition_sampler::X` keeps working.
pub use distributions::contract;
use distributions::{alias, index, rect};
mod builder;
mod density;
mod error;
#[cfg(test)]
mod layout_tests;
mod leaf;
mod limits;
mod persist;
mod pyramid;
mod quadtree_sampler;
mod sampled;
mod shape;
mod tabulated;
mod tree;
mod user_bound;

pub use allocate::{AllocationMode, allocate, stratum_weights};
pub use audit::{Audit, AuditCounters, FLUSH_EVERY, count_trials, thread_trials};
pub use builder::{MAX_DEPTH_LIMIT, QuadTreeBuilder};
pub use contract::{
    AsDistribution, InvertibleSampler2D, Point2, Sample2, Sampler2D, UniformSequence, UniformSource,
};
pub use density::{
    Density, DensityShape, IntegralSource, ProviderKind, RegionEstimate, RegionStats, SharedDensity,
};
pub use distributions::parallel::{
    PAR_CHUNK, Shard, ShardError, chunk_rng, chunk_seed, sample_par,
};
pub use distributions::piecewise_constant::{
    PiecewiseConstant1D, PiecewiseConstant2D, PiecewiseConstantError, Sample1, fill_cdf,
    fill_guide, find_cell, find_cell_guided,
};
pub use distributions::rect::{Domain, Rect};
pub use error::{AllocationError, AttachError, BuildError, DensityError, PersistError};
pub use persist::FORMAT_VERSION;
pub use quadtree_sampler::{
    Batch, MAX_TRIALS_PER_SAMPLE, MemoryReport, QuadTreeSampler, SamplerStats,
};
pub use sampled::{
    DEFAULT_REFINEMENT_COARSEST, DEFAULT_REFINEMENT_TOLERANCE, DEFAULT_SAFETY_FACTOR, GridOptions,
    Refinement, SampledGridDensity,
};
pub use tabulated::{
    RowFactor, SinPiRows, TabulatedDensity, UnitRows, sin_pi_unit, sin_pi_unit_block,
};
pub use tree::{LeafChoice, LeafInfo, QuadTree, SAMPLING_CONFIGS, Scheme, TreeCounts, TreeParams};
pub use user_bound::UserBoundDensity;
