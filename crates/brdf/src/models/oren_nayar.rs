//! Oren & Nayar (1994), "Generalization of Lambert's reflectance model" — the qualitative model.
//!
//! `f_r = ρ/π · (A + B · max(0, cos(φi − φo)) · sin α · tan β)`, `α = max(θi, θo)`,
//! `β = min(θi, θo)`, `A = 1 − 0.5 σ²/(σ² + 0.33)`, `B = 0.45 σ²/(σ² + 0.09)`.
//! Since `cos(φi−φo) sinθi sinθo = ωi.x ωo.x + ωi.y ωo.y`, the bracket equals
//! `A + B · max(0, ωi.x ωo.x + ωi.y ωo.y) / max(cosθi, cosθo)`, evaluated without trigonometry.
//!
//! Keys: `rho ∈ [0, 1]` (default 0.8), `sigma ∈ [0, π/2]` (facet-slope standard deviation in
//! radians, default 0.5; the GRAPP 2008 scene used "roughness 0.83"). `σ = 0` is Lambert.
//! Reciprocal and isotropic. The qualitative model is not energy-conserving in general: for
//! small σ its albedo slightly exceeds ρ at grazing view (≈ 1.008 ρ for σ = 0.1 at θo = 89.9°),
//! so `conserves_energy()` is true only for σ = 0.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::Range;
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2};

model! {
    /// Parameters of [`OrenNayar`].
    pub struct OrenNayarParams in PARAMS {
        rho = [0.8] in Range::closed(0.0, 1.0), "albedo ρ";
        sigma = [0.5] in Range::closed(0.0, FRAC_PI_2), "facet slope deviation σ (radians)";
    }
    registry INFO: NAME = "oren-nayar", ["oren"], Always,
        "rough diffuse, qualitative model (Oren & Nayar 1994)";
    /// Oren–Nayar rough-diffuse BRDF (qualitative model).
    pub struct OrenNayar(params) {
        let s2 = params.sigma * params.sigma;
        let k = params.rho * FRAC_1_PI;
        a: f64 = k * (1.0 - 0.5 * s2 / (s2 + 0.33)),
        b: f64 = k * 0.45 * s2 / (s2 + 0.09),
    }
}

impl OrenNayar {
    /// Symmetries and energy: `cos(φi − φo)` and angles only (isotropic, even under `y ↦ −y`),
    /// reciprocal; conserves energy only in the Lambertian limit `sigma = 0`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.sigma == 0.0)
    }
}

impl Brdf for OrenNayar {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let dxy = wi.x * wo.x + wi.y * wo.y;
        if dxy > 0.0 {
            self.a + self.b * dxy / wi.z.max(wo.z)
        } else {
            self.a
        }
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
