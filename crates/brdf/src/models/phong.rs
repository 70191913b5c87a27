//! Modified (energy-conserving) Phong model — Phong 1975, normalised as in Lewis 1993 and
//! Lafortune & Willems 1994.
//!
//! `f_r = kd/π + ks · (n+2)/(2π) · max(0, ω_r·ωi)^n`, with `ω_r = (−ωo.x, −ωo.y, ωo.z)` the mirror
//! direction. Parameters: exponent `n ∈ [0, 10⁵]` (default 50), `ks ∈ [0, 1]` (default 0.7),
//! `kd ∈ [0, 1]` (default 0.3).
//!
//! The `(n+2)/(2π)` factor makes the specular lobe's albedo exactly `ks` at normal incidence and
//! smaller elsewhere, so the model conserves energy iff `kd + ks ≤ 1`. Reciprocal and isotropic.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, above_with_mirror_cos};
use crate::params::Range;
use std::f64::consts::{FRAC_1_PI, PI};

model! {
    /// Parameters of [`Phong`].
    pub struct PhongParams in PARAMS {
        n = [50.0] in Range::closed(0.0, 1e5), "specular exponent";
        ks = [0.7] in Range::closed(0.0, 1.0), "specular albedo at normal incidence";
        kd = [0.3] in Range::closed(0.0, 1.0), "diffuse albedo";
    }
    registry INFO: NAME = "phong", ["modified-phong"], Always,
        "modified energy-conserving Phong, kd/π + ks(n+2)/(2π) cos^n α (Phong 1975; Lafortune & Willems 1994)";
    /// Modified Phong BRDF.
    pub struct Phong(params) {
        diffuse: f64 = params.kd * FRAC_1_PI,
        spec_scale: f64 = params.ks * (params.n + 2.0) / (2.0 * PI),
    }
}

impl Phong {
    /// Symmetries and energy: `ω_r·ωi` and cosines only (isotropic, even under `y ↦ −y`),
    /// reciprocal; conserves energy iff `kd + ks ≤ 1`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.kd + self.params.ks <= 1.0)
    }
}

impl Brdf for Phong {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some(c) = above_with_mirror_cos(wo, wi) else {
            return 0.0;
        };
        let spec = if c > 0.0 {
            self.spec_scale * c.powf(self.params.n)
        } else {
            0.0
        };
        self.diffuse + spec
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
            lobe: Some(crate::SpecularLobe::Phong {
                exponent: self.params.n,
            }),
        })
    }
}
