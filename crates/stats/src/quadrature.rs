//! Adaptive tensor Gauss–Legendre quadrature over bins, with accuracy tied to the sample count.
//!
//! Each bin is a union of [`Patch`]es; each patch is mapped to a rectangle `(a, t)` (with
//! `u = sin a` when an edge is a circle arc, and `v = lo(u) + t (hi(u) − lo(u))`), split into
//! `2^min_depth × 2^min_depth` initial cells, and refined recursively: a cell's `q × q`
//! Gauss–Legendre value is compared with the sum over its four children, and the children are
//! refined further (each with half the parent's tolerance) until the difference is within
//! tolerance or `max_depth` is reached. The accepted value is the children's sum.
//!
//! For chi-square tests the tolerance of a bin with estimated mass `m` and `N` samples is
//! `accuracy · √max(N m, 1) / N` in mass, i.e. an expected-count error of
//! `accuracy · √max(E, 1)` — a fixed fraction of the Poisson noise `√E`, so the quadrature gets
//! more accurate as `N` grows — never below `rel_floor · m`.
//!
//! **Non-finite values stop refinement.** A cell (or 1D piece, or projection-CDF slab) whose
//! refined estimate is not finite is accepted as it is, without evaluating the integrand any
//! deeper. Callers rely on it: the validation suite serves the pdf of a sampler that prefers
//! batched queries (e.g. one written in Python) by running a quadrature with NaN at the points
//! not evaluated yet, evaluating the points it asked for in one batch, and running it again;
//! thanks to this rule a pass asks for the next refinement level of every cell still refining
//! and nothing below an unknown value (a level-synchronous quadrature, one batched call per
//! level), and the last pass, which meets no unknown point, is the direct quadrature's result
//! bit for bit. (A pass may stop a refinement early where a NaN meets values already known,
//! e.g. from another test; only the last pass's result is used.)

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::binning::{Binning, Patch};
use crate::error::StatsError;

/// Options of the adaptive quadrature.
///
/// A bin whose refinement stops at `max_depth` or at the evaluation budget before meeting its
/// tolerance is reported in [`MassTable::unconverged_bins`] (or [`Integral::converged`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuadratureOptions {
    /// Gauss–Legendre points per dimension in each cell (2..=20; default 5, exact for degree 9).
    pub order: usize,
    /// Initial uniform subdivision: `2^min_depth` cells per side of each patch (default 1).
    /// Raise it for pdfs with features narrower than a bin.
    pub min_depth: u32,
    /// Maximum refinement depth below the initial cells (default 10; at most 30).
    pub max_depth: u32,
    /// Target expected-count error as a fraction of `√max(E, 1)` (default 0.01).
    pub accuracy: f64,
    /// Smallest relative tolerance per bin (default 1e-11), so refinement always terminates.
    pub rel_floor: f64,
    /// Refinement of a bin stops once it has used this many integrand evaluations
    /// (default 4 000 000), a safety net against integrands that never settle (e.g. noisy).
    pub max_evaluations_per_bin: u64,
}

impl Default for QuadratureOptions {
    fn default() -> Self {
        Self {
            order: 5,
            min_depth: 1,
            max_depth: 10,
            accuracy: 0.01,
            rel_floor: 1e-11,
            max_evaluations_per_bin: 4_000_000,
        }
    }
}

impl QuadratureOptions {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`StatsError::InvalidQuadrature`] naming the offending field.
    pub fn validate(&self) -> Result<(), StatsError> {
        if !(2..=20).contains(&self.order) {
            return Err(StatsError::InvalidQuadrature(format!(
                "order must be in 2..=20, got {}",
                self.order
            )));
        }
        if self.min_depth > 8 || self.max_depth > 30 {
            return Err(StatsError::InvalidQuadrature(format!(
                "min_depth <= 8 and max_depth <= 30 required, got {} and {}",
                self.min_depth, self.max_depth
            )));
        }
        if !(self.accuracy > 0.0 && self.accuracy.is_finite()) {
            return Err(StatsError::InvalidQuadrature(format!(
                "accuracy must be finite and > 0, got {}",
                self.accuracy
            )));
        }
        if !(self.rel_floor > 0.0 && self.rel_floor < 1.0) {
            return Err(StatsError::InvalidQuadrature(format!(
                "rel_floor must lie in (0, 1), got {}",
                self.rel_floor
            )));
        }
        if self.max_evaluations_per_bin == 0 {
            return Err(StatsError::InvalidQuadrature(
                "max_evaluations_per_bin must be > 0".into(),
            ));
        }
        Ok(())
    }
}

