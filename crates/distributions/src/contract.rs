//! The common shape of every 2D sampler in brdf-lab.
//!
//! A sampler draws points `x` of a planar domain (a rectangle or the unit disc) with a
//! probability density `p(x)` **with respect to area (Lebesgue measure) on that domain**.
//! Samplers never own a random generator: they consume caller-given uniform numbers from a
//! [`UniformSource`], so pseudo-random, quasi-random and stratified streams all work.

use rand::Rng;

/// A point of the plane, `[x, y]`.
pub type Point2 = [f64; 2];

/// One drawn point with its density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample2 {
    /// The point, inside the sampler's domain.
    pub point: Point2,
    /// Probability density of `point` with respect to area on the domain.
    pub pdf: f64,
}

/// A stream of independent uniform numbers in `[0, 1)`.
///
/// Implemented for every [`rand::Rng`] and for [`UniformSequence`] (a caller-given slice, e.g.
/// quasi-Monte Carlo points). Inversion samplers consume exactly two numbers per sample;
/// rejection samplers consume a random, bounded-in-mean number of them.
pub trait UniformSource {
    /// The next uniform number in `[0, 1)`.
    fn next_uniform(&mut self) -> f64;

    /// The next four numbers, in order: the same values as four [`Self::next_uniform`] calls
    /// (one call instead of four through a `dyn UniformSource`; a rejection trial of the
    /// quadtree sampler consumes four).
    #[inline]
    fn next_uniform4(&mut self) -> [f64; 4] {
        [
            self.next_uniform(),
            self.next_uniform(),
            self.next_uniform(),
            self.next_uniform(),
        ]
    }

    /// Four uniforms on `[0, 1)` for one rejection trial, each with **at least 32 random
    /// bits**: `k · 2⁻³²` for a uniform integer `k < 2³²` (or finer). A generator
    /// ([`rand::Rng`]) draws them from two 64-bit words `w₀, w₁` as their halves
    /// `[hi(w₀), lo(w₀), hi(w₁), lo(w₁)] · 2⁻³²` — half the generator steps of
    /// [`Self::next_uniform4`], another stream; the default is [`Self::next_uniform4`]
    /// (caller-given sequences keep their values and their order). For consumers whose law
    /// needs no finer grid than 2⁻³² (the exact BRDF sampler's leaf pick, point and accept
    /// test, issue 29).
    #[inline]
    fn next_uniform4_split(&mut self) -> [f64; 4] {
        self.next_uniform4()
    }

    /// `out.len()` split trials in order: `out[k]` is the `k`-th of as many
    /// [`Self::next_uniform4_split`] calls (the same values, the same state afterwards; one
    /// call through a `dyn UniformSource` for a block of trials). A consumer that fills
    /// ahead must consume every filled trial before the stream's next use, or the order (and
    /// the state after it) changes.
    #[inline]
    fn fill_uniform4_split(&mut self, out: &mut [[f64; 4]]) {
        for us in out {
            *us = self.next_uniform4_split();
        }
    }
}

/// 53 random mantissa bits of `bits`: uniform on `[0, 1)` with spacing 2⁻⁵³.
#[inline(always)]
fn unit_from_bits(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

impl<R: Rng + ?Sized> UniformSource for R {
    #[inline]
    fn next_uniform(&mut self) -> f64 {
        unit_from_bits(self.next_u64())
    }

    #[inline]
    fn next_uniform4(&mut self) -> [f64; 4] {
        [
            unit_from_bits(self.next_u64()),
            unit_from_bits(self.next_u64()),
            unit_from_bits(self.next_u64()),
            unit_from_bits(self.next_u64()),
        ]
    }

    #[inline]
    fn next_uniform4_split(&mut self) -> [f64; 4] {
        let (w0, w1) = (self.next_u64(), self.next_u64());
        [
            halves_unit(w0 >> 32),
            halves_unit(w0 & 0xffff_ffff),
            halves_unit(w1 >> 32),
            halves_unit(w1 & 0xffff_ffff),
        ]
    }

    #[inline]
    fn fill_uniform4_split(&mut self, out: &mut [[f64; 4]]) {
        for us in out {
            let (w0, w1) = (self.next_u64(), self.next_u64());
            *us = [
                halves_unit(w0 >> 32),
                halves_unit(w0 & 0xffff_ffff),
                halves_unit(w1 >> 32),
                halves_unit(w1 & 0xffff_ffff),
            ];
        }
    }
}

/// `k · 2⁻³²` for `k < 2³²`: exact in `f64`.
#[inline(always)]
fn halves_unit(k: u64) -> f64 {
    k as f64 * (1.0 / (1u64 << 32) as f64)
}

/// Uniform numbers read from a caller-given slice, in order.
///
/// When the slice is exhausted the stream wraps around to its start, so a sampler never
/// panics on a short sequence (a caller who cares checks [`UniformSequence::consumed`]).
#[derive(Debug, Clone)]
pub struct UniformSequence<'a> {
    values: &'a [f64],
    next: usize,
    consumed: usize,
}

impl<'a> UniformSequence<'a> {
    /// A stream over `values`; each value should lie in `[0, 1)`.
    pub fn new(values: &'a [f64]) -> Self {
        Self {
            values,
            next: 0,
            consumed: 0,
        }
    }

