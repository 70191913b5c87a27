//! The per-slice fit of the lobe's exponent and defensive weight.
//!
//! For one outgoing direction `ωo`, with `g(ω) = f_r(ωo, ω)·max(0, cos θ)` (luminance for RGB),
//! the estimator `g/p` of `∫_Ω g dσ` has second moment `M(n, w) = ∫_Ω g²/p dσ` for the mixture
//! `p = w·cos⁺θ/π + (1−w)·L_n/A` (`A = 1` on the sphere, the exact above-horizon mass on Ω).
//! `M` is evaluated by a fixed quadrature of the sphere in lobe coordinates `(α, φ)` about the
//! mirror direction: `α ∈ [0, π]` on geometrically graded Gauss–Legendre panels (finest
//! `0.25/√(1+n_max)`, so the narrowest admissible lobe is resolved), `φ` on a 64-point
//! midpoint rule. The exponent is searched over `s = ln(1+n)`: a 17-point scan, then a
//! golden-section refinement between the best point's neighbours; for each `n` the weight
//! `w ∈ [w_min, 1]` minimises `M` (convex in `w`) by golden section.

use std::f64::consts::{FRAC_1_PI, PI, TAU};

use brdf::quadrature::GaussLegendre;
use brdf::{Brdf, Vec3, mirror};

use super::cosine_lobe::{MASS_NODES, above_horizon_mass, tangents};

/// Azimuthal nodes of the fit quadrature.
const PHI_NODES: usize = 64;
/// Gauss–Legendre nodes per α panel.
const ALPHA_NODES: usize = 6;
/// Points of the exponent scan.
const SCAN_POINTS: usize = 17;
/// Golden-section iterations of the exponent refinement (bracket shrinks by 0.618¹⁸ ≈ 2·10⁻⁴).
const EXPONENT_ITERATIONS: usize = 18;
/// Golden-section iterations of the defensive weight (to ≈ 5·10⁻⁴).
const WEIGHT_ITERATIONS: usize = 16;

/// One quadrature point with `g > 0`: `W·g²`, `ln(r·ω)` (`−∞` outside the lobe), `cos⁺θ/π`.
struct Point {
    weighted_g2: f64,
    ln_c: f64,
    cosine: f64,
}

/// The second moment `M(n, w)` of one slice.
pub(crate) struct SecondMoment {
    points: Vec<Point>,
    /// Polar angle of the mirror direction (radians), for the above-horizon mass.
    theta_r: f64,
    /// Whether the lobe is renormalised over Ω (`lobe-hemisphere`).
    truncated: bool,
}

impl SecondMoment {
    /// Tabulates `g` of `brdf` at `wo` on the fit quadrature (finest α panel `0.25/√(1+n_max)`).
    pub(crate) fn new(brdf: &dyn Brdf, wo: &Vec3, max_exponent: f64, truncated: bool) -> Self {
        let r = mirror(wo);
        let (t, b) = tangents(&r);
        let gl = GaussLegendre::new(ALPHA_NODES);
        let mut edges = vec![0.0];
        let mut e = 0.25 / (1.0 + max_exponent).sqrt();
        while e < PI {
            edges.push(e);
            e *= 2.0;
        }
        edges.push(PI);
        let mut points = Vec::new();
        for pair in edges.windows(2) {
            let (a0, a1) = (pair[0], pair[1]);
            let half = 0.5 * (a1 - a0);
            for (x, wx) in gl.nodes().iter().zip(gl.weights()) {
                let alpha = a0 + half * (1.0 + x);
                let (s, c) = alpha.sin_cos();
                let w_alpha = wx * half * s * TAU / PHI_NODES as f64;
                for j in 0..PHI_NODES {
                    let phi = TAU * (j as f64 + 0.5) / PHI_NODES as f64;
                    let w = t * (s * phi.cos()) + b * (s * phi.sin()) + r * c;
                    if !(w.z > 0.0) {
                        continue;
                    }
                    let g = brdf.eval(wo, &w) * w.z;
                    if g > 0.0 && g.is_finite() {
                        points.push(Point {
                            weighted_g2: w_alpha * g * g,
                            ln_c: if c > 0.0 { c.ln() } else { f64::NEG_INFINITY },
                            cosine: w.z * FRAC_1_PI,
                        });
                    }
                }
            }
        }
        Self {
            points,
            theta_r: r.z.clamp(-1.0, 1.0).acos(),
            truncated,
        }
    }

    /// `M(n, w)` (`+∞` where `g > 0` and `p = 0`).
    pub(crate) fn eval(&self, n: f64, w: f64) -> f64 {
        let mass = if self.truncated {
            above_horizon_mass(self.theta_r, n, MASS_NODES)
        } else {
            1.0
        };
        let ln_scale = ((n + 1.0) / (TAU * mass)).ln();
        self.points
            .iter()
            .map(|p| {
                let lobe = if p.ln_c > f64::NEG_INFINITY {
                    (ln_scale + n * p.ln_c).exp()
                } else {
                    0.0
                };
                p.weighted_g2 / (w * p.cosine + (1.0 - w) * lobe)
            })
            .sum()
    }

