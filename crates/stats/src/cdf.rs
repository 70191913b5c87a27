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

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::binning::{Axis, Binning};
use crate::error::StatsError;
use crate::quadrature::{GaussLegendre, QuadratureOptions, integrate_1d};

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
        build(range, n_samples, opts, MIN_INITIAL_SLABS, f)
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
    opts.validate()?;
    let rule = GaussLegendre::new(opts.order);
    let grid = binning.grid();
    let (range, other, other_cells, own_cells) = match axis {
        Axis::U => (grid.u_range(), grid.v_range(), grid.nv(), grid.nu()),
        Axis::V => (grid.v_range(), grid.u_range(), grid.nu(), grid.nv()),
    };
    let eps = epsilon(n_samples, opts);
    let inner_tol = 0.125 * eps / (range[1] - range[0]);
    let marginal = |t: f64| -> f64 {
        binning
            .section(axis, t)
            .into_iter()
            .map(|[c0, c1]| {
                let frac = ((c1 - c0) / (other[1] - other[0])).clamp(0.0, 1.0);
                let pieces =
                    ((frac * other_cells as f64).ceil().max(1.0) as usize) << opts.min_depth;
                let g = |s: f64| {
                    let uv = match axis {
                        Axis::U => [t, s],
                        Axis::V => [s, t],
                    };
                    pdf(binning.point_at(uv)) * binning.jacobian(uv)
                };
                integrate_1d(
                    &g,
                    [c0, c1],
                    inner_tol,
                    &rule,
                    opts.max_depth.max(20),
                    pieces,
                )
                .value
            })
            .sum()
    };
    build(
        range,
        n_samples,
        opts,
        own_cells.max(MIN_INITIAL_SLABS),
        &marginal,
    )
}

fn epsilon(n_samples: u64, opts: &QuadratureOptions) -> f64 {
    opts.accuracy / (n_samples.max(1) as f64).sqrt()
}

/// Tabulates the CDF of the 1D density `f` on `range` by adaptive slabs.
fn build(
    range: [f64; 2],
    n_samples: u64,
    opts: &QuadratureOptions,
    initial_slabs: usize,
    f: &(dyn Fn(f64) -> f64 + Sync),
) -> Result<TabulatedCdf, StatsError> {
    let rule = GaussLegendre::new(opts.order);
    let ctx = Refine {
        eps: epsilon(n_samples, opts),
        width: range[1] - range[0],
        rule: &rule,
        f,
    };
    let at = |k: usize| {
        if k == initial_slabs {
            range[1]
        } else {
            range[0] + ctx.width * (k as f64 / initial_slabs as f64)
        }
    };
    let edge_density: Vec<f64> = (0..=initial_slabs)
        .into_par_iter()
        .map(|k| f(at(k)))
        .collect();
    let slabs: Vec<Vec<Knot>> = (0..initial_slabs)
        .into_par_iter()
        .map(|i| {
            let (a, b) = (at(i), at(i + 1));
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
