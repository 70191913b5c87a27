//! Strauss (1990), "A realistic lighting model for computer animators" (IEEE CG&A 10(6)).
//!
//! Strauss gives reflected intensities per unit light: diffuse `Qd = cosθi · d · rd · c` and
//! specular `Qs = rj · Cs · max(0, ω_r·ωi)^{h}`, with smoothness `s`, metalness `m`,
//! transparency `t` and colour `c` (grey here):
//!
//! * `rd = (1 − s³)(1 − t)`, `d = 1 − m s`, `rn = (1 − t) − rd`, `h = 3/(1 − s)`;
//! * `j = F(x_i) G(x_i) G(x_o)` with `x = θ/(π/2)` the normalised incidence/view angles,
//!   `rj = min(1, rn + (rn + 0.1) j)`, `Cs = 1 + m (1 − F(x_i)) (c − 1)`;
//! * `F(x) = (1/(x−kf)² − 1/kf²) / (1/(1−kf)² − 1/kf²)`, `kf = 1.12` (Fresnel-like);
//! * `G(x) = (1/(1−kg)² − 1/(x−kg)²) / (1/(1−kg)² − 1/kg²)`, `kg = 1.01` (shadowing).
//!
//! As a BRDF we take `f_r = (Qd + Qs) / (π cosθi)`, i.e.
//! `f_r = d rd c/π + rj Cs max(0, ω_r·ωi)^h / (π cosθi)` (cosθi clamped at 10⁻¹²), so that the
//! diffuse part is a Lambertian of albedo `d rd c` and `f_r cosθi` reproduces Strauss' intensity
//! ratio. Keys: `s ∈ [0, 0.99]` (default 0.8, "mostly smooth"), `m ∈ [0, 1]` (default 0),
//! `t ∈ [0, 1]` (default 0), `c ∈ [0, 1]` (default 0.8). Isotropic; not reciprocal (`F` and
//! the `1/cosθi` use the incidence angle only); not energy-conserving.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, above_with_mirror_cos};
use crate::params::Range;
use std::f64::consts::{FRAC_1_PI, FRAC_2_PI};

const KF: f64 = 1.12;
const KG: f64 = 1.01;

model! {
    /// Parameters of [`Strauss`].
    pub struct StraussParams in PARAMS {
        s = [0.8] in Range::closed(0.0, 0.99), "smoothness";
        m = [0.0] in Range::closed(0.0, 1.0), "metalness";
        t = [0.0] in Range::closed(0.0, 1.0), "transparency";
        c = [0.8] in Range::closed(0.0, 1.0), "surface colour (grey level)";
    }
    registry INFO: NAME = "strauss", [], Always,
        "smoothness/metalness artist model (Strauss 1990)";
    /// Strauss BRDF.
    pub struct Strauss(params) {
        let StraussParams { s, m, t, c } = params;
        let rd = (1.0 - s * s * s) * (1.0 - t);
        let d = 1.0 - m * s;
        diffuse: f64 = d * rd * c * FRAC_1_PI,
        rn: f64 = (1.0 - t) - rd,
        exponent: f64 = 3.0 / (1.0 - s),
    }
}

#[inline]
fn strauss_f(x: f64) -> f64 {
    let a = 1.0 / ((x - KF) * (x - KF)) - 1.0 / (KF * KF);
    let b = 1.0 / ((1.0 - KF) * (1.0 - KF)) - 1.0 / (KF * KF);
    a / b
}

#[inline]
fn strauss_g(x: f64) -> f64 {
    let a = 1.0 / ((1.0 - KG) * (1.0 - KG)) - 1.0 / ((x - KG) * (x - KG));
    let b = 1.0 / ((1.0 - KG) * (1.0 - KG)) - 1.0 / (KG * KG);
    a / b
}

impl Strauss {
    /// Symmetries: isotropic, even under `y ↦ −y`; not reciprocal, energy not guaranteed,
    /// unbounded at the horizon.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC | Properties::UNBOUNDED_AT_HORIZON
    }
}

impl Brdf for Strauss {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some(c) = above_with_mirror_cos(wo, wi) else {
            return 0.0;
        };
        if c <= 0.0 {
            return self.diffuse;
        }
        let xi = wi.z.min(1.0).acos() * FRAC_2_PI;
        let xo = wo.z.min(1.0).acos() * FRAC_2_PI;
        let fi = strauss_f(xi);
        let j = fi * strauss_g(xi) * strauss_g(xo);
        let rj = (self.rn + (self.rn + 0.1) * j).min(1.0);
        let cs = 1.0 + self.params.m * (1.0 - fi) * (self.params.c - 1.0);
        let spec = rj * cs * c.powf(self.exponent) * FRAC_1_PI / wi.z.max(1e-12);
        self.diffuse + spec.max(0.0)
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
