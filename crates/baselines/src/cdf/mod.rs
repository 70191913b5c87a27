//! Tabulated CDFs per outgoing slice (baselines.md §B): the uncompressed marginal/conditional
//! CDF (`tabulated-cdf`, seed 000's "uncompressed CDF") and Lawrence et al. 2005's cascade of
//! Douglas–Peucker-compressed 1D CDFs (`cascade-cdf`).
//!
//! Per outgoing slice, a fine grid over `(z = cos θi, φi) ∈ [0,1] × [0, 2π)` holds
//! `g = f_r · cos θi` ([`GridShape`]; each cell supersampled, plus a defensive floor so that
//! every cell has positive mass). Because `dz dφ = dω`, a density piecewise constant (or
//! piecewise linear in its CDF) over `(z, φ)` is directly the solid-angle pdf: no `1/sin θ`.
//!
//! * [`TabulatedCdf`] = [`CdfSampler`]`<`[`TabulatedSlice`]`>`: the marginal CDF over rows and
//!   one conditional per row, at every cell edge.
//! * [`CascadeCdf`] = [`CdfSampler`]`<`[`CascadeSlice`]`>`: the same CDFs each simplified by
//!   [`douglas_peucker`] (vertical L∞ tolerance `ε`), sampled and evaluated on the
//!   compressed piecewise-linear CDFs (pdf = product of segment slopes, conditional of the
//!   fine row containing `z`).
//!
//! ```
//! use baselines::{CascadeCdf, CdfOptions};
//! use brdf_sampling::DirectionSampler;
//! use partition_sampler::UniformSequence;
//!
//! let brdf = brdf::parse_spec("phong:n=20")?;
//! let options = CdfOptions { slices: 4, n_z: 32, n_phi: 64, ..CdfOptions::default() };
//! let cascade = CascadeCdf::build(brdf.as_ref(), &options)?;
//! assert!(cascade.report().compression_ratio() < 1.0);
//!
//! let wo = brdf::direction_from_angles(30.0, 0.0);
//! let s = cascade.sample(&wo, &mut UniformSequence::new(&[0.3, 0.7]));
//! assert!((cascade.pdf(&wo, &s.wi) - s.pdf).abs() <= 1e-12 * s.pdf);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod cascade;
mod douglas_peucker;
mod grid;
mod linear;
mod sampler;
mod tabulated;

pub use cascade::CascadeSlice;
pub use douglas_peucker::{CompressedCdf, douglas_peucker};
pub use grid::GridShape;
pub use sampler::{CdfReport, CdfSampler, SliceCdf, SlicePoint, cdf_layout};
pub use tabulated::TabulatedSlice;

/// The uncompressed marginal/conditional CDF per slice (`tabulated-cdf`).
pub type TabulatedCdf = CdfSampler<TabulatedSlice>;

/// Lawrence et al. 2005's cascade of Douglas–Peucker-compressed CDFs per slice
/// (`cascade-cdf`).
pub type CascadeCdf = CdfSampler<CascadeSlice>;
