//! Tabulated CDFs of 1D projections, built by quadrature of a density.
//!
//! The CDF of the projection of a 2D density onto a parameter axis (`cos θ` or `φ` for
//! directions; columns `x` or rows `y` of an image) is `F(t) = ∫_{u ≤ t} pdf dμ`. It is
//! tabulated at knots and interpolated linearly. Knots start as 32 equal slabs; a slab
//! `[a, b]` is halved while the linear interpolant misses the integrated midpoint value
//! `F(mid)` by more than `ε = accuracy / √n` (the KS noise level is `≈ 1/√n`); slab masses are
//! integrated with an absolute tolerance `ε/4 · (b − a)/(range)`, so the accumulated error of
//! `F` stays below `ε/4`. Values are normalised by the total mass (a density that does not
//! integrate to one is the normalisation test's business).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::binning::{Axis, Binning};
use crate::error::StatsError;
use crate::quadrature::{GaussLegendre, QuadratureOptions, integrate_1d, integrate_rect};

const INITIAL_SLABS: usize = 32;
const MAX_KNOT_DEPTH: u32 = 24;

/// A monotone piecewise-linear CDF on `[knots₀, knots_last]`: 0 below, 1 above.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TabulatedCdf {
    knots: Vec<f64>,
    values: Vec<f64>,
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
            total_mass: total,
        })
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
        f0 + (f1 - f0) * ((x - x0) / (x1 - x0))
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
        let rule = GaussLegendre::new(opts.order);
        let mass = |a: f64, b: f64, tol: f64| {
            integrate_1d(f, [a, b], tol, &rule, opts.max_depth.max(20)).value
        };
        build(range, n_samples, opts, &mass)
    }
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
    let grid = binning.grid();
    let (range, other) = match axis {
        Axis::U => (grid.u_range(), grid.v_range()),
        Axis::V => (grid.v_range(), grid.u_range()),
    };
    let mass = |a: f64, b: f64, tol: f64| {
        let (u, v) = match axis {
            Axis::U => ([a, b], other),
            Axis::V => (other, [a, b]),
        };
        // The tolerance is always valid (positive, finite) by construction.
        integrate_rect(pdf, binning, u, v, tol, opts).map_or(f64::NAN, |r| r.value)
    };
    build(range, n_samples, opts, &mass)
}

/// Builds knots by adaptive halving; `mass(a, b, tol)` integrates the density over `[a, b]`.
fn build(
    range: [f64; 2],
    n_samples: u64,
    opts: &QuadratureOptions,
    mass: &(dyn Fn(f64, f64, f64) -> f64 + Sync),
) -> Result<TabulatedCdf, StatsError> {
    let eps = opts.accuracy / (n_samples.max(1) as f64).sqrt();
    let width = range[1] - range[0];
    let slab_mass = |a: f64, b: f64| mass(a, b, (0.25 * eps * (b - a) / width).max(1e-300));
    let slabs: Vec<Vec<(f64, f64)>> = (0..INITIAL_SLABS)
        .into_par_iter()
        .map(|i| {
            let a = range[0] + width * (i as f64 / INITIAL_SLABS as f64);
            let b = if i + 1 == INITIAL_SLABS {
                range[1]
            } else {
                range[0] + width * ((i + 1) as f64 / INITIAL_SLABS as f64)
            };
            let mut out = Vec::new();
            refine(a, b, slab_mass(a, b), eps, MAX_KNOT_DEPTH, &slab_mass, &mut out);
            out
        })
        .collect();
    let mut knots = vec![range[0]];
    let mut values = vec![0.0];
    let mut acc = 0.0;
    for (b, m) in slabs.into_iter().flatten() {
        if !m.is_finite() {
            return Err(StatsError::InvalidMass { mass: m });
        }
        acc += m;
        knots.push(b);
        values.push(acc);
    }
    TabulatedCdf::new(knots, values)
}

/// Appends `(right knot, mass)` pairs covering `[a, b]` (whose mass is `m`).
///
/// A slab is accepted when its mass is at most `eps` (linear interpolation cannot then be off by
/// more than `eps`), or when linear interpolation predicts the integrated CDF at the midpoint
/// *and* at both quarter points within `eps` (the quarter check guards against a feature
/// centred on the midpoint); it then contributes knots at its quarters. Otherwise both halves
/// are refined.
fn refine(
    a: f64,
    b: f64,
    m: f64,
    eps: f64,
    depth_left: u32,
    slab_mass: &(dyn Fn(f64, f64) -> f64 + Sync),
    out: &mut Vec<(f64, f64)>,
) {
    let h = b - a;
    let (x1, x2, x3) = (a + 0.25 * h, a + 0.5 * h, a + 0.75 * h);
    if m.abs() <= eps || depth_left == 0 || !m.is_finite() || !(a < x1 && x3 < b) {
        out.push((b, m));
        return;
    }
    let q = [
        slab_mass(a, x1),
        slab_mass(x1, x2),
        slab_mass(x2, x3),
        slab_mass(x3, b),
    ];
    let (ml, mr) = (q[0] + q[1], q[2] + q[3]);
    let pass = 0.5 * (ml - mr).abs() <= eps
        && 0.5 * (q[0] - q[1]).abs() <= eps
        && 0.5 * (q[2] - q[3]).abs() <= eps;
    if pass {
        out.extend([(x1, q[0]), (x2, q[1]), (x3, q[2]), (b, q[3])]);
        return;
    }
    refine(a, x2, ml, eps, depth_left - 1, slab_mass, out);
    refine(x2, b, mr, eps, depth_left - 1, slab_mass, out);
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
