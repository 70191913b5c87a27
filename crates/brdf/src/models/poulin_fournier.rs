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
//! `r = 2(n·ωo)n − ωo`. The diffuse part is integrated in closed form.
//!
//! **Specular part.** With `A = |ωo,yz| |ωi,yz|`, `B = −ωo,x ωi,x`, `Δ = ψi − ψo` and
//! `δ = γ − (ψo + ψi)/2`, one has `r·ωi = A cos2δ + B` and `(n·ωo)(n·ωi) = (A/2)(cos2δ + cosΔ)`,
//! so the integrand `F(δ) = (A cos2δ + B)^{n_exp} (A/2)(cos2δ + cosΔ)` is even in `δ`, peaks at
//! `δ = 0` and vanishes beyond the root `cos2δ = u_c = −B/A`. For `n_exp ≥ 10`, a range
//! `[δa, δb]` containing the peak is split into `∫_0^{δb} F + ∫_0^{−δa} F`, and with `u = cos2δ`
//! each `∫_0^{x} F` is computed as follows:
//! * if `|x|` reaches the root or the point where `((A cos2δ + B)/(A + B))^{n_exp} = e^{−37}`
//!   (so the rest of the lobe is below 10⁻¹⁶ of its peak), `∫_0^{|x|} F` is the whole lobe
//!   `∫_{u_c}^1 (A(u − u_c))^{n_exp} (A/4)(u + cosΔ) (1 − u)^{−1/2} (1 + u)^{−1/2} du`, evaluated
//!   by a 16-node Gauss–Jacobi rule for the weight `(u − u_c)^{n_exp} (1 − u)^{−1/2}` (built at
//!   construction by the Golub–Welsch algorithm), which absorbs the power exactly;
//! * otherwise (the lobe is cut by masking) by a Gauss–Jacobi rule for `(1 − u)^{−1/2}` on
//!   `[cos2|x|, 1]` with 12–20 nodes chosen from the lobe's log-variation (≤ 37), or, when
//!   `cos2|x| < −1/2` (where the `(1 + u)^{−1/2}` factor is nearly singular), a Gauss–Legendre
//!   rule in `δ` (16–32 nodes, again from the log-variation).
//!
//! A range on one flank of the lobe (peak outside `[δa, δb]`) is integrated directly with that
//! Gauss–Legendre rule in `δ`, up to the point where the lobe has fallen to `e^{−37}`.
//!
//! Against a composite 16-point Gauss–Legendre rule refined around the peak and the roots (the
//! tests) the deviation is below 10⁻¹¹ of the value or 2·10⁻¹² of the lobe peak.
//!
//! For `n_exp < 10` the specular part uses 12-point Gauss–Legendre panels in `γ` split at the
//! projected half vector and ± a few lobe widths (the pre-optimisation rule); it is inaccurate
//! (up to ~10⁻² of the lobe peak for `n_exp → 0`, where the integrand has a kink or jump at the
//! root `r·ωi = 0`).
//!
//! Simplifications (documented): the floor between cylinders (visible only when `d cosψ > 2`)
//! is black and interreflections are ignored; the original paper also allows partially buried
//! cylinders. Keys: `d ∈ [2, 100]` (default 2), `n ∈ [0, 10⁴]` (default 20), `ks ∈ [0, 1]`
//! (default 0.6), `kd ∈ [0, 1]` (default 0.4). Reciprocal (the integrand is symmetric);
//! anisotropic. Visible cylinder area projects exactly onto `d cosθ` per period, and masking
//! only removes light, so the model conserves energy when `kd + ks ≤ 1`.

use super::{Properties, brdf_properties, model};
use crate::brdf::Brdf;
use crate::geometry::{Vec3, both_above};
use crate::params::Range;
use crate::quadrature::GaussLegendre;
use crate::special::ln_gamma_diff;
use nalgebra::{DMatrix, SymmetricEigen};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, PI};
use std::sync::LazyLock;

/// Gauss–Legendre nodes/weights on [−1, 1] (12 points) for the specular panels (`n_exp < 10`).
const GL_POINTS: usize = 12;
/// Smallest Phong exponent evaluated with the Gauss–Jacobi lobe rules.
const JACOBI_MIN_EXPONENT: f64 = 10.0;
/// Nodes of the whole-lobe Gauss–Jacobi rule.
const LOBE_NODES: usize = 16;
/// The lobe is negligible where `((A cos2δ + B)/(A + B))^n < e^{−TAIL_LN}`.
const TAIL_LN: f64 = 37.0;
/// Cut lobes with `cos2δ` below this use the Gauss–Legendre rule in `δ`.
const CUT_U_MIN: f64 = -0.5;
/// Largest Gauss–Legendre rule in `δ` for lobe pieces.
const CUT_DELTA_NODES: usize = 32;

