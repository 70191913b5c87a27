//! Importance samplers of a lat-long map: directions ∝ luminance per solid angle.

use std::time::{Duration, Instant};

use distributions::{Point2, Rect, Sample2, Sampler2D, UniformSource};
use partition_sampler::{
    LeafChoice, MemoryReport, QuadTreeBuilder, QuadTreeSampler, SamplerStats, Scheme, SinPiRows,
    TabulatedDensity, TreeParams,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cdf::QuantisedCdf2D;
use crate::lanes::LaneRng;
use crate::latlong::{direction_to_uv, pdf_uv_to_solid_angle, uv_to_direction};
use crate::{EnvMap, EnvMapError};

/// Parameters of the adaptive-partition sampler of a map: the partition sampler's own
/// [`TreeParams`], with the environment-map default [`AdaptiveOptions::DEFAULT_N_MAX`], and the
/// leaf budget of the tightening ladder ([`AdaptiveOptions::leaf_budget`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveOptions {
    /// Split threshold, depth, scheme ([`Scheme::Envelope`] by default, exact) and leaf choice
    /// ([`LeafChoice::Alias`] by default, O(1)). With a [`AdaptiveOptions::leaf_budget`],
    /// `tree.n_max` is the loosest threshold of the ladder.
    pub tree: TreeParams,
    /// The tightening ladder's leaf budget `B` (`None`: build at `tree.n_max` exactly).
    ///
    /// With `Some(B)` the sampler is built at the thresholds
    /// `n_k = 1 + (n_max − 1) / 2^k`, `k = 0, 1, …, `[`AdaptiveOptions::LADDER_STEPS`], in turn,
    /// and keeps the tree of the largest `k` whose leaves number at most `B` (the tree of
    /// `k = 0` is kept whatever its size). Every tree samples the same exact density
    /// `Y · sin(πv) / Î`; a tighter threshold only lowers the expected trials per sample
    /// `E = Σ V_i / Σ I_i ≤ n_k` at the price of more leaf records (32 bytes each), which is
    /// what the budget bounds. Other trees give other samples for the same seed (same law).
    #[serde(default = "AdaptiveOptions::default_leaf_budget")]
    pub leaf_budget: Option<usize>,
}

impl AdaptiveOptions {
    /// Default split threshold for environment maps: 1.6 rather than the generic
    /// [`TreeParams::DEFAULT_N_MAX`] = 2, the loosest rung of the tightening ladder.
    ///
    /// A map is tabulated, so its bounds are exact and deeper trees cost little: on the
    /// 1024×512 maps of `docs/benchmarks.md`, `n_max = 1.6` lowers the mean trials per sample
    /// from 1.33–1.78 to 1.19–1.35 and raises 2-thread throughput above 30 M samples/s on every
    /// map, while the build stays under 8 ms.
    pub const DEFAULT_N_MAX: f64 = 1.6;

    /// Default leaf budget of the tightening ladder: 2¹⁶ leaves, i.e. 2 MiB of 32-byte leaf
    /// records (one core's L2 on the host of `docs/benchmarks.md` §25.6, where the budget was
    /// chosen from four 1024 × 512 maps: on the two whose tighter trees stay under it the
    /// thread CPU per sample fell, on the one whose next rung has 82 171 leaves it rose).
    pub const DEFAULT_LEAF_BUDGET: usize = 1 << 16;

    /// Rungs of the ladder after the first: thresholds down to `1 + (n_max − 1) / 8`
    /// (1.075 from the default 1.6).
    pub const LADDER_STEPS: u32 = 3;

    fn default_leaf_budget() -> Option<usize> {
        Some(Self::DEFAULT_LEAF_BUDGET)
    }

    /// The default options with another scheme and leaf choice.
    pub fn with_scheme(scheme: Scheme, leaf_choice: LeafChoice) -> Self {
        let mut o = Self::default();
        o.tree.scheme = scheme;
        o.tree.leaf_choice = leaf_choice;
        o
    }

