//! Densities and region-statistics providers (upper bound `M_i` and integral `I_i` of a cell).

use serde::{Deserialize, Serialize};

use crate::contract::Point2;
use crate::error::DensityError;
use crate::rect::{Domain, Rect};
pub use crate::shape::{DensityShape, ProviderKind};

/// A non-negative function `f` on the plane, evaluated pointwise.
///
/// `f` need not be normalised. Samplers treat `f` as zero outside their domain.
/// Implemented for every closure `Fn(Point2) -> f64 + Sync`.
pub trait Density: Sync {
    /// `f(p) ≥ 0`.
    fn eval(&self, p: Point2) -> f64;

    /// `out[k] = f(points[k])` for every `k` (the lengths must match; extra entries of the
    /// longer slice are left alone), bit for bit what [`Density::eval`] returns.
    ///
    /// The batch path of the quadtree sampler calls it once per block of candidate points so
    /// that a provider can issue its memory lookups together (a tabulated density gathers all
    /// cell values first, letting the cache misses overlap) before doing the arithmetic.
    #[inline]
    fn eval_block(&self, points: &[Point2], out: &mut [f64]) {
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.eval(p);
        }
    }

    /// `f(p)`, or [`DensityError::InvalidSample`] when it is NaN, negative or infinite (what
    /// the region-statistics providers use on user densities).
    fn eval_checked(&self, p: Point2) -> Result<f64, DensityError> {
        let v = self.eval(p);
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(DensityError::InvalidSample {
                x: p[0],
                y: p[1],
                value: v,
            })
        }
    }
}

impl<F: Fn(Point2) -> f64 + Sync> Density for F {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self(p)
    }
}

/// What a provider knows about a region `R` (a quadtree cell intersected with the domain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegionEstimate {
    /// `M ≥ sup_{x ∈ R ∩ D} f(x)` (exact for tabulated densities, an estimate with a safety
    /// factor for sampled ones: the sampler audits it).
    pub max_bound: f64,
    /// `I ≈ ∫_{R ∩ D} f dA` (area measure on the domain).
    pub integral: f64,
    /// Estimated relative error of `integral`, when the provider knows one.
    pub integral_rel_err: Option<f64>,
}

/// How a provider obtains integrals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum IntegralSource {
    /// Exact up to floating-point rounding (tabulated densities).
    Exact,
    /// Midpoint rule on a dense grid (the papers' "image map"), with a Richardson error estimate.
    GridEstimate,
    /// Per-cell quadrature at a caller-given resolution.
    Quadrature,
}

/// A density that can also bound and integrate itself over rectangles: what the quadtree
/// builder needs.
///
/// Contract: `region(cell)` describes `f` on `cell ∩ domain()`; `max_bound` must be an upper
/// bound of `f` there for the sampler to be exact (violations are counted by the sampler's
/// audit); integrals are with respect to area.
pub trait RegionStats: Density {
    /// The domain `D` of the density (`f` is taken as 0 outside it).
    fn domain(&self) -> Domain;

    /// Upper bound and integral of `f` on `cell ∩ D`.
    fn region(&self, cell: &Rect) -> RegionEstimate;

    /// How integrals are obtained.
    fn integral_source(&self) -> IntegralSource;

    /// Estimated relative error of the integral over the whole domain, when known globally.
    fn total_rel_err(&self) -> Option<f64> {
        None
    }

    /// Smallest useful cell `[width, height]`: the builder never splits a cell into children
    /// smaller than this (e.g. the fine-grid cell of a sampled density).
    fn min_cell_size(&self) -> Option<[f64; 2]> {
        None
    }

    /// Shape and fingerprint, checked when a stored tree is re-attached.
    fn shape(&self) -> DensityShape;

    /// Heap and inline bytes held by the provider.
    fn bytes_used(&self) -> usize;
}

/// A density shared between samplers: `SharedDensity(Arc<T>)` implements [`Density`] and
/// [`RegionStats`] by delegation (a blanket impl for `&T` or `Arc<T>` would overlap with the
/// one for closures).
#[derive(Debug, Clone)]
pub struct SharedDensity<T: ?Sized>(pub std::sync::Arc<T>);

impl<T> SharedDensity<T> {
    /// Wraps `value` in an `Arc`.
    pub fn new(value: T) -> Self {
        Self(std::sync::Arc::new(value))
    }
}

impl<T: Density + Send + ?Sized> Density for SharedDensity<T> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.0.eval(p)
    }
    #[inline]
    fn eval_block(&self, points: &[Point2], out: &mut [f64]) {
        self.0.eval_block(points, out)
    }
}

impl<T: RegionStats + Send + ?Sized> RegionStats for SharedDensity<T> {
    fn domain(&self) -> Domain {
        self.0.domain()
    }
    fn region(&self, cell: &Rect) -> RegionEstimate {
        self.0.region(cell)
    }
    fn integral_source(&self) -> IntegralSource {
        self.0.integral_source()
    }
    fn total_rel_err(&self) -> Option<f64> {
        self.0.total_rel_err()
    }
    fn min_cell_size(&self) -> Option<[f64; 2]> {
        self.0.min_cell_size()
    }
    fn shape(&self) -> DensityShape {
        self.0.shape()
    }
    /// Bytes of the shared provider (counted by every sampler that holds it).
    fn bytes_used(&self) -> usize {
        self.0.bytes_used()
    }
}