/// A quadrature rule on `[0, 1]`: `∫_0^1 w(s) g(s) ds ≈ Σ weight_k g(s_k)`.
#[derive(Debug, Clone)]
struct Rule {
    s: Vec<f64>,
    weight: Vec<f64>,
}

/// Gauss–Jacobi rule for the weight `(1 − x)^α (1 + x)^β` on `[−1, 1]` by the Golub–Welsch
/// algorithm, returned as nodes `s = (1 − x)/2 ∈ (0, 1)` (ascending in `x`, so descending in
/// `s`) and weights normalised to sum to 1.
fn gauss_jacobi(points: usize, alpha: f64, beta: f64) -> Rule {
    let mut jacobi = DMatrix::<f64>::zeros(points, points);
    for k in 0..points {
        let kf = k as f64;
        let s = 2.0 * kf + alpha + beta;
        jacobi[(k, k)] = if k == 0 {
            (beta - alpha) / (alpha + beta + 2.0)
        } else {
            (beta * beta - alpha * alpha) / (s * (s + 2.0))
        };
        if k + 1 < points {
            let k1 = kf + 1.0;
            let s1 = 2.0 * k1 + alpha + beta;
            let off = (4.0 * k1 * (k1 + alpha) * (k1 + beta) * (k1 + alpha + beta)
                / (s1 * s1 * (s1 + 1.0) * (s1 - 1.0)))
                .sqrt();
            jacobi[(k, k + 1)] = off;
            jacobi[(k + 1, k)] = off;
        }
    }
    let eigen = SymmetricEigen::new(jacobi);
    let mut pairs: Vec<(f64, f64)> = (0..points)
        .map(|i| (eigen.eigenvalues[i], eigen.eigenvectors[(0, i)].powi(2)))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = pairs.iter().map(|p| p.1).sum();
    Rule {
        s: pairs.iter().map(|p| 0.5 * (1.0 - p.0)).collect(),
        weight: pairs.iter().map(|p| p.1 / total).collect(),
    }
}

/// Rules for cut lobes: `∫_0^1 s^{−1/2} g(s) ds` (weights sum to 2) with 12, 16 and 20 nodes,
/// and Gauss–Legendre on `[0, 1]` (weights sum to 1) with 16, 24 and 32 nodes.
struct CutRules {
    jacobi: [Rule; 3],
    legendre: [Rule; 3],
}

impl CutRules {
    /// The coarsest of three rules whose limit is at least the log-`variation` of the power
    /// over the piece (the last rule beyond the last limit).
    fn pick(rules: &[Rule; 3], limits: [f64; 2], variation: f64) -> &Rule {
        if variation <= limits[0] {
            &rules[0]
        } else if variation <= limits[1] {
            &rules[1]
        } else {
            &rules[2]
        }
    }

    /// The Gauss–Jacobi rule in `u` for a log-variation up to 12, 24 or more.
    fn jacobi_for(&self, variation: f64) -> &Rule {
        Self::pick(&self.jacobi, [12.0, 24.0], variation)
    }

    /// The Gauss–Legendre rule in `δ` for a log-variation up to 4, 16 or more.
    fn legendre_for(&self, variation: f64) -> &Rule {
        Self::pick(&self.legendre, [4.0, 16.0], variation)
    }
}

static CUT_RULES: LazyLock<CutRules> = LazyLock::new(|| {
    let scaled = |points| {
        let mut r = gauss_jacobi(points, -0.5, 0.0);
        for w in &mut r.weight {
            *w *= 2.0;
        }
        r
    };
    let legendre = |points| {
        let gl = GaussLegendre::new(points);
        Rule {
            s: gl.nodes().iter().map(|x| 0.5 * (1.0 + x)).collect(),
            weight: gl.weights().iter().map(|w| 0.5 * w).collect(),
        }
    };
    CutRules {
        jacobi: [scaled(12), scaled(16), scaled(20)],
        legendre: [legendre(16), legendre(24), legendre(CUT_DELTA_NODES)],
    }
});