    /// The threshold of rung `k` of the ladder, `1 + (n_max − 1) / 2^k` (`n_max` itself for
    /// `k = 0`).
    pub fn ladder_threshold(&self, k: u32) -> f64 {
        1.0 + (self.tree.n_max - 1.0) * 0.5f64.powi(k as i32)
    }
}

impl Default for AdaptiveOptions {
    /// [`TreeParams::default`] with `n_max = `[`AdaptiveOptions::DEFAULT_N_MAX`] and the leaf
    /// budget [`AdaptiveOptions::DEFAULT_LEAF_BUDGET`].
    fn default() -> Self {
        Self {
            tree: TreeParams {
                n_max: Self::DEFAULT_N_MAX,
                ..TreeParams::default()
            },
            leaf_budget: Self::default_leaf_budget(),
        }
    }
}

/// Which sampler an [`EnvMapSampler`] is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum SamplerKind {
    /// The adaptive-partition (quadtree + rejection) sampler of the exact target density
    /// `Y(pixel) · sin(πv)`.
    Adaptive(AdaptiveOptions),
    /// The classic marginal/conditional CDF over `Y(pixel) · sin(π v_centre)` per pixel.
    PiecewiseConstant,
}

/// One sampled direction of an environment map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvSample {
    /// Lat-long column coordinate in `[0, 1)` (φ = 2πu).
    pub u: f64,
    /// Lat-long row coordinate in `[0, 1)` (θ = πv, v = 0 at the zenith `+z`).
    pub v: f64,
    /// Density w.r.t. area on `[0,1]²` at `(u, v)`.
    pub pdf_uv: f64,
    /// Density w.r.t. solid angle at `direction`: `pdf_uv / (2π² sin(πv))` (0 exactly at a pole).
    pub pdf_sa: f64,
    /// Unit direction `(sinθ cosφ, sinθ sinφ, cosθ)`.
    pub direction: [f64; 3],
}

impl EnvSample {
    /// Completes a planar sample of `[0,1]²` with its direction and solid-angle pdf.
    #[inline]
    pub fn from_uv(s: Sample2) -> Self {
        let [u, v] = s.point;
        Self {
            u,
            v,
            pdf_uv: s.pdf,
            pdf_sa: pdf_uv_to_solid_angle(s.pdf, v),
            direction: uv_to_direction(u, v),
        }
    }
}

/// One per built sampler, never in an array: the size of the table variant (its marginal's
/// guide inline) costs nothing, and boxing it would add a load to every draw.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
enum Inner {
    Adaptive(Box<QuadTreeSampler<TabulatedDensity<SinPiRows>>>),
    PiecewiseConstant(QuantisedCdf2D),
}

/// An importance sampler of directions ∝ luminance per solid angle for one [`EnvMap`].
///
/// It samples `(u, v) ∈ [0,1)²` with density `pdf_uv` (w.r.t. area on the square) and maps them
/// to directions; `pdf_sa = pdf_uv / (2π² sin(πv))` w.r.t. solid angle.
///
/// * [`SamplerKind::Adaptive`]: target `Y(pixel)·sin(πv)` exactly (the sine varies inside a
///   pixel); `pdf_uv = Y·sin(πv)/Î` with `Î` the exact integral, so `pdf_sa = Y/(2π²Î)` is
///   constant on a pixel.
/// * [`SamplerKind::PiecewiseConstant`]: the classic approximation `Y(pixel)·sin(π v_c)`,
///   constant per pixel (`v_c` = the pixel row's centre); its `pdf_uv` is that step function
///   normalised, and `pdf_sa` is converted with the exact `sin(πv)` of the sample, so the pair
///   `(sample, pdf)` is consistent (unbiased estimators) even though the target is approximate.
///
/// Immutable and `Sync`; `sample_par` is reproducible (depends only on `n` and `seed`).
#[derive(Debug)]
pub struct EnvMapSampler {
    inner: Inner,
    kind: SamplerKind,
    width: usize,
    height: usize,
    build_time: Duration,
}