    /// How many numbers have been read so far.
    pub fn consumed(&self) -> usize {
        self.consumed
    }
}

impl UniformSource for UniformSequence<'_> {
    #[inline]
    fn next_uniform(&mut self) -> f64 {
        if self.values.is_empty() {
            return 0.5;
        }
        let v = self.values[self.next];
        self.next = (self.next + 1) % self.values.len();
        self.consumed += 1;
        v
    }
}

/// A sampler of a planar density: `sample(u) -> (point, pdf)`, `pdf(point)`, `bytes_used()`.
///
/// Built samplers are immutable and `Sync`: one instance serves every thread.
pub trait Sampler2D: Sync {
    /// Draws one point from uniforms taken from `u`.
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2;

    /// Fills `out` with consecutive draws from `u`, exactly as `out.len()` calls of
    /// [`Sampler2D::sample`] would. Samplers with per-call bookkeeping override it to do that
    /// once per slice; [`crate::sample_par`] calls it once per chunk.
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        for s in out {
            *s = self.sample(u);
        }
    }

    /// Density of `p` with respect to area on the domain (0 outside the support).
    fn pdf(&self, p: Point2) -> f64;

    /// Heap and inline bytes of the structures the sampler needs to draw samples.
    fn bytes_used(&self) -> usize;
}

/// A sampler that is a bijective warp of the unit square: exactly two uniforms per sample.
pub trait InvertibleSampler2D: Sampler2D {
    /// Warps `u ∈ [0,1)²` to a point and its density.
    fn sample_square(&self, u: Point2) -> Sample2;

    /// The `u` that [`InvertibleSampler2D::sample_square`] maps to `p`, when `p` is in the support.
    fn invert(&self, p: Point2) -> Option<Point2>;
}

/// Adapts any [`Sampler2D`] to [`rand::distr::Distribution`], yielding [`Sample2`].
#[derive(Debug, Clone, Copy)]
pub struct AsDistribution<'a, S: ?Sized>(pub &'a S);

impl<S: Sampler2D + ?Sized> rand::distr::Distribution<Sample2> for AsDistribution<'_, S> {
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Sample2 {
        self.0.sample(rng)
    }
}

#[cfg(test)]
mod tests {
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{Rng, SeedableRng};

    use super::{UniformSequence, UniformSource};

    /// A generator's split trial is the halves of its next two words, high half first, and
    /// advances the generator by exactly two words; every value is `k · 2⁻³²` in `[0, 1)`,
    /// and over many draws each of the four positions has mean ½ and its low bits alive.
    #[test]
    fn a_generators_split_trial_is_the_halves_of_two_words() {
        let mut a = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut b = a.clone();
        let mut sums = [0.0; 4];
        let mut low_bits = [0u64; 4];
        let n = 20_000;
        for _ in 0..n {
            let us = a.next_uniform4_split();
            let (w0, w1) = (b.next_u64(), b.next_u64());
            let want = [w0 >> 32, w0 & 0xffff_ffff, w1 >> 32, w1 & 0xffff_ffff];
            for j in 0..4 {
                let k = us[j] * 4_294_967_296.0;
                assert_eq!(k, want[j] as f64);
                assert!((0.0..1.0).contains(&us[j]));
                sums[j] += us[j];
                low_bits[j] += want[j] & 1;
            }
        }
        assert_eq!(a.next_u64(), b.next_u64());
        for j in 0..4 {
            assert!((sums[j] / f64::from(n) - 0.5).abs() < 0.01, "{sums:?}");
            assert!(low_bits[j] > 9_000 && low_bits[j] < 11_000, "{low_bits:?}");
        }
    }

    /// A block of split trials is the same trials as one call each, in order, and leaves the
    /// generator (and a caller-given sequence) where those calls would.
    #[test]
    fn a_block_of_split_trials_is_that_many_calls() {
        let mut a = Xoshiro256PlusPlus::seed_from_u64(5);
        let mut b = a.clone();
        let mut block = [[0.0; 4]; 37];
        a.fill_uniform4_split(&mut block[..0]);
        a.fill_uniform4_split(&mut block);
        for us in &block {
            assert_eq!(*us, b.next_uniform4_split());
        }
        assert_eq!(a.next_u64(), b.next_u64());
        let v: Vec<f64> = (0..11).map(|k| f64::from(k) / 11.0).collect();
        let (mut s, mut t) = (UniformSequence::new(&v), UniformSequence::new(&v));
        let mut two = [[0.0; 4]; 2];
        s.fill_uniform4_split(&mut two);
        assert_eq!(two, [t.next_uniform4_split(), t.next_uniform4_split()]);
        assert_eq!(s.consumed(), 8);
        assert_eq!(s.next_uniform(), t.next_uniform());
    }

    /// A caller-given sequence hands its own values, in order, to a split trial.
    #[test]
    fn a_sequences_split_trial_is_its_next_four_values() {
        let v = [0.1, 0.2, 0.3, 0.4, 0.5];
        let mut s = UniformSequence::new(&v);
        assert_eq!(s.next_uniform4_split(), [0.1, 0.2, 0.3, 0.4]);
        assert_eq!(s.next_uniform(), 0.5);
        assert_eq!(s.consumed(), 5);
    }
}
