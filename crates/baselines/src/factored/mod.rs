//! Lawrence, Rusinkiewicz & Ramamoorthi 2004: BRDF importance sampling from a factored
//! representation (baselines.md §A).
//!
//! * [`nmf`] — weighted non-negative matrix factorisation (Lee–Seung multiplicative updates,
//!   Euclidean or Kullback–Leibler cost);
//! * `grid` — the outgoing cells, the `(θp, φp)` cells and the half-angle map;
//! * `build` — data matrix `Y[o, p] = f_r cos θi`, the two levels `Y ≈ F G`,
//!   `G_j ≈ U_j V_j`, normalisation by bin measures and the term weights;
//! * `sampler` — [`FactoredSampler`], a [`brdf_sampling::DirectionSampler`] whose pdf is the
//!   mixture over all `J·K` terms (w.r.t. solid angle of `ωi`);
//! * `report` — [`FactoredReport`] (fit, convergence, time, memory) and [`FactoredError`].
//!
//! MERL entries that are not measured cannot be seen through [`brdf::Brdf`] (the reader
//! returns 0 for them), so they enter the data matrix as zeros with weight 1; the weighted
//! factorisation ([`nmf::factorise`]'s mask) is ready for a BRDF that exposes them.

mod build;
mod grid;
pub mod nmf;
mod report;
mod sampler;

pub use report::{FactoredError, FactoredReport};
pub use sampler::FactoredSampler;
