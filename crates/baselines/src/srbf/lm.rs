//! Joint refinement of an SRBF mixture by a bound-constrained Levenberg–Marquardt method on the
//! weighted residuals (the fit is a nonlinear least-squares problem; baselines.md §C.2).
//!
//! Residuals `r_i = √A_i (Σ_k c_k G_ik − f_i) / √(Σ A f²)`, so `‖r‖²` is the squared relative
//! L2 error. Four parameters per lobe: the amplitude `c ≥ 0` (the model is linear in it), the
//! log-bandwidth `ℓ = ln λ ∈ [ln λ_min, ln λ_max]` and two tangent-plane coordinates `(u, w)` of
//! the axis, `ξ' = normalize(ξ + u t₁ + w t₂)`, re-centred after every accepted step (no gauge
//! freedom, unlike `ξ = v/‖v‖`). Bounds by an active set: a variable at a bound whose gradient
//! points out of the box is held for the iteration, the others take the damped Gauss–Newton
//! step `(H + μ D) δ = −g` (`H = JᵀJ`, `g = Jᵀr`, `D = diag H`: Marquardt's scale-free damping)
//! and are clamped to the box; `μ` follows Nielsen's gain-ratio rule.
//!
//! Convergence is scale-free: the reduction of `‖r‖²` the linearised model predicts for the
//! undamped Gauss–Newton step over the free variables, `gᵀH⁻¹g`, is at most [`GN_TOL`] of
//! `‖r‖²` — the squared cosine between the residual and the span of the Jacobian's free
//! columns, invariant to the scale of the target and of every parameter (or: the cost is zero
//! to rounding, or no step, however damped, lowers it in f64). A fit that has not met it at
//! the iteration cap is reported as not converged.

use brdf::Vec3;
use nalgebra::{DMatrix, DVector};

use super::target::FitTarget;
use super::vmf::SgLobe;

/// Convergence threshold on `gᵀH⁻¹g / ‖r‖²` (see the module docs): the linear model promises
/// at most this relative decrease of the squared error, i.e. the relative L2 error can fall by
/// at most half of it (0.005 %). Measured on nine slices of `phong:n=50`: the squared error at
/// 10⁻⁴ is within 0.04 % of that at 10⁻⁸, for 1.5–7× fewer steps.
pub(crate) const GN_TOL: f64 = 1e-4;

/// Parameters per lobe.
const P: usize = 4;

/// The result of a refinement.
#[derive(Debug, Clone)]
pub(crate) struct Refined {
    /// The lobes at the last accepted step.
    pub(crate) lobes: Vec<SgLobe>,
    /// Trial steps run (accepted or not).
    pub(crate) iterations: usize,
    /// Whether the scale-free test was met before the cap.
    pub(crate) converged: bool,
}

/// An orthonormal pair spanning the plane orthogonal to unit `n` (Duff et al. 2017).
fn tangents(n: &Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

struct Lm<'a> {
    target: &'a FitTarget,
    /// `√A_i / √(Σ A f²)`.
    scale: Vec<f64>,
    lambda_min: f64,
    lambda_max: f64,
    log_min: f64,
    log_max: f64,
}

/// Below this exponent `λ(η·ξ − 1)` a lobe's value `e^{λ(η·ξ−1)} < e^{−40} ≈ 4·10⁻¹⁸` is taken
/// as 0 (and its `exp` not evaluated): a relative change below f64 rounding of the model at
/// any point a broader lobe or the target reaches, and it spares most `exp`s of narrow lobes.
const EXP_CUTOFF: f64 = -40.0;