/// Per-bin integrals of a density with their quadrature diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassTable {
    /// `masses[b] = ∫_bin f dμ`.
    pub masses: Vec<f64>,
    /// Estimated absolute error per bin (sum of `|children − parent|` over accepted cells; an
    /// overestimate for smooth integrands).
    pub error_estimates: Vec<f64>,
    /// Bins in which some cell hit `max_depth` before meeting its tolerance.
    pub unconverged_bins: usize,
    /// Total integrand evaluations.
    pub evaluations: u64,
}

impl MassTable {
    /// `Σ_b masses[b]`, summed in bin order.
    pub fn total(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// `Σ_b error_estimates[b]`.
    pub fn total_error_estimate(&self) -> f64 {
        self.error_estimates.iter().sum()
    }
}

/// Probability mass of every bin, `∫_bin pdf dμ`, accurate enough for a chi-square test with
/// `n_samples` samples (default [`QuadratureOptions`]; see the module docs for the tolerance).
///
/// `pdf` is a density with respect to the binning's measure (area, or solid angle for
/// directions). Bins are integrated in parallel; the result does not depend on the thread count.
/// `n_samples = 0` is treated as 1.
pub fn expected_masses<B: Binning + ?Sized>(
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    n_samples: u64,
) -> Vec<f64> {
    let opts = QuadratureOptions::default();
    let rule = GaussLegendre::new(opts.order);
    let n = n_samples.max(1) as f64;
    let tol =
        |m: f64| (opts.accuracy * (n * m.abs()).max(1.0).sqrt() / n).max(opts.rel_floor * m.abs());
    integrate_all_bins(pdf, binning, &rule, &opts, &tol).masses
}

/// [`expected_masses`] with explicit options, returning the quadrature diagnostics too.
///
/// # Errors
/// [`StatsError::InvalidQuadrature`] for out-of-range options.
pub fn expected_masses_with<B: Binning + ?Sized>(
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    n_samples: u64,
    opts: &QuadratureOptions,
) -> Result<MassTable, StatsError> {
    opts.validate()?;
    let rule = GaussLegendre::new(opts.order);
    let n = n_samples.max(1) as f64;
    let tol =
        |m: f64| (opts.accuracy * (n * m.abs()).max(1.0).sqrt() / n).max(opts.rel_floor * m.abs());
    Ok(integrate_all_bins(pdf, binning, &rule, opts, &tol))
}

/// Integrals of `f` (any integrand, with respect to the binning's measure) over every bin, with
/// a total absolute tolerance `abs_tol` shared equally by the bins (`opts.accuracy` is unused).
///
/// # Errors
/// [`StatsError::InvalidTolerance`] or [`StatsError::InvalidQuadrature`].
pub fn integrate_bins<B: Binning + ?Sized>(
    f: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    abs_tol: f64,
    opts: &QuadratureOptions,
) -> Result<MassTable, StatsError> {
    opts.validate()?;
    if !(abs_tol > 0.0 && abs_tol.is_finite()) {
        return Err(StatsError::InvalidTolerance(abs_tol));
    }
    let rule = GaussLegendre::new(opts.order);
    let per_bin = abs_tol / binning.n_bins() as f64;
    let tol = |m: f64| per_bin.max(opts.rel_floor * m.abs());
    Ok(integrate_all_bins(f, binning, &rule, opts, &tol))
}

/// An integral with its quadrature diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Integral {
    /// The estimate.
    pub value: f64,
    /// Estimated absolute error (an overestimate for smooth integrands).
    pub error_estimate: f64,
    /// Whether every cell met its tolerance before `max_depth`.
    pub converged: bool,
    /// Integrand evaluations.
    pub evaluations: u64,
}

