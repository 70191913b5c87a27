//! Minnaert (1941), "The reciprocity principle in lunar photometry".
//!
//! `f_r = ρ (k+1)/(2π) · (cosθi cosθo)^{k−1}`. The factor `(k+1)/(2π)` makes the albedo exactly
//! `ρ` at normal incidence; in general `albedo(θo) = ρ cos^{k−1}θo`, so the model conserves
//! energy iff `k ≥ 1` (limb darkening `k < 1` brightens grazing views without bound). `k = 1` is
//! Lambert. Keys: `rho ∈ [0, 1]` (default 0.8), `k ∈ [0, 2]` (default 0.7). Reciprocal, isotropic.
//! Values are finite for every direction strictly above the horizon (the product of cosines is
//! clamped at 10⁻³⁰⁰ before the power, which only matters for subnormal inputs).

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::Range;
use std::f64::consts::PI;

model! {
    /// Parameters of [`Minnaert`].
    pub struct MinnaertParams in PARAMS {
        rho = [0.8] in Range::closed(0.0, 1.0), "albedo at normal incidence";
        k = [0.7] in Range::closed(0.0, 2.0), "Minnaert limb-darkening exponent";
    }
    registry INFO: NAME = "minnaert", [], Always,
        "lunar limb darkening ρ(k+1)/(2π)(cosθi cosθo)^(k−1) (Minnaert 1941)";
    /// Minnaert BRDF.
    pub struct Minnaert(params) {
        scale: f64 = params.rho * (params.k + 1.0) / (2.0 * PI),
    }
}

impl Minnaert {
    /// Symmetries and energy: cosines only (isotropic, even under `y ↦ −y`), reciprocal;
    /// conserves energy iff `k ≥ 1`; unbounded at the horizon when `k < 1` and `rho > 0`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.k >= 1.0)
            | Properties::UNBOUNDED_AT_HORIZON
                .when(!(self.params.k >= 1.0 || self.params.rho == 0.0))
    }
}

impl Brdf for Minnaert {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let c = (wi.z * wo.z).max(1e-300);
        self.scale * c.powf(self.params.k - 1.0)
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
