//! Non-negative Gaussian SRBF mixtures fitted to tabulated spherical functions (Tsai et al.
//! 2008 via Tsai & Shih 2006; baselines.md §C.2).
//!
//! Model `f(η) ≈ Σ_k c_k e^{λ_k(η·ξ_k − 1)}`, `c_k ≥ 0`, `λ_k ∈ [λ_min, λ_max]`, unit `ξ_k`;
//! objective the solid-angle-weighted least squares `E = Σ_i A_i (Σ_k c_k G_ik − f_i)²` over the
//! target's sample directions (its quadrature weights `A_i` w.r.t. solid angle).
//!
//! 1. Initial guess: one broad lobe from the target's first moment (mean direction and
//!    concentration), then greedily a lobe at the residual's peak, `λ = ln 2 / (1 − cos α½)` from the
//!    nearest sample below half the peak, `c` by 1D non-negative least squares, subtract, repeat;
//!    then all `c_k` jointly by NNLS (projected coordinate descent on the normal equations).
//! 2. Joint refinement of every parameter: [`fit`] (BRDF slices) by bound-constrained
//!    Levenberg–Marquardt on the weighted residuals ([`super::lm`]), stopped by a scale-free
//!    test; [`fit_lbfgs`] (the map) by L-BFGS ([`super::lbfgs`]) in bound-free parameters:
//!    `c = e^a`, `λ = λ_min + (λ_max − λ_min)·σ(b)`, `ξ = v/‖v‖` (`v ∈ ℝ³`), on
//!    `E / Σ A_i f_i²`, the analytic gradient (§C.2) chained through the reparametrisation (a
//!    test checks it against finite differences). L-BFGS crawled on the slices: near-duplicate
//!    lobes make the problem ill-conditioned, and the README's `phong:n=50` slices were still
//!    improving after 3000 iterations; Levenberg–Marquardt reaches a lower error than that
//!    within 50 (docs/benchmarks.md).

use std::time::Instant;

use brdf::Vec3;

use super::SrbfError;
use super::lbfgs::{Stop, minimise};
use super::vmf::SgLobe;

pub use super::target::FitTarget;

/// Settings of one fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// Number of lobes `K` (≥ 1).
    pub lobes: usize,
    /// Lower bandwidth bound `λ_min > 0`.
    pub lambda_min: f64,
    /// Upper bandwidth bound `λ_max > λ_min`.
    pub lambda_max: f64,
    /// Iteration cap of the refinement (Levenberg–Marquardt trial steps, or L-BFGS iterations).
    pub max_iter: usize,
}

impl FitSettings {
    /// Checks `K ≥ 1`, `0 < λ_min < λ_max < ∞`.
    pub fn validate(&self, what: &'static str) -> Result<(), SrbfError> {
        if self.lobes == 0 {
            return Err(SrbfError::ZeroLobes { what });
        }
        if !(self.lambda_min > 0.0
            && self.lambda_max > self.lambda_min
            && self.lambda_max.is_finite())
        {
            return Err(SrbfError::BadBandwidth {
                what,
                min: self.lambda_min,
                max: self.lambda_max,
            });
        }
        Ok(())
    }
}

/// Quality and cost of one fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitReport {
    /// Lobes with `c > 0` in the result.
    pub lobes: usize,
    /// Relative L2 error `√(Σ A r² / Σ A f²)` over the target's samples.
    pub rel_l2: f64,
    /// Relative L1 error `Σ A |r| / Σ A f`.
    pub rel_l1: f64,
    /// Relative L2 error of the greedy initial guess (before the refinement).
    pub initial_rel_l2: f64,
    /// Refinement iterations.
    pub iterations: usize,
    /// Whether the refinement met its stopping test before the iteration cap; if not,
    /// `rel_l2` is the residual it reached.
    pub converged: bool,
    /// Wall time of the fit in seconds.
    pub seconds: f64,
}