/// `∫ f dμ` over the part of the domain inside the parameter rectangle `u × v`, to absolute
/// tolerance `abs_tol` (or `rel_floor` relative, whichever is larger).
///
/// # Errors
/// [`StatsError::InvalidTolerance`] or [`StatsError::InvalidQuadrature`].
pub fn integrate_rect<B: Binning + ?Sized>(
    f: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    u: [f64; 2],
    v: [f64; 2],
    abs_tol: f64,
    opts: &QuadratureOptions,
) -> Result<Integral, StatsError> {
    opts.validate()?;
    if !(abs_tol > 0.0 && abs_tol.is_finite()) {
        return Err(StatsError::InvalidTolerance(abs_tol));
    }
    let rule = GaussLegendre::new(opts.order);
    let tol = |m: f64| abs_tol.max(opts.rel_floor * m.abs());
    Ok(integrate_patches(
        f,
        binning,
        &binning.clip(u, v),
        &rule,
        opts,
        &tol,
    ))
}

/// `∫ f dμ` over the whole domain of `binning`, to total absolute tolerance `abs_tol`
/// (bins are integrated in parallel and summed in order).
///
/// # Errors
/// [`StatsError::InvalidTolerance`] or [`StatsError::InvalidQuadrature`].
pub fn integrate<B: Binning + ?Sized>(
    f: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    abs_tol: f64,
    opts: &QuadratureOptions,
) -> Result<Integral, StatsError> {
    let table = integrate_bins(f, binning, abs_tol, opts)?;
    Ok(Integral {
        value: table.total(),
        error_estimate: table.total_error_estimate(),
        converged: table.unconverged_bins == 0,
        evaluations: table.evaluations,
    })
}

fn integrate_all_bins<B: Binning + ?Sized>(
    f: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    rule: &GaussLegendre,
    opts: &QuadratureOptions,
    tol: &(dyn Fn(f64) -> f64 + Sync),
) -> MassTable {
    let results: Vec<Integral> = (0..binning.n_bins())
        .into_par_iter()
        .map(|bin| integrate_patches(f, binning, &binning.bin_patches(bin), rule, opts, tol))
        .collect();
    MassTable {
        masses: results.iter().map(|r| r.value).collect(),
        error_estimates: results.iter().map(|r| r.error_estimate).collect(),
        unconverged_bins: results.iter().filter(|r| !r.converged).count(),
        evaluations: results.iter().map(|r| r.evaluations).sum(),
    }
}

/// Gauss–Legendre nodes and weights on `[−1, 1]`.
///
/// Independent implementation on purpose: the validation suite must not share numerics with
/// the samplers it checks. The project's rule for BRDF-side code is
/// `brdf::quadrature::GaussLegendre` (used by the models and by `brdf-sampling`'s leaf
/// normalisation); a bug there must not be able to hide itself by also skewing the references
/// and expected counts computed here, so `stats` depends on no project crate and keeps this
/// copy.
#[derive(Debug, Clone)]
pub(crate) struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule (`n ≥ 1`), nodes by Newton iteration on `P_n`.
    pub(crate) fn new(n: usize) -> Self {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d != 0.0 {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Self { nodes, weights }
    }

    /// `∫_a^b g` by this rule.
    pub(crate) fn integrate_1d(&self, g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
        let (h, c) = (0.5 * (b - a), 0.5 * (b + a));
        let s: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * g(c + h * x))
            .sum();
        s * h
    }

    /// Tensor rule over `[a₀, a₁] × [b₀, b₁]`.
    fn integrate_2d(&self, g: &dyn Fn(f64, f64) -> f64, a: [f64; 2], b: [f64; 2]) -> f64 {
        let (ha, ca) = (0.5 * (a[1] - a[0]), 0.5 * (a[1] + a[0]));
        let (hb, cb) = (0.5 * (b[1] - b[0]), 0.5 * (b[1] + b[0]));
        let mut s = 0.0;
        for (&xi, &wi) in self.nodes.iter().zip(&self.weights) {
            let ai = ca + ha * xi;
            let mut row = 0.0;
            for (&xj, &wj) in self.nodes.iter().zip(&self.weights) {
                row += wj * g(ai, cb + hb * xj);
            }
            s += wi * row;
        }
        s * ha * hb
    }

    fn len(&self) -> u64 {
        self.nodes.len() as u64
    }

    /// Nodes and weights on `[−1, 1]`.
    pub(crate) fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.nodes.iter().copied().zip(self.weights.iter().copied())
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