impl Lm<'_> {
    /// The target's points: direction `η_i`, value `f_i` and residual scale `s_i`.
    fn points(&self) -> impl Iterator<Item = (&Vec3, f64, f64)> {
        let t = self.target;
        t.directions()
            .iter()
            .zip(t.values())
            .zip(&self.scale)
            .map(|((d, &f), &s)| (d, f, s))
    }

    /// `‖r‖²` of `lobes`, storing `s_i e^{λ_k(η_i·ξ_k − 1)}` (row-major, `K` per point) in
    /// `cache` for [`Self::normal_equations`] (so each `exp` is evaluated once per point and
    /// trial step, not again for the accepted step's normal equations).
    fn cost(&self, lobes: &[SgLobe], cache: &mut Vec<f64>) -> f64 {
        let t = self.target;
        let k = lobes.len();
        cache.clear();
        cache.resize(k * t.len(), 0.0);
        let mut cost = 0.0;
        for ((d, f, s), row) in self.points().zip(cache.chunks_exact_mut(k.max(1))) {
            let mut model = 0.0;
            for (l, e) in lobes.iter().zip(row.iter_mut()) {
                let arg = l.lambda * (d.dot(&l.axis) - 1.0);
                if arg >= EXP_CUTOFF {
                    *e = s * arg.exp();
                    model += l.amplitude * *e;
                }
            }
            let r = model - s * f;
            cost += r * r;
        }
        cost
    }

    /// `‖r‖²`, `H = JᵀJ` and `g = Jᵀr` at `lobes`, parameters `(c, ln λ, u, w)` per lobe with
    /// `u = w = 0` at the current axes, from the `cache` that [`Self::cost`] filled for the
    /// same `lobes`. `J` is never formed: each point adds its row's rank-1 update to the upper
    /// triangle of `H`, over the lobes that reach it only (a lobe below [`EXP_CUTOFF`] there
    /// has a zero row block), and the lower triangle is mirrored at the end.
    fn normal_equations(
        &self,
        lobes: &[SgLobe],
        frames: &[(Vec3, Vec3)],
        cache: &[f64],
    ) -> (f64, DMatrix<f64>, DVector<f64>) {
        let k = lobes.len();
        let n = P * k;
        // Column-major `n × n` (nalgebra's layout); entry (p, q) at `p + n q`, filled for p ≤ q.
        let mut h = vec![0.0; n * n];
        let mut g = vec![0.0; n];
        let mut idx: Vec<usize> = Vec::with_capacity(n);
        let mut val: Vec<f64> = Vec::with_capacity(n);
        let mut cost = 0.0;
        for ((d, f, s), row) in self.points().zip(cache.chunks_exact(k.max(1))) {
            idx.clear();
            val.clear();
            let mut r = -s * f;
            for (j, ((l, (t1, t2)), &sg)) in lobes.iter().zip(frames).zip(row).enumerate() {
                if sg == 0.0 {
                    continue;
                }
                r += l.amplitude * sg;
                let clg = sg * l.amplitude * l.lambda;
                idx.extend([P * j, P * j + 1, P * j + 2, P * j + 3]);
                val.extend([
                    sg,
                    clg * (d.dot(&l.axis) - 1.0),
                    clg * d.dot(t1),
                    clg * d.dot(t2),
                ]);
            }
            cost += r * r;
            for (a, (&p, &vp)) in idx.iter().zip(&val).enumerate() {
                g[p] += vp * r;
                let col = &mut h[n * p..n * p + n];
                // Upper triangle by columns: entries (q, p) for q ≤ p, i.e. the first `a + 1`
                // active indices.
                for (&q, &vq) in idx[..=a].iter().zip(&val[..=a]) {
                    col[q] += vq * vp;
                }
            }
        }
        for p in 0..n {
            for q in 0..p {
                h[p + n * q] = h[q + n * p];
            }
        }
        (cost, DMatrix::from_vec(n, n, h), DVector::from_vec(g))
    }

    /// Whether variable `i` (of lobe `i / P`) is held at a bound this iteration.
    fn held(&self, lobes: &[SgLobe], g: &DVector<f64>, i: usize) -> bool {
        let l = &lobes[i / P];
        match i % P {
            0 => l.amplitude <= 0.0 && g[i] >= 0.0,
            // A lobe at c = 0 has no bandwidth or axis derivative.
            _ if l.amplitude <= 0.0 => true,
            1 => {
                let ll = l.lambda.ln();
                (ll <= self.log_min && g[i] >= 0.0) || (ll >= self.log_max && g[i] <= 0.0)
            }
            _ => false,
        }
    }

    /// Solves `(H_ff + μ D_ff) δ = −g_f` over the free variables; `None` if not positive definite.
    fn solve(h: &DMatrix<f64>, g: &DVector<f64>, free: &[usize], mu: f64) -> Option<DVector<f64>> {
        let m = free.len();
        let max_diag = free.iter().map(|&i| h[(i, i)]).fold(0.0, f64::max);
        let floor = 1e-12 * max_diag.max(f64::MIN_POSITIVE);
        let mut a = DMatrix::<f64>::zeros(m, m);
        let mut b = DVector::<f64>::zeros(m);
        for (p, &i) in free.iter().enumerate() {
            b[p] = -g[i];
            for (q, &j) in free.iter().enumerate() {
                a[(p, q)] = h[(i, j)];
            }
            a[(p, p)] += mu * h[(i, i)].max(floor);
        }
        let x = a.cholesky()?.solve(&b);
        x.iter().all(|v| v.is_finite()).then_some(x)
    }

    /// The lobes after step `delta` (over the free variables), clamped to the box, and the
    /// step actually taken (full length, zero where held or clamped away).
    fn step(
        &self,
        lobes: &[SgLobe],
        frames: &[(Vec3, Vec3)],
        free: &[usize],
        delta: &DVector<f64>,
    ) -> (Vec<SgLobe>, DVector<f64>) {
        let mut full = DVector::<f64>::zeros(P * lobes.len());
        for (p, &i) in free.iter().enumerate() {
            full[i] = delta[p];
        }
        let mut taken = full.clone();
        let out = lobes
            .iter()
            .zip(frames)
            .enumerate()
            .map(|(k, (l, (t1, t2)))| {
                let c = (l.amplitude + full[P * k]).max(0.0);
                taken[P * k] = c - l.amplitude;
                let ll0 = l.lambda.ln();
                let ll = (ll0 + full[P * k + 1]).clamp(self.log_min, self.log_max);
                taken[P * k + 1] = ll - ll0;
                let v = l.axis + t1 * full[P * k + 2] + t2 * full[P * k + 3];
                SgLobe {
                    amplitude: c,
                    // At a bound exactly the bound (so `held` sees `ln λ` at it).
                    lambda: if ll <= self.log_min {
                        self.lambda_min
                    } else if ll >= self.log_max {
                        self.lambda_max
                    } else {
                        ll.exp().clamp(self.lambda_min, self.lambda_max)
                    },
                    axis: v / v.norm(),
                }
            })
            .collect();
        (out, taken)
    }
}