/// A fitted mixture with its report.
#[derive(Debug, Clone, PartialEq)]
pub struct SrbfFit {
    /// The lobes (`c_k > 0`).
    pub lobes: Vec<SgLobe>,
    /// Its quality and cost.
    pub report: FitReport,
}

/// Fits `settings.lobes` non-negative Gaussian SRBFs to `target`: greedy guess, NNLS, then
/// the joint bound-constrained Levenberg–Marquardt refinement of [`super::lm`] (scale-free
/// convergence test; what the BRDF slices use).
pub fn fit(target: &FitTarget, settings: &FitSettings) -> Result<SrbfFit, SrbfError> {
    fit_with(target, settings, Refiner::LevenbergMarquardt, None)
}

/// [`fit`] warm-started from `start` (e.g. the converged lobes of the neighbouring `θo`
/// slice): the refinement starts from whichever of `start` (bandwidths clamped to the box,
/// amplitudes refitted by NNLS, topped up to `settings.lobes` by greedy residual peaks) and
/// the greedy guess has the lower error on `target`, so it
/// is never started worse than [`fit`] is. An empty `start` is [`fit`].
pub fn fit_from(
    target: &FitTarget,
    settings: &FitSettings,
    start: &[SgLobe],
) -> Result<SrbfFit, SrbfError> {
    fit_with(target, settings, Refiner::LevenbergMarquardt, Some(start))
}

/// [`fit`] with the bound-free L-BFGS refinement instead (the environment map's fit: its 64
/// lobes make the Levenberg–Marquardt normal equations 256 × 256, measured 30× slower there
/// for no better product sampling; docs/benchmarks.md).
pub fn fit_lbfgs(target: &FitTarget, settings: &FitSettings) -> Result<SrbfFit, SrbfError> {
    fit_with(target, settings, Refiner::Lbfgs, None)
}

#[derive(Debug, Clone, Copy)]
enum Refiner {
    LevenbergMarquardt,
    Lbfgs,
}

fn fit_with(
    target: &FitTarget,
    settings: &FitSettings,
    refiner: Refiner,
    warm: Option<&[SgLobe]>,
) -> Result<SrbfFit, SrbfError> {
    settings.validate("fit")?;
    let mut settings = *settings;
    if let Some(cap) = target.lambda_cap() {
        settings.lambda_max = settings.lambda_max.min(cap).max(2.0 * settings.lambda_min);
    }
    let settings = &settings;
    let start = Instant::now();
    let mut lobes = greedy_guess(target, settings);
    nnls_amplitudes(target, &mut lobes);
    lobes.retain(|l| l.amplitude > 0.0);
    let mut initial_rel_l2 = target.errors(&lobes).0;
    if let Some(warm) = warm.filter(|w| !w.is_empty() && w.len() <= settings.lobes) {
        let mut warm: Vec<SgLobe> = warm
            .iter()
            .filter(|l| l.amplitude > 0.0 && l.amplitude.is_finite() && l.lambda.is_finite())
            .map(|l| SgLobe {
                lambda: l.lambda.clamp(settings.lambda_min, settings.lambda_max),
                amplitude: l.amplitude,
                axis: l.axis,
            })
            .collect();
        nnls_amplitudes(target, &mut warm);
        warm.retain(|l| l.amplitude > 0.0);
        if !warm.is_empty() && warm.len() < settings.lobes {
            // Lobes the neighbour's fit dropped (c = 0) are placed again on the residual:
            // without it they are lost down the chain (measured: 248 → 211 lobes and +31 %
            // mean rel. L2 on ggx:alpha=0.2).
            warm = greedy_extend(target, settings, warm);
            nnls_amplitudes(target, &mut warm);
            warm.retain(|l| l.amplitude > 0.0);
        }
        let warm_l2 = target.errors(&warm).0;
        if !warm.is_empty() && warm_l2 < initial_rel_l2 {
            lobes = warm;
            initial_rel_l2 = warm_l2;
        }
    }
    let (mut iterations, mut converged) = (0, true);
    if !lobes.is_empty() && settings.max_iter > 0 {
        let (refined, its, conv) = match refiner {
            Refiner::LevenbergMarquardt => {
                let r = super::lm::refine(
                    target,
                    &lobes,
                    settings.lambda_min,
                    settings.lambda_max,
                    settings.max_iter,
                    super::lm::GN_TOL,
                );
                (r.lobes, r.iterations, r.converged)
            }
            Refiner::Lbfgs => {
                let problem = Problem {
                    target,
                    lambda_min: settings.lambda_min,
                    lambda_max: settings.lambda_max,
                };
                let min = minimise(
                    |x, g| problem.objective(x, Some(g)),
                    problem.encode(&lobes),
                    Stop {
                        max_iter: settings.max_iter,
                        grad_tol: 1e-9,
                        rel_tol: 1e-9,
                    },
                );
                (problem.decode(&min.x), min.iterations, min.converged)
            }
        };
        iterations = its;
        converged = conv;
        if target.errors(&refined).0 <= initial_rel_l2 {
            lobes = refined;
        }
    }
    lobes.retain(|l| l.amplitude > 0.0 && l.amplitude.is_finite());
    let (rel_l2, rel_l1) = target.errors(&lobes);
    Ok(SrbfFit {
        report: FitReport {
            lobes: lobes.len(),
            rel_l2,
            rel_l1,
            initial_rel_l2,
            iterations,
            converged,
            seconds: start.elapsed().as_secs_f64(),
        },
        lobes,
    })
}

