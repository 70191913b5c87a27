//! Modified (energy-conserving) Phong model — Phong 1975, normalised as in Lewis 1993 and
//! Lafortune & Willems 1994.
//!
//! `f_r = kd/π + ks · (n+2)/(2π) · max(0, ω_r·ωi)^n`, with `ω_r = (−ωo.x, −ωo.y, ωo.z)` the mirror
//! direction. Parameters: exponent `n ∈ [0, 10⁵]` (default 50), `ks ∈ [0, 1]` (default 0.7),
//! `kd ∈ [0, 1]` (default 0.3).
//!
//! The `(n+2)/(2π)` factor makes the specular lobe's albedo exactly `ks` at normal incidence and
//! smaller elsewhere, so the model conserves energy iff `kd + ks ≤ 1`. Reciprocal and isotropic.

use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::{FRAC_1_PI, PI};

pub(crate) const NAME: &str = "phong";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param("n", 50.0, Range::closed(0.0, 1e5), "specular exponent"),
    param(
        "ks",
        0.7,
        Range::closed(0.0, 1.0),
        "specular albedo at normal incidence",
    ),
    param("kd", 0.3, Range::closed(0.0, 1.0), "diffuse albedo"),
];

/// Parameters of [`Phong`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhongParams {
    /// Cosine-lobe exponent `n ≥ 0`.
    pub n: f64,
    /// Specular coefficient.
    pub ks: f64,
    /// Diffuse coefficient.
    pub kd: f64,
}

impl Default for PhongParams {
    fn default() -> Self {
        let [n, ks, kd] = defaults(PARAMS);
        Self { n, ks, kd }
    }
}

/// Modified Phong BRDF.
#[derive(Debug, Clone)]
pub struct Phong {
    params: PhongParams,
    diffuse: f64,
    spec_scale: f64,
}

impl Phong {
    /// Validate the parameters and build the model.
    pub fn new(params: PhongParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.n, params.ks, params.kd])?;
        Ok(Self {
            params,
            diffuse: params.kd * FRAC_1_PI,
            spec_scale: params.ks * (params.n + 2.0) / (2.0 * PI),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &PhongParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [n, ks, kd] = super::take(v);
        Self::new(PhongParams { n, ks, kd })
    }
}

impl Default for Phong {
    fn default() -> Self {
        super::expect_default(Self::new(PhongParams::default()))
    }
}

impl Brdf for Phong {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let c = -wo.x * wi.x - wo.y * wi.y + wo.z * wi.z;
        let spec = if c > 0.0 {
            self.spec_scale * c.powf(self.params.n)
        } else {
            0.0
        };
        self.diffuse + spec
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): ω_r·ωi and cosines only.
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
        self.params.kd + self.params.ks <= 1.0
    }
    fn analytic_lobes(&self) -> Option<crate::AnalyticLobes> {
        Some(crate::AnalyticLobes {
            diffuse: self.params.kd,
            specular: self.params.ks,
            lobe: Some(crate::SpecularLobe::Phong {
                exponent: self.params.n,
            }),
        })
    }
    fn name(&self) -> &str {
        NAME
    }
}