/// Per-evaluation constants of the specular lobe `F(δ) = (A cos2δ + B)^n (A/2)(cos2δ + cosΔ)`.
struct Lobe {
    a: f64,
    b: f64,
    cos_delta: f64,
    /// `ln(A + B)` (the lobe peak is `(A + B)^n`).
    ln_peak: f64,
    /// `u_c = −B/A`: root of `A u + B`.
    u_root: f64,
    /// `∫_0^{|x|} F` is the whole lobe when `cos2|x| ≤ u_whole` (`−∞` if never).
    u_whole: f64,
}

model! {
    /// Parameters of [`PoulinFournier`].
    pub struct PoulinFournierParams in PARAMS {
        d = [2.0] in Range::closed(2.0, 100.0), "cylinder spacing in radii (2 = touching)";
        n = [20.0] in Range::closed(0.0, 1e4), "Phong exponent of the cylinder surface";
        ks = [0.6] in Range::closed(0.0, 1.0), "specular albedo of the cylinder surface";
        kd = [0.4] in Range::closed(0.0, 1.0), "diffuse albedo of the cylinder surface";
    }
    registry INFO: NAME = "poulin-fournier", ["poulin"], Never,
        "anisotropic parallel cylinders with Phong surface (Poulin & Fournier 1990)";
    /// Poulin–Fournier parallel-cylinder anisotropic BRDF.
    pub struct PoulinFournier(params) {
        let gl = GaussLegendre::new(GL_POINTS);
        let n = params.n;
        nodes: [f64; GL_POINTS] = std::array::from_fn(|i| gl.nodes()[i]),
        weights: [f64; GL_POINTS] = std::array::from_fn(|i| gl.weights()[i]),
        spec_scale: f64 = params.ks * (n + 2.0) / (2.0 * PI),
        // cos^n(2Δ) has fallen to ~e^{-8} at 2Δ ≈ 4/√n: use Δ ≈ 2/√(n+1) per side.
        lobe_width: f64 = 2.0 / (n + 1.0).sqrt(),
        /// Whole-lobe rule for `(1 + x)^n (1 − x)^{−1/2}`, weights scaled to sum to `B(n + 1, 1/2)`
        /// (`None` when `n < 10`).
        lobe_rule: Option<Rule> = (n >= JACOBI_MIN_EXPONENT).then(|| {
            let mut rule = gauss_jacobi(LOBE_NODES, -0.5, n);
            // B(n + 1, 1/2) = Γ(n + 1) Γ(1/2) / Γ(n + 3/2).
            let beta = (ln_gamma_diff(n + 1.0, n + 1.5) + 0.5 * PI.ln()).exp();
            for w in &mut rule.weight {
                *w *= beta;
            }
            rule
        }),
        /// `e^{−TAIL_LN/n}`.
        tail_factor: f64 = (-TAIL_LN / n).exp(),
    }
}

impl PoulinFournier {
    /// Range of cylinder angles γ visible from direction `w` (upper hemisphere), given
    /// `psi = atan2(w_y, w_z)` and `r = |w_yz|`.
    fn visible_range(&self, w: &Vec3, psi: f64, r: f64) -> (f64, f64) {
        let d = self.params.d;
        // cos|ψ| = w_z/r, sin|ψ| = |w_y|/r.
        let up1 = (d * w.z / r - 1.0).clamp(-1.0, 1.0).asin();
        let up2 = (d * w.y.abs() / r).clamp(-1.0, 1.0).acos();
        // Blocked set: {δ > up1} ∩ {|δ| > up2}. For d ≥ 2, up1 < −up2 only when up2 = 0.
        let upper = if up1 >= -up2 { up1.max(up2) } else { up1 }.min(FRAC_PI_2);
        if psi >= 0.0 {
            (psi - FRAC_PI_2, psi + upper)
        } else {
            (psi - upper, psi + FRAC_PI_2)
        }
    }

    /// `∫_{a}^{b} f_spec(γ)(n·ωi)(n·ωo) dγ` by Gauss–Legendre on one panel (`n < 10`).
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