/// A patch mapped to the rectangle `(a, t) ∈ [a₀, a₁] × [0, 1]`.
pub(crate) struct PatchMap<'a, B: Binning + ?Sized> {
    binning: &'a B,
    f: &'a (dyn Fn(B::Point) -> f64 + Sync),
    patch: Patch,
    circle: bool,
}

impl<'a, B: Binning + ?Sized> PatchMap<'a, B> {
    pub(crate) fn new(
        binning: &'a B,
        f: &'a (dyn Fn(B::Point) -> f64 + Sync),
        patch: Patch,
    ) -> Self {
        let circle = patch.lo.is_circle() || patch.hi.is_circle();
        Self {
            binning,
            f,
            patch,
            circle,
        }
    }

    /// Range of the outer variable `a` (`u`, or `asin u` for patches with circle edges).
    pub(crate) fn a_range(&self) -> [f64; 2] {
        if self.circle {
            [
                self.patch.u[0].clamp(-1.0, 1.0).asin(),
                self.patch.u[1].clamp(-1.0, 1.0).asin(),
            ]
        } else {
            self.patch.u
        }
    }

    /// Parameters `(u, v)` at `(a, t)` and the weight `J(u, v) · du/da · (hi − lo)`
    /// (zero where the patch is empty).
    pub(crate) fn map(&self, a: f64, t: f64) -> ([f64; 2], f64) {
        let (u, du, c) = if self.circle {
            let (s, c) = a.sin_cos();
            (s, c, c)
        } else {
            (a, 1.0, 0.0)
        };
        let edge = |e: &crate::binning::Edge| match *e {
            crate::binning::Edge::Const(k) => k,
            crate::binning::Edge::CircleUpper => c,
            crate::binning::Edge::CircleLower => -c,
        };
        let (lo, hi) = if self.circle {
            (edge(&self.patch.lo), edge(&self.patch.hi))
        } else {
            (self.patch.lo.at(u), self.patch.hi.at(u))
        };
        let len = hi - lo;
        if !(len > 0.0) {
            return ([u, lo], 0.0);
        }
        let uv = [u, lo + t * len];
        (uv, self.binning.jacobian(uv) * du * len)
    }

    fn eval(&self, a: f64, t: f64) -> f64 {
        let (uv, w) = self.map(a, t);
        if w == 0.0 {
            return 0.0;
        }
        (self.f)(self.binning.point_at(uv)) * w
    }
}

#[derive(Default)]
struct Tally {
    evals: u64,
    budget: u64,
    err: f64,
    unconverged: bool,
}