impl EnvMapSampler {
    /// Builds the sampler of `kind` for `map` (timed: see [`EnvMapSampler::build_time`]).
    pub fn new(map: &EnvMap, kind: SamplerKind) -> Result<Self, EnvMapError> {
        match kind {
            SamplerKind::Adaptive(options) => Self::adaptive(map, options),
            SamplerKind::PiecewiseConstant => Self::piecewise_constant(map),
        }
    }

    /// The adaptive-partition sampler: a [`TabulatedDensity`] of the pixel luminances times
    /// [`SinPiRows`] on `[0,1]²`, partitioned by a [`QuadTreeBuilder`] with `options` (the
    /// tightening ladder of [`AdaptiveOptions::leaf_budget`] when it is set). The build time
    /// includes computing the luminance table and every rung built.
    pub fn adaptive(map: &EnvMap, options: AdaptiveOptions) -> Result<Self, EnvMapError> {
        let start = Instant::now();
        let density =
            TabulatedDensity::new(map.width(), map.height(), map.luminance(), Rect::UNIT)?
                .with_row_factor(SinPiRows)?;
        let sampler = Self::ladder(density, options)?;
        Ok(Self {
            inner: Inner::Adaptive(Box::new(sampler)),
            kind: SamplerKind::Adaptive(options),
            width: map.width(),
            height: map.height(),
            build_time: start.elapsed(),
        })
    }

    /// The tree of [`AdaptiveOptions::leaf_budget`]'s ladder on `density`: rung `k` built at
    /// [`AdaptiveOptions::ladder_threshold`]`(k)` while the previous rung kept at most `B`
    /// leaves; the last rung within the budget is kept (rung 0 always). All rungs borrow the
    /// one density, whose region pyramids are built once.
    fn ladder(
        density: TabulatedDensity<SinPiRows>,
        options: AdaptiveOptions,
    ) -> Result<QuadTreeSampler<TabulatedDensity<SinPiRows>>, EnvMapError> {
        let Some(budget) = options.leaf_budget else {
            return Ok(QuadTreeBuilder::from_params(options.tree).build(density)?);
        };
        let mut params = options.tree;
        let mut kept = QuadTreeBuilder::from_params(params).build_tree(&density)?;
        for k in 1..=AdaptiveOptions::LADDER_STEPS {
            let n = options.ladder_threshold(k);
            if !(n < params.n_max) || kept.counts().leaves > budget {
                break;
            }
            params.n_max = n;
            let tree = QuadTreeBuilder::from_params(params).build_tree(&density)?;
            if tree.counts().leaves > budget {
                break;
            }
            kept = tree;
        }
        Ok(QuadTreeSampler::from_parts(kept, density)?)
    }

