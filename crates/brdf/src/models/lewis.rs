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

use super::half_vector_lobe::HalfVectorLobe;
use crate::brdf::Brdf;
use crate::geometry::Vec3;
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::PI;

pub(crate) const NAME: &str = "lewis";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param("n", 50.0, Range::closed(0.0, 1e5), "half-vector exponent"),
    param("ks", 0.6, Range::closed(0.0, 1.0), "specular coefficient"),
    param("kd", 0.4, Range::closed(0.0, 1.0), "diffuse albedo"),
];

/// Lewis-normalised Blinn–Phong BRDF.
#[derive(Debug, Clone)]
pub struct Lewis {
    params: LewisParams,
    lobe: HalfVectorLobe,
}

/// Parameters of [`Lewis`] (SPEC keys `n`, `ks`, `kd`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LewisParams {
    /// Half-vector exponent `n ∈ [0, 10⁵]`.
    pub n: f64,
    /// Specular coefficient, in `[0, 1]`.
    pub ks: f64,
    /// Diffuse albedo, in `[0, 1]`.
    pub kd: f64,
}

impl Default for LewisParams {
    /// n = 50, ks = 0.6, kd = 0.4.
    fn default() -> Self {
        let [n, ks, kd] = defaults(PARAMS);
        Self { n, ks, kd }
    }
}

/// Default parameters of [`Lewis`]: n = 50, ks = 0.6, kd = 0.4 (as [`LewisParams::default`]).
pub fn lewis_defaults() -> LewisParams {
    LewisParams::default()
}

impl Lewis {
    /// Validate the parameters and build the model.
    pub fn new(params: LewisParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.n, params.ks, params.kd])?;
        let n = params.n;
        let norm = (n + 2.0) / (4.0 * PI * (2.0 - (-0.5 * n).exp2()));
        Ok(Self {
            params,
            lobe: HalfVectorLobe::new(n, params.ks, params.kd, norm),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &LewisParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [n, ks, kd] = super::take(v);
        Self::new(LewisParams { n, ks, kd })
    }
}

impl Default for Lewis {
    fn default() -> Self {
        super::expect_default(Self::new(lewis_defaults()))
    }
}

impl Brdf for Lewis {
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
