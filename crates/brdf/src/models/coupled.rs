//! Kelemen & Szirmay-Kalos (2001), "A microfacet based coupled specular-matte BRDF model with
//! importance sampling" (Eurographics short presentations).
//!
//! * Specular: `f_s = F(ωi·h) D(h) / (4 (ωi·h)²)` — the microfacet BRDF with the paper's
//!   approximation `G/(cosθi cosθo) ≈ 1/(ωi·h)²`; `D` is the isotropic Beckmann distribution
//!   with RMS slope `m`, `F(c) = f0 + (1 − f0)(1 − c)^5`.
//! * Matte, coupled through the specular albedo `a(ω) = ∫ f_s(ω, ωi) cosθi dσ(ωi)`:
//!   `f_m = kd (1 − a(ωo))(1 − a(ωi)) / (π (1 − ā))`, `ā = (1/π)∫ a(ω) cosθ dσ(ω)`.
//!
//! Then the total albedo is `a(ωo) + kd (1 − a(ωo)) ≤ 1`: energy-conserving and reciprocal.
//! `a` is tabulated at construction at the 257 nodes `cosθ = (i/256)²` (computed in
//! half-vector space with composite Gauss–Legendre quadrature split at the kinks of the
//! integrand, about 10⁻⁷ accurate) and
//! interpolated linearly; `ā` is integrated exactly from the interpolant, so the coupling
//! identity holds for the tabulated `a`. Where the approximate specular albedo would exceed 1
//! (very rough, grazing) it is clamped to 1 in the table, and `conserves_energy()` then reports
//! false. Keys: `m ∈ [0.01, 1]` (default 0.2), `f0 ∈ [0, 1]` (default 0.1), `kd ∈ [0, 1]`
//! (default 0.8). Isotropic.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::fresnel::fresnel_schlick;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, Range};
use crate::quadrature::GaussLegendre;
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, PI};

/// Number of intervals of the albedo table.
const TABLE_INTERVALS: usize = 256;

/// Table node `i`: `cosθ = (i/N)²`, dense near grazing where `a` varies fastest.
#[inline]
fn node(i: usize) -> f64 {
    let x = i as f64 / TABLE_INTERVALS as f64;
    x * x
}

model! {
    /// Parameters of [`Coupled`].
    pub struct CoupledParams in PARAMS for Coupled {
        m = [0.2] in Range::closed(0.01, 1.0), "RMS microfacet slope (Beckmann)";
        f0 = [0.1] in Range::closed(0.0, 1.0), "Fresnel reflectance at normal incidence";
        kd = [0.8] in Range::closed(0.0, 1.0), "matte albedo";
    }
    registry INFO: NAME = "coupled", ["kelemen", "kelemen-szirmay-kalos"], Always,
        "coupled specular–matte microfacet model (Kelemen & Szirmay-Kalos 2001)";
}

/// Kelemen–Szirmay-Kalos coupled specular–matte BRDF.
#[derive(Debug, Clone)]
pub struct Coupled {
    params: CoupledParams,
    inv_m2: f64,
    d_scale: f64,
    /// Specular albedo at the nodes `cosθ = node(i)`, clamped to [0, 1].
    albedo: Vec<f64>,
    /// Largest unclamped table value.
    max_raw_albedo: f64,
    /// kd / (π (1 − ā)).
    matte_scale: f64,
}

impl Coupled {
    /// Validate the parameters, tabulate the specular albedo and build the model.
    pub fn new(params: CoupledParams) -> Result<Self, ParamError> {
        params.validate(NAME)?;
        let m2 = params.m * params.m;
        let mut model = Self {
            params,
            inv_m2: 1.0 / m2,
            d_scale: 1.0 / (PI * m2),
            albedo: Vec::new(),
            max_raw_albedo: 0.0,
            matte_scale: 0.0,
        };
        let gl_t = GaussLegendre::new(16);
        let gl_p = GaussLegendre::new(24);
        let mut table = Vec::with_capacity(TABLE_INTERVALS + 1);
        let mut max_raw: f64 = 0.0;
        for i in 0..=TABLE_INTERVALS {
            let mu = node(i);
            let a = model.specular_albedo(mu, &gl_t, &gl_p);
            max_raw = max_raw.max(a);
            table.push(a.clamp(0.0, 1.0));
        }
        // ā = 2 ∫_0^1 a(μ) μ dμ, exact for the piecewise-linear interpolant.
        let mut abar = 0.0;
        for i in 0..TABLE_INTERVALS {
            let (m0, m1) = (node(i), node(i + 1));
            let h = m1 - m0;
            let (a0, a1) = (table[i], table[i + 1]);
            // ∫ (a0 + (a1−a0)(μ−m0)/h) μ dμ over [m0, m1]
            abar += a0 * 0.5 * (m1 * m1 - m0 * m0)
                + (a1 - a0) / h
                    * ((m1.powi(3) - m0.powi(3)) / 3.0 - m0 * 0.5 * (m1 * m1 - m0 * m0));
        }
        abar *= 2.0;
        model.albedo = table;
        model.max_raw_albedo = max_raw;
        model.matte_scale = if abar < 1.0 {
            params.kd * FRAC_1_PI / (1.0 - abar)
        } else {
            0.0
        };
        Ok(model)
    }

