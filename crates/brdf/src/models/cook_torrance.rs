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

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::fresnel::fresnel_dielectric;
use crate::geometry::{Vec3, above_with_half};
use crate::params::Range;
use std::f64::consts::{FRAC_1_PI, PI};

model! {
    /// Parameters of [`CookTorrance`].
    pub struct CookTorranceParams in PARAMS {
        m = [0.2] in Range::closed(0.001, 2.0), "RMS microfacet slope (Beckmann)";
        ior = [1.5] in Range::left_open(1.0, 100.0), "relative index of refraction (Fresnel)";
        ks = [0.8] in Range::closed(0.0, 1.0), "specular weight";
        kd = [0.2] in Range::closed(0.0, 1.0), "diffuse albedo";
    }
    registry INFO: NAME = "cook-torrance", ["torrance", "ct"], Always,
        "Beckmann D, V-cavity G, dielectric Fresnel (Cook & Torrance 1982)";
    /// Cook–Torrance BRDF.
    pub struct CookTorrance(params) {
        let m2 = params.m * params.m;
        diffuse: f64 = params.kd * FRAC_1_PI,
        inv_m2: f64 = 1.0 / m2,
        d_scale: f64 = 1.0 / (PI * m2),
    }
}

impl CookTorrance {
    /// Symmetries and energy: `n·h`, `ωo·h` and cosines only (isotropic, even under `y ↦ −y`),
    /// reciprocal; conserves energy iff `kd + ks ≤ 1`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.kd + self.params.ks <= 1.0)
    }
}

impl Brdf for CookTorrance {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some((ci, co, h)) = above_with_half(wo, wi) else {
            return 0.0;
        };
        let nh = h.z;
        let vh = wo.dot(&h).max(1e-300);
        let nh2 = nh * nh;
        let tan2 = (1.0 - nh2) / nh2;
        let d = self.d_scale * (-tan2 * self.inv_m2).exp() / (nh2 * nh2);
        let g = (2.0 * nh * co.min(ci) / vh).min(1.0);
        let f = fresnel_dielectric(vh, self.params.ior);
        self.diffuse + self.params.ks * f * d * g / (4.0 * ci * co)
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
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
}
