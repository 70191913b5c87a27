//! Poulin & Fournier (1990), "A model for anisotropic reflection" — a surface of parallel
//! cylinders, evaluated by integrating a local reflection model over the visible and lit part of
//! each cylinder's cross-section.
//!
//! Geometry: unit-radius cylinders with axes along the tangent x, centres `d ≥ 2` apart in y, all
//! at the same height. A direction `ω` projects in the (y, z) cross-section to the angle
//! `ψ = atan2(ω_y, ω_z)`; the point of a cylinder at polar angle `γ` (normal
//! `n(γ) = (0, sinγ, cosγ)`) is seen from `ω` iff `|γ − ψ| < π/2` and the neighbouring cylinder
//! does not block the ray. For `ψ ≥ 0` and `δ = γ − ψ`, the neighbour at `+d` blocks iff the ray
//! passes within distance 1 of its centre (`sin δ > d cosψ − 1`, i.e. `δ > δ1 = asin(d cosψ − 1)`)
//! with the closest approach ahead (`cos δ < d sinψ`, i.e. `|δ| > δ2 = acos(d sinψ)`), so the
//! visible range is `δ ≤ max(δ1, δ2)` when `δ1 ≥ −δ2` and `δ ≤ δ1` otherwise (mirrored for
//! `ψ < 0`; arguments clamped to [−1, 1]). Farther cylinders never block more.
//! With `[γ0, γ1]` the intersection of the ranges seen from `ωo` and lit from `ωi`,
//!
//! `f_r(ωo, ωi) = 1/(d cosθi cosθo) ∫_{γ0}^{γ1} f_loc(n(γ); ωo, ωi) (n·ωi)(n·ωo) dγ`,
//!
//! with the local model the modified Phong `f_loc = kd/π + ks (n_exp+2)/(2π) max(0, r·ωi)^{n_exp}`,
//! `r = 2(n·ωo)n − ωo`. The diffuse part is integrated in closed form; the specular part with
//! 12-point Gauss–Legendre panels split at the lobe peak (the `γ` whose normal is the projected
//! half vector) and at ± a few lobe widths.
//!
//! Simplifications (documented): the floor between cylinders (visible only when `d cosψ > 2`)
//! is black and interreflections are ignored; the original paper also allows partially buried
//! cylinders. Keys: `d ∈ [2, 100]` (default 2), `n ∈ [0, 10⁴]` (default 20), `ks ∈ [0, 1]`
//! (default 0.6), `kd ∈ [0, 1]` (default 0.4). Reciprocal (the integrand is symmetric);
//! anisotropic. Visible cylinder area projects exactly onto `d cosθ` per period, and masking
//! only removes light, so the model conserves energy when `kd + ks ≤ 1`.

use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::{ParamError, ParamInfo, Range, defaults, param, validate};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, PI};

pub(crate) const NAME: &str = "poulin-fournier";

pub(crate) const PARAMS: &[ParamInfo] = &[
    param(
        "d",
        2.0,
        Range::closed(2.0, 100.0),
        "cylinder spacing in radii (2 = touching)",
    ),
    param(
        "n",
        20.0,
        Range::closed(0.0, 1e4),
        "Phong exponent of the cylinder surface",
    ),
    param(
        "ks",
        0.6,
        Range::closed(0.0, 1.0),
        "specular albedo of the cylinder surface",
    ),
    param(
        "kd",
        0.4,
        Range::closed(0.0, 1.0),
        "diffuse albedo of the cylinder surface",
    ),
];

/// Gauss–Legendre nodes/weights on [−1, 1] (12 points) for the specular panels.
const GL_POINTS: usize = 12;

/// Parameters of [`PoulinFournier`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoulinFournierParams {
    /// Centre spacing in cylinder radii.
    pub d: f64,
    /// Local Phong exponent.
    pub n: f64,
    /// Local specular albedo.
    pub ks: f64,
    /// Local diffuse albedo.
    pub kd: f64,
}

