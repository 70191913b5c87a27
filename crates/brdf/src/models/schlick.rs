//! Schlick (1994), "An inexpensive BRDF model for physically-based rendering" (CGF 13(3)).
//!
//! With `t = n·h`, `u = ωi·h`, `v = cosθo`, `v' = cosθi`, `w = cos φh` (azimuth of `h` from the
//! tangent x), roughness `r ∈ (0, 1]` and isotropy `p ∈ (0, 1]`:
//!
//! * `Z(t) = r / (1 + r t² − t²)²` (zenith; `Z/π` is the GGX distribution with `α² = r`),
//! * `A(w) = √(p / (p² − p² w² + w²))` (azimuth; `A ≡ 1` for `p = 1`),
//! * `G(v) = v / (r − r v + v)` (Smith-type masking),
//! * `S(u) = C + (1 − C)(1 − u)^5` (Fresnel),
//! * `D = G(v)G(v') Z(t) A(w) / (4π v v') + (1 − G(v)G(v'))/π` (the second term re-emits the
//!   masked energy diffusely, as in Schlick's single-slope material).
//!
//! Two registry entries (the seeds' "Schlick (S)" and "Schlick (D)"):
//!
//! * **`schlick-specular`** — single-layer glossy material `f_r = S(u) · D`;
//!   keys `c` (default 0.9), `r` (0.05), `p` (1).
//! * **`schlick-diffuse`** — two-layer material from the same paper's layered formulation: the
//!   glossy layer over a Lambertian substrate of albedo `d`,
//!   `f_r = S(u) · D + (1 − S(u)) · d/π`; keys `c` (default 0.04), `r` (0.3), `p` (1), `d` (0.8).
//!
//! At `h = n` the azimuth is undefined and `A` is taken as 1. Both variants are reciprocal;
//! isotropic iff `p = 1`. Not energy-conserving: Schlick's `G(v) ≈ v/r` for small `v` exceeds the
//! exact Smith masking at grazing angles, so the albedo passes 1 near the horizon (≈ 0.97 at
//! θo = 0 but ≈ 2.4 at θo = 89° for `c = 1, r = 0.05`; measured in the tests).

use super::{Properties, brdf_properties};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use crate::registry::registry_entry;
use std::f64::consts::FRAC_1_PI;

registry_entry! {
    INFO_DIFFUSE: NAME_DIFFUSE = "schlick-diffuse", ["schlick-d"], WhenParamsEqual, PARAMS_DIFFUSE,
    Schlick::diffuse_from_values,
    "Schlick glossy coat over a Lambertian base (Schlick 1994)"
}

registry_entry! {
    INFO_SPECULAR: NAME_SPECULAR = "schlick-specular", ["schlick-s", "schlick"], WhenParamsEqual, PARAMS_SPECULAR,
    Schlick::specular_from_values,
    "Schlick single-slope glossy material (Schlick 1994)"
}

pub(crate) const PARAMS_SPECULAR: &[ParamInfo] = &[
    param(
        "c",
        0.9,
        Range::closed(0.0, 1.0),
        "reflectance at normal incidence (Fresnel C)",
    ),
    param(
        "r",
        0.05,
        Range::left_open(0.0, 1.0),
        "roughness (0 mirror, 1 Lambertian)",
    ),
    param(
        "p",
        1.0,
        Range::left_open(0.0, 1.0),
        "isotropy (1 isotropic, → 0 anisotropic along x)",
    ),
];

pub(crate) const PARAMS_DIFFUSE: &[ParamInfo] = &[
    param(
        "c",
        0.04,
        Range::closed(0.0, 1.0),
        "coat reflectance at normal incidence",
    ),
    param("r", 0.3, Range::left_open(0.0, 1.0), "coat roughness"),
    param("p", 1.0, Range::left_open(0.0, 1.0), "coat isotropy"),
    param(
        "d",
        0.8,
        Range::closed(0.0, 1.0),
        "substrate (Lambertian) albedo",
    ),
];

