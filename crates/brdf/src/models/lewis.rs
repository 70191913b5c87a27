//! Lewis (1993), "Making shaders more physically plausible": the half-vector (Blinn) lobe with
//! Lewis' normalisation.
//!
//! `f_r = kd/π + ks · (n+2) / (4π (2 − 2^{−n/2})) · (n·h)^n`. The constant makes the lobe
//! integrate to `ks` over solid angle *without* the cosine at normal incidence
//! (`∫ (n·h)^n dσ = 4π(2 − 2^{−n/2})/(n+2)`). The cosine-weighted albedo of the lobe is then
//! below `ks` at normal incidence and decreases with θo (checked numerically in the tests), so the
//! model conserves energy iff `kd + ks ≤ 1`. Parameters ([`LewisParams`]): `n ∈ [0, 10⁵]`
//! (default 50), `ks` (default 0.6), `kd` (default 0.4). Reciprocal and isotropic. (Lewis'
//! normalisation of the mirror-direction lobe, `(n+2)/(2π)`, is the [`Phong`](super::Phong)
//! model of this crate.)

use super::half_vector_lobe::half_vector_model;
use super::model_params;
use crate::params::Range;
use crate::registry::registry_entry;
use std::f64::consts::PI;

registry_entry! {
    INFO: NAME = "lewis", [], Always, PARAMS,
    Lewis::from_values,
    "Blinn lobe with Lewis' plausible normalisation (Lewis 1993)"
}

model_params! {
    /// Parameters of [`Lewis`] (SPEC keys `n`, `ks`, `kd`).
    pub struct LewisParams in PARAMS {
        n = [50.0] in Range::closed(0.0, 1e5), "half-vector exponent";
        ks = [0.6] in Range::closed(0.0, 1.0), "specular coefficient";
        kd = [0.4] in Range::closed(0.0, 1.0), "diffuse albedo";
    }
}

/// Default parameters of [`Lewis`]: n = 50, ks = 0.6, kd = 0.4 (as [`LewisParams::default`]).
pub fn lewis_defaults() -> LewisParams {
    LewisParams::default()
}

half_vector_model!(
    /// Lewis-normalised Blinn–Phong BRDF.
    Lewis(LewisParams),
    NAME,
    norm = |n| (n + 2.0) / (4.0 * PI * (2.0 - (-0.5 * n).exp2()))
);