/// A broad moment-fitted lobe, then greedy residual peaks (baselines.md §C.2 steps 1–5).
fn greedy_guess(target: &FitTarget, settings: &FitSettings) -> Vec<SgLobe> {
    greedy_extend(target, settings, Vec::with_capacity(settings.lobes))
}

/// [`greedy_guess`] continued from `lobes`: the floor lobe only if `lobes` is empty, then
/// residual peaks (of the target minus `lobes`) until `settings.lobes` lobes (the warm start's
/// top-up: a lobe the previous slice's fit dropped at `c = 0` is placed again).
fn greedy_extend(
    target: &FitTarget,
    settings: &FitSettings,
    mut lobes: Vec<SgLobe>,
) -> Vec<SgLobe> {
    let mut residual = target.values.clone();
    for (d, r) in target.directions.iter().zip(residual.iter_mut()) {
        *r -= lobes.iter().map(|l| l.eval(d)).sum::<f64>();
    }
    // Lobe 1 (with K ≥ 2): the floor. Peaks alone leave a wide, low part of the target (a
    // diffuse term, a sky behind a sun) to the lobes' e^{−2λ} tails, which no sampler built on
    // them can recover. The floor is the moment fit of the target clipped at its solid-angle-
    // weighted 90th percentile (so a sun or a specular peak does not dominate it): mean
    // direction and the concentration of the mean resultant length R̄ (Banerjee et al. 2005:
    // κ ≈ R̄(3 − R̄²)/(1 − R̄²)), amplitude by least squares on the clipped target.
    if settings.lobes >= 2
        && lobes.is_empty()
        && let Some(lobe) = floor_lobe(target, settings)
    {
        for (d, r) in target.directions.iter().zip(residual.iter_mut()) {
            *r -= lobe.eval(d);
        }
        lobes.push(lobe);
    }
    let mut attempts = 0;
    while lobes.len() < settings.lobes && attempts < 4 * settings.lobes {
        attempts += 1;
        let Some((peak, &peak_value)) = residual
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
        else {
            break;
        };
        if !(peak_value > 0.0) {
            break;
        }
        let axis = target.directions[peak];
        if lobes.iter().any(|l| l.axis.dot(&axis) > 1.0 - 1e-12) {
            // A peak narrower than the bandwidth cap: another lobe here only duplicates the
            // first; move on to the next peak.
            residual[peak] = 0.0;
            continue;
        }
        // Half-maximum radius: the closest sample (largest cosine) below half the peak.
        let cos_half = residual
            .iter()
            .zip(&target.directions)
            .filter(|(r, _)| **r < 0.5 * peak_value)
            .map(|(_, d)| d.dot(&axis))
            .fold(-1.0f64, f64::max);
        let lambda = (std::f64::consts::LN_2 / (1.0 - cos_half).max(1e-12))
            .clamp(settings.lambda_min, settings.lambda_max);
        let mut lobe = SgLobe {
            axis,
            lambda,
            amplitude: 1.0,
        };
        let (mut num, mut den) = (0.0, 0.0);
        for ((d, &a), &r) in target.directions.iter().zip(&target.weights).zip(&residual) {
            let g = lobe.eval(d);
            num += a * r * g;
            den += a * g * g;
        }
        // 1D least squares on the residual; where earlier lobes overshoot around this peak it
        // can be ≤ 0: start from the peak height instead (the joint NNLS settles it).
        let ls = if den > 0.0 { num / den } else { 0.0 };
        lobe.amplitude = if ls > 0.0 { ls } else { peak_value };
        for (d, r) in target.directions.iter().zip(residual.iter_mut()) {
            *r -= lobe.eval(d);
        }
        lobes.push(lobe);
    }
    lobes
}

