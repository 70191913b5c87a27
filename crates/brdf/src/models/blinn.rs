//! Blinn–Phong model (Blinn 1977) with the exact normal-incidence normalisation.
//!
//! `f_r = kd/π + ks · (n+2)(n+4) / (8π (n + 2^{−n/2})) · (n·h)^n`, `h = (ωo+ωi)/|ωo+ωi|`.
//! The constant makes the lobe's directional albedo exactly `ks` at normal incidence
//! (`∫ (n·h)^n cosθi dσ = 8π(n + 2^{−n/2})/((n+2)(n+4))` for `ωo = n`); it is the closed form of
//! the approximation `(n+8)/(8π)` popularised by Akenine-Möller et al. Parameters as
//! [`Phong`](super::Phong): `n ∈ [0, 10⁵]` (default 100), `ks` (default 0.6), `kd` (default 0.4).
//! The albedo is largest at normal incidence (checked numerically in the tests), so the model
//! conserves energy iff `kd + ks ≤ 1`. Reciprocal and isotropic.

use super::half_vector_lobe::HalfVectorLobe;
use super::phong::PhongParams;
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
    lobe: HalfVectorLobe,
}

/// Default parameters of [`Blinn`] (n = 100, ks = 0.6, kd = 0.4).
pub fn blinn_defaults() -> PhongParams {
    let [n, ks, kd] = defaults(PARAMS);
    PhongParams { n, ks, kd }
}

impl Blinn {
    /// Validate the parameters and build the model.
    pub fn new(params: PhongParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.n, params.ks, params.kd])?;
        let n = params.n;
        let norm = (n + 2.0) * (n + 4.0) / (8.0 * PI * (n + (-0.5 * n).exp2()));
        Ok(Self {
            lobe: HalfVectorLobe::new(params, norm),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &PhongParams {
        &self.lobe.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [n, ks, kd] = super::take(v);
        Self::new(PhongParams { n, ks, kd })
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
    fn name(&self) -> &str {
        NAME
    }
}
