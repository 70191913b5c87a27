//! Blinn–Phong model (Blinn 1977) with the exact normal-incidence normalisation.
//!
//! `f_r = kd/π + ks · (n+2)(n+4) / (8π (n + 2^{−n/2})) · (n·h)^n`, `h = (ωo+ωi)/|ωo+ωi|`.
//! The constant makes the lobe's directional albedo exactly `ks` at normal incidence
//! (`∫ (n·h)^n cosθi dσ = 8π(n + 2^{−n/2})/((n+2)(n+4))` for `ωo = n`); it is the closed form of
//! the approximation `(n+8)/(8π)` popularised by Akenine-Möller et al. Parameters
//! ([`BlinnParams`]): `n ∈ [0, 10⁵]` (default 100), `ks` (default 0.6), `kd` (default 0.4).
//! The albedo is largest at normal incidence (checked numerically in the tests), so the model
//! conserves energy iff `kd + ks ≤ 1`. Reciprocal and isotropic.

use super::half_vector_lobe::half_vector_model;
use super::model_params;
use crate::params::Range;
use crate::registry::registry_entry;
use std::f64::consts::PI;

registry_entry! {
    INFO: NAME = "blinn", ["blinn-phong"], Always, PARAMS,
    Blinn::from_values,
    "normalised Blinn–Phong half-vector lobe (Blinn 1977)"
}

model_params! {
    /// Parameters of [`Blinn`] (SPEC keys `n`, `ks`, `kd`).
    pub struct BlinnParams in PARAMS {
        n = [100.0] in Range::closed(0.0, 1e5), "half-vector exponent";
        ks = [0.6] in Range::closed(0.0, 1.0), "specular albedo at normal incidence";
        kd = [0.4] in Range::closed(0.0, 1.0), "diffuse albedo";
    }
}

/// Default parameters of [`Blinn`]: n = 100, ks = 0.6, kd = 0.4 (as [`BlinnParams::default`]).
pub fn blinn_defaults() -> BlinnParams {
    BlinnParams::default()
}

half_vector_model!(
    /// Blinn–Phong BRDF (normalised half-vector cosine lobe).
    Blinn(BlinnParams),
    NAME,
    norm = |n| (n + 2.0) * (n + 4.0) / (8.0 * PI * (n + (-0.5 * n).exp2()))
);