impl Default for PoulinFournierParams {
    fn default() -> Self {
        let [d, n, ks, kd] = defaults(PARAMS);
        Self { d, n, ks, kd }
    }
}

/// Poulin–Fournier parallel-cylinder anisotropic BRDF.
#[derive(Debug, Clone)]
pub struct PoulinFournier {
    params: PoulinFournierParams,
    nodes: [f64; GL_POINTS],
    weights: [f64; GL_POINTS],
    spec_scale: f64,
    lobe_width: f64,
}

impl PoulinFournier {
    /// Validate the parameters and build the model.
    pub fn new(params: PoulinFournierParams) -> Result<Self, ParamError> {
        validate(NAME, PARAMS, &[params.d, params.n, params.ks, params.kd])?;
        let gl = crate::quadrature::GaussLegendre::new(GL_POINTS);
        let mut nodes = [0.0; GL_POINTS];
        let mut weights = [0.0; GL_POINTS];
        nodes.copy_from_slice(gl.nodes());
        weights.copy_from_slice(gl.weights());
        Ok(Self {
            params,
            nodes,
            weights,
            spec_scale: params.ks * (params.n + 2.0) / (2.0 * PI),
            // cos^n(2Δ) has fallen to ~e^{-8} at 2Δ ≈ 4/√n: use Δ ≈ 2/√(n+1) per side.
            lobe_width: 2.0 / (params.n + 1.0).sqrt(),
        })
    }

    /// The parameters this model was built with.
    pub fn params(&self) -> &PoulinFournierParams {
        &self.params
    }

    pub(crate) fn from_values(v: &[f64]) -> Result<Self, ParamError> {
        let [d, n, ks, kd] = super::take(v);
        Self::new(PoulinFournierParams { d, n, ks, kd })
    }

    /// Range of cylinder angles γ visible from direction `w` (upper hemisphere).
    fn visible_range(&self, w: &Vec3) -> (f64, f64) {
        let psi = w.y.atan2(w.z);
        let a = psi.abs();
        let d = self.params.d;
        let up1 = (d * a.cos() - 1.0).clamp(-1.0, 1.0).asin();
        let up2 = (d * a.sin()).clamp(-1.0, 1.0).acos();
        // Blocked set: {δ > up1} ∩ {|δ| > up2}. For d ≥ 2, up1 < −up2 only when up2 = 0.
        let upper = if up1 >= -up2 { up1.max(up2) } else { up1 }.min(FRAC_PI_2);
        if psi >= 0.0 {
            (psi - FRAC_PI_2, psi + upper)
        } else {
            (psi - upper, psi + FRAC_PI_2)
        }
    }

    /// `∫_{a}^{b} f_spec(γ)(n·ωi)(n·ωo) dγ` by Gauss–Legendre on one panel.
    fn spec_panel(&self, wo: &Vec3, wi: &Vec3, a: f64, b: f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        let cosio = wo.dot(wi);
        let mut s = 0.0;
        for (x, w) in self.nodes.iter().zip(&self.weights) {
            let (sg, cg) = (mid + half * x).sin_cos();
            let no = sg * wo.y + cg * wo.z;
            let ni = sg * wi.y + cg * wi.z;
            let c = 2.0 * no * ni - cosio; // r·ωi
            if c > 0.0 && no > 0.0 && ni > 0.0 {
                s += w * c.powf(self.params.n) * no * ni;
            }
        }
        s * half * self.spec_scale
    }
}

impl Default for PoulinFournier {
    fn default() -> Self {
        super::expect_default(Self::new(PoulinFournierParams::default()))
    }
}