fn integrate_patches<B: Binning + ?Sized>(
    f: &(dyn Fn(B::Point) -> f64 + Sync),
    binning: &B,
    patches: &[Patch],
    rule: &GaussLegendre,
    opts: &QuadratureOptions,
    tol_of_mass: &(dyn Fn(f64) -> f64 + Sync),
) -> Integral {
    let k = 1usize << opts.min_depth;
    let per_cell = rule.len() * rule.len();
    let mut tally = Tally {
        budget: opts.max_evaluations_per_bin,
        ..Tally::default()
    };
    let maps: Vec<PatchMap<'_, B>> = patches
        .iter()
        .map(|p| PatchMap::new(binning, f, *p))
        .collect();
    // Initial cells: (map index, a range, t range, coarse value).
    let mut cells = Vec::with_capacity(maps.len() * k * k);
    for (m, map) in maps.iter().enumerate() {
        let ar = map.a_range();
        let g = |a: f64, t: f64| map.eval(a, t);
        for i in 0..k {
            let a = split(ar, k, i);
            for j in 0..k {
                let t = split([0.0, 1.0], k, j);
                let value = rule.integrate_2d(&g, a, t);
                tally.evals += per_cell;
                cells.push((m, a, t, value));
            }
        }
    }
    if cells.is_empty() {
        return Integral {
            value: 0.0,
            error_estimate: 0.0,
            converged: true,
            evaluations: 0,
        };
    }
    let m0: f64 = cells.iter().map(|c| c.3).sum();
    let tol_cell = tol_of_mass(m0) / cells.len() as f64;
    let mut value = 0.0;
    for (m, a, t, coarse) in cells {
        let map = &maps[m];
        let g = |a: f64, t: f64| map.eval(a, t);
        value += adapt(&g, rule, a, t, coarse, tol_cell, opts.max_depth, &mut tally);
    }
    Integral {
        value,
        error_estimate: tally.err,
        converged: !tally.unconverged,
        evaluations: tally.evals,
    }
}

/// The `i`-th of `k` equal parts of `r`.
pub(crate) fn split(r: [f64; 2], k: usize, i: usize) -> [f64; 2] {
    let at = |j: usize| {
        if j == k {
            r[1]
        } else {
            r[0] + (r[1] - r[0]) * (j as f64 / k as f64)
        }
    };
    [at(i), at(i + 1)]
}

#[allow(clippy::too_many_arguments)]
fn adapt(
    g: &dyn Fn(f64, f64) -> f64,
    rule: &GaussLegendre,
    a: [f64; 2],
    t: [f64; 2],
    coarse: f64,
    tol: f64,
    depth_left: u32,
    tally: &mut Tally,
) -> f64 {
    let am = 0.5 * (a[0] + a[1]);
    let tm = 0.5 * (t[0] + t[1]);
    let kids = [
        ([a[0], am], [t[0], tm]),
        ([am, a[1]], [t[0], tm]),
        ([a[0], am], [tm, t[1]]),
        ([am, a[1]], [tm, t[1]]),
    ];
    let vals = kids.map(|(ka, kt)| rule.integrate_2d(g, ka, kt));
    tally.evals += 4 * rule.len() * rule.len();
    let fine: f64 = vals.iter().sum();
    let err = (fine - coarse).abs();
    if err <= tol || depth_left == 0 || !err.is_finite() || tally.evals >= tally.budget {
        if !(err <= tol) {
            tally.unconverged = true;
        }
        tally.err += err;
        return fine;
    }
    let mut sum = 0.0;
    for (i, (ka, kt)) in kids.iter().enumerate() {
        sum += adapt(g, rule, *ka, *kt, vals[i], 0.5 * tol, depth_left - 1, tally);
    }
    sum
}

