//! Tabulated CDFs of 1D projections, built by quadrature of a density.
//!
//! The CDF of the projection of a 2D density onto a parameter axis (`cos θ` or `φ` for
//! directions; columns `x` or rows `y` of an image) is `F(t) = ∫_{u ≤ t} pdf dμ`, the integral
//! of the marginal density `f(t)`. It is tabulated at knots and interpolated by monotone cubic
//! Hermite polynomials (slopes: `f` at the knots), with
//! target accuracy `ε = accuracy / √n` (the KS noise level is `≈ 1/√n`). Knots start as equal
//! slabs (32, or one per grid cell along the axis if more); each slab's mass is compared with the sum
//! over its quarters (Gauss–Legendre rules of `f`), and the slab is halved until the masses
//! agree within `ε/4 · (b − a)/range` (so the accumulated error of `F` stays below `ε/4`) and
//! the interpolant reproduces the integrated `F` at the slab's midpoint and quarter points
//! within `ε`. Values are normalised by the total mass (a density that does not integrate to
//! one is the normalisation test's business); the accuracy assumes a mass of order one.

use std::collections::HashMap;
use std::sync::RwLock;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::binning::{Axis, Binning};
use crate::error::StatsError;
use crate::quadrature::{GaussLegendre, QuadratureOptions, integrate_1d, split};
use crate::singular::{LINE_FLOOR_FRACTION, graded_breaks};

const MIN_INITIAL_SLABS: usize = 32;
const MAX_KNOT_DEPTH: u32 = 24;

/// A monotone CDF tabulated on `[knots₀, knots_last]` (0 below, 1 above): piecewise linear, or
/// piecewise cubic Hermite when the density at the knots is known (with the Fritsch–Carlson
/// limiter, so it stays monotone).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TabulatedCdf {
    knots: Vec<f64>,
    values: Vec<f64>,
    /// Normalised density at the knots (cubic Hermite slopes), if known.
    slopes: Option<Vec<f64>>,
    total_mass: f64,
}

impl TabulatedCdf {
    /// A CDF through `(knots[i], values[i])`, normalised by the last value.
    ///
    /// # Errors
    /// Fewer than two knots, lengths that differ, knots not strictly increasing or not finite,
    /// values decreasing, negative, or a last value that is not finite and positive.
    pub fn new(knots: Vec<f64>, values: Vec<f64>) -> Result<Self, StatsError> {
        if knots.len() != values.len() {
            return Err(StatsError::LengthMismatch {
                observed: knots.len(),
                expected: values.len(),
            });
        }
        if knots.len() < 2 {
            return Err(StatsError::TooFewSamples {
                needed: 2,
                got: knots.len(),
            });
        }
        for i in 0..knots.len() {
            let bad_knot = !knots[i].is_finite() || (i > 0 && !(knots[i] > knots[i - 1]));
            let bad_value = !(values[i] >= 0.0) || (i > 0 && !(values[i] >= values[i - 1]));
            if bad_knot || bad_value {
                return Err(StatsError::NonMonotoneCdf { index: i });
            }
        }
        let total = values[values.len() - 1] - values[0];
        if !(total > 0.0 && total.is_finite()) {
            return Err(StatsError::InvalidMass { mass: total });
        }
        let v0 = values[0];
        let values = values.iter().map(|v| ((v - v0) / total).min(1.0)).collect();
        Ok(Self {
            knots,
            values,
            slopes: None,
            total_mass: total,
        })
    }

    /// Like [`TabulatedCdf::new`], interpolating by monotone cubic Hermite with the density
    /// `densities[i] = F'(knots[i])` (unnormalised, like `values`).
    ///
    /// # Errors
    /// As [`TabulatedCdf::new`], plus a length mismatch or a negative or non-finite density.
    pub fn with_densities(
        knots: Vec<f64>,
        values: Vec<f64>,
        densities: Vec<f64>,
    ) -> Result<Self, StatsError> {
        if densities.len() != knots.len() {
            return Err(StatsError::LengthMismatch {
                observed: densities.len(),
                expected: knots.len(),
            });
        }
        if let Some(index) = densities.iter().position(|d| !(*d >= 0.0 && d.is_finite())) {
            return Err(StatsError::NonMonotoneCdf { index });
        }
        let mut cdf = Self::new(knots, values)?;
        let total = cdf.total_mass;
        cdf.slopes = Some(densities.iter().map(|d| d / total).collect());
        Ok(cdf)
    }