/// The broad floor lobe of the greedy guess (see there), if the target has one.
fn floor_lobe(target: &FitTarget, settings: &FitSettings) -> Option<SgLobe> {
    let mut order: Vec<usize> = (0..target.len()).collect();
    order.sort_by(|&i, &j| target.values[i].total_cmp(&target.values[j]));
    let total: f64 = target.weights.iter().sum();
    let mut acc = 0.0;
    let mut clip = 0.0;
    for &i in &order {
        acc += target.weights[i];
        clip = target.values[i];
        if acc >= 0.9 * total {
            break;
        }
    }
    if !(clip > 0.0) {
        return None;
    }
    let clipped = |i: usize| target.values[i].min(clip);
    let mut resultant = Vec3::zeros();
    let mut mass = 0.0;
    for (i, (d, &a)) in target.directions.iter().zip(&target.weights).enumerate() {
        resultant += d * (a * clipped(i));
        mass += a * clipped(i);
    }
    let r = (resultant.norm() / mass).min(1.0 - 1e-9);
    if !(r > 0.0) {
        return None;
    }
    let lambda =
        (r * (3.0 - r * r) / (1.0 - r * r)).clamp(settings.lambda_min, settings.lambda_max);
    let mut lobe = SgLobe {
        axis: resultant / resultant.norm(),
        lambda,
        amplitude: 1.0,
    };
    let (mut num, mut den) = (0.0, 0.0);
    for (i, (d, &a)) in target.directions.iter().zip(&target.weights).enumerate() {
        let g = lobe.eval(d);
        num += a * clipped(i) * g;
        den += a * g * g;
    }
    if !(num > 0.0 && den > 0.0) {
        return None;
    }
    lobe.amplitude = num / den;
    Some(lobe)
}

/// Refits every amplitude jointly with `c ≥ 0` (projected coordinate descent on the normal
/// equations `Gram · c = b`), keeping centres and bandwidths.
fn nnls_amplitudes(target: &FitTarget, lobes: &mut [SgLobe]) {
    let k = lobes.len();
    if k == 0 {
        return;
    }
    let mut gram = vec![0.0; k * k];
    let mut rhs = vec![0.0; k];
    let mut g = vec![0.0; k];
    for ((d, &a), &f) in target
        .directions
        .iter()
        .zip(&target.weights)
        .zip(&target.values)
    {
        for (gj, l) in g.iter_mut().zip(lobes.iter()) {
            *gj = l.eval(d) / l.amplitude.max(f64::MIN_POSITIVE);
        }
        for p in 0..k {
            rhs[p] += a * f * g[p];
            for q in 0..k {
                gram[p * k + q] += a * g[p] * g[q];
            }
        }
    }
    let mut c: Vec<f64> = lobes.iter().map(|l| l.amplitude).collect();
    for _ in 0..200 {
        let mut change = 0.0f64;
        for p in 0..k {
            let diag = gram[p * k + p];
            if !(diag > 0.0) {
                continue;
            }
            let grad: f64 = (0..k).map(|q| gram[p * k + q] * c[q]).sum::<f64>() - rhs[p];
            let new = (c[p] - grad / diag).max(0.0);
            change = change.max((new - c[p]).abs() / c[p].max(new).max(1e-300));
            c[p] = new;
        }
        if change < 1e-10 {
            break;
        }
    }
    for (l, c) in lobes.iter_mut().zip(c) {
        l.amplitude = c;
    }
}

