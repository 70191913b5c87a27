//! Cook & Torrance (1982), "A reflectance model for computer graphics".
//!
//! `f_r = kd/π + ks · F(ωi·h) D(h) G / (4 cosθi cosθo)` with
//!
//! * Beckmann distribution `D = exp(−tan²θh/m²) / (π m² cos⁴θh)` (normalised: `∫ D cosθh dσ = 1`);
//! * V-cavity masking `G = min(1, 2(n·h)(n·ωo)/(ωo·h), 2(n·h)(n·ωi)/(ωo·h))`;
//! * full unpolarised dielectric Fresnel `F` with relative index `ior` (the paper's formula with
//!   `g² = η² + c² − 1`).
//!
//! Normalisation: the paper writes `F D G/(π cosθi cosθo)` with an un-normalised `D`; we use the
//! normalised `D` with `1/4` (Walter et al. 2007), the form consistent with microfacet theory.
//! With it the specular albedo is at most `max F ≤ 1`, so the model conserves energy iff
//! `kd + ks ≤ 1`. Keys: `m ∈ [0.001, 2]` (RMS slope, default 0.2), `ior ∈ (1, 100]`
//! (default 1.5), `ks ∈ [0, 1]` (default 0.8), `kd ∈ [0, 1]` (default 0.2). Reciprocal, isotropic.

use crate::brdf::Brdf;
use crate::fresnel::fresnel_dielectric;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::{FRAC_1_PI, PI};

pub(crate) const NAME: &str = "cook-torrance";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param(
        "m",
        0.2,
        Range::closed(0.001, 2.0),
        "RMS microfacet slope (Beckmann)",
    ),
    param(
        "ior",
        1.5,
        Range::left_open(1.0, 100.0),
        "relative index of refraction (Fresnel)",
    ),
    param("ks", 0.8, Range::closed(0.0, 1.0), "specular weight"),
    param("kd", 0.2, Range::closed(0.0, 1.0), "diffuse albedo"),
];

/// Parameters of [`CookTorrance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CookTorranceParams {
    /// RMS slope `m`.
    pub m: f64,
    /// Index of refraction.
    pub ior: f64,
    /// Specular weight.
    pub ks: f64,
    /// Diffuse albedo.
    pub kd: f64,
}

impl Default for CookTorranceParams {
    fn default() -> Self {
        let [m, ior, ks, kd] = defaults(PARAMS);
        Self { m, ior, ks, kd }
    }
}

/// Cook–Torrance BRDF.
#[derive(Debug, Clone)]
pub struct CookTorrance {
    params: CookTorranceParams,
    diffuse: f64,
    inv_m2: f64,
    d_scale: f64,
}

impl CookTorrance {
    /// Validate the parameters and build the model.
    pub fn new(params: CookTorranceParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.m, params.ior, params.ks, params.kd])?;
        let m2 = params.m * params.m;
        Ok(Self {
            params,
            diffuse: params.kd * FRAC_1_PI,
            inv_m2: 1.0 / m2,
            d_scale: 1.0 / (PI * m2),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &CookTorranceParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [m, ior, ks, kd] = super::take(v);
        Self::new(CookTorranceParams { m, ior, ks, kd })
    }
}

impl Default for CookTorrance {
    fn default() -> Self {
        super::expect_default(Self::new(CookTorranceParams::default()))
    }
}

impl Brdf for CookTorrance {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let (ci, co) = (wi.z, wo.z);
        let h = (wo + wi).normalize();
        let nh = h.z;
        let vh = wo.dot(&h).max(1e-300);
        let nh2 = nh * nh;
        let tan2 = (1.0 - nh2) / nh2;
        let d = self.d_scale * (-tan2 * self.inv_m2).exp() / (nh2 * nh2);
        let g = (2.0 * nh * co.min(ci) / vh).min(1.0);
        let f = fresnel_dielectric(vh, self.params.ior);
        self.diffuse + self.params.ks * f * d * g / (4.0 * ci * co)
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): n·h, ωo·h and cosines only.
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
            lobe: Some(crate::SpecularLobe::Microfacet {
                distribution: super::NormalDistribution::Beckmann,
                alpha_x: self.params.m,
                alpha_y: self.params.m,
            }),
        })
    }
    fn name(&self) -> &str {
        NAME
    }
}