    /// `F(x)`: 0 below the first knot, 1 above the last, linear in between.
    pub fn eval(&self, x: f64) -> f64 {
        let n = self.knots.len();
        if !(x > self.knots[0]) {
            return if x.is_nan() { f64::NAN } else { 0.0 };
        }
        if x >= self.knots[n - 1] {
            return 1.0;
        }
        let i = self.knots.partition_point(|&k| k <= x).clamp(1, n - 1);
        let (x0, x1) = (self.knots[i - 1], self.knots[i]);
        let (f0, f1) = (self.values[i - 1], self.values[i]);
        match &self.slopes {
            Some(d) => hermite(x0, x1, f0, f1, d[i - 1], d[i], x),
            None => f0 + (f1 - f0) * ((x - x0) / (x1 - x0)),
        }
    }

    /// The knots (strictly increasing).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Normalised CDF values at the knots (from 0 to 1).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Mass of the density before normalisation.
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// CDF of a 1D density `f ≥ 0` on `range`, tabulated accurately enough for a KS test with
    /// `n_samples` samples (see the module docs).
    ///
    /// # Errors
    /// Invalid options or range, or a density whose mass is not finite and positive or that is
    /// negative somewhere (a decreasing tabulated CDF).
    pub fn from_density(
        f: &(dyn Fn(f64) -> f64 + Sync),
        range: [f64; 2],
        n_samples: u64,
        opts: &QuadratureOptions,
    ) -> Result<Self, StatsError> {
        opts.validate()?;
        check_range(range)?;
        build(
            n_samples,
            opts,
            &graded_breaks(range, MIN_INITIAL_SLABS, &[], false),
            f,
        )
    }
}

/// Monotone cubic Hermite interpolation on `[x0, x1]` between `(x0, f0)` and `(x1, f1)` with
/// end slopes `d0`, `d1` (Fritsch–Carlson: slopes scaled so that `α² + β² ≤ 9`), clamped to
/// `[f0, f1]`.
fn hermite(x0: f64, x1: f64, f0: f64, f1: f64, d0: f64, d1: f64, x: f64) -> f64 {
    let h = x1 - x0;
    let delta = (f1 - f0) / h;
    if !(delta > 0.0) {
        return f0;
    }
    let (mut d0, mut d1) = (d0.max(0.0), d1.max(0.0));
    let (a, b) = (d0 / delta, d1 / delta);
    let r2 = a * a + b * b;
    if r2 > 9.0 {
        let tau = 3.0 / r2.sqrt();
        d0 *= tau;
        d1 *= tau;
    }
    let s = (x - x0) / h;
    let (s2, s3) = (s * s, s * s * s);
    let y = (2.0 * s3 - 3.0 * s2 + 1.0) * f0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * f1
        + (s3 - s2) * h * d1;
    y.clamp(f0, f1)
}

fn check_range(range: [f64; 2]) -> Result<(), StatsError> {
    if !(range[0].is_finite() && range[1].is_finite() && range[0] < range[1]) {
        return Err(StatsError::InvalidBinning(format!(
            "range [{}, {}] must be finite with lower < upper",
            range[0], range[1]
        )));
    }
    Ok(())
}

/// CDF of the projection of `pdf` (a density with respect to the binning's measure) onto
/// parameter axis `axis`, accurate enough for a KS test with `n_samples` samples.
///
/// The marginal density `f(t) = ∫ pdf J d(other)` over the section [`Binning::section`] is
/// integrated by adaptive Gauss–Legendre quadrature (one piece per grid cell spanned, times
/// `2^min_depth`, to absolute accuracy `ε / (8 · range)`), then tabulated as in the module docs.
/// Same as [`projection_cdf_with_singularities`] with no singular point.
///
/// # Errors
/// Invalid options, or a density whose mass is not finite and positive or that is negative
/// somewhere.
pub fn projection_cdf<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    axis: Axis,
    n_samples: u64,
    opts: &QuadratureOptions,
) -> Result<TabulatedCdf, StatsError> {
    projection_cdf_with_singularities(binning, pdf, axis, n_samples, opts, &[])
}