    /// The piecewise-constant CDF sampler ([`QuantisedCdf2D`], fixed-point CDF tables whose
    /// stored law is the pdf) of `Y(pixel) · sin(π (y + ½)/H)` on `[0,1]²`. The build time
    /// includes the table.
    pub fn piecewise_constant(map: &EnvMap) -> Result<Self, EnvMapError> {
        let start = Instant::now();
        let (w, h) = (map.width(), map.height());
        let row_weight: Vec<f64> = (0..h)
            .map(|y| (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin())
            .collect();
        let values: Vec<f64> = map
            .rgb()
            .iter()
            .enumerate()
            .map(|(i, &p)| crate::luminance(p) * row_weight[i / w])
            .collect();
        let table = QuantisedCdf2D::new(w, h, &values)?;
        Ok(Self {
            inner: Inner::PiecewiseConstant(table),
            kind: SamplerKind::PiecewiseConstant,
            width: w,
            height: h,
            build_time: start.elapsed(),
        })
    }

    /// What this sampler is.
    pub fn kind(&self) -> SamplerKind {
        self.kind
    }

    /// Width of the map it was built from, in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height of the map it was built from, in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Wall-clock time the constructor took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Bytes of the sampling structures (for the adaptive sampler: quadtree + density tables,
    /// see [`EnvMapSampler::memory`]; for the CDF sampler: values and CDF arrays).
    pub fn bytes_used(&self) -> usize {
        match &self.inner {
            Inner::Adaptive(s) => s.bytes_used(),
            Inner::PiecewiseConstant(t) => t.bytes_used(),
        }
    }

    /// Per-structure memory of the adaptive sampler; `None` for the CDF sampler.
    pub fn memory(&self) -> Option<MemoryReport> {
        match &self.inner {
            Inner::Adaptive(s) => Some(s.memory()),
            Inner::PiecewiseConstant(_) => None,
        }
    }

    /// Structure and cost figures of the adaptive sampler (expected and measured mean trials,
    /// bound violations, `Î`...); `None` for the CDF sampler (always exactly one "trial").
    pub fn stats(&self) -> Option<SamplerStats> {
        match &self.inner {
            Inner::Adaptive(s) => Some(s.stats()),
            Inner::PiecewiseConstant(_) => None,
        }
    }

    /// The adaptive sampler itself, for callers that need its full API.
    pub fn as_adaptive(&self) -> Option<&QuadTreeSampler<TabulatedDensity<SinPiRows>>> {
        match &self.inner {
            Inner::Adaptive(s) => Some(s),
            Inner::PiecewiseConstant(_) => None,
        }
    }

    /// The CDF sampler itself, for callers that need its full API (e.g. cell probabilities).
    pub fn as_piecewise_constant(&self) -> Option<&QuantisedCdf2D> {
        match &self.inner {
            Inner::Adaptive(_) => None,
            Inner::PiecewiseConstant(t) => Some(t),
        }
    }

    /// One planar sample `(u, v)` with its pdf w.r.t. area on `[0,1]²` (no trigonometry).
    #[inline]
    pub fn sample_uv<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        match &self.inner {
            Inner::Adaptive(s) => s.sample(u),
            Inner::PiecewiseConstant(t) => t.sample(u),
        }
    }

    /// One direction with both pdfs.
    #[inline]
    pub fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> EnvSample {
        EnvSample::from_uv(self.sample_uv(u))
    }

    /// `n` planar samples drawn in parallel by [`distributions::sample_par`] (fixed chunks of
    /// `distributions::PAR_CHUNK`, one generator per chunk seeded from `(seed, chunk)`): the
    /// result depends only on `(n, seed)`, never on the thread count.
    pub fn sample_uv_par(&self, n: usize, seed: u64) -> Vec<Sample2> {
        distributions::sample_par(self, n, seed)
    }

    /// `n` planar samples drawn in parallel through the lane-parallel generator: fixed chunks
    /// of `distributions::PAR_CHUNK`, each drawn by [`Sampler2D::sample_into`] from
    /// [`LaneRng::for_chunk`]`(seed, chunk)`. The same law as [`EnvMapSampler::sample_uv_par`]
    /// (other uniforms, so other samples); a function of `(n, seed)` only, whatever the
    /// thread count.
    pub fn sample_uv_par_lanes(&self, n: usize, seed: u64) -> Vec<Sample2> {
        let mut out = vec![
            Sample2 {
                point: [0.0, 0.0],
                pdf: 0.0
            };
            n
        ];
        out.par_chunks_mut(distributions::PAR_CHUNK)
            .enumerate()
            .for_each(|(chunk, slot)| {
                self.sample_into(&mut LaneRng::for_chunk(seed, chunk as u64), slot)
            });
        out
    }

    /// `n` directions drawn in parallel: [`EnvMapSampler::sample_uv_par`] completed (also in
    /// parallel) with directions and solid-angle pdfs.
    pub fn sample_par(&self, n: usize, seed: u64) -> Vec<EnvSample> {
        self.sample_uv_par(n, seed)
            .into_par_iter()
            .map(EnvSample::from_uv)
            .collect()
    }

