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

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::fresnel::fresnel_conductor;
use crate::geometry::{Vec3, above_with_half};
use crate::params::{ParamError, Range};
use std::f64::consts::{FRAC_1_PI, PI};

/// The normal-incidence Fresnel reflectance `R(0)` of `ior + i·kappa`, which the model divides
/// by: an error unless it is positive.
fn normal_incidence_reflectance(p: &BeardMaxwellParams) -> Result<f64, ParamError> {
    let r0 = fresnel_conductor(1.0, p.ior, p.kappa);
    if !(r0 > 0.0) {
        return Err(ParamError::Constraint {
            model: NAME,
            message: "normal-incidence Fresnel reflectance R(0) must be > 0 (ior ≠ 1 or kappa > 0)"
                .into(),
        });
    }
    Ok(r0)
}

model! {
    /// Parameters of [`BeardMaxwell`].
    pub struct BeardMaxwellParams in PARAMS {
        rs = [0.7] in Range::closed(0.0, 1.0), "first-surface (specular) reflectance";
        rd = [0.5] in Range::closed(0.0, 1.0), "volumetric Lambertian reflectance";
        rv = [0.2] in Range::closed(0.0, 1.0), "volumetric directional reflectance";
        sigma = [0.15] in Range::closed(0.005, 1.0), "facet tilt spread σ (radians)";
        omega = [1.0] in Range::left_open(0.0, 90.0), "obscuration constant Ω (degrees)";
        tau = [0.0] in Range::closed(0.0, 90.0), "shadowing decay τ (degrees; 0 = no shadowing recovery)";
        ior = [0.2] in Range::left_open(0.0, 100.0), "refractive index, real part";
        kappa = [3.0] in Range::closed(0.0, 100.0), "refractive index, imaginary part";
    }
    registry INFO: NAME = "beard-maxwell", ["beardmaxwell", "beard"], Always,
        "painted surfaces: first-surface facets + volumetric terms (Maxwell, Beard et al. 1973)";
    /// Beard–Maxwell painted-surface BRDF.
    pub struct BeardMaxwell(params) {
        let p = params;
        let r0 = normal_incidence_reflectance(&p)?;
        inv_r0: f64 = 1.0 / r0,
        fs_scale: f64 = p.rs / (4.0 * PI * p.sigma * p.sigma),
        inv_sigma2: f64 = 1.0 / (p.sigma * p.sigma),
    }
}

impl BeardMaxwell {
    /// Symmetries: isotropic, even under `y ↦ −y`, reciprocal; the shadowing term leaves `f_r`
    /// unbounded at the horizon; energy conservation is not guaranteed.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC | Properties::RECIPROCAL | Properties::UNBOUNDED_AT_HORIZON
    }
}

impl Brdf for BeardMaxwell {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some((ci, co, h)) = above_with_half(wo, wi) else {
            return 0.0;
        };
        let p = &self.params;
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
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
