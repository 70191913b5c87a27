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

/// The mark of a point [`Lattice::ensure`] has claimed but not evaluated yet (a value is never
/// negative).
const CLAIMED: f64 = -1.0;

/// Points per [`Density::eval_block`] call of [`Lattice::ensure`].
const ENSURE_BLOCK: usize = 64;

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
    ///
    /// The points to evaluate are the first occurrence of each unknown point, in request
    /// order: a point is claimed by writing [`CLAIMED`] (negative, never a value) into its slot,
    /// so a repeat is skipped without a hash set. They are evaluated in blocks of
    /// [`ENSURE_BLOCK`] by [`Density::eval_block`] (bit for bit `eval`, the trait's contract),
    /// so a density that evaluates blocks in vector lanes can; the values are checked as
    /// [`Density::eval_checked`] checks them.
    pub(super) fn ensure(&mut self, points: &[GridPoint]) -> Result<(), DensityError> {
        let mut todo: Vec<(usize, GridPoint)> = Vec::with_capacity(points.len());
        for &p in points {
            let p = self.canonical(p);
            let id = self.id(p);
            if self.values[id].is_nan() {
                self.values[id] = CLAIMED;
                todo.push((id, p));
            }
        }
        let (f, domain) = (self.f, self.domain);
        let mut values = vec![0.0f64; todo.len()];
        // Per point: inside the domain (evaluated) or not (0, no call to `f`).
        let mut inside = vec![false; todo.len()];
        todo.par_chunks(ENSURE_BLOCK)
            .zip(values.par_chunks_mut(ENSURE_BLOCK))
            .zip(inside.par_chunks_mut(ENSURE_BLOCK))
            .for_each(|((todo, values), inside)| {
                let mut at = [[0.0f64; 2]; ENSURE_BLOCK];
                let mut slot = [0usize; ENSURE_BLOCK];
                let mut m = 0;
                for (k, &(_, p)) in todo.iter().enumerate() {
                    let x = self.position(p);
                    if domain.contains(x) {
                        inside[k] = true;
                        at[m] = x;
                        slot[m] = k;
                        m += 1;
                    }
                }
                let mut out = [0.0f64; ENSURE_BLOCK];
                f.eval_block(&at[..m], &mut out[..m]);
                for (&k, &v) in slot[..m].iter().zip(&out[..m]) {
                    values[k] = v;
                }
            });
        for (k, &(id, p)) in todo.iter().enumerate() {
            let v = values[k];
            if inside[k] && !(v.is_finite() && v >= 0.0) {
                // Leave the lattice as it was: the unevaluated points unknown again.
                for &(id, _) in &todo[k..] {
                    self.values[id] = f64::NAN;
                }
                let x = self.position(p);
                return Err(DensityError::InvalidSample {
                    x: x[0],
                    y: x[1],
                    value: v,
                });
            }
            self.evaluations += usize::from(inside[k]);
            self.values[id] = v;
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

#[cfg(test)]
mod tests {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

    use super::*;

    /// A density that records every point it is asked for and the size of every block call.
    struct Recorder {
        calls: Mutex<Vec<Point2>>,
        blocks: AtomicUsize,
        /// `f` is NaN at these points (an invalid value).
        bad: Vec<Point2>,
    }

    impl Recorder {
        fn new(bad: Vec<Point2>) -> Self {
            Self {
                calls: Mutex::new(Vec::new()),
                blocks: AtomicUsize::new(0),
                bad,
            }
        }
        fn f(p: Point2) -> f64 {
            1.0 + p[0] * p[0] + 2.0 * (p[1] + 0.25).abs()
        }
    }

    impl Density for Recorder {
        fn eval(&self, p: Point2) -> f64 {
            self.calls.lock().unwrap().push(p);
            if self.bad.contains(&p) {
                f64::NAN
            } else {
                Self::f(p)
            }
        }
        fn eval_block(&self, points: &[Point2], out: &mut [f64]) {
            self.blocks.fetch_add(1, Relaxed);
            for (o, &p) in out.iter_mut().zip(points) {
                *o = self.eval(p);
            }
        }
    }

    fn every_point(n: usize) -> Vec<GridPoint> {
        let mut p: Vec<GridPoint> = (0..=n)
            .flat_map(|b| (0..=n).map(move |a| GridPoint::Corner(a, b)))
            .collect();
        p.extend((0..n).flat_map(|b| (0..n).map(move |a| GridPoint::Centre(a, b))));
        p
    }

    /// Issue 29 (docs/benchmarks.md §27.4): every requested point, repeated or mirrored, is
    /// evaluated once, through `eval_block`, and reads `f` at its own position (its mirror
    /// image's when mirroring); points outside the disc are 0 without a call.
    #[test]
    fn ensure_evaluates_each_point_once_in_blocks() {
        for (domain, mirror) in [
            (Domain::Rect(Rect::new(-1.0, -1.0, 1.0, 0.5)), false),
            (Domain::UnitDisc, false),
            (Domain::UnitDisc, true),
        ] {
            let n = 16;
            let f = Recorder::new(Vec::new());
            let mut lat = Lattice::new(&f, domain, n, mirror);
            let all = every_point(n);
            // Requested twice over, in two calls, with repeats inside each call.
            let (first, second) = all.split_at(all.len() / 3);
            let twice: Vec<GridPoint> = first.iter().chain(first).copied().collect();
            lat.ensure(&twice).unwrap();
            lat.ensure(&all).unwrap();
            lat.ensure(second).unwrap();
            let calls = f.calls.lock().unwrap().clone();
            let mut unique = calls.clone();
            unique.sort_by(|a, b| a.partial_cmp(b).unwrap());
            unique.dedup();
            assert_eq!(
                unique.len(),
                calls.len(),
                "{domain:?} {mirror}: a point twice"
            );
            assert_eq!(lat.evaluations(), calls.len());
            assert!(f.blocks.load(Relaxed) <= calls.len().div_ceil(ENSURE_BLOCK) + 4);
            for &p in &all {
                let x = lat.position(p);
                let at = lat.position(lat.canonical(p));
                assert!(!mirror || at[1] <= 0.0);
                let want = if domain.contains(at) {
                    Recorder::f(at)
                } else {
                    0.0
                };
                assert_eq!(lat.get(p).to_bits(), want.to_bits(), "{p:?} at {x:?}");
                assert_eq!(calls.contains(&at), domain.contains(at), "{p:?}");
            }
        }
    }

    /// An invalid value is the error of the first invalid point in request order, the points
    /// before it keep their values and the others stay unknown (a later request evaluates
    /// them).
    #[test]
    fn ensure_names_the_first_invalid_point_and_leaves_the_rest_unknown() {
        let n = 8;
        let domain = Domain::Rect(Rect::new(0.0, 0.0, 1.0, 1.0));
        let probe = Lattice::new(&|_: Point2| 0.0, domain, n, false);
        let points = every_point(n);
        let (k1, k2) = (50, 70);
        let bad = vec![probe.position(points[k2]), probe.position(points[k1])];
        let f = Recorder::new(bad.clone());
        let mut lat = Lattice::new(&f, domain, n, false);
        match lat.ensure(&points) {
            Err(DensityError::InvalidSample { x, y, value }) => {
                assert_eq!([x, y], bad[1]);
                assert!(value.is_nan());
            }
            other => panic!("{other:?}"),
        }
        for (k, &p) in points.iter().enumerate() {
            let v = lat.get(p);
            if k < k1 {
                assert_eq!(v, Recorder::f(lat.position(p)), "{k}");
            } else {
                assert!(v.is_nan(), "{k}: {v}");
            }
        }
        let ok = Recorder::new(Vec::new());
        let mut lat = Lattice::new(&ok, domain, n, false);
        lat.ensure(&points[..k1]).unwrap();
        lat.ensure(&points).unwrap();
        assert_eq!(lat.evaluations(), points.len());
    }
}