    /// Density w.r.t. area on `[0,1]²` at `(u, v)` (0 outside the square).
    pub fn pdf_uv(&self, u: f64, v: f64) -> f64 {
        match &self.inner {
            Inner::Adaptive(s) => s.pdf([u, v]),
            Inner::PiecewiseConstant(t) => t.pdf([u, v]),
        }
    }

    /// Density w.r.t. solid angle of the direction `d` (normalised here):
    /// `pdf_uv(u, v) / (2π² sin(πv))` at its lat-long coordinates; 0 at the poles and for the
    /// zero vector.
    pub fn pdf_sa(&self, d: [f64; 3]) -> f64 {
        let (u, v) = direction_to_uv(d);
        pdf_uv_to_solid_angle(self.pdf_uv(u, v), v)
    }
}

impl Sampler2D for EnvMapSampler {
    /// See [`EnvMapSampler::sample_uv`].
    #[inline]
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        self.sample_uv(u)
    }

    /// The inner sampler's own `sample_into` (one dispatch per slice).
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        match &self.inner {
            Inner::Adaptive(s) => s.sample_into(u, out),
            Inner::PiecewiseConstant(t) => t.sample_into(u, out),
        }
    }

    /// Density w.r.t. area on `[0,1]²`.
    fn pdf(&self, p: Point2) -> f64 {
        self.pdf_uv(p[0], p[1])
    }

    fn bytes_used(&self) -> usize {
        EnvMapSampler::bytes_used(self)
    }
}

#[cfg(test)]
mod ladder_tests {
    use super::*;
    use crate::procedural_sky;

    /// Leaves and expected trials of the adaptive sampler built with `options`.
    fn shape(map: &EnvMap, options: AdaptiveOptions) -> (usize, u64) {
        let s = EnvMapSampler::adaptive(map, options).unwrap();
        let stats = s.stats().unwrap();
        (stats.leaves, stats.expected_mean_trials.to_bits())
    }

    #[test]
    fn the_ladder_keeps_the_last_rung_within_the_budget() {
        // Each rung built alone (no budget) against the ladder with budgets at and just below
        // each rung's leaf count: the ladder must keep exactly the last rung that fits.
        let map = procedural_sky(256, 128).unwrap();
        let fixed = AdaptiveOptions {
            leaf_budget: None,
            ..AdaptiveOptions::default()
        };
        let rungs: Vec<(usize, u64)> = (0..=AdaptiveOptions::LADDER_STEPS)
            .map(|k| {
                let mut o = fixed;
                o.tree.n_max = fixed.ladder_threshold(k);
                shape(&map, o)
            })
            .collect();
        // The rungs really differ (more leaves, fewer trials), else the test proves nothing.
        for w in rungs.windows(2) {
            assert!(w[1].0 > w[0].0, "{rungs:?}");
            assert!(f64::from_bits(w[1].1) < f64::from_bits(w[0].1), "{rungs:?}");
        }
        assert_eq!(shape(&map, fixed), rungs[0]);
        for (k, &(leaves, _)) in rungs.iter().enumerate() {
            let at = AdaptiveOptions {
                leaf_budget: Some(leaves),
                ..fixed
            };
            assert_eq!(shape(&map, at), rungs[k], "budget = rung {k}'s leaves");
            let below = AdaptiveOptions {
                leaf_budget: Some(leaves - 1),
                ..fixed
            };
            // Rung 0 is kept whatever its size.
            assert_eq!(
                shape(&map, below),
                rungs[k.saturating_sub(1)],
                "budget below rung {k}"
            );
        }
        // The default budget on this small map: the tightest rung.
        assert_eq!(
            shape(&map, AdaptiveOptions::default()),
            rungs[AdaptiveOptions::LADDER_STEPS as usize]
        );
        // Rung thresholds: n_max, then halving the excess over 1.
        assert_eq!(fixed.ladder_threshold(0), AdaptiveOptions::DEFAULT_N_MAX);
        assert_eq!(fixed.ladder_threshold(3), 1.075);
    }
}