/// [`projection_cdf`] for a density with integrable point singularities at the parameter
/// coordinates `singular` (`[u, v]`; wedge-shaped neighbourhoods, see [`crate::singular`]'s
/// module docs, e.g. the half-vector pdfs at `ωi = −ωo`).
///
/// Every line integral `∫ pdf J d(other)` at `t` is split at each singular point's other
/// coordinate `s₀` and graded geometrically towards it, down to `2⁻¹⁶ |t − t₀|` (`t₀` its
/// coordinate on `axis`; at least `10⁻¹²` of the range), with the tolerance shared equally by
/// the pieces. The knots are not graded towards `t₀`: there the marginal itself is at worst
/// log-singular (integrable), which the adaptive slabs resolve by halving, while graded knots
/// next to it cost a full-depth refinement for nothing (measured: the φ CDF of `analytic ×
/// blinn` at 89° went from 0.8 s to > 300 s). Points outside the parameter rectangle grade towards the nearer edge when within
/// one piece of it (pass `v ± 2π` copies for a periodic `φ`). An empty `singular` is exactly
/// [`projection_cdf`].
///
/// # Errors
/// As [`projection_cdf`].
pub fn projection_cdf_with_singularities<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    axis: Axis,
    n_samples: u64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
) -> Result<TabulatedCdf, StatsError> {
    projection_cdf_memo(binning, pdf, axis, n_samples, opts, singular, None)
}

/// The marginal densities of one projection CDF, kept across repeated runs of it: the
/// validation suite's level-synchronous batched passes (see the quadrature module's docs) run
/// the same projection CDF once per refinement level revealed, with NaN at the pdf values not
/// known yet; a marginal that met none (a finite one) is the direct run's value and is not
/// recomputed by the next pass, so a pass costs only the marginals still refining. A
/// marginal is kept only when every pdf value it used was a number: a NaN (a value not known
/// yet) may have stopped a refinement of the direct run (next to points another test already
/// evaluated) and left a finite but different value.
///
/// A memo belongs to one `(binning, pdf, axis, n_samples, options, singular points)`: it is
/// keyed by the coordinate along the axis only.
#[derive(Debug, Default)]
pub struct MarginalMemo {
    values: RwLock<HashMap<u64, f64>>,
    /// The line integrals of the marginals not finished, by (t, section, piece).
    pieces: RwLock<HashMap<(u64, usize, usize), f64>>,
}

impl MarginalMemo {
    /// Number of marginals kept.
    pub fn len(&self) -> usize {
        self.values.read().map_or(0, |m| m.len())
    }

    /// Whether no marginal is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn get(&self, t: f64) -> Option<f64> {
        self.values.read().ok()?.get(&t.to_bits()).copied()
    }

    fn keep(&self, t: f64, value: f64) {
        if value.is_finite()
            && let Ok(mut m) = self.values.write()
        {
            m.insert(t.to_bits(), value);
        }
    }

    fn piece(&self, key: &(u64, usize, usize)) -> Option<f64> {
        self.pieces.read().ok()?.get(key).copied()
    }

    fn keep_piece(&self, key: (u64, usize, usize), value: f64) {
        if value.is_finite()
            && let Ok(mut m) = self.pieces.write()
        {
            m.insert(key, value);
        }
    }
}

/// [`projection_cdf_with_singularities`] reusing (and filling) `memo`'s finite marginals: the
/// same result as without it, as long as the memo belongs to the same inputs
/// ([`MarginalMemo`]).
///
/// # Errors
/// As [`projection_cdf`].
pub fn projection_cdf_with_memo<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    axis: Axis,
    n_samples: u64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
    memo: &MarginalMemo,
) -> Result<TabulatedCdf, StatsError> {
    projection_cdf_memo(binning, pdf, axis, n_samples, opts, singular, Some(memo))
}