    /// Tabulated specular albedo `a(ω)` for `cosθ = mu` (linear interpolation, clamped to [0, 1]).
    pub fn specular_albedo_at(&self, mu: f64) -> f64 {
        let mu = mu.clamp(0.0, 1.0);
        let i = ((mu.sqrt() * TABLE_INTERVALS as f64) as usize).min(TABLE_INTERVALS - 1);
        let (m0, m1) = (node(i), node(i + 1));
        let t = ((mu - m0) / (m1 - m0)).clamp(0.0, 1.0);
        match (self.albedo.get(i), self.albedo.get(i + 1)) {
            (Some(a0), Some(a1)) => a0 + t * (a1 - a0),
            _ => 0.0,
        }
    }

    #[inline]
    fn beckmann(&self, cos_h: f64) -> f64 {
        let c2 = cos_h * cos_h;
        self.d_scale * (-(1.0 - c2) / c2 * self.inv_m2).exp() / (c2 * c2)
    }

    #[inline]
    fn specular(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let h = (wo + wi).normalize();
        let u = wi.dot(&h).max(1e-12);
        fresnel_schlick(self.params.f0, u) * self.beckmann(h.z) / (4.0 * u * u)
    }

    /// `a(ωo)` for `cosθo = mu` by quadrature in half-vector space:
    /// `a = ∫ F D(h) cosθi/(ωo·h) dσ(h)` over the half vectors whose reflection is above the
    /// horizon (`dσ(ωi) = 4 (ωo·h) dσ(h)`).
    fn specular_albedo(&self, mu: f64, gl_t: &GaussLegendre, gl_p: &GaussLegendre) -> f64 {
        let so = (1.0 - mu * mu).max(0.0).sqrt();
        let theta_o = mu.clamp(-1.0, 1.0).acos();
        let m = self.params.m;
        // Panels in θh at tanθh = m·k, plus the kinks of the visible φh range: all φh are valid
        // below θ1 = (π/2 − θo)/2 and none above θ2 = (π/2 + θo)/2.
        let (t1, t2) = (0.5 * (FRAC_PI_2 - theta_o), 0.5 * (FRAC_PI_2 + theta_o));
        let ks = [0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0];
        let mut edges: Vec<f64> = ks.iter().map(|k| (m * k).atan()).collect();
        edges.push(t1);
        edges.push(t2);
        edges.retain(|&e| e <= t2);
        edges.sort_by(f64::total_cmp);
        edges.dedup();
        let mut total = 0.0;
        for w in edges.windows(2) {
            total += gl_t.integrate(w[0], w[1], |th| {
                let (sh, ch) = th.sin_cos();
                // ωi.z = 2(ωo·h) h_z − μ > 0  ⇔  cosφh > μ (1 − 2ch²) / (2 so sh ch)
                let phi_max = if so * sh * ch > 0.0 {
                    let c = mu * (1.0 - 2.0 * ch * ch) / (2.0 * so * sh * ch);
                    if c >= 1.0 { 0.0 } else { c.max(-1.0).acos() }
                } else if 2.0 * ch * ch - 1.0 > 0.0 || mu == 0.0 {
                    PI
                } else {
                    0.0
                };
                if phi_max <= 0.0 {
                    return 0.0;
                }
                let d = self.beckmann(ch);
                let ring = gl_p.integrate(0.0, phi_max, |ph| {
                    let oh = so * sh * ph.cos() + mu * ch;
                    if oh <= 0.0 {
                        return 0.0;
                    }
                    let ci = 2.0 * oh * ch - mu;
                    if ci <= 0.0 {
                        return 0.0;
                    }
                    fresnel_schlick(self.params.f0, oh) * ci / oh
                });
                2.0 * ring * d * sh
            });
        }
        total
    }

    /// Symmetries and energy: isotropic, even under `y ↦ −y`, reciprocal; conserves energy when
    /// the tabulated albedo stays at most 1.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.max_raw_albedo <= 1.0 + 1e-9)
    }
}

impl Brdf for Coupled {
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let matte = self.matte_scale
            * (1.0 - self.specular_albedo_at(wo.z))
            * (1.0 - self.specular_albedo_at(wi.z));
        self.specular(wo, wi) + matte
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}
