//! Broken planar (quadtree) samplers.

use partition_sampler::{
    Density, DensityShape, Domain, IntegralSource, LeafInfo, Point2, QuadTreeSampler, Rect,
    RegionEstimate, RegionStats, Sampler2D, UniformSource,
};

use crate::subject::SamplerUnderTest;

/// A region-statistics provider whose leaf bounds are `factor < 1` times too low (as if the
/// sampled density's safety factor were below one): rejection clips `f` at `M_i`, so the
/// samples under-represent the peaks, and the sampler's audit counts violations.
#[derive(Debug, Clone)]
pub struct ScaledBounds<D> {
    /// The honest provider.
    pub inner: D,
    /// Multiplier of every bound.
    pub factor: f64,
}

impl<D: Density> Density for ScaledBounds<D> {
    fn eval(&self, p: Point2) -> f64 {
        self.inner.eval(p)
    }
}

impl<D: RegionStats> RegionStats for ScaledBounds<D> {
    fn domain(&self) -> Domain {
        self.inner.domain()
    }
    fn region(&self, cell: &Rect) -> RegionEstimate {
        let mut r = self.inner.region(cell);
        r.max_bound *= self.factor;
        r
    }
    fn integral_source(&self) -> IntegralSource {
        self.inner.integral_source()
    }
    fn total_rel_err(&self) -> Option<f64> {
        self.inner.total_rel_err()
    }
    fn min_cell_size(&self) -> Option<[f64; 2]> {
        self.inner.min_cell_size()
    }
    fn shape(&self) -> DensityShape {
        self.inner.shape()
    }
    fn bytes_used(&self) -> usize {
        self.inner.bytes_used()
    }
}

/// What a [`FloorSplit`] does with the remainder `N − Σ ⌊N p_i⌋`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Remainder {
    /// Given to the first leaf.
    ToFirstLeaf,
    /// Dropped: the batch is short.
    Dropped,
}

/// A quadtree sampler whose batch mode rounds the per-leaf counts down (`n_i = ⌊N p_i⌋`) and
/// mishandles the remainder, drawing by rejection inside each leaf. One-sample draws are the
/// correct ones.
pub struct FloorSplit<D> {
    sampler: QuadTreeSampler<D>,
    leaves: Vec<LeafInfo>,
    remainder: Remainder,
}

impl<D: RegionStats> FloorSplit<D> {
    /// Wraps a built sampler.
    pub fn new(sampler: QuadTreeSampler<D>, remainder: Remainder) -> Self {
        let leaves = sampler.tree().leaves().collect();
        Self {
            sampler,
            leaves,
            remainder,
        }
    }

    fn draw_in_leaf(&self, leaf: &LeafInfo, u: &mut dyn UniformSource) -> (Point2, f64) {
        let r = leaf.rect;
        let mut last = [r.x0, r.y0];
        for _ in 0..(1u32 << 20) {
            let p = [
                r.x0 + u.next_uniform() * (r.x1 - r.x0),
                r.y0 + u.next_uniform() * (r.y1 - r.y0),
            ];
            let z = u.next_uniform() * leaf.max_bound;
            last = p;
            if z < self.sampler.density().eval(p) {
                return (p, self.sampler.pdf(p));
            }
        }
        (last, 0.0)
    }
}

impl<D: RegionStats + Send> SamplerUnderTest<Point2> for FloorSplit<D> {
    fn sample(&self, u: &mut dyn UniformSource) -> (Point2, f64) {
        let s = self.sampler.sample(u);
        (s.point, s.pdf)
    }

    fn pdf(&self, p: Point2) -> f64 {
        self.sampler.pdf(p)
    }

    fn sample_batch(&self, n: usize, u: &mut dyn UniformSource) -> Vec<(Point2, f64)> {
        let total: f64 = self.leaves.iter().map(|l| l.integral).sum();
        let mut counts: Vec<usize> = self
            .leaves
            .iter()
            .map(|l| (n as f64 * l.integral / total).floor() as usize)
            .collect();
        let assigned: usize = counts.iter().sum();
        if self.remainder == Remainder::ToFirstLeaf
            && let Some(c) = counts.first_mut()
        {
            *c += n.saturating_sub(assigned);
        }
        let mut out = Vec::with_capacity(n);
        for (leaf, &k) in self.leaves.iter().zip(&counts) {
            for _ in 0..k {
                out.push(self.draw_in_leaf(leaf, u));
            }
        }
        out
    }

    fn bound_violations(&self) -> Option<u64> {
        Some(self.sampler.stats().bound_violations)
    }

    fn normaliser_rel_err(&self) -> Option<f64> {
        self.sampler.stats().integral_rel_err
    }
}
