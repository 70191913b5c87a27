//! The points where a [`super::SampledGridDensity`] evaluates `f`, evaluated lazily and in
//! parallel, with an optional mirror symmetry `f(x, −y) = f(x, y)`.

use rayon::prelude::*;

use crate::contract::Point2;
use crate::density::Density;
use crate::error::DensityError;
use crate::rect::{Domain, Rect};

/// A point of the `n × n` fine-cell grid: a corner `(a, b)`, `0 ≤ a, b ≤ n`, or the centre of
/// fine cell `(a, b)`, `0 ≤ a, b < n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum GridPoint {
    /// Lattice corner.
    Corner(usize, usize),
    /// Centre of a fine cell.
    Centre(usize, usize),
}

/// Values of `f` at grid points, `NaN` until evaluated (a valid value is never `NaN`).
pub(super) struct Lattice<'a, D> {
    f: &'a D,
    domain: Domain,
    grid: Rect,
    n: usize,
    /// `f(x, −y) = f(x, y)` is assumed: only points with `y ≤ 0` are evaluated.
    mirror: bool,
    /// `(n + 1)²` corners (row-major), then `n²` centres.
    values: Vec<f64>,
    evaluations: usize,
}

impl<'a, D: Density> Lattice<'a, D> {
    pub(super) fn new(f: &'a D, domain: Domain, n: usize, mirror: bool) -> Self {
        Self {
            f,
            domain,
            grid: domain.bounding_rect(),
            n,
            mirror,
            values: vec![f64::NAN; (n + 1) * (n + 1) + n * n],
            evaluations: 0,
        }
    }

    fn id(&self, p: GridPoint) -> usize {
        match p {
            GridPoint::Corner(a, b) => b * (self.n + 1) + a,
            GridPoint::Centre(a, b) => (self.n + 1) * (self.n + 1) + b * self.n + a,
        }
    }

    /// The point evaluated for `p`: its mirror image when mirroring and `p` has `y > 0`.
    fn canonical(&self, p: GridPoint) -> GridPoint {
        if !self.mirror {
            return p;
        }
        match p {
            GridPoint::Corner(a, b) if b > self.n - b => GridPoint::Corner(a, self.n - b),
            GridPoint::Centre(a, b) if b > self.n - 1 - b => GridPoint::Centre(a, self.n - 1 - b),
            _ => p,
        }
    }

    fn position(&self, p: GridPoint) -> Point2 {
        let (hx, hy) = (
            self.grid.width() / self.n as f64,
            self.grid.height() / self.n as f64,
        );
        let (a, b, off) = match p {
            GridPoint::Corner(a, b) => (a, b, 0.0),
            GridPoint::Centre(a, b) => (a, b, 0.5),
        };
        [
            self.grid.x0 + (a as f64 + off) * hx,
            self.grid.y0 + (b as f64 + off) * hy,
        ]
    }

    /// Evaluates `f` at every point of `points` not evaluated yet (in parallel; the result does
    /// not depend on the thread count). Points outside the domain are 0 without a call to `f`.
    /// Errors name the first invalid value in the order of `points`.
    pub(super) fn ensure(&mut self, points: &[GridPoint]) -> Result<(), DensityError> {
        let mut todo: Vec<(usize, GridPoint)> = points
            .iter()
            .map(|&p| self.canonical(p))
            .map(|p| (self.id(p), p))
            .filter(|&(id, _)| self.values[id].is_nan())
            .collect();
        // Keep the first occurrence of each point, in request order.
        let mut seen = std::collections::HashSet::with_capacity(todo.len());
        todo.retain(|&(id, _)| seen.insert(id));
        let (f, domain) = (self.f, self.domain);
        // `None`: outside the domain (0, no call to `f`).
        let results: Vec<Result<Option<f64>, DensityError>> = todo
            .par_iter()
            .map(|&(_, p)| {
                let x = self.position(p);
                domain.contains(x).then(|| f.eval_checked(x)).transpose()
            })
            .collect();
        for (&(id, _), r) in todo.iter().zip(results) {
            let v = r?;
            self.evaluations += usize::from(v.is_some());
            self.values[id] = v.unwrap_or(0.0);
        }
        if self.mirror {
            for &p in points {
                let id = self.id(p);
                if self.values[id].is_nan() {
                    self.values[id] = self.values[self.id(self.canonical(p))];
                }
            }
        }
        Ok(())
    }

    /// The value at `p` (`NaN` if it was never requested).
    #[inline]
    pub(super) fn get(&self, p: GridPoint) -> f64 {
        self.values[self.id(p)]
    }

    /// Points where `f` was called.
    pub(super) fn evaluations(&self) -> usize {
        self.evaluations
    }
}
