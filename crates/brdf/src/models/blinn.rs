//! Blinn–Phong model (Blinn 1977) with the exact normal-incidence normalisation.
//!
//! `f_r = kd/π + ks · (n+2)(n+4) / (8π (n + 2^{−n/2})) · (n·h)^n`, `h = (ωo+ωi)/|ωo+ωi|`.
//! The constant makes the lobe's directional albedo exactly `ks` at normal incidence
//! (`∫ (n·h)^n cosθi dσ = 8π(n + 2^{−n/2})/((n+2)(n+4))` for `ωo = n`); it is the closed form of
//! the approximation `(n+8)/(8π)` popularised by Akenine-Möller et al. Parameters
//! ([`BlinnParams`]): `n ∈ [0, 10⁵]` (default 100), `ks` (default 0.6), `kd` (default 0.4).
//! The albedo is largest at normal incidence (checked numerically in the tests), so the model
//! conserves energy iff `kd + ks ≤ 1`. Reciprocal and isotropic.

use super::half_vector_lobe::HalfVectorLobe;
use crate::brdf::Brdf;
use crate::geometry::Vec3;
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::PI;

pub(crate) const NAME: &str = "blinn";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param("n", 100.0, Range::closed(0.0, 1e5), "half-vector exponent"),
    param(
        "ks",
        0.6,
        Range::closed(0.0, 1.0),
        "specular albedo at normal incidence",
    ),
    param("kd", 0.4, Range::closed(0.0, 1.0), "diffuse albedo"),
];

/// Blinn–Phong BRDF (normalised half-vector cosine lobe).
#[derive(Debug, Clone)]
pub struct Blinn {
    params: BlinnParams,
    lobe: HalfVectorLobe,
}

/// Parameters of [`Blinn`] (SPEC keys `n`, `ks`, `kd`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlinnParams {
    /// Half-vector exponent `n ∈ [0, 10⁵]`.
    pub n: f64,
    /// Specular albedo at normal incidence, in `[0, 1]`.
    pub ks: f64,
    /// Diffuse albedo, in `[0, 1]`.
    pub kd: f64,
}

impl Default for BlinnParams {
    /// n = 100, ks = 0.6, kd = 0.4.
    fn default() -> Self {
        let [n, ks, kd] = defaults(PARAMS);
        Self { n, ks, kd }
    }
}

/// Default parameters of [`Blinn`]: n = 100, ks = 0.6, kd = 0.4 (as [`BlinnParams::default`]).
pub fn blinn_defaults() -> BlinnParams {
    BlinnParams::default()
}

impl Blinn {
    /// Validate the parameters and build the model.
    pub fn new(params: BlinnParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.n, params.ks, params.kd])?;
        let n = params.n;
        let norm = (n + 2.0) * (n + 4.0) / (8.0 * PI * (n + (-0.5 * n).exp2()));
        Ok(Self {
            params,
            lobe: HalfVectorLobe::new(n, params.ks, params.kd, norm),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &BlinnParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [n, ks, kd] = super::take(v);
        Self::new(BlinnParams { n, ks, kd })
    }
}

impl Default for Blinn {
    fn default() -> Self {
        super::expect_default(Self::new(blinn_defaults()))
    }
}

impl Brdf for Blinn {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.lobe.eval(wo, wi)
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): n·h only.
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
        self.lobe.conserves_energy()
    }
    fn analytic_lobes(&self) -> Option<crate::AnalyticLobes> {
        Some(crate::AnalyticLobes {
            diffuse: self.params.kd,
            specular: self.params.ks,
            lobe: Some(crate::SpecularLobe::HalfVector {
                exponent: self.params.n,
            }),
        })
    }
    fn name(&self) -> &str {
        NAME
    }
}
