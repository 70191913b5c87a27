//! Lambert (1760): ideal diffuse reflection.
//!
//! `f_r = ρ/π`. Parameter `rho ∈ [0, 1]` (default 0.8) is the albedo.
//! Reciprocal, isotropic, energy-conserving (albedo = ρ exactly).

use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::FRAC_1_PI;

pub(crate) const NAME: &str = "lambert";

pub(crate) const PARAMS: &[ParamInfo] = &[param(
    "rho",
    0.8,
    Range::closed(0.0, 1.0),
    "diffuse albedo ρ",
)];

/// Parameters of [`Lambert`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LambertParams {
    /// Albedo ρ ∈ [0, 1].
    pub rho: f64,
}

impl Default for LambertParams {
    fn default() -> Self {
        let [rho] = defaults(PARAMS);
        Self { rho }
    }
}

/// Lambertian BRDF `ρ/π`.
#[derive(Debug, Clone)]
pub struct Lambert {
    params: LambertParams,
    value: f64,
}

impl Lambert {
    /// Validate the parameters and build the model.
    pub fn new(params: LambertParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.rho])?;
        Ok(Self {
            params,
            value: params.rho * FRAC_1_PI,
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &LambertParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [rho] = super::take(v);
        Self::new(LambertParams { rho })
    }
}

impl Default for Lambert {
    fn default() -> Self {
        let p = LambertParams::default();
        Self {
            params: p,
            value: p.rho * FRAC_1_PI,
        }
    }
}

impl Brdf for Lambert {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if both_above(wo, wi) { self.value } else { 0.0 }
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): constant.
        true
    }
    fn is_half_turn_symmetric(&self) -> bool {
        // Isotropic, and R_π is a rotation about the normal.
        true
    }
    fn is_reciprocal(&self) -> bool {
        true
    }
    fn conserves_energy(&self) -> bool {
        true
    }
    fn analytic_lobes(&self) -> Option<crate::AnalyticLobes> {
        Some(crate::AnalyticLobes {
            diffuse: 1.0,
            specular: 0.0,
            lobe: None,
        })
    }
    fn name(&self) -> &str {
        NAME
    }
}
