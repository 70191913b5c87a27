//! Minnaert (1941), "The reciprocity principle in lunar photometry".
//!
//! `f_r = ρ (k+1)/(2π) · (cosθi cosθo)^{k−1}`. The factor `(k+1)/(2π)` makes the albedo exactly
//! `ρ` at normal incidence; in general `albedo(θo) = ρ cos^{k−1}θo`, so the model conserves
//! energy iff `k ≥ 1` (limb darkening `k < 1` brightens grazing views without bound). `k = 1` is
//! Lambert. Keys: `rho ∈ [0, 1]` (default 0.8), `k ∈ [0, 2]` (default 0.7). Reciprocal, isotropic.
//! Values are finite for every direction strictly above the horizon (the product of cosines is
//! clamped at 10⁻³⁰⁰ before the power, which only matters for subnormal inputs).

use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::PI;

pub(crate) const NAME: &str = "minnaert";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param(
        "rho",
        0.8,
        Range::closed(0.0, 1.0),
        "albedo at normal incidence",
    ),
    param(
        "k",
        0.7,
        Range::closed(0.0, 2.0),
        "Minnaert limb-darkening exponent",
    ),
];

/// Parameters of [`Minnaert`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinnaertParams {
    /// Albedo.
    pub rho: f64,
    /// Exponent k.
    pub k: f64,
}

impl Default for MinnaertParams {
    fn default() -> Self {
        let [rho, k] = defaults(PARAMS);
        Self { rho, k }
    }
}

/// Minnaert BRDF.
#[derive(Debug, Clone)]
pub struct Minnaert {
    params: MinnaertParams,
    scale: f64,
}

impl Minnaert {
    /// Validate the parameters and build the model.
    pub fn new(params: MinnaertParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.rho, params.k])?;
        Ok(Self {
            params,
            scale: params.rho * (params.k + 1.0) / (2.0 * PI),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &MinnaertParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [rho, k] = super::take(v);
        Self::new(MinnaertParams { rho, k })
    }
}

impl Default for Minnaert {
    fn default() -> Self {
        super::expect_default(Self::new(MinnaertParams::default()))
    }
}

impl Brdf for Minnaert {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let c = (wi.z * wo.z).max(1e-300);
        self.scale * c.powf(self.params.k - 1.0)
    }
    fn bounded_at_horizon(&self) -> bool {
        // (cosθi cosθo)^{k−1} grows without bound as θi → 90° when k < 1.
        self.params.k >= 1.0 || self.params.rho == 0.0
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): cosines only.
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
        self.params.k >= 1.0
    }
    fn name(&self) -> &str {
        NAME
    }
}
