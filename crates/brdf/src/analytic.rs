//! What a model tells a renderer-style importance sampler about itself: the hook
//! [`Brdf::analytic_lobes`](crate::Brdf::analytic_lobes).
//!
//! A model with a standard analytic sampler describes its reflectance as a diffuse part and
//! (at most) one specular lobe, with non-negative weights (its own `kd`/`ks`-type parameters).
//! A sampler picks the diffuse part (cosine-weighted hemisphere sampling) with probability
//! `diffuse / (diffuse + specular)` and the lobe's own sampler otherwise. The weights only shape
//! the sampler; they need not be the albedos.

use crate::models::NormalDistribution;

/// The specular lobe of a model that has a standard importance sampler.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpecularLobe {
    /// Phong: `∝ max(0, ω_r·ωi)^n` around the mirror direction `ω_r = (−ωo.x, −ωo.y, ωo.z)`.
    Phong {
        /// Exponent `n ≥ 0`.
        exponent: f64,
    },
    /// Blinn-type half-vector lobe: `∝ (n·h)^n`, `h = (ωo+ωi)/|ωo+ωi|`.
    HalfVector {
        /// Exponent `n ≥ 0`.
        exponent: f64,
    },
    /// Ward's anisotropic Gaussian of the half-vector slopes, RMS slopes `αx`, `αy`.
    Ward {
        /// RMS slope along the tangent x.
        alpha_x: f64,
        /// RMS slope along the bitangent y.
        alpha_y: f64,
    },
    /// A microfacet normal distribution with Smith masking (sampled by its visible normals).
    Microfacet {
        /// Beckmann or GGX.
        distribution: NormalDistribution,
        /// Roughness along x.
        alpha_x: f64,
        /// Roughness along y.
        alpha_y: f64,
    },
}

/// A model's reflectance as a renderer's importance sampler sees it: a diffuse weight, a
/// specular weight and the specular lobe (`None` for a purely diffuse model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticLobes {
    /// Weight of the diffuse (cosine-sampled) part, `≥ 0` (e.g. `kd`).
    pub diffuse: f64,
    /// Weight of the specular lobe, `≥ 0` (e.g. `ks`); ignored when `lobe` is `None`.
    pub specular: f64,
    /// The specular lobe.
    pub lobe: Option<SpecularLobe>,
}