/// Parameters of [`Schlick`]. `d = None` is the single-layer specular material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SchlickParams {
    /// Fresnel reflectance at normal incidence.
    pub c: f64,
    /// Roughness.
    pub r: f64,
    /// Isotropy.
    pub p: f64,
    /// Lambertian substrate albedo (`Some` for the two-layer `schlick-diffuse`).
    pub d: Option<f64>,
}

impl SchlickParams {
    /// Defaults of `schlick-specular`.
    pub fn specular() -> Self {
        let [c, r, p] = defaults(PARAMS_SPECULAR);
        Self { c, r, p, d: None }
    }

    /// Defaults of `schlick-diffuse`.
    pub fn diffuse() -> Self {
        let [c, r, p, d] = defaults(PARAMS_DIFFUSE);
        Self {
            c,
            r,
            p,
            d: Some(d),
        }
    }
}

/// Schlick BRDF (single-layer glossy or glossy-over-Lambertian).
#[derive(Debug, Clone)]
pub struct Schlick {
    params: SchlickParams,
}

impl Schlick {
    /// Validate the parameters and build the model.
    pub fn new(params: SchlickParams) -> Result<Self, ParamError> {
        match params.d {
            None => validate(
                NAME_SPECULAR,
                PARAMS_SPECULAR,
                &[params.c, params.r, params.p],
            )?,
            Some(d) => validate(
                NAME_DIFFUSE,
                PARAMS_DIFFUSE,
                &[params.c, params.r, params.p, d],
            )?,
        }
        Ok(Self { params })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &SchlickParams {
        &self.params
    }

    pub(crate) fn specular_from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [c, r, p] = crate::params::take(v);
        Self::new(SchlickParams { c, r, p, d: None })
    }

    pub(crate) fn diffuse_from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [c, r, p, d] = crate::params::take(v);
        Self::new(SchlickParams {
            c,
            r,
            p,
            d: Some(d),
        })
    }

    #[inline]
    fn g(&self, v: f64) -> f64 {
        let r = self.params.r;
        v / (r - r * v + v)
    }

    /// Symmetries: `A(w)` is even in `cos φh`, so half-turn symmetric; isotropic and mirror-symmetric
    /// iff `p = 1`; reciprocal; not energy-conserving (see the module docs).
    pub fn properties(&self) -> Properties {
        Properties::elliptical(self.params.p == 1.0) | Properties::RECIPROCAL
    }
}

crate::params::default_from!(Schlick = Self::new(SchlickParams::specular()));

impl Brdf for Schlick {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let SchlickParams { c, r, p, d } = self.params;
        let (v, vp) = (wo.z, wi.z);
        let h = (wo + wi).normalize();
        let t = h.z;
        let u = wi.dot(&h).clamp(0.0, 1.0);
        let q = 1.0 + r * t * t - t * t;
        let z = r / (q * q);
        let a = if p == 1.0 {
            1.0
        } else {
            let s2 = h.x * h.x + h.y * h.y;
            if s2 > 0.0 {
                let w2 = h.x * h.x / s2;
                (p / (p * p - p * p * w2 + w2)).sqrt()
            } else {
                1.0
            }
        };
        let gg = self.g(v) * self.g(vp);
        let glossy = gg * z * a / (4.0 * std::f64::consts::PI * v * vp) + (1.0 - gg) * FRAC_1_PI;
        let m = 1.0 - u;
        let m2 = m * m;
        let s = c + (1.0 - c) * m2 * m2 * m;
        match d {
            None => s * glossy,
            Some(d) => s * glossy + (1.0 - s) * d * FRAC_1_PI,
        }
    }
    brdf_properties!();
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
    fn name(&self) -> &str {
        if self.params.d.is_some() {
            NAME_DIFFUSE
        } else {
            NAME_SPECULAR
        }
    }
}
