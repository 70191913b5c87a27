//! Oren & Nayar (1994), "Generalization of Lambert's reflectance model" — the qualitative model.
//!
//! `f_r = ρ/π · (A + B · max(0, cos(φi − φo)) · sin α · tan β)`, `α = max(θi, θo)`,
//! `β = min(θi, θo)`, `A = 1 − 0.5 σ²/(σ² + 0.33)`, `B = 0.45 σ²/(σ² + 0.09)`.
//! Since `cos(φi−φo) sinθi sinθo = ωi.x ωo.x + ωi.y ωo.y`, the bracket equals
//! `A + B · max(0, ωi.x ωo.x + ωi.y ωo.y) / max(cosθi, cosθo)`, evaluated without trigonometry.
//!
//! Keys: `rho ∈ [0, 1]` (default 0.8), `sigma ∈ [0, π/2]` (facet-slope standard deviation in
//! radians, default 0.5; the GRAPP 2008 scene used "roughness 0.83"). `σ = 0` is Lambert.
//! Reciprocal and isotropic. The qualitative model is not energy-conserving in general: for
//! small σ its albedo slightly exceeds ρ at grazing view (≈ 1.008 ρ for σ = 0.1 at θo = 89.9°),
//! so `conserves_energy()` is true only for σ = 0.

use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2};

pub(crate) const NAME: &str = "oren-nayar";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param("rho", 0.8, Range::closed(0.0, 1.0), "albedo ρ"),
    param(
        "sigma",
        0.5,
        Range::closed(0.0, FRAC_PI_2),
        "facet slope deviation σ (radians)",
    ),
];

/// Parameters of [`OrenNayar`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrenNayarParams {
    /// Albedo.
    pub rho: f64,
    /// Roughness σ in radians.
    pub sigma: f64,
}

impl Default for OrenNayarParams {
    fn default() -> Self {
        let [rho, sigma] = defaults(PARAMS);
        Self { rho, sigma }
    }
}

/// Oren–Nayar rough-diffuse BRDF (qualitative model).
#[derive(Debug, Clone)]
pub struct OrenNayar {
    params: OrenNayarParams,
    a: f64,
    b: f64,
}

impl OrenNayar {
    /// Validate the parameters and build the model.
    pub fn new(params: OrenNayarParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.rho, params.sigma])?;
        let s2 = params.sigma * params.sigma;
        let k = params.rho * FRAC_1_PI;
        Ok(Self {
            params,
            a: k * (1.0 - 0.5 * s2 / (s2 + 0.33)),
            b: k * 0.45 * s2 / (s2 + 0.09),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &OrenNayarParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [rho, sigma] = super::take(v);
        Self::new(OrenNayarParams { rho, sigma })
    }
}

impl Default for OrenNayar {
    fn default() -> Self {
        super::expect_default(Self::new(OrenNayarParams::default()))
    }
}

impl Brdf for OrenNayar {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let dxy = wi.x * wo.x + wi.y * wo.y;
        if dxy > 0.0 {
            self.a + self.b * dxy / wi.z.max(wo.z)
        } else {
            self.a
        }
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): ωi.x ωo.x + ωi.y ωo.y and cosines only.
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
        self.params.sigma == 0.0
    }
    fn name(&self) -> &str {
        NAME
    }
}