/// Refines `lobes` on `target` (bandwidths in `[lambda_min, lambda_max]`) by at most `max_iter`
/// Levenberg–Marquardt iterations (see the module docs).
pub(crate) fn refine(
    target: &FitTarget,
    lobes: &[SgLobe],
    lambda_min: f64,
    lambda_max: f64,
    max_iter: usize,
    tol: f64,
) -> Refined {
    let norm: f64 = target
        .values()
        .iter()
        .zip(target.weights())
        .map(|(f, a)| a * f * f)
        .sum();
    let inv = 1.0 / norm.sqrt();
    let lm = Lm {
        target,
        scale: target.weights().iter().map(|a| a.sqrt() * inv).collect(),
        lambda_min,
        lambda_max,
        log_min: lambda_min.ln(),
        log_max: lambda_max.ln(),
    };
    let mut lobes: Vec<SgLobe> = lobes
        .iter()
        .map(|l| SgLobe {
            lambda: l.lambda.clamp(lambda_min, lambda_max),
            ..*l
        })
        .collect();
    let mut mu = 1e-3;
    let mut nu = 2.0;
    let mut iterations = 0;
    let mut converged = false;
    let mut fresh = true;
    let (mut cost, mut h, mut g) = (0.0, DMatrix::zeros(0, 0), DVector::zeros(0));
    let mut frames: Vec<(Vec3, Vec3)> = Vec::new();
    let mut free: Vec<usize> = Vec::new();
    // The `exp`s of the current lobes (see `Lm::cost`) and of the last trial.
    let mut cache = Vec::new();
    let mut trial_cache = Vec::new();
    lm.cost(&lobes, &mut cache);
    loop {
        if fresh {
            frames = lobes.iter().map(|l| tangents(&l.axis)).collect();
            (cost, h, g) = lm.normal_equations(&lobes, &frames, &cache);
            free = (0..g.len()).filter(|&i| !lm.held(&lobes, &g, i)).collect();
            // The scale-free test: the undamped model's best decrease, relative to the cost.
            let gn = Lm::solve(&h, &g, &free, 1e-10);
            let promised = gn.map_or(f64::INFINITY, |d| {
                -free
                    .iter()
                    .enumerate()
                    .map(|(p, &i)| g[i] * d[p])
                    .sum::<f64>()
            });
            // `cost ≤ 10⁻²⁴`: a relative L2 error of 10⁻¹², exact to rounding.
            if cost <= 1e-24 || free.is_empty() || promised <= tol * cost {
                converged = true;
                break;
            }
            fresh = false;
        }
        if mu > 1e16 {
            // Not even a step of relative length ~10⁻¹⁶ lowers the cost: a minimum to f64
            // precision.
            converged = true;
            break;
        }
        if iterations >= max_iter {
            break;
        }
        iterations += 1;
        let Some(delta) = Lm::solve(&h, &g, &free, mu) else {
            mu *= nu;
            nu *= 2.0;
            continue;
        };
        let (trial, taken) = lm.step(&lobes, &frames, &free, &delta);
        // Predicted decrease of the linear model for the step taken: −(2gᵀδ + δᵀHδ).
        let predicted = -(2.0 * g.dot(&taken) + taken.dot(&(&h * &taken)));
        let trial_cost = lm.cost(&trial, &mut trial_cache);
        let rho = (cost - trial_cost) / predicted;
        if trial_cost.is_finite() && trial_cost < cost && predicted > 0.0 && rho > 0.0 {
            lobes = trial;
            std::mem::swap(&mut cache, &mut trial_cache);
            mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            nu = 2.0;
            fresh = true;
        } else {
            mu *= nu;
            nu *= 2.0;
        }
    }
    Refined {
        lobes,
        iterations,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::srbf::fit::tests::{sphere_target, two_lobes};

    #[test]
    fn accumulated_normal_equations_equal_the_explicit_jacobian_products() {
        // Three lobes, one narrow (λ = 400: most points below the exp cutoff) and one at
        // c = 0, on a target unlike the model, so every block of H and g is exercised.
        let target = sphere_target(|d| 0.3 + (d.z + d.x).max(0.0).powi(3), 48, 24);
        let lobes = [
            SgLobe {
                axis: Vec3::new(0.0, 0.6, 0.8),
                lambda: 400.0,
                amplitude: 2.0,
            },
            SgLobe {
                axis: Vec3::new(-0.8, 0.0, 0.6),
                lambda: 3.0,
                amplitude: 0.5,
            },
            SgLobe {
                axis: Vec3::new(0.0, 0.0, 1.0),
                lambda: 10.0,
                amplitude: 0.0,
            },
        ];
        let lm = Lm {
            target: &target,
            scale: target.weights().iter().map(|a| a.sqrt()).collect(),
            lambda_min: 0.5,
            lambda_max: 1e3,
            log_min: 0.5f64.ln(),
            log_max: 1e3f64.ln(),
        };
        let frames: Vec<(Vec3, Vec3)> = lobes.iter().map(|l| tangents(&l.axis)).collect();
        // The explicit Jacobian, every entry by its formula (no cutoff).
        let n = P * lobes.len();
        let mut jac = DMatrix::<f64>::zeros(target.len(), n);
        let mut r = DVector::<f64>::zeros(target.len());
        for (i, ((d, &f), &s)) in target
            .directions()
            .iter()
            .zip(target.values())
            .zip(&lm.scale)
            .enumerate()
        {
            r[i] = -s * f;
            for (k, (l, (t1, t2))) in lobes.iter().zip(&frames).enumerate() {
                let cos = d.dot(&l.axis);
                let sg = s * (l.lambda * (cos - 1.0)).exp();
                r[i] += l.amplitude * sg;
                let clg = sg * l.amplitude * l.lambda;
                jac[(i, P * k)] = sg;
                jac[(i, P * k + 1)] = clg * (cos - 1.0);
                jac[(i, P * k + 2)] = clg * d.dot(t1);
                jac[(i, P * k + 3)] = clg * d.dot(t2);
            }
        }
        let (h_ref, g_ref) = (jac.tr_mul(&jac), jac.tr_mul(&r));
        let mut cache = Vec::new();
        let cost = lm.cost(&lobes, &mut cache);
        let (cost2, h, g) = lm.normal_equations(&lobes, &frames, &cache);
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
        assert!(
            rel(cost, r.norm_squared()) < 1e-12,
            "{cost} vs {}",
            r.norm_squared()
        );
        assert!(rel(cost2, r.norm_squared()) < 1e-12);
        let h_scale = h_ref.amax();
        for p in 0..n {
            assert!(
                (g[p] - g_ref[p]).abs() <= 1e-12 * g_ref.amax(),
                "g[{p}]: {} vs {}",
                g[p],
                g_ref[p]
            );
            for q in 0..n {
                assert!(
                    (h[(p, q)] - h_ref[(p, q)]).abs() <= 1e-12 * h_scale,
                    "H[{p},{q}]: {} vs {}",
                    h[(p, q)],
                    h_ref[(p, q)]
                );
            }
        }
        // The narrow lobe's block is not trivially zero (the cutoff keeps its support).
        assert!(h_ref[(0, 0)] > 1e-6 * h_scale);
    }

    #[test]
    fn recovers_a_mixture_from_a_perturbed_start_and_holds_bounds() {
        let truth = two_lobes([40.0, 4.0]);
        let target = sphere_target(|d| truth.iter().map(|l| l.eval(d)).sum(), 96, 48);
        let start: Vec<SgLobe> = truth
            .iter()
            .map(|l| SgLobe {
                axis: (l.axis + Vec3::new(0.1, -0.05, 0.05)).normalize(),
                lambda: 0.5 * l.lambda,
                amplitude: 1.5 * l.amplitude,
            })
            .collect();
        let r = refine(&target, &start, 0.5, 1e3, 200, GN_TOL);
        assert!(r.converged && r.iterations < 100, "{r:?}");
        assert!(target.errors(&r.lobes).0 < 1e-6, "{r:?}");
        for (l, t) in r.lobes.iter().zip(&truth) {
            assert!(
                (l.lambda - t.lambda).abs() < 1e-4 * t.lambda,
                "{l:?} vs {t:?}"
            );
            assert!(l.axis.dot(&t.axis) > 1.0 - 1e-9, "{l:?} vs {t:?}");
        }
        // The same target with the bandwidth capped below the narrow lobe's 40: it ends at the
        // cap, held there, and the fit still converges (to the best capped mixture).
        let r = refine(&target, &start, 0.5, 20.0, 200, GN_TOL);
        assert!(r.converged, "{r:?}");
        assert!(r.lobes.iter().all(|l| l.lambda <= 20.0 && l.lambda >= 0.5));
        assert!(r.lobes.iter().any(|l| l.lambda == 20.0), "{r:?}");
        // An iteration cap too small to converge is reported as such.
        let r = refine(&target, &start, 0.5, 1e3, 2, GN_TOL);
        assert!(!r.converged && r.iterations == 2, "{r:?}");
    }
}