/// The bound-free least-squares problem: 5 parameters per lobe `(a, b, v₁, v₂, v₃)`.
pub(crate) struct Problem<'a> {
    pub(crate) target: &'a FitTarget,
    pub(crate) lambda_min: f64,
    pub(crate) lambda_max: f64,
}

fn sigmoid(b: f64) -> f64 {
    1.0 / (1.0 + (-b).exp())
}

impl Problem<'_> {
    /// Parameters of `lobes` (amplitudes floored at 10⁻⁶ of the largest, so `a = ln c` is finite).
    pub(crate) fn encode(&self, lobes: &[SgLobe]) -> Vec<f64> {
        let c_max = lobes.iter().map(|l| l.amplitude).fold(0.0, f64::max);
        let mut x = Vec::with_capacity(5 * lobes.len());
        for l in lobes {
            let t = ((l.lambda - self.lambda_min) / (self.lambda_max - self.lambda_min))
                .clamp(1e-9, 1.0 - 1e-9);
            x.push(l.amplitude.max(1e-6 * c_max).max(f64::MIN_POSITIVE).ln());
            x.push((t / (1.0 - t)).ln());
            x.extend([l.axis.x, l.axis.y, l.axis.z]);
        }
        x
    }

    /// The lobes of parameters `x`.
    pub(crate) fn decode(&self, x: &[f64]) -> Vec<SgLobe> {
        x.chunks_exact(5)
            .map(|p| {
                let v = Vec3::new(p[2], p[3], p[4]);
                let norm = v.norm();
                SgLobe {
                    amplitude: p[0].exp(),
                    lambda: self.lambda_min + (self.lambda_max - self.lambda_min) * sigmoid(p[1]),
                    axis: if norm > 0.0 { v / norm } else { Vec3::z() },
                }
            })
            .collect()
    }

    /// `E(x) / Σ A f²` and, if asked, its gradient.
    pub(crate) fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let lobes = self.decode(x);
        let k = lobes.len();
        let t = self.target;
        // Per lobe: Σ A r G, Σ A r G (η·ξ − 1), Σ A r G η.
        let mut s_c = vec![0.0; k];
        let mut s_l = vec![0.0; k];
        let mut s_x = vec![Vec3::zeros(); k];
        let mut g = vec![0.0; k];
        let mut cosines = vec![0.0; k];
        let (mut e, mut norm) = (0.0, 0.0);
        let want_grad = grad.is_some();
        for ((d, &a), &f) in t.directions.iter().zip(&t.weights).zip(&t.values) {
            let mut model = 0.0;
            for j in 0..k {
                let cos = d.dot(&lobes[j].axis);
                cosines[j] = cos;
                g[j] = (lobes[j].lambda * (cos - 1.0)).exp();
                model += lobes[j].amplitude * g[j];
            }
            let r = model - f;
            e += a * r * r;
            norm += a * f * f;
            if want_grad {
                let ar = a * r;
                for j in 0..k {
                    let w = ar * g[j];
                    s_c[j] += w;
                    s_l[j] += w * (cosines[j] - 1.0);
                    s_x[j] += d * w;
                }
            }
        }
        if let Some(grad) = grad {
            let span = self.lambda_max - self.lambda_min;
            for (j, l) in lobes.iter().enumerate() {
                let p = &x[5 * j..5 * j + 5];
                let gp = &mut grad[5 * j..5 * j + 5];
                // ∂E/∂c · ∂c/∂a, with ∂c/∂a = c.
                gp[0] = 2.0 * s_c[j] * l.amplitude / norm;
                let s = sigmoid(p[1]);
                gp[1] = 2.0 * l.amplitude * s_l[j] * span * s * (1.0 - s) / norm;
                // ∂E/∂ξ = 2 c λ Σ A r G η, projected: ∂ξ/∂v = (I − ξξᵀ)/‖v‖.
                let v = Vec3::new(p[2], p[3], p[4]);
                let vn = v.norm().max(f64::MIN_POSITIVE);
                let de_dxi = s_x[j] * (2.0 * l.amplitude * l.lambda / norm);
                let proj = (de_dxi - l.axis * l.axis.dot(&de_dxi)) / vn;
                gp[2] = proj.x;
                gp[3] = proj.y;
                gp[4] = proj.z;
            }
        }
        e / norm
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::srbf::vmf::vmf_sample;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// A lat-long grid of the whole sphere with exact solid-angle weights (also used by the
    /// Levenberg–Marquardt tests).
    pub(in crate::srbf) fn sphere_target(
        f: impl Fn(&Vec3) -> f64,
        w: usize,
        h: usize,
    ) -> FitTarget {
        let (mut d, mut a, mut v) = (Vec::new(), Vec::new(), Vec::new());
        for y in 0..h {
            let (t0, t1) = (
                std::f64::consts::PI * y as f64 / h as f64,
                std::f64::consts::PI * (y + 1) as f64 / h as f64,
            );
            let t = 0.5 * (t0 + t1);
            for x in 0..w {
                let p = std::f64::consts::TAU * (x as f64 + 0.5) / w as f64;
                let dir = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                a.push(std::f64::consts::TAU / w as f64 * (t0.cos() - t1.cos()));
                v.push(f(&dir));
                d.push(dir);
            }
        }
        FitTarget::new(d, a, v).unwrap()
    }

    /// The two-lobe truth the fit tests recover: a sharp lobe (sharpness `lambda[0]`, amplitude
    /// 2) tilted towards +y and a broad one (`lambda[1]`, amplitude 0.5) towards −x.
    pub(in crate::srbf) fn two_lobes(lambda: [f64; 2]) -> [SgLobe; 2] {
        [
            SgLobe {
                axis: Vec3::new(0.0, 0.6, 0.8),
                lambda: lambda[0],
                amplitude: 2.0,
            },
            SgLobe {
                axis: Vec3::new(-0.8, 0.0, 0.6),
                lambda: lambda[1],
                amplitude: 0.5,
            },
        ]
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let target = sphere_target(
            |d| (3.0 * (d.z - 1.0)).exp() + 0.3 * (10.0 * (d.x - 1.0)).exp(),
            32,
            16,
        );
        let problem = Problem {
            target: &target,
            lambda_min: 0.5,
            lambda_max: 100.0,
        };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
        let lobes: Vec<SgLobe> = (0..3)
            .map(|_| SgLobe {
                axis: vmf_sample(&Vec3::z(), 0.0, rng.random()),
                lambda: 1.0 + 20.0 * rng.random::<f64>(),
                amplitude: 0.2 + rng.random::<f64>(),
            })
            .collect();
        let x = problem.encode(&lobes);
        let mut g = vec![0.0; x.len()];
        problem.objective(&x, Some(&mut g));
        for i in 0..x.len() {
            let h = 1e-6;
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i] += h;
            xm[i] -= h;
            let fd = (problem.objective(&xp, None) - problem.objective(&xm, None)) / (2.0 * h);
            assert!(
                (fd - g[i]).abs() <= 1e-6 * fd.abs().max(1e-3),
                "param {i}: analytic {} vs fd {fd}",
                g[i]
            );
        }
    }

    #[test]
    fn recovers_a_two_lobe_mixture() {
        let truth = two_lobes([20.0, 5.0]);
        let target = sphere_target(|d| truth.iter().map(|l| l.eval(d)).sum(), 128, 64);
        let settings = FitSettings {
            lobes: 2,
            lambda_min: 0.5,
            lambda_max: 1e3,
            max_iter: 300,
        };
        let fit = fit(&target, &settings).unwrap();
        assert!(fit.report.rel_l2 < 1e-3, "{:?}", fit.report);
        assert!(fit.report.rel_l2 <= fit.report.initial_rel_l2);
    }

    #[test]
    fn warm_start_from_a_neighbouring_fit_reaches_the_same_error_in_fewer_steps() {
        // Two neighbouring "slices": the same mixture, the sharp lobe moved by 0.005 rad. (At
        // 0.05 rad, 0.4 of the lobe's width, the greedy guess starts lower and is taken.)
        let a = two_lobes([60.0, 3.0]);
        let mut b = a;
        b[0].axis = Vec3::new(0.0, (0.6435f64 + 0.005).sin(), (0.6435f64 + 0.005).cos());
        // A floor the lobes cannot represent exactly, so the fits end at a positive error.
        let floor = |d: &Vec3| 0.05 * d.z.max(0.0);
        let target_of = |lobes: &[SgLobe]| {
            sphere_target(
                |d| lobes.iter().map(|l| l.eval(d)).sum::<f64>() + floor(d),
                96,
                48,
            )
        };
        let (ta, tb) = (target_of(&a), target_of(&b));
        let settings = FitSettings {
            lobes: 4,
            lambda_min: 0.5,
            lambda_max: 1e3,
            max_iter: 2000,
        };
        let fa = fit(&ta, &settings).unwrap();
        let cold = fit(&tb, &settings).unwrap();
        let warm = fit_from(&tb, &settings, &fa.lobes).unwrap();
        assert!(cold.report.converged && warm.report.converged);
        assert!(
            warm.report.initial_rel_l2 < cold.report.initial_rel_l2,
            "{:?} vs {:?}",
            warm.report,
            cold.report
        );
        assert!(
            warm.report.rel_l2 <= 1.02 * cold.report.rel_l2,
            "{:?} vs {:?}",
            warm.report,
            cold.report
        );
        assert!(
            warm.report.iterations < cold.report.iterations,
            "{:?} vs {:?}",
            warm.report,
            cold.report
        );
        // An empty start is the cold fit.
        assert_eq!(fit_from(&tb, &settings, &[]).unwrap().lobes, cold.lobes);
    }

    #[test]
    fn rejects_bad_settings_and_targets() {
        let target = sphere_target(|d| d.z.max(0.0), 8, 4);
        let bad = |lobes, lambda_min, lambda_max| {
            fit(
                &target,
                &FitSettings {
                    lobes,
                    lambda_min,
                    lambda_max,
                    max_iter: 10,
                },
            )
            .unwrap_err()
        };
        assert_eq!(bad(0, 1.0, 2.0), SrbfError::ZeroLobes { what: "fit" });
        assert!(matches!(bad(2, 0.0, 2.0), SrbfError::BadBandwidth { .. }));
        assert!(matches!(bad(2, 3.0, 2.0), SrbfError::BadBandwidth { .. }));
        assert!(matches!(
            bad(2, f64::NAN, 2.0),
            SrbfError::BadBandwidth { .. }
        ));
        assert_eq!(
            FitTarget::new(vec![Vec3::z()], vec![1.0], vec![0.0]).unwrap_err(),
            SrbfError::BlackTarget
        );
        assert!(matches!(
            FitTarget::new(vec![Vec3::z()], vec![1.0], vec![f64::NAN]),
            Err(SrbfError::BadTarget { .. })
        ));
        assert!(matches!(
            FitTarget::new(vec![], vec![], vec![]),
            Err(SrbfError::TargetShape { .. })
        ));
    }
}