    /// Specular integral over `[g0, g1]` by panels split at the peak `γ_h` and ± the lobe
    /// width (`n < 10`).
    fn spec_panels(&self, wo: &Vec3, wi: &Vec3, g0: f64, g1: f64) -> f64 {
        let s = wo + wi;
        let gh = s.y.atan2(s.z);
        let w = self.lobe_width;
        let mut cuts = [g0, gh - 2.0 * w, gh - w, gh, gh + w, gh + 2.0 * w, g1];
        for c in cuts.iter_mut() {
            *c = c.clamp(g0, g1);
        }
        cuts.sort_by(|a, b| a.total_cmp(b));
        cuts.windows(2)
            .map(|p| self.spec_panel(wo, wi, p[0], p[1]))
            .sum()
    }

    /// `∫_0^{len} F(δ) dδ` for `len ∈ [0, π/2]` with `u = cos(2 len)` (see the module docs);
    /// `whole` caches the whole-lobe integral.
    fn half_lobe(&self, lobe: &Lobe, u: f64, len: f64, whole: &mut Option<f64>) -> f64 {
        if u <= lobe.u_whole {
            *whole.get_or_insert_with(|| self.whole_lobe(lobe))
        } else if u >= CUT_U_MIN {
            self.cut_lobe_in_u(lobe, u)
        } else {
            self.lobe_piece_in_delta(lobe, 0.0, len)
        }
    }

    /// The whole lobe `∫_0^{δ_root} F dδ
    /// = (A + B)^n √(1 − u_c) (A/4) ∫_{−1}^{1} (1+x)^n (1−x)^{−1/2} (u + cosΔ)/√(1 + u) dx / 2^{n+1/2}`
    /// with `u = 1 − (1 − u_c)(1 − x)/2`. Without a root (`u_c < −1`) nodes below `u = −1` lie
    /// where the lobe is below `e^{−37}` of its peak and are dropped.
    fn whole_lobe(&self, lobe: &Lobe) -> f64 {
        let Some(rule) = &self.lobe_rule else {
            return 0.0;
        };
        let span = 1.0 - lobe.u_root;
        let mut sum = 0.0;
        for (s, w) in rule.s.iter().zip(&rule.weight) {
            let u = 1.0 - span * s;
            if u > -1.0 {
                sum += w * (u + lobe.cos_delta) / (1.0 + u).sqrt();
            }
        }
        (self.params.n * lobe.ln_peak).exp() * span.sqrt() * 0.25 * lobe.a * sum
    }

    /// `∫_{u_cut}^{1} (A u + B)^n (A/4)(u + cosΔ)(1 − u)^{−1/2}(1 + u)^{−1/2} du` by the
    /// Gauss–Jacobi rule for `(1 − u)^{−1/2}` (12, 16 or 20 nodes for a log-variation of the
    /// power up to 12, 24 or 37).
    fn cut_lobe_in_u(&self, lobe: &Lobe, u_cut: f64) -> f64 {
        let n = self.params.n;
        let span = 1.0 - u_cut;
        let variation = n * (lobe.ln_peak - (lobe.a * u_cut + lobe.b).ln());
        let rule = CUT_RULES.jacobi_for(variation);
        let mut sum = 0.0;
        for (s, w) in rule.s.iter().zip(&rule.weight) {
            let u = 1.0 - span * s;
            let power = (n * ((lobe.a * u + lobe.b).ln() - lobe.ln_peak)).exp();
            sum += w * power * (u + lobe.cos_delta) / (1.0 + u).sqrt();
        }
        (n * lobe.ln_peak).exp() * span.sqrt() * 0.25 * lobe.a * sum
    }

    /// `∫_{lo}^{hi} F(δ) dδ` (`0 ≤ lo ≤ hi ≤ π/2`, no root of `A cos2δ + B` inside) by
    /// Gauss–Legendre in `δ` with 16, 24 or 32 nodes for a log-variation of the power over the
    /// piece up to 4, 16 or 37.
    fn lobe_piece_in_delta(&self, lobe: &Lobe, lo: f64, hi: f64) -> f64 {
        let n = self.params.n;
        let len = hi - lo;
        let power_ln = |d: f64| {
            let c = lobe.a * (2.0 * d).cos() + lobe.b;
            n * (c.ln() - lobe.ln_peak)
        };
        let variation = power_ln(lo) - power_ln(hi);
        let rule = CUT_RULES.legendre_for(variation);
        let mut sum = 0.0;
        for (s, w) in rule.s.iter().zip(&rule.weight) {
            let c2 = (2.0 * (lo + len * s)).cos();
            let c = lobe.a * c2 + lobe.b;
            if c > 0.0 {
                sum += w * (n * (c.ln() - lobe.ln_peak)).exp() * (c2 + lobe.cos_delta);
            }
        }
        (n * lobe.ln_peak).exp() * 0.5 * lobe.a * len * sum
    }

