//! Densities whose region bounds the caller supplies (Lipschitz or analytic bounds).

use crate::contract::Point2;
use crate::density::{
    Density, DensityShape, IntegralSource, ProviderKind, RegionEstimate, RegionStats,
};
use crate::error::DensityError;
use crate::rect::{Domain, Rect};

/// A density `f` with a caller-supplied bound `upper_bound(cell) ≥ sup_{cell ∩ D} f`;
/// integrals by the `q × q` midpoint rule on each cell (points outside the disc count as 0),
/// with the relative error estimated per cell by Richardson extrapolation against the
/// `q/2 × q/2` rule (`|I_q − I_{q/2}| / 3`).
///
/// Exactness of the envelope scheme rests only on the bound; the integrals only shape the
/// tree and normalise the pdf.
#[derive(Clone)]
pub struct UserBoundDensity<D, B> {
    f: D,
    bound: B,
    domain: Domain,
    q: usize,
}

impl<D: Density, B: Fn(&Rect) -> f64 + Sync> UserBoundDensity<D, B> {
    /// `f`, its bound, the domain and the per-cell quadrature resolution `q` (even, 2..=1024).
    pub fn new(f: D, upper_bound: B, domain: Domain, q: usize) -> Result<Self, DensityError> {
        if !(2..=1024).contains(&q) || !q.is_multiple_of(2) {
            return Err(DensityError::InvalidQuadrature(q));
        }
        if !domain.is_valid() {
            return Err(DensityError::InvalidDomain(domain.bounding_rect()));
        }
        Ok(Self {
            f,
            bound: upper_bound,
            domain,
            q,
        })
    }

    /// The wrapped density.
    pub fn inner(&self) -> &D {
        &self.f
    }

    /// Midpoint rule with `k × k` points on `cell ∩ D`.
    fn midpoint(&self, cell: &Rect, k: usize) -> f64 {
        let (w, h) = (cell.width(), cell.height());
        let mut s = 0.0;
        for b in 0..k {
            for a in 0..k {
                let p = [
                    cell.x0 + (a as f64 + 0.5) / k as f64 * w,
                    cell.y0 + (b as f64 + 0.5) / k as f64 * h,
                ];
                s += self.eval(p);
            }
        }
        s * cell.area() / (k * k) as f64
    }
}

impl<D, B> std::fmt::Debug for UserBoundDensity<D, B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UserBoundDensity")
            .field("domain", &self.domain)
            .field("q", &self.q)
            .finish_non_exhaustive()
    }
}

impl<D: Density, B: Fn(&Rect) -> f64 + Sync> Density for UserBoundDensity<D, B> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.domain.restrict(p, |p| self.f.eval(p))
    }
}

impl<D: Density, B: Fn(&Rect) -> f64 + Sync> RegionStats for UserBoundDensity<D, B> {
    fn domain(&self) -> Domain {
        self.domain
    }

    fn region(&self, cell: &Rect) -> RegionEstimate {
        let fine = self.midpoint(cell, self.q);
        let coarse = self.midpoint(cell, self.q / 2);
        let rel = if fine > 0.0 {
            (fine - coarse).abs() / 3.0 / fine
        } else {
            0.0
        };
        RegionEstimate {
            max_bound: (self.bound)(cell),
            integral: fine,
            integral_rel_err: Some(rel),
        }
    }

    fn integral_source(&self) -> IntegralSource {
        IntegralSource::Quadrature
    }

    fn shape(&self) -> DensityShape {
        DensityShape {
            kind: ProviderKind::UserBound,
            domain: self.domain,
            dims: [self.q as u64, self.q as u64],
            fingerprint: 0,
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
    }
}
