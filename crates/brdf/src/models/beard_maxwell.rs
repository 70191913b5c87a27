//! Maxwell, Beard, Weiner & Ladd (1973), "Bidirectional reflectance model validation and
//! utilization" (AFAL-TR-73-303) — the Beard–Maxwell model for painted surfaces, in the form of
//! Westlund & Meyer (2002, eq. 10) and the NEF database:
//!
//! `f_r = R(β)/R(0) · ρ_fs(θN) cos²θN / (cosθi cosθo) · SO(θN, β) + rd/π + 2 rv / (π (cosθi + cosθo))`
//!
//! * `θN = acos(n·h)` is the facet tilt, `β = acos(ωi·h)` the half bistatic angle;
//! * `R` is the unpolarised Fresnel reflectance of the index `ior + i·kappa` (default roughly
//!   gold at 600–650 nm, as in seed 000);
//! * first-surface facet distribution (a Gaussian in tilt, as in the NEF fits):
//!   `ρ_fs(θN) = rs · exp(−θN²/σ²) / (4π σ²)`, scaled so that `rs` is approximately the
//!   first-surface albedo at normal incidence for small σ;
//! * shadowing/obscuration `SO = (1 + (θN/Ω) e^{−2β/τ}) / (1 + θN/Ω)` with `θN`, `β`, `Ω`, `τ` in
//!   **degrees**; `τ = 0` means `e^{−2β/τ} = 0` (seed 000: Ω = 1, τ = 0);
//! * volumetric terms: Lambertian `rd/π` and `2 rv/(π(cosθi + cosθo))`. (NEF writes these without
//!   `1/π`; we divide so that `rd`, `rv` read as reflectances.)
//!
//! Keys: `rs` (0.7), `rd` (0.5), `rv` (0.2), all in `[0, 1]`; `sigma ∈ [0.005, 1]` rad
//! (default 0.15); `omega ∈ (0, 90]` deg (default 1); `tau ∈ [0, 90]` deg (default 0);
//! `ior ∈ (0, 100]` (default 0.2), `kappa ∈ [0, 100]` (default 3). Reciprocal and isotropic;
//! not energy-conserving in general.

use crate::brdf::Brdf;
use crate::fresnel::fresnel_conductor;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::{FRAC_1_PI, PI};

pub(crate) const NAME: &str = "beard-maxwell";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param(
        "rs",
        0.7,
        Range::closed(0.0, 1.0),
        "first-surface (specular) reflectance",
    ),
    param(
        "rd",
        0.5,
        Range::closed(0.0, 1.0),
        "volumetric Lambertian reflectance",
    ),
    param(
        "rv",
        0.2,
        Range::closed(0.0, 1.0),
        "volumetric directional reflectance",
    ),
    param(
        "sigma",
        0.15,
        Range::closed(0.005, 1.0),
        "facet tilt spread σ (radians)",
    ),
    param(
        "omega",
        1.0,
        Range::left_open(0.0, 90.0),
        "obscuration constant Ω (degrees)",
    ),
    param(
        "tau",
        0.0,
        Range::closed(0.0, 90.0),
        "shadowing decay τ (degrees; 0 = no shadowing recovery)",
    ),
    param(
        "ior",
        0.2,
        Range::left_open(0.0, 100.0),
        "refractive index, real part",
    ),
    param(
        "kappa",
        3.0,
        Range::closed(0.0, 100.0),
        "refractive index, imaginary part",
    ),
];

/// Parameters of [`BeardMaxwell`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeardMaxwellParams {
    /// First-surface reflectance.
    pub rs: f64,
    /// Volumetric Lambertian reflectance.
    pub rd: f64,
    /// Volumetric directional reflectance.
    pub rv: f64,
    /// Facet tilt spread (radians).
    pub sigma: f64,
    /// Obscuration constant Ω (degrees).
    pub omega: f64,
    /// Shadowing decay τ (degrees).
    pub tau: f64,
    /// Refractive index (real).
    pub ior: f64,
    /// Extinction coefficient.
    pub kappa: f64,
}

impl Default for BeardMaxwellParams {
    fn default() -> Self {
        let [rs, rd, rv, sigma, omega, tau, ior, kappa] = defaults(PARAMS);
        Self {
            rs,
            rd,
            rv,
            sigma,
            omega,
            tau,
            ior,
            kappa,
        }
    }
}

/// Beard–Maxwell painted-surface BRDF.
#[derive(Debug, Clone)]
pub struct BeardMaxwell {
    params: BeardMaxwellParams,
    inv_r0: f64,
    fs_scale: f64,
    inv_sigma2: f64,
}

impl BeardMaxwell {
    /// Validate the parameters and build the model.
    pub fn new(params: BeardMaxwellParams) -> Result<Self, ParamError> {
        let p = params;
        validate(
            NAME,
            PARAMS,
            &[p.rs, p.rd, p.rv, p.sigma, p.omega, p.tau, p.ior, p.kappa],
        )?;
        let r0 = fresnel_conductor(1.0, p.ior, p.kappa);
        if !(r0 > 0.0) {
            return Err(ParamError::Constraint {
                model: NAME,
                message:
                    "normal-incidence Fresnel reflectance R(0) must be > 0 (ior ≠ 1 or kappa > 0)"
                        .into(),
            });
        }
        Ok(Self {
            params,
            inv_r0: 1.0 / r0,
            fs_scale: p.rs / (4.0 * PI * p.sigma * p.sigma),
            inv_sigma2: 1.0 / (p.sigma * p.sigma),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &BeardMaxwellParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [rs, rd, rv, sigma, omega, tau, ior, kappa] = super::take(v);
        Self::new(BeardMaxwellParams {
            rs,
            rd,
            rv,
            sigma,
            omega,
            tau,
            ior,
            kappa,
        })
    }
}

impl Default for BeardMaxwell {
    fn default() -> Self {
        super::expect_default(Self::new(BeardMaxwellParams::default()))
    }
}

impl Brdf for BeardMaxwell {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let p = &self.params;
        let (ci, co) = (wi.z, wo.z);
        let h = (wo + wi).normalize();
        let cos_n = h.z.clamp(0.0, 1.0);
        let cos_b = wi.dot(&h).clamp(0.0, 1.0);
        let theta_n = cos_n.acos();
        let ratio = fresnel_conductor(cos_b, p.ior, p.kappa) * self.inv_r0;
        let rho_fs = self.fs_scale * (-theta_n * theta_n * self.inv_sigma2).exp();
        let tilt = theta_n.to_degrees() / p.omega;
        let recovery = if p.tau > 0.0 {
            (-2.0 * cos_b.acos().to_degrees() / p.tau).exp()
        } else {
            0.0
        };
        let so = (1.0 + tilt * recovery) / (1.0 + tilt);
        let first = ratio * rho_fs * cos_n * cos_n / (ci * co) * so;
        let vol = p.rd * FRAC_1_PI + 2.0 * p.rv * FRAC_1_PI / (ci + co);
        first + vol
    }
    fn bounded_at_horizon(&self) -> bool {
        // The first-surface term carries 1/(cosθi cosθo).
        false
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Even under (x, y, z) ↦ (x, −y, z): n·h, ωi·h and cosines only.
        true
    }
    fn is_half_turn_symmetric(&self) -> bool {
        // Isotropic, and R_π is a rotation about the normal.
        true
    }
    fn is_reciprocal(&self) -> bool {
        true
    }
    fn name(&self) -> &str {
        NAME
    }
}