fn projection_cdf_memo<B: Binning + ?Sized>(
    binning: &B,
    pdf: &(dyn Fn(B::Point) -> f64 + Sync),
    axis: Axis,
    n_samples: u64,
    opts: &QuadratureOptions,
    singular: &[[f64; 2]],
    memo: Option<&MarginalMemo>,
) -> Result<TabulatedCdf, StatsError> {
    opts.validate()?;
    let rule = GaussLegendre::new(opts.order);
    let grid = binning.grid();
    let (range, other, other_cells, own_cells) = match axis {
        Axis::U => (grid.u_range(), grid.v_range(), grid.nv(), grid.nu()),
        Axis::V => (grid.v_range(), grid.u_range(), grid.nu(), grid.nv()),
    };
    // (coordinate on `axis`, coordinate along the lines) of each singular point.
    let points: Vec<(f64, f64)> = singular
        .iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .map(|p| match axis {
            Axis::U => (p[0], p[1]),
            Axis::V => (p[1], p[0]),
        })
        .collect();
    let eps = epsilon(n_samples, opts);
    let inner_tol = 0.125 * eps / (range[1] - range[0]);
    // The marginal at `t` is a sum of 1D adaptive integrals ("pieces") along the lines of the
    // sections. With a memo, a marginal or piece is kept when every pdf value it used was a
    // number (a NaN is a value not known yet in a batched pass: such a value is not kept even
    // when finite, since a NaN may have stopped a refinement that the direct run makes).
    // Pieces are integrated one by one with their share of the tolerance and summed in order,
    // exactly as `integrate_1d` over all of them does.
    let line_integrals = |t: f64| -> (f64, bool) {
        let nans = std::cell::Cell::new(0u64);
        let piece = |section: usize, i: usize, range: [f64; 2], tol: f64, depth: u32| -> f64 {
            let key = (t.to_bits(), section, i);
            if let Some(v) = memo.and_then(|m| m.piece(&key)) {
                return v;
            }
            let before = nans.get();
            let g = |s: f64| {
                let uv = match axis {
                    Axis::U => [t, s],
                    Axis::V => [s, t],
                };
                let p = pdf(binning.point_at(uv));
                if p.is_nan() {
                    nans.set(nans.get() + 1);
                }
                p * binning.jacobian(uv)
            };
            let v = integrate_1d(&g, range, tol, &rule, depth, 1).value;
            if let Some(m) = memo
                && nans.get() == before
            {
                m.keep_piece(key, v);
            }
            v
        };
        let value = binning
            .section(axis, t)
            .into_iter()
            .enumerate()
            .map(|(section, [c0, c1])| {
                let frac = ((c1 - c0) / (other[1] - other[0])).clamp(0.0, 1.0);
                let pieces =
                    ((frac * other_cells as f64).ceil().max(1.0) as usize) << opts.min_depth;
                if points.is_empty() {
                    let tol = inner_tol / pieces as f64;
                    let depth = opts.max_depth.max(20);
                    let mut value = 0.0;
                    for i in 0..pieces {
                        value += piece(section, i, split([c0, c1], pieces, i), tol, depth);
                    }
                    return value;
                }
                let centres: Vec<(f64, f64)> = points
                    .iter()
                    .map(|&(t0, s0)| (s0, LINE_FLOOR_FRACTION * (t - t0).abs()))
                    .collect();
                let breaks = graded_breaks([c0, c1], pieces, &centres, true);
                // Equal shares of the tolerance; the graded pieces already have the scale of
                // the feature, so refinement below them stops at `max_depth` (not 20: next to
                // the singularity the pdf's round-off would otherwise drive every piece to the
                // full depth).
                let tol = inner_tol / (breaks.len() - 1).max(1) as f64;
                breaks
                    .windows(2)
                    .enumerate()
                    .map(|(i, w)| piece(section, i, [w[0], w[1]], tol, opts.max_depth))
                    .sum::<f64>()
            })
            .sum();
        (value, nans.get() == 0)
    };
    let marginal = |t: f64| -> f64 {
        if let Some(v) = memo.and_then(|m| m.get(t)) {
            return v;
        }
        let (value, clean) = line_integrals(t);
        if let Some(m) = memo
            && clean
        {
            m.keep(t, value);
        }
        value
    };
    let starts = graded_breaks(range, own_cells.max(MIN_INITIAL_SLABS), &[], false);
    build(n_samples, opts, &starts, &marginal)
}