    /// Specular integral `∫_{δa}^{δb} F dδ` (unscaled) for `n ≥ 10`; `cos_a = cos 2δa`,
    /// `cos_b = cos 2δb`.
    fn spec_lobe(
        &self,
        wo: &Vec3,
        wi: &Vec3,
        a: f64,
        cos_delta: f64,
        ends: [(f64, f64); 2],
    ) -> f64 {
        let b = -wo.x * wi.x;
        if !(a + b > 0.0) {
            return 0.0;
        }
        let u_tail = ((a + b) * self.tail_factor - b) / a;
        let lobe = Lobe {
            a,
            b,
            cos_delta,
            ln_peak: (a + b).ln(),
            u_root: -b / a,
            u_whole: if u_tail > -1.0 {
                u_tail
            } else {
                f64::NEG_INFINITY
            },
        };
        let [(da, cos_a), (db, cos_b)] = ends;
        if da < 0.0 && db > 0.0 {
            // The range contains the peak: two half-lobes.
            let mut whole = None;
            self.half_lobe(&lobe, cos_b, db, &mut whole)
                + self.half_lobe(&lobe, cos_a, -da, &mut whole)
        } else {
            // One flank [l1, l2] of the lobe, integrated directly (a difference of half-lobes
            // would cancel); beyond the tail point the lobe is negligible.
            let (l1, l2) = if da >= 0.0 { (da, db) } else { (-db, -da) };
            let tail = if lobe.u_whole > -1.0 {
                0.5 * lobe.u_whole.acos()
            } else {
                FRAC_PI_2
            };
            let hi = l2.min(tail);
            if hi > l1 {
                self.lobe_piece_in_delta(&lobe, l1, hi)
            } else {
                0.0
            }
        }
    }

    /// Symmetries and energy: anisotropic (cylinders along x) but half-turn symmetric,
    /// reciprocal; conserves energy iff `kd + ks ≤ 1`.
    pub fn properties(&self) -> Properties {
        Properties::HALF_TURN_SYMMETRIC
            | Properties::RECIPROCAL
            | Properties::CONSERVES_ENERGY.when(self.params.kd + self.params.ks <= 1.0)
    }
}

