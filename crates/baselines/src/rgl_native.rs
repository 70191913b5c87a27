//! The RGL format's own importance sampling (Dupuy & Jakob 2018; Mitsuba's `measured`
//! plugin): the state of the art for `.bsdf` files, built from the file's tables alone.
//!
//! **Warp.** For `ωo` of elevation `θo` and azimuth `φo`, a uniform `u ∈ [0,1)²` is warped by
//! the file's luminance density (on the VNDF's uniform square, conditioned on `θo`) to `s`, then
//! by the VNDF warp to the half-vector coordinates `u_m = (√(2θm/π), (φm − φo + π)/(2π))`;
//! `m = (sinθm cosφm, sinθm sinφm, cosθm)` and `ωi = 2(ωo·m)m − ωo` (which may fall below the
//! horizon: a zero-contribution sample, so the support is the sphere).
//!
//! **Pdf** (w.r.t. solid angle, exact for this map): the density of `u_m` is
//! `p_lum(s) · p_vndf(u_m)` (the VNDF warp's Jacobian is `1/p_vndf`), `dω_m = 2π² u_m.x sinθm
//! du_m` and `dω_i = 4|ωo·m| dω_m`, so `p(ωi) = p_lum(s) p_vndf(u_m) / (2π² u_m.x sinθm ·
//! 4|ωo·m|)` with `s = vndf⁻¹(u_m)`. Unlike Mitsuba, the Jacobian is not clamped from below, so
//! the reported pdf is the density of the drawn samples everywhere.

use std::f64::consts::PI;

use brdf::measured::rgl::{RglBrdf, u_to_phi, u_to_theta};
use brdf::{Brdf, Vec3};
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;

/// The RGL file's own sampler (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct RglNative {
    brdf: RglBrdf,
}

/// `rgl-native` was asked to sample a BRDF that is not an RGL file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the rgl-native sampler needs an RGL material (`rgl:PATH`), not `{brdf}`")]
pub struct NotRglError {
    /// The BRDF's name.
    pub brdf: String,
}

impl RglNative {
    /// The sampler of an RGL material.
    pub fn new(brdf: RglBrdf) -> Self {
        Self { brdf }
    }

    /// The sampler of `brdf` if it is an RGL material ([`Brdf::as_any`]).
    pub fn for_brdf(brdf: &dyn Brdf) -> Result<Self, NotRglError> {
        brdf.as_any()
            .and_then(|a| a.downcast_ref::<RglBrdf>())
            .map(|b| Self::new(b.clone()))
            .ok_or_else(|| NotRglError {
                brdf: brdf.name().to_string(),
            })
    }

    /// Whether `brdf` is an RGL material.
    pub fn accepts(brdf: &dyn Brdf) -> bool {
        brdf.as_any().is_some_and(|a| a.is::<RglBrdf>())
    }
}

/// `2π² u sinθ · 4|ωo·m|`: `dω_i / du_m`.
fn jacobian(u_mx: f64, sin_theta_m: f64, wo_dot_m: f64) -> f64 {
    2.0 * PI * PI * u_mx * sin_theta_m * 4.0 * wo_dot_m.abs()
}

impl DirectionSampler for RglNative {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let u = [u.next_uniform(), u.next_uniform()];
        let below = DirSample {
            wi: Vec3::new(0.0, 0.0, -1.0),
            pdf: 0.0,
        };
        let Some(c) = RglBrdf::half_coords_any(wo, &Vec3::new(0.0, 0.0, 1.0)) else {
            return below;
        };
        let theta_o = c.theta_o;
        let phi_o = wo.y.atan2(wo.x);
        let (s, p_lum) = self.brdf.luminance_warp().sample(u, theta_o);
        let (u_m, p_vndf) = self.brdf.vndf().sample(s, theta_o);
        let theta_m = u_to_theta(u_m[0]);
        let phi_m = u_to_phi(u_m[1]) + phi_o;
        let (st, ct) = theta_m.sin_cos();
        let m = Vec3::new(st * phi_m.cos(), st * phi_m.sin(), ct);
        let d = wo.dot(&m);
        let wi = (2.0 * d * m - wo).normalize();
        let jac = jacobian(u_m[0], st, d);
        if jac.is_nan() || jac <= 0.0 || !wi.iter().all(|v| v.is_finite()) {
            return below;
        }
        DirSample {
            wi,
            pdf: p_lum * p_vndf / jac,
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some(c) = RglBrdf::half_coords_any(wo, wi) else {
            return 0.0;
        };
        let (s, p_vndf) = self.brdf.vndf().invert(c.u_m, c.theta_o);
        let p_lum = self.brdf.luminance_warp().eval(s, c.theta_o);
        let sin_theta_m = c.m.x.hypot(c.m.y);
        let jac = jacobian(c.u_m[0], sin_theta_m, wo.dot(&c.m));
        if jac > 0.0 { p_lum * p_vndf / jac } else { 0.0 }
    }

    /// 0: the sampler precomputes nothing; the warp tables it reads are the BRDF's own (shared,
    /// not copied).
    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for RglNative {}