    /// The best defensive weight in `[w_min, 1]` for exponent `n`, and `M` there.
    pub(crate) fn best_weight(&self, n: f64, w_min: f64) -> (f64, f64) {
        golden(|w| self.eval(n, w), w_min, 1.0, WEIGHT_ITERATIONS)
    }
}

/// Minimises a unimodal `f` on `[a, b]`; returns `(argmin, min)` (the better endpoint if it
/// beats the interior).
fn golden(f: impl Fn(f64) -> f64, a: f64, b: f64, iterations: usize) -> (f64, f64) {
    let ratio = (5.0_f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (a, b);
    let mut x1 = b - ratio * (b - a);
    let mut x2 = a + ratio * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..iterations {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - ratio * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + ratio * (b - a);
            f2 = f(x2);
        }
    }
    let mut best = if f1 <= f2 { (x1, f1) } else { (x2, f2) };
    for x in [a, b] {
        let fx = f(x);
        if fx < best.1 {
            best = (x, fx);
        }
    }
    best
}

/// The fitted `(exponent, defensive weight, second moment)` of one slice: the exponent over
/// `[n_min, n_max]` (or `fixed`), the weight over `[w_min, 1]`.
pub(crate) fn fit_slice(
    moment: &SecondMoment,
    fixed: Option<f64>,
    n_min: f64,
    n_max: f64,
    w_min: f64,
) -> (f64, f64, f64) {
    let at = |s: f64| {
        let n = s.exp_m1().max(0.0);
        let (w, m) = moment.best_weight(n, w_min);
        (n, w, m)
    };
    if let Some(n) = fixed {
        let (w, m) = moment.best_weight(n, w_min);
        return (n, w, m);
    }
    let (s0, s1) = ((n_min).ln_1p(), (n_max).ln_1p());
    if !(s1 > s0) {
        return at(s0);
    }
    let step = (s1 - s0) / (SCAN_POINTS - 1) as f64;
    let scan: Vec<(f64, f64, f64)> = (0..SCAN_POINTS).map(|i| at(s0 + step * i as f64)).collect();
    let best = (0..SCAN_POINTS)
        .min_by(|&i, &j| scan[i].2.total_cmp(&scan[j].2))
        .unwrap_or(0);
    let lo = s0 + step * best.saturating_sub(1) as f64;
    let hi = (s0 + step * (best + 1) as f64).min(s1);
    let (s, _) = golden(|s| at(s).2, lo, hi, EXPONENT_ITERATIONS);
    let refined = at(s);
    if refined.2 <= scan[best].2 {
        refined
    } else {
        scan[best]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::direction_from_angles;

    /// The second moment of BRDF `spec` at `θo = theta_deg` (`φo = 0`; exponents up to 10⁴,
    /// `truncated` as in [`SecondMoment::new`]) and its [`fit_slice`] with no warm start.
    fn fit_at(spec: &str, theta_deg: f64, truncated: bool) -> (SecondMoment, (f64, f64, f64)) {
        let brdf = brdf::parse_spec(spec).unwrap();
        let wo = direction_from_angles(theta_deg, 0.0);
        let m = SecondMoment::new(brdf.as_ref(), &wo, 1e4, truncated);
        let fit = fit_slice(&m, None, 0.0, 1e4, 0.02);
        (m, fit)
    }

    #[test]
    fn lambert_prefers_the_cosine_component_and_phong_a_lobe_near_its_exponent() {
        let (_, (_, w, _)) = fit_at("lambert", 30.0, false);
        assert!(w > 0.99, "lambert defensive weight {w}");

        // Pure Phong lobe (kd = 0) at normal incidence: g = ks(n+2)/(2π) c^n cosθ, so the best
        // lobe exponent lies near n (cosθ adds about one), and nowhere near the bounds.
        let (_, (n, w, _)) = fit_at("phong:n=50,kd=0,ks=1", 0.0, true);
        assert!((40.0..70.0).contains(&n), "phong exponent {n}");
        assert!(w < 0.1, "phong defensive weight {w}");
    }

    #[test]
    fn second_moment_at_the_optimum_is_not_above_other_choices() {
        let (m, (n, w, best)) = fit_at("ggx:alpha=0.3", 60.0, false);
        assert!((best - m.eval(n, w)).abs() <= 1e-12 * best);
        for (n2, w2) in [
            (0.0, 1.0),
            (1.0, 0.5),
            (10.0, 0.1),
            (100.0, 0.02),
            (1e3, 0.3),
        ] {
            assert!(best <= m.eval(n2, w2) * (1.0 + 1e-9), "{n2} {w2}");
        }
    }
}