impl Brdf for PoulinFournier {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        // |ω_yz| ≥ ω_z > 0, so the plain square root cannot overflow or vanish.
        let ro = (wo.y * wo.y + wo.z * wo.z).sqrt();
        let ri = (wi.y * wi.y + wi.z * wi.z).sqrt();
        let (psi_o, psi_i) = (wo.y.atan2(wo.z), wi.y.atan2(wi.z));
        let (lo_o, hi_o) = self.visible_range(wo, psi_o, ro);
        let (lo_i, hi_i) = self.visible_range(wi, psi_i, ri);
        let (g0, g1) = (lo_o.max(lo_i), hi_o.min(hi_i));
        if !(g1 > g0) {
            return 0.0;
        }
        // Diffuse: ∫ (n·ωi)(n·ωo) dγ = (A/2) ∫ (cos2δ + cosΔ) dγ with n·ω = |ω_yz| cos(γ − ψ).
        let a = ri * ro;
        let cos_delta = (wo.y * wi.y + wo.z * wi.z) / a;
        let mid = 0.5 * (psi_o + psi_i);
        let (da, db) = (g0 - mid, g1 - mid);
        let (sin_a, cos_a) = (2.0 * da).sin_cos();
        let (sin_b, cos_b) = (2.0 * db).sin_cos();
        let diffuse =
            self.params.kd * FRAC_1_PI * a * 0.5 * ((g1 - g0) * cos_delta + 0.5 * (sin_b - sin_a));
        let mut spec = 0.0;
        if self.params.ks > 0.0 {
            spec = if self.lobe_rule.is_some() {
                self.spec_scale * self.spec_lobe(wo, wi, a, cos_delta, [(da, cos_a), (db, cos_b)])
            } else {
                self.spec_panels(wo, wi, g0, g1)
            };
        }
        ((diffuse + spec) / (self.params.d * wi.z * wo.z)).max(0.0)
    }
    brdf_properties!(NAME);
    /// Grey: the default `eval_rgb`, `[eval; 3]`.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        Some([1.0; 3])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mirror;
    use crate::test_support::compare_to_reference;

    /// The implementation before the speed work (12-point Gauss–Legendre panels split at
    /// `atan2(s_y, s_z)` and ± the lobe width, for every exponent), the reference for the
    /// comparison tests. The panel rule itself is the model's own
    /// [`spec_panels`](PoulinFournier::spec_panels), which still serves exponents below 10;
    /// the visibility angles keep their original trigonometric form.
    struct PreOptimisationReference {
        model: PoulinFournier,
    }

    impl PreOptimisationReference {
        fn new(params: PoulinFournierParams) -> Self {
            Self {
                model: PoulinFournier::new(params).unwrap(),
            }
        }

        fn params(&self) -> &PoulinFournierParams {
            self.model.params()
        }

        fn visible_range(&self, w: &Vec3) -> (f64, f64) {
            let psi = w.y.atan2(w.z);
            let a = psi.abs();
            let d = self.params().d;
            let up1 = (d * a.cos() - 1.0).clamp(-1.0, 1.0).asin();
            let up2 = (d * a.sin()).clamp(-1.0, 1.0).acos();
            let upper = if up1 >= -up2 { up1.max(up2) } else { up1 }.min(FRAC_PI_2);
            if psi >= 0.0 {
                (psi - FRAC_PI_2, psi + upper)
            } else {
                (psi - upper, psi + FRAC_PI_2)
            }
        }

        /// The cylinder angles `[γ0, γ1]` seen from both directions, `None` when either is
        /// below the horizon or the range is empty.
        fn common_range(&self, wo: &Vec3, wi: &Vec3) -> Option<(f64, f64)> {
            if !both_above(wo, wi) {
                return None;
            }
            let (lo_o, hi_o) = self.visible_range(wo);
            let (lo_i, hi_i) = self.visible_range(wi);
            let (g0, g1) = (lo_o.max(lo_i), hi_o.min(hi_i));
            (g1 > g0).then_some((g0, g1))
        }

        fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            let Some((g0, g1)) = self.common_range(wo, wi) else {
                return 0.0;
            };
            let (ri, psi_i) = (wi.y.hypot(wi.z), wi.y.atan2(wi.z));
            let (ro, psi_o) = (wo.y.hypot(wo.z), wo.y.atan2(wo.z));
            let prim =
                |g: f64| 0.5 * (g * (psi_i - psi_o).cos() + 0.5 * (2.0 * g - psi_i - psi_o).sin());
            let diffuse = self.params().kd * FRAC_1_PI * ri * ro * (prim(g1) - prim(g0));
            let spec = if self.params().ks > 0.0 {
                self.model.spec_panels(wo, wi, g0, g1)
            } else {
                0.0
            };
            ((diffuse + spec) / (self.params().d * wi.z * wo.z)).max(0.0)
        }

        /// The same integral by a composite 16-point Gauss–Legendre rule, 8 panels per
        /// segment, segments split at the lobe peak `(ψo + ψi)/2`, at the roots of `r·ωi` and
        /// at the peak ± 2^j lobe widths (accurate to ~10⁻¹⁴ for every exponent).
        fn brute_force(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            let Some((g0, g1)) = self.common_range(wo, wi) else {
                return 0.0;
            };
            let p = *self.params();
            let cosio = wo.dot(wi);
            let integrand = |g: f64| {
                let (sg, cg) = g.sin_cos();
                let no = sg * wo.y + cg * wo.z;
                let ni = sg * wi.y + cg * wi.z;
                let c = 2.0 * no * ni - cosio;
                let spec = if c > 0.0 {
                    self.model.spec_scale * c.powf(p.n)
                } else {
                    0.0
                };
                (p.kd * FRAC_1_PI + spec) * no.max(0.0) * ni.max(0.0)
            };
            let (ro, ri) = (wo.y.hypot(wo.z), wi.y.hypot(wi.z));
            let gh = 0.5 * (wo.y.atan2(wo.z) + wi.y.atan2(wi.z));
            let (a, b) = (ro * ri, -wo.x * wi.x);
            let mut cuts = vec![g0, g1, gh];
            if (-b / a).abs() < 1.0 {
                let root = 0.5 * (-b / a).acos();
                cuts.extend([gh - root, gh + root]);
            }
            let width = 0.5 / (p.n + 1.0).sqrt();
            for j in -3..8 {
                let off = width * 2f64.powi(j);
                cuts.extend([gh - off, gh + off]);
            }
            let mut cuts: Vec<f64> = cuts.into_iter().map(|c| c.clamp(g0, g1)).collect();
            cuts.sort_by(|a, b| a.total_cmp(b));
            let gl = GaussLegendre::new(16);
            let mut sum = 0.0;
            for seg in cuts.windows(2) {
                let h = (seg[1] - seg[0]) / 8.0;
                for k in 0..8 {
                    let lo = seg[0] + h * k as f64;
                    sum += gl.integrate(lo, lo + h, integrand);
                }
            }
            (sum / (p.d * wi.z * wo.z)).max(0.0)
        }
    }

    /// [`compare_to_reference`] on 40 × 40 pairs (seed 77).
    fn compare(
        new: impl Fn(&Vec3, &Vec3) -> f64,
        reference: impl Fn(&Vec3, &Vec3) -> f64,
        rel: f64,
        abs: f64,
    ) -> (f64, f64, f64) {
        compare_to_reference(new, reference, (77, 40, 40), rel, abs)
    }

    fn pf(d: f64, n: f64, ks: f64, kd: f64) -> PoulinFournierParams {
        PoulinFournierParams { d, n, ks, kd }
    }

    /// A method of [`PreOptimisationReference`] the model is compared with.
    type Reference = fn(&PreOptimisationReference, &Vec3, &Vec3) -> f64;

    /// [`compare`] the model with `reference` (named `what`) at the parameters `p`: prints the
    /// deviations and asserts they are within `max(rel·|ref|, abs·peak)`.
    fn assert_matches(
        p: PoulinFournierParams,
        reference: Reference,
        what: &str,
        rel: f64,
        abs: f64,
    ) {
        let new = PoulinFournier::new(p).unwrap();
        let old = PreOptimisationReference::new(p);
        let (worst, max_rel, max_abs) = compare(
            |o, i| new.eval(o, i),
            |o, i| reference(&old, o, i),
            rel,
            abs,
        );
        eprintln!(
            "{p:?}: vs {what} worst/allowed {worst:.2e}, max rel {max_rel:.2e}, max abs/peak {max_abs:.2e}"
        );
        assert!(worst <= 1.0, "{p:?}: off {what} by {worst} × the tolerance");
    }

    /// Parameter sets where the pre-optimisation quadrature is itself accurate to the
    /// tolerance (it is not for e.g. n = 10: 2·10⁻¹¹ of the peak, or n → 0 and n = 10⁴).
    #[test]
    fn optimised_eval_matches_pre_optimisation_reference() {
        for p in [
            PoulinFournierParams::default(),
            pf(3.0, 100.0, 0.6, 0.4),
            pf(2.0, 50.0, 0.9, 0.1),
            pf(100.0, 40.0, 0.9, 0.1),
        ] {
            assert_matches(p, PreOptimisationReference::eval, "reference", 1e-9, 1e-12);
        }
    }

    /// Gauss–Jacobi evaluation (n ≥ 10) against the brute-force integral, including large
    /// exponents where the pre-optimisation panels missed the lobe.
    #[test]
    fn lobe_quadrature_matches_brute_force_integral() {
        for p in [
            PoulinFournierParams::default(),
            pf(2.0, 10.0, 1.0, 0.0),
            pf(3.0, 100.0, 1.0, 0.0),
            pf(2.0, 1e4, 1.0, 0.0),
            pf(100.0, 1000.0, 0.5, 0.5),
            pf(2.2, 13.7, 1.0, 0.0),
        ] {
            let brute_force = PreOptimisationReference::brute_force;
            assert_matches(p, brute_force, "brute force", 1e-10, 1e-13);
        }
    }

    /// Special geometries: normal incidence, directions in the (x, z) and (y, z) planes,
    /// mirror and retro-reflection pairs, grazing directions.
    #[test]
    fn lobe_quadrature_handles_special_geometries() {
        let dirs: Vec<Vec3> = [
            (0.0, 0.0),
            (30.0, 0.0),
            (30.0, 180.0),
            (60.0, 90.0),
            (60.0, 270.0),
            (45.0, 45.0),
            (89.0, 0.0),
            (89.0, 90.0),
            (89.0, 135.0),
            (10.0, 300.0),
        ]
        .iter()
        .map(|&(t, p)| crate::geometry::direction_from_angles(t, p))
        .collect();
        for p in [
            PoulinFournierParams::default(),
            pf(2.0, 1e4, 1.0, 0.0),
            pf(3.0, 10.0, 1.0, 0.0),
        ] {
            let new = PoulinFournier::new(p).unwrap();
            let old = PreOptimisationReference::new(p);
            for wo in &dirs {
                let peak = dirs
                    .iter()
                    .chain([mirror(wo)].iter())
                    .map(|wi| old.brute_force(wo, wi))
                    .fold(0.0, f64::max);
                for wi in dirs.iter().chain([mirror(wo), *wo].iter()) {
                    let (v, r) = (new.eval(wo, wi), old.brute_force(wo, wi));
                    assert!(
                        (v - r).abs() <= (1e-10 * r).max(1e-13 * peak),
                        "{p:?} {wo:?} {wi:?}: {v} vs {r}"
                    );
                }
            }
        }
    }

    /// Allowance of the panel rule (exponents below 10) against the brute-force integral.
    const SMALL_EXPONENT_REL: f64 = 1e-5;
    /// Allowance relative to the peak, for values near zero.
    const SMALL_EXPONENT_ABS: f64 = 1e-6;

    /// Exponents below 10 keep the panel rule: same values as before (up to rounding in the
    /// visibility angles).
    #[test]
    fn small_exponents_keep_the_panel_rule() {
        for p in [
            pf(2.0, 0.0, 1.0, 0.0),
            pf(2.0, 3.7, 0.6, 0.4),
            pf(5.0, 9.5, 1.0, 0.0),
        ] {
            assert_matches(p, PreOptimisationReference::eval, "reference", 1e-9, 1e-12);
            // The reference shares the panel rule, so check the rule itself independently (not
            // at n = 0, where the lobe is a step at `r·ωi = 0` that 12-point panels resolve only
            // to ~10⁻¹ of the peak).
            if p.n > 0.0 {
                let (rel, abs) = (SMALL_EXPONENT_REL, SMALL_EXPONENT_ABS);
                assert_matches(
                    p,
                    PreOptimisationReference::brute_force,
                    "brute force",
                    rel,
                    abs,
                );
            }
        }
    }

    /// The brute-force comparison must be able to fail: cutting the lobe tail at e^{−12}
    /// instead of e^{−37} is detected.
    #[test]
    fn comparison_catches_a_truncated_lobe() {
        let p = PoulinFournierParams::default();
        let mut broken = PoulinFournier::new(p).unwrap();
        broken.tail_factor = (-12.0 / p.n).exp();
        let old = PreOptimisationReference::new(p);
        let (worst, _, _) = compare(
            |o, i| broken.eval(o, i),
            |o, i| old.brute_force(o, i),
            1e-10,
            1e-13,
        );
        assert!(worst > 1.0, "broken variant not detected ({worst})");
    }

    #[test]
    fn gauss_jacobi_integrates_jacobi_polynomial_moments() {
        // ∫_{-1}^{1} (1−x)^{−1/2} (1+x)^β x^k dx / ∫ (1−x)^{−1/2} (1+x)^β dx for k ≤ 2N−1
        // against a brute-force substitution x = 1 − 2 t², t ∈ [0, 1].
        for beta in [0.0, 10.0, 123.4] {
            let rule = gauss_jacobi(8, -0.5, beta);
            let gl = GaussLegendre::new(64);
            let moment = |k: i32| {
                let f = |t: f64| {
                    let x = 1.0 - 2.0 * t * t;
                    (1.0 + x).powf(beta) * x.powi(k)
                };
                gl.integrate(0.0, 0.5, f) + gl.integrate(0.5, 1.0, f)
            };
            let m0 = moment(0);
            for k in 0..16 {
                let q: f64 = rule
                    .s
                    .iter()
                    .zip(&rule.weight)
                    .map(|(s, w)| w * (1.0 - 2.0 * s).powi(k))
                    .sum();
                let exact = moment(k) / m0;
                assert!((q - exact).abs() < 1e-12, "β={beta} k={k}: {q} vs {exact}");
            }
        }
    }

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
                let (lo, hi) = pf.visible_range(&w, w.y.atan2(w.z), w.y.hypot(w.z));
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
