//! Lambert (1760): ideal diffuse reflection.
//!
//! `f_r = ρ/π`. Parameter `rho ∈ [0, 1]` (default 0.8) is the albedo.
//! Reciprocal, isotropic, energy-conserving (albedo = ρ exactly).

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::Range;
use std::f64::consts::FRAC_1_PI;

model! {
    /// Parameters of [`Lambert`].
    pub struct LambertParams in PARAMS {
        rho = [0.8] in Range::closed(0.0, 1.0), "diffuse albedo ρ";
    }
    registry INFO: NAME = "lambert", ["lambertian", "diffuse"], Always,
        "ideal diffuse ρ/π (Lambert 1760)";
    /// Lambertian BRDF `ρ/π`.
    pub struct Lambert(params) {
        value: f64 = params.rho * FRAC_1_PI,
    }
}

impl Lambert {
    /// Symmetries and energy: constant, so isotropic, symmetric, reciprocal; albedo `rho ≤ 1`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC | Properties::RECIPROCAL | Properties::CONSERVES_ENERGY
    }
}

impl Brdf for Lambert {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if both_above(wo, wi) { self.value } else { 0.0 }
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
    fn analytic_lobes(&self) -> Option<crate::AnalyticLobes> {
        Some(crate::AnalyticLobes {
            diffuse: 1.0,
            specular: 0.0,
            lobe: None,
        })
    }
}