/// `∫_a^b f` by 1D adaptive Gauss–Legendre: `pieces` equal initial pieces (tolerance shared
/// equally), then halving where a piece and its halves disagree; children get half the
/// tolerance.
pub(crate) fn integrate_1d(
    f: &dyn Fn(f64) -> f64,
    range: [f64; 2],
    abs_tol: f64,
    rule: &GaussLegendre,
    max_depth: u32,
    pieces: usize,
) -> Integral {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        f: &dyn Fn(f64) -> f64,
        rule: &GaussLegendre,
        a: f64,
        b: f64,
        coarse: f64,
        tol: f64,
        depth_left: u32,
        tally: &mut Tally,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (l, r) = (rule.integrate_1d(f, a, m), rule.integrate_1d(f, m, b));
        tally.evals += 2 * rule.len();
        let fine = l + r;
        let err = (fine - coarse).abs();
        if err <= tol || depth_left == 0 || !err.is_finite() {
            if !(err <= tol) {
                tally.unconverged = true;
            }
            tally.err += err;
            return fine;
        }
        rec(f, rule, a, m, l, 0.5 * tol, depth_left - 1, tally)
            + rec(f, rule, m, b, r, 0.5 * tol, depth_left - 1, tally)
    }
    let mut tally = Tally {
        budget: u64::MAX,
        ..Tally::default()
    };
    let pieces = pieces.max(1);
    let mut value = 0.0;
    for i in 0..pieces {
        let [a, b] = split(range, pieces, i);
        let coarse = rule.integrate_1d(f, a, b);
        tally.evals += rule.len();
        value += rec(
            f,
            rule,
            a,
            b,
            coarse,
            abs_tol / pieces as f64,
            max_depth,
            &mut tally,
        );
    }
    Integral {
        value,
        error_estimate: tally.err,
        converged: !tally.unconverged,
        evaluations: tally.evals,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn gauss_legendre_is_exact_for_degree_2n_minus_1() {
        for n in 1..=20usize {
            let rule = GaussLegendre::new(n);
            let wsum: f64 = rule.points().map(|(_, w)| w).sum();
            assert_relative_eq!(wsum, 2.0, max_relative = 1e-13);
            for deg in 0..(2 * n) {
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                let got = rule.integrate_1d(&|x: f64| x.powi(deg as i32), -1.0, 1.0);
                assert!(
                    (got - exact).abs() < 1e-13,
                    "n={n} deg={deg}: {got} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn adaptive_1d_handles_a_kink() {
        let rule = GaussLegendre::new(5);
        let f = |x: f64| (x - 0.3).abs();
        let r = integrate_1d(&f, [0.0, 1.0], 1e-12, &rule, 40, 1);
        assert!(r.converged);
        assert!((r.value - (0.045 + 0.245)).abs() < 1e-11, "{}", r.value);
    }

    /// The rule the level-synchronous batched passes of the validation suite rely on (module
    /// docs): a non-finite estimate stops refinement at once. Without it, a NaN cell would be
    /// refined to `max_depth` (4^10 times the evaluations).
    #[test]
    fn non_finite_values_stop_refinement_at_once() {
        use crate::binning::SphereBinning;
        use std::sync::atomic::{AtomicU64, Ordering};
        let bins = SphereBinning::hemisphere(3, 4).unwrap();
        let opts = QuadratureOptions::default();
        let k = 1u64 << opts.min_depth;
        let per_cell = (opts.order * opts.order) as u64;
        let patches: u64 = (0..bins.n_bins())
            .map(|b| bins.bin_patches(b).len() as u64)
            .sum();
        let initial = patches * k * k * per_cell;
        let calls = AtomicU64::new(0);
        let nan = |_: [f64; 3]| {
            calls.fetch_add(1, Ordering::Relaxed);
            f64::NAN
        };
        let t = integrate_bins(&nan, &bins, 1e-9, &opts).unwrap();
        // The initial cells, then one level of children, and no further.
        assert_eq!(t.evaluations, 5 * initial);
        assert!(calls.load(Ordering::Relaxed) <= 5 * initial);
        assert_eq!(t.unconverged_bins, bins.n_bins());
        // A finite pdf with a jump refines far deeper (the count above is not a cap).
        let jump = |d: [f64; 3]| if d[0] > 0.5 { 1.02 } else { 1.0 };
        let t = integrate_bins(&jump, &bins, 1e-9, &opts).unwrap();
        assert!(t.evaluations > 50 * initial, "{}", t.evaluations);

        let rule = GaussLegendre::new(5);
        let r = integrate_1d(&|_| f64::NAN, [0.0, 1.0], 1e-12, &rule, 40, 4);
        assert_eq!(r.evaluations, 4 * 3 * 5);
        assert!(!r.converged);

        // The projection CDF (KS tests): refused, after a bounded number of calls (a NaN
        // marginal refined to the inner depth of 20 would cost > 10^8 calls).
        calls.store(0, Ordering::Relaxed);
        let cdf = crate::cdf::projection_cdf(&bins, &nan, crate::Axis::U, 20_000, &opts);
        assert!(cdf.is_err());
        let n = calls.load(Ordering::Relaxed);
        assert!(n < 1_000_000, "{n} calls");
    }
}