fn epsilon(n_samples: u64, opts: &QuadratureOptions) -> f64 {
    opts.accuracy / (n_samples.max(1) as f64).sqrt()
}

/// Tabulates the CDF of the 1D density `f` on `[starts₀, starts_last]` by adaptive slabs,
/// starting from the slabs between consecutive `starts` (sorted, at least two).
fn build(
    n_samples: u64,
    opts: &QuadratureOptions,
    starts: &[f64],
    f: &(dyn Fn(f64) -> f64 + Sync),
) -> Result<TabulatedCdf, StatsError> {
    let rule = GaussLegendre::new(opts.order);
    let range = [starts[0], starts[starts.len() - 1]];
    let ctx = Refine {
        eps: epsilon(n_samples, opts),
        width: range[1] - range[0],
        rule: &rule,
        f,
    };
    let edge_density: Vec<f64> = starts.par_iter().map(|&x| f(x)).collect();
    let slabs: Vec<Vec<Knot>> = (0..starts.len() - 1)
        .into_par_iter()
        .map(|i| {
            let (a, b) = (starts[i], starts[i + 1]);
            let mut out = Vec::new();
            let ends = (edge_density[i], edge_density[i + 1]);
            ctx.refine(a, b, ctx.mass(a, b), ends, MAX_KNOT_DEPTH, &mut out);
            out
        })
        .collect();
    let mut knots = vec![range[0]];
    let mut values = vec![0.0];
    let mut densities = vec![edge_density[0]];
    let mut acc = 0.0;
    for k in slabs.into_iter().flatten() {
        if !(k.mass.is_finite() && k.density.is_finite()) {
            return Err(StatsError::InvalidMass { mass: k.mass });
        }
        acc += k.mass;
        knots.push(k.at);
        values.push(acc);
        densities.push(k.density.max(0.0));
    }
    TabulatedCdf::with_densities(knots, values, densities)
}

/// The right end of an accepted slab.
struct Knot {
    at: f64,
    mass: f64,
    density: f64,
}

struct Refine<'a> {
    eps: f64,
    width: f64,
    rule: &'a GaussLegendre,
    f: &'a (dyn Fn(f64) -> f64 + Sync),
}

impl Refine<'_> {
    fn mass(&self, a: f64, b: f64) -> f64 {
        self.rule.integrate_1d(self.f, a, b)
    }

    /// Appends the accepted slabs covering `[a, b]` (mass estimate `m`, densities `ends` at the
    /// end points).
    ///
    /// The slab's quarters are integrated; it is accepted when (1) the quarters' sum agrees
    /// with `m` within `ε/4 · (b − a)/range` (so the masses are accurate) and (2) the slab mass
    /// is at most `ε`, or the monotone cubic Hermite interpolant over the slab reproduces the
    /// integrated CDF at the midpoint and both quarter points within `ε`. Otherwise it is halved.
    fn refine(
        &self,
        a: f64,
        b: f64,
        m: f64,
        ends: (f64, f64),
        depth_left: u32,
        out: &mut Vec<Knot>,
    ) {
        let h = b - a;
        let (x1, x2, x3) = (a + 0.25 * h, a + 0.5 * h, a + 0.75 * h);
        let accept = |mass: f64, out: &mut Vec<Knot>| {
            out.push(Knot {
                at: b,
                mass,
                density: ends.1,
            })
        };
        if !(a < x1 && x1 < x2 && x2 < x3 && x3 < b) {
            accept(m, out);
            return;
        }
        let q = [
            self.mass(a, x1),
            self.mass(x1, x2),
            self.mass(x2, x3),
            self.mass(x3, b),
        ];
        let total = q.iter().sum::<f64>();
        let eps = self.eps;
        let mass_ok = (total - m).abs() <= 0.25 * eps * h / self.width;
        let small = total.abs() <= eps;
        let interp_ok = total > 0.0 && {
            let predict = |x: f64| hermite(a, b, 0.0, total, ends.0, ends.1, x);
            (predict(x1) - q[0]).abs() <= eps
                && (predict(x2) - q[0] - q[1]).abs() <= eps
                && (predict(x3) - (total - q[3])).abs() <= eps
        };
        if (mass_ok && (small || interp_ok)) || depth_left == 0 || !total.is_finite() {
            accept(total, out);
            return;
        }
        let fm = (self.f)(x2);
        self.refine(a, x2, q[0] + q[1], (ends.0, fm), depth_left - 1, out);
        self.refine(x2, b, q[2] + q[3], (fm, ends.1), depth_left - 1, out);
    }
}

