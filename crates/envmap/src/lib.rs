//! Lat-long environment maps and their importance samplers.
//!
//! **Loading.** [`EnvMap::load`] reads Radiance `.hdr` (`#?RADIANCE` or `#?RGBE` signature,
//! flat or run-length-encoded scanlines), OpenEXR `.exr` and PFM `.pfm` (`PF`/`Pf`, either
//! endianness) files; [`procedural_sky`] builds a deterministic sky with a sun when no file is
//! given. Every failure is a typed [`EnvMapError`]; malformed files never panic.
//!
//! **Convention.** `u` runs along the width, `v` down the height, both in `[0,1)`; the polar
//! angle is θ = πv (`v = 0` is the zenith `+z`) and the azimuth φ = 2πu, so a pixel `(x, y)`
//! of a `W × H` map covers `[x/W, (x+1)/W) × [y/H, (y+1)/H)` and `(u, v)` maps to the direction
//! `(sinθ cosφ, sinθ sinφ, cosθ)` ([`latlong`]). Luminance is
//! `Y = 0.2126 R + 0.7152 G + 0.0722 B` ([`luminance`]).
//!
//! **Sampling.** The target density on `[0,1]²` is `∝ Y(pixel) · sin(πv)`, pixels piecewise
//! constant, which makes directions ∝ luminance with respect to solid angle. Every sample
//! carries `pdf_uv` (w.r.t. area on `[0,1]²`) and `pdf_sa = pdf_uv / (2π² sin(πv))` (w.r.t.
//! solid angle). [`EnvMapSampler`] offers the adaptive-partition sampler of
//! `partition_sampler` (exact target; envelope or paper scheme; alias or descent leaf choice)
//! and the classic piecewise-constant CDF [`QuantisedCdf2D`] (midpoint approximation of the
//! sine; fixed-point tables whose stored law is the reported pdf).
//!
//! ```
//! use envmap::{AdaptiveOptions, EnvMapSampler, SamplerKind, procedural_sky};
//! use rand::SeedableRng;
//!
//! let sky = procedural_sky(256, 128)?;
//! let sampler = EnvMapSampler::new(&sky, SamplerKind::Adaptive(AdaptiveOptions::default()))?;
//!
//! let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
//! let s = sampler.sample(&mut rng);
//! assert!(s.pdf_uv > 0.0 && s.pdf_uv == sampler.pdf_uv(s.u, s.v));
//! let expected = s.pdf_uv / (2.0 * std::f64::consts::PI.powi(2) * (std::f64::consts::PI * s.v).sin());
//! assert!((s.pdf_sa - expected).abs() <= 1e-12 * expected);
//!
//! // Most samples land near the sun, which holds most of the sky's power.
//! let batch = sampler.sample_par(10_000, 42); // reproducible: depends only on (n, seed)
//! let sun = envmap::sun_direction();
//! let near = batch.iter().filter(|e| (0..3).map(|i| e.direction[i] * sun[i]).sum::<f64>() > 0.99).count();
//! assert!(near > 5_000);
//!
//! // The piecewise-constant CDF baseline has the same interface.
//! let cdf = EnvMapSampler::new(&sky, SamplerKind::PiecewiseConstant)?;
//! assert!(cdf.pdf_sa(s.direction) > 0.0);
//! # Ok::<(), envmap::EnvMapError>(())
//! ```

// Validation is written `if !(x >= 0.0)` on purpose so that NaN fails too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cdf;
mod error;
mod format;
pub mod lanes;
pub mod latlong;
mod load;
mod map;
pub mod pyramid;
mod sampler;
mod sky;

pub use cdf::QuantisedCdf2D;
pub use error::EnvMapError;
pub use format::MapFormat;
pub use lanes::LaneRng;
pub use map::{EnvMap, MAX_PIXELS, luminance};
pub use partition_sampler::{LeafChoice, Scheme, TreeParams};
pub use pyramid::{CellGeometry, CellSample, PowerPyramid};
pub use sampler::{AdaptiveOptions, EnvMapSampler, EnvSample, SamplerKind};
pub use sky::{SUN_RADIANCE, SUN_RADIUS, SUN_UV, procedural_sky, sun_direction};