impl Brdf for PoulinFournier {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let (lo_o, hi_o) = self.visible_range(wo);
        let (lo_i, hi_i) = self.visible_range(wi);
        let (g0, g1) = (lo_o.max(lo_i), hi_o.min(hi_i));
        if !(g1 > g0) {
            return 0.0;
        }
        // Diffuse: ∫ (n·ωi)(n·ωo) dγ with n·ω = |ω_yz| cos(γ − ψ).
        let (ri, psi_i) = (wi.y.hypot(wi.z), wi.y.atan2(wi.z));
        let (ro, psi_o) = (wo.y.hypot(wo.z), wo.y.atan2(wo.z));
        let prim =
            |g: f64| 0.5 * (g * (psi_i - psi_o).cos() + 0.5 * (2.0 * g - psi_i - psi_o).sin());
        let diffuse = self.params.kd * FRAC_1_PI * ri * ro * (prim(g1) - prim(g0));
        // Specular: panels split at the peak γ_h and ± the lobe width.
        let mut spec = 0.0;
        if self.params.ks > 0.0 {
            let s = wo + wi;
            let gh = s.y.atan2(s.z);
            let w = self.lobe_width;
            let mut cuts = [g0, gh - 2.0 * w, gh - w, gh, gh + w, gh + 2.0 * w, g1];
            for c in cuts.iter_mut() {
                *c = c.clamp(g0, g1);
            }
            cuts.sort_by(|a, b| a.total_cmp(b));
            for k in 0..cuts.len() - 1 {
                spec += self.spec_panel(wo, wi, cuts[k], cuts[k + 1]);
            }
        }
        ((diffuse + spec) / (self.params.d * wi.z * wo.z)).max(0.0)
    }
    fn is_isotropic(&self) -> bool {
        false
    }
    fn is_reciprocal(&self) -> bool {
        true
    }
    fn conserves_energy(&self) -> bool {
        self.params.kd + self.params.ks <= 1.0
    }
    fn name(&self) -> &str {
        NAME
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force visibility of the cross-section point at angle γ from 2D direction angle ψ:
    /// self-facing and no intersection with the neighbouring circles k = ±1..±8.
    fn visible_brute(d: f64, psi: f64, gamma: f64) -> bool {
        let (py, pz) = (gamma.sin(), gamma.cos());
        let (uy, uz) = (psi.sin(), psi.cos());
        if py * uy + pz * uz <= 0.0 {
            return false;
        }
        for k in (-8..=8).filter(|&k| k != 0) {
            let cy = k as f64 * d;
            // Ray P + t u hits the unit circle at (cy, 0) for some t > 0?
            let (oy, oz) = (py - cy, pz);
            let b = oy * uy + oz * uz;
            let c = oy * oy + oz * oz - 1.0;
            let disc = b * b - c;
            if disc > 0.0 && -b + disc.sqrt() > 0.0 && -b - disc.sqrt() > 1e-12 {
                return false;
            }
        }
        true
    }

    #[test]
    fn visible_range_matches_ray_casting() {
        for d in [2.0, 2.3, 3.0, 5.0] {
            let pf = PoulinFournier::new(PoulinFournierParams {
                d,
                ..Default::default()
            })
            .unwrap();
            for i in 0..60 {
                let psi = -1.55 + 3.1 * i as f64 / 59.0;
                let w = Vec3::new(0.0, psi.sin(), psi.cos());
                let (lo, hi) = pf.visible_range(&w);
                for j in 0..400 {
                    let gamma = -PI + 2.0 * PI * (j as f64 + 0.5) / 400.0;
                    if (gamma - lo).abs() < 1e-6 || (gamma - hi).abs() < 1e-6 {
                        continue;
                    }
                    let inside = gamma > lo && gamma < hi;
                    assert_eq!(
                        inside,
                        visible_brute(d, psi, gamma),
                        "d={d} ψ={psi} γ={gamma}"
                    );
                }
            }
        }
    }

    #[test]
    fn normal_incidence_diffuse_matches_closed_form() {
        // ωo = ωi = n, d = 2, kd only: (kd/π)/(2) ∫_{-π/2}^{π/2} cos²γ dγ = kd/4.
        let pf = PoulinFournier::new(PoulinFournierParams {
            d: 2.0,
            n: 1.0,
            ks: 0.0,
            kd: 0.8,
        })
        .unwrap();
        let n = Vec3::new(0.0, 0.0, 1.0);
        assert!((pf.eval(&n, &n) - 0.8 / 4.0).abs() < 1e-12);
    }
}