/// Parameter coordinates of points along an axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Projection {
    /// Coordinate `u` or `v` of each point inside the domain, in input order.
    pub values: Vec<f64>,
    /// Points outside the domain (or not finite), which have no coordinate.
    pub outside: usize,
}

/// Projects points onto a parameter axis (`cos θ`/`φ` for directions, `x`/`y` for planar points).
pub fn project<B: Binning + ?Sized>(binning: &B, points: &[B::Point], axis: Axis) -> Projection {
    let mut values = Vec::with_capacity(points.len());
    let mut outside = 0;
    for p in points {
        match binning.param_of(p) {
            Some(uv) => values.push(match axis {
                Axis::U => uv[0],
                Axis::V => uv[1],
            }),
            None => outside += 1,
        }
    }
    Projection { values, outside }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binning::SphereBinning;
    use std::sync::Mutex;

    /// Runs `cdf` pass by pass as the validation suite's batched passes do: NaN at the points
    /// not known yet, then those points evaluated, until a pass meets no unknown point.
    type Pdf<'a> = dyn Fn([f64; 3]) -> f64 + Sync + 'a;

    fn replay(
        known: &RwLock<HashMap<[u64; 3], f64>>,
        pdf: &Pdf<'_>,
        cdf: &dyn Fn(&Pdf<'_>) -> TabulatedCdf,
    ) -> (TabulatedCdf, usize) {
        for pass in 1.. {
            let missing: Mutex<Vec<[f64; 3]>> = Mutex::default();
            let r = {
                let values = known.read().unwrap();
                cdf(&|p: [f64; 3]| match values.get(&p.map(f64::to_bits)) {
                    Some(&v) => v,
                    None => {
                        missing.lock().unwrap().push(p);
                        f64::NAN
                    }
                })
            };
            let missing = missing.into_inner().unwrap();
            if missing.is_empty() {
                return (r, pass);
            }
            let mut values = known.write().unwrap();
            for p in missing {
                values.insert(p.map(f64::to_bits), pdf(p));
            }
        }
        unreachable!()
    }

    /// The values known from the first axis's passes are known to the second's (as in the
    /// suite, where every test of a sampler shares them): a marginal finished next to such
    /// points while a NaN stopped a refinement would be kept wrong without the NaN check.
    #[test]
    fn memoised_passes_give_the_direct_cdf() {
        let known = RwLock::default();
        let bins = SphereBinning::hemisphere(4, 8).unwrap();
        let opts = QuadratureOptions::default();
        let pdf = |d: [f64; 3]| {
            let p = 3.0 / (2.0 * std::f64::consts::PI) * d[2].max(0.0).powi(2);
            if d[0] > 0.5 { 1.02 * p } else { p }
        };
        for axis in [Axis::U, Axis::V] {
            let direct = projection_cdf(&bins, &pdf, axis, 20_000, &opts).unwrap();
            let memo = MarginalMemo::default();
            let (passed, passes) = replay(&known, &pdf, &|f| match projection_cdf_with_memo(
                &bins,
                f,
                axis,
                20_000,
                &opts,
                &[],
                &memo,
            ) {
                Ok(c) => c,
                Err(_) => TabulatedCdf::new(vec![0.0, 1.0], vec![0.0, 1.0]).unwrap(),
            });
            assert!(passes > 3, "{axis:?}: {passes} passes");
            assert_eq!(direct.knots(), passed.knots(), "{axis:?}");
            assert_eq!(direct.values(), passed.values(), "{axis:?}");
        }
    }
}
