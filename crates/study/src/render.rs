//! The sphere renderer: direct lighting of a row of spheres (one per BRDF of the study) under
//! one light, orthographic camera, one image per sampler at equal samples and at equal time,
//! and a reference image; the papers' relative error per image.
//!
//! **Scene.** World up is `+z`, the zenith of the lat-long maps. The camera looks along `+y`
//! (orthographic, `ωo = (0, −1, 0)` at every pixel); sphere `j` covers a square of
//! `sphere_px²` pixels. A pixel whose centre hits a sphere has the normal
//! `n = (x, −√(1 − x² − z²), z)` and a tangent frame `t = normalize(z × n)` (or `+x` at the
//! poles), `b = n × t`; directions are sampled in that frame and looked up in world space.
//! There are no shadows (the spheres are convex and do not occlude each other in the lit
//! hemisphere of any pixel to first order) and no background (black).
//!
//! **Pixel estimate.** `(1/N) Σ f_r(ωo, ωk) ⊙ L(ωk) cos θk / p_σ(ωk)` (RGB), by the
//! `estimators` crate's batch path ([`estimators::Batch`]): the pixels of one image row on one
//! sphere are served by **one** `sample_eval_batch` call (queries = each pixel's `ωo` × `N`),
//! the segment's generator seeded from `(seed, sampler, first pixel of the segment)`:
//! reproducible for any thread count. (Before issue 29 each pixel had its own generator and
//! called `sample` `N` times; the images' law is the same, the values per seed differ.)
//!
//! **The fused f.** The batch is handed the BRDF object the sampler was built with. For a BRDF
//! of constant colour ([`Brdf::rgb_scale`]: the analytic models, grey) and a sampler whose
//! `sample_eval` returns an `f` it computed while drawing
//! ([`DirectionSampler::fuses_eval`]: `adaptive-exact`'s accepted trial), the RGB value is the
//! colour times that `f`: no further evaluation. Every other pair gets one `eval_rgb` per
//! sample, as before (for a sampler that would evaluate `f` once after its draw anyway, the
//! fused loop measured slower — docs/benchmarks.md §24.7 — so each sampler keeps its faster
//! path). The values change by rounding only (the accepted trial's `f` was evaluated in the
//! sampler's frame); the uniforms drawn are the same.
//!
//! **Reference.** Multiple importance sampling (balance heuristic, equal counts;
//! [`estimators::Batch::mis`], the estimator of `product` and of the study's MIS cells) of the
//! reference BRDF sampler (`adaptive`, checked by the validation suite) and the light's own
//! sampler (the `envmap-adaptive` registry sampler for maps, uniform directions in the cone of
//! the area light; BRDF sampling alone under constant light), `reference_spp` samples of each
//! per pixel. With the adaptive product images (a map light, MIS images, `adaptive-exact`
//! built), the reference is `w M + (1 − w) K`: `M` that MIS at `reference_spp / 4` pairs, `K`
//! the adaptive product at `3/2 · reference_spp` samples (own seeds), `w` per sphere the
//! inverse-relative-variance weight from independent pilot renders (so the reference stays
//! unbiased). Each part is made as two independent halves, whose difference estimates the
//! reference's own relative error ([`ReferenceError`], printed with the reference).
//!
//! **Error.** The papers' relative error: the mean over pixels with non-null reference
//! luminance of `|Y(I) − Y(I_ref)| / Y(I_ref)`.
//!
//! **MIS images.** Beside the BRDF-sampling images, with [`RenderConfig::mis`] (the default)
//! every sampler is also combined with the light's own sampler (the reference's: the
//! `envmap-adaptive` map sampler, or the area light's cone) by MIS, balance heuristic, one BRDF
//! sample and one light sample per "spp" ([`estimators::Batch::mis`], the reference's and the
//! study's MIS cells' estimator): kinds `MIS equal samples` and `MIS equal time`. Under a
//! constant light there is nothing to sample and no MIS image is made.
//!
//! **Equal time.** Each sampler's time per pixel sample is measured on one thread on a fixed
//! subset of row segments, on the render's own path (a row of pixels per batch call:
//! *coherent* ωo), and also with each query at a random pixel of the same sphere (*random*
//! ωo, same batch sizes), with the BRDF evaluations per sample, the sampler's and the
//! estimator's (a count that does not depend on the machine's load); with MIS images, also the time per MIS pixel sample on the
//! coherent path (both samples, the other technique's pdf at each, the integrand at each). The
//! clock is the timing thread's CPU clock where the platform has one (wall time elsewhere), and
//! the [`TIMING_REPEATS`] runs of every sampler and path are interleaved (repeat `r` of every
//! sampler before repeat `r + 1` of any), the median kept, so that a burst of load on the
//! machine does not fall on one sampler. Every equal-time image gets the same time per pixel,
//! `spp × t_adaptive`, `t_adaptive` the `adaptive` sampler's BRDF-sampling time per sample (or
//! the mean of the samplers' when it is not in the study): a sampler gets
//! `spp × t_adaptive / t_sampler` BRDF samples per pixel, and `spp × t_adaptive / t_MIS,sampler`
//! MIS pairs (at least 1 each; [`equal_time_spp`]). Equal-time images therefore depend on
//! timings.

use std::time::Instant;

use brdf::{Brdf, Vec3};
use brdf_sampling::DirectionSampler;
use distributions::{UniformSource, chunk_seed};
use envmap::{AdaptiveOptions, EnvMapSampler, PowerPyramid};
use estimators::{
    Batch, LightTechnique, LocalFrame, MisHeuristic, ProductBatch, ProductOptions, Query,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{Light, StudyError, StudyPlan};

/// Timing runs per sampler and path for the equal-time budget (interleaved; the median is used).
pub const TIMING_REPEATS: usize = 9;

/// The kinds of sphere images ([`Image::kind`]), in the report's order (the reference aside):
/// BRDF sampling alone at equal samples and at equal time, then MIS with the light's sampler.
pub const IMAGE_KINDS: [&str; 4] = [
    "equal samples",
    "equal time",
    "MIS equal samples",
    "MIS equal time",
];

/// The kinds of the adaptive product images ([`Image::kind`], sampler [`PRODUCT_NAME`]): at
/// equal samples and at equal time. Made under a map light with [`RenderConfig::mis`].
pub const PRODUCT_KINDS: [&str; 2] = ["product equal samples", "product equal time"];

/// The image name of the adaptive product estimator ([`estimators::ProductBatch`]: a per-pixel
/// cut of the map's power pyramid weighted by the BRDF, `adaptive-exact` as its defensive
/// sampler).
pub const PRODUCT_NAME: &str = "adaptive-product";

/// The defensive BRDF sampler of the adaptive product images.
pub const PRODUCT_DEFENSIVE: &str = "adaptive-exact";

/// Samples per pixel of each pilot render that fixes the reference's weights (two independent
/// pilots per part, seeds of their own).
pub(crate) const REFERENCE_PILOT_SPP: usize = 16;

/// With product images, the reference's MIS part gets `reference_spp / REFERENCE_MIS_DIVISOR`
/// pairs per pixel and its adaptive product part `reference_spp · 3/2` samples (about the time
/// of `reference_spp` MIS pairs alone: docs/benchmarks.md §26.7).
pub(crate) const REFERENCE_MIS_DIVISOR: usize = 4;

/// The reference's own error, estimated from its samples. Each part of the reference is the
/// mean of two independent half renders `h₁, h₂` (own seeds); the reference per pixel is
/// `R_p = w M_p + (1 − w) K_p` (`M` the MIS part, `K` the adaptive product part, `w` fixed per
/// sphere from independent pilot renders, so `w` does not depend on the parts' samples and
/// `R_p` is unbiased). `d_p = w (M₁ − M₂)/2 + (1 − w)(K₁ − K₂)/2` (luminance) has the variance of
/// `R_p` and mean 0, so for a normal `R_p` the expected relative error
/// `E|R_p − μ_p| / μ_p = √(2/π) sd_p / μ_p` is estimated by `|d_p| / Y(R_p)`; the figures are
/// its mean over the pixels with non-null reference luminance (the images' error metric).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceError {
    /// Per sphere, left to right: the MIS part's weight `w` (the product part's is `1 − w`;
    /// 1 without a product part).
    pub mis_weight: Vec<f64>,
    /// Per sphere: the estimated mean relative error of the reference, `mean_p |d_p| / Y(R_p)`.
    pub per_sphere: Vec<f64>,
    /// Per sphere: the pilots' relative variance per sample of the MIS part (per pair) and of
    /// the product part (per sample; 0 without one), `mean_p Var_p / Ŷ_p² · n` over the sphere's
    /// pixels, `Ŷ_p` the pilots' mean luminance: what the weights are made of.
    pub pilot_rel_var: Vec<(f64, f64)>,
    /// The whole row: `mean_p |d_p| / Y(R_p)` over every pixel with non-null luminance.
    pub whole: f64,
    /// Process CPU seconds (all threads; a timing) of the MIS part, the pilots and the product
    /// part (0 for a part not made); `None` where the platform has no process CPU clock.
    pub cpu_seconds: Option<[f64; 3]>,
}

/// The MIS part's weight `w = V_K / (V_M + V_K)` (inverse-variance, the weights sum to 1) of the
/// pixels `idx`, from two independent pilot renders of each part at `pilot_spp`:
/// `V_X = mean_p (Y(X₁) − Y(X₂))_p² / (2 Ŷ_p²) · pilot_spp / n_X`, the mean relative variance of
/// part `X` at its `n_X` samples per pixel (`Ŷ_p` the mean luminance of the four pilots; pixels with
/// `Ŷ_p = 0` skipped). Also returns the per-sample relative variances `(V_M n_M, V_K n_K)`.
/// 1 (MIS alone) when the product's variance is not a finite number or both are 0.
fn reference_mis_weight(
    mis: [&[[f64; 3]]; 2],
    product: [&[[f64; 3]]; 2],
    idx: &[usize],
    pilot_spp: usize,
    n_mis: usize,
    n_product: usize,
) -> (f64, f64, f64) {
    let y = |v: &[[f64; 3]], p: usize| colour::luminance(v[p]);
    let (mut vm, mut vk, mut count) = (0.0, 0.0, 0usize);
    for &p in idx {
        let mean = (y(mis[0], p) + y(mis[1], p) + y(product[0], p) + y(product[1], p)) / 4.0;
        if mean > 0.0 {
            vm += (y(mis[0], p) - y(mis[1], p)).powi(2) / (2.0 * mean * mean);
            vk += (y(product[0], p) - y(product[1], p)).powi(2) / (2.0 * mean * mean);
            count += 1;
        }
    }
    let scale = pilot_spp as f64 / count.max(1) as f64;
    let (per_m, per_k) = (vm * scale, vk * scale);
    let (vm, vk) = (per_m / n_mis.max(1) as f64, per_k / n_product.max(1) as f64);
    let w = vk / (vm + vk);
    if w.is_finite() {
        (w.clamp(0.0, 1.0), per_m, per_k)
    } else {
        (1.0, per_m, per_k)
    }
}

/// The reference from the parts' halves: per pixel `R = w_M M + w_K K`, `M = (M₁ + M₂)/2`,
/// `K = (K₁ + K₂)/2` (`K` absent: `R = M`), `(w_M, w_K) = weights(pixel)` (the render passes
/// `(w, 1 − w)`: unbiased); and per pixel the luminance
/// `d_p = w_M (M₁ − M₂)/2 + w_K (K₁ − K₂)/2` of [`ReferenceError`].
fn combine_reference(
    mis: [&[[f64; 3]]; 2],
    product: Option<[&[[f64; 3]]; 2]>,
    weights: impl Fn(usize) -> (f64, f64),
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let n = mis[0].len();
    let mut rgb = vec![[0.0; 3]; n];
    let mut d = vec![0.0; n];
    for p in 0..n {
        let (w, wk) = weights(p);
        let half = |a: [f64; 3], b: [f64; 3]| {
            (
                [
                    (a[0] + b[0]) / 2.0,
                    (a[1] + b[1]) / 2.0,
                    (a[2] + b[2]) / 2.0,
                ],
                (colour::luminance(a) - colour::luminance(b)) / 2.0,
            )
        };
        let (m, dm) = half(mis[0][p], mis[1][p]);
        match product {
            Some(k) => {
                let (k, dk) = half(k[0][p], k[1][p]);
                for c in 0..3 {
                    rgb[p][c] = w * m[c] + wk * k[c];
                }
                d[p] = w * dm + wk * dk;
            }
            None => {
                rgb[p] = m;
                d[p] = dm;
            }
        }
    }
    (rgb, d)
}

/// `mean_p |d_p| / Y(R_p)` over the pixels `idx` with `Y(R_p) > 0` (0 when there are none).
fn reference_self_error(rgb: &[[f64; 3]], d: &[f64], idx: &[usize]) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for &p in idx {
        let y = colour::luminance(rgb[p]);
        if y > 0.0 {
            sum += d[p].abs() / y;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { sum / count as f64 }
}

/// Samples (or MIS pairs) per pixel at equal time: `spp × budget_ns / ns` rounded, at least 1
/// (`budget_ns` the time per sample of the budget's sampler at `spp`, `ns` this sampler's time
/// per sample on the same path; 1 when `ns` is not a positive number).
pub fn equal_time_spp(spp: usize, budget_ns: f64, ns: f64) -> usize {
    let x = spp as f64 * budget_ns / ns;
    if x.is_finite() && x > 0.0 {
        (x.round() as usize).max(1)
    } else {
        1
    }
}

/// Settings of the sphere images.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RenderConfig {
    /// Pixels per sphere side.
    pub sphere_px: usize,
    /// Samples per pixel of the equal-samples images.
    pub spp: usize,
    /// Samples per pixel of each strategy of the reference.
    pub reference_spp: usize,
    /// Index of the study's light to render under.
    pub light: usize,
    /// Seed of the images.
    pub seed: u64,
    /// Also render the MIS images (each sampler with the light's own sampler; see the module
    /// docs). No effect under a constant light.
    #[serde(default = "mis_default")]
    pub mis: bool,
}

fn mis_default() -> bool {
    true
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            sphere_px: 80,
            spp: 64,
            reference_spp: 512,
            light: 0,
            seed: 1,
            mis: true,
        }
    }
}

/// A rendered image (linear RGB, row-major, top row first).
#[derive(Debug, Clone)]
pub struct Image {
    /// Sampler name (or `reference`).
    pub sampler: String,
    /// One of [`IMAGE_KINDS`], or `reference`.
    pub kind: String,
    /// Samples per pixel (per strategy for the reference and the MIS images).
    pub spp: usize,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Linear RGB radiance per pixel.
    pub rgb: Vec<[f64; 3]>,
    /// Relative error against the reference (`None` for the reference).
    pub rel_error: Option<f64>,
    /// Render time (s, all threads) — a timing.
    pub seconds: f64,
}

/// One image's relative error on one sphere (or on the whole row of spheres) with its 95 %
/// interval, and how it compares with the lowest-error image of its kind there.
///
/// **The interval.** The error is `ē = (1/P) Σ_p e_p` over the `P` pixels with non-null
/// reference luminance, `e_p = |Y_p − Y_ref,p| / Y_ref,p`. The pixels' estimates are
/// independent (each sample has its own uniforms), so given the reference
/// `Var ē = (1/P²) Σ_p Var e_p`, estimated by `s² / P` with `s²` the successive-difference
/// variance of the `e_p` in row-major pixel order (`mean_sd`: the neighbours' differences
/// remove the smooth variation of the pixels' expected errors over the sphere, which is not
/// noise; what is left of it only widens the interval): `ci95 = z₉₅ s / √P`. Checked against
/// the spread of independent renders (test
/// `the_pixel_intervals_match_the_spread_of_independent_renders`). Two images of one sphere
/// are compared pixel by pixel, `d_p = e_p(x) − e_p(best)` (independent renders), by the
/// interval `d̄ ± z s_d / √P` with `z` the two-sided normal quantile at the
/// Šidák level over the `m` comparisons with the best ([`crate::ranking::sidak_alpha`],
/// family level [`crate::ranking::ALPHA`] = 0.05, the studies' ranking rule): `x` is **tied**
/// with the best when that interval contains 0, **worse** otherwise. The intervals cover the
/// images' noise at their samples per pixel; the equal-time budgets (from timings) and the
/// reference image are held fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereError {
    /// The sampler.
    pub sampler: String,
    /// Samples (or MIS pairs) per pixel of the image.
    pub spp: usize,
    /// The relative error `ē`.
    pub error: f64,
    /// Half-width of its 95 % interval, `z₉₅ s / √P` (infinite with fewer than 2 pixels).
    pub ci95: f64,
    /// `ē − ē(best)`, 0 for the best.
    pub above_best: f64,
    /// Half-width of the Šidák-corrected interval of `above_best` (0 for the best).
    pub above_best_hw: f64,
    /// The best itself, or an image whose difference from the best is not significant.
    pub tied_with_best: bool,
}

/// `e_p = |Y_p − Y_ref,p| / Y_ref,p` at the pixels `idx` with non-null reference luminance,
/// in order (the terms of [`relative_error`]).
fn pixel_errors(image: &[[f64; 3]], reference: &[[f64; 3]], idx: &[usize]) -> Vec<f64> {
    idx.iter()
        .filter_map(|&p| {
            let yr = colour::luminance(reference[p]);
            (yr > 0.0).then(|| (colour::luminance(image[p]) - yr).abs() / yr)
        })
        .collect()
}

/// Mean and the successive-difference estimate of the terms' standard deviation,
/// `s² = Σ_p (v_{p+1} − v_p)² / (2 (P − 1))` (von Neumann): for independent terms with a
/// common mean it is unbiased; a mean that varies from term to term (pixels in row-major
/// order: neighbours on a smooth image) adds only its local roughness, where the ordinary
/// sample variance would add the whole spread of the pixels' expected errors. NaN with fewer
/// than 2 values.
fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v
        .windows(2)
        .map(|w| (w[1] - w[0]) * (w[1] - w[0]))
        .sum::<f64>()
        / (2.0 * (n - 1.0));
    (m, var.sqrt())
}

/// The images `(sampler, spp, e_p)` (per-pixel errors over the same pixels) ranked, lowest
/// mean first, with the intervals and verdicts of [`SphereError`].
pub fn rank_pixel_errors(rows: Vec<(String, usize, Vec<f64>)>) -> Vec<SphereError> {
    let mut stats: Vec<(String, usize, Vec<f64>, f64, f64)> = rows
        .into_iter()
        .map(|(name, spp, e)| {
            let (m, sd) = if e.is_empty() {
                (0.0, f64::NAN)
            } else {
                mean_sd(&e)
            };
            (name, spp, e, m, sd)
        })
        .collect();
    stats.sort_by(|a, b| a.3.total_cmp(&b.3));
    let z95 = crate::ranking::two_sided_z(0.05);
    let m = stats.len().saturating_sub(1);
    let z = crate::ranking::two_sided_z(crate::ranking::sidak_alpha(crate::ranking::ALPHA, m));
    let Some(best) = stats.first().map(|b| b.2.clone()) else {
        return Vec::new();
    };
    stats
        .iter()
        .enumerate()
        .map(|(i, (name, spp, e, mean, sd))| {
            let ci95 = if sd.is_finite() {
                z95 * sd / (e.len() as f64).sqrt()
            } else {
                f64::INFINITY
            };
            let (above, hw) = if i == 0 {
                (0.0, 0.0)
            } else {
                let d: Vec<f64> = e.iter().zip(&best).map(|(a, b)| a - b).collect();
                let (dm, dsd) = if d.len() == e.len() && d.len() == best.len() && d.len() > 1 {
                    mean_sd(&d)
                } else {
                    (mean - stats[0].3, f64::NAN)
                };
                let hw = if dsd.is_finite() {
                    z * dsd / (d.len() as f64).sqrt()
                } else {
                    f64::INFINITY
                };
                (dm, hw)
            };
            SphereError {
                sampler: name.clone(),
                spp: *spp,
                error: *mean,
                ci95,
                above_best: above,
                above_best_hw: hw,
                tied_with_best: i == 0 || !(above - hw > 0.0),
            }
        })
        .collect()
}

/// Whether an adaptive sampler ([`crate::is_adaptive`]) has the lowest error among the ranked
/// images of one sphere and kind ([`rank_pixel_errors`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AdaptiveVerdict {
    /// The best image is this adaptive sampler's and every non-adaptive image is significantly
    /// worse.
    Lowest(String),
    /// An adaptive sampler (`adaptive`, the lowest of them) and a non-adaptive one (`other`)
    /// are both the best or tied with it: no significant difference decides.
    Tied {
        /// The best adaptive sampler among the best and those tied with it.
        adaptive: String,
        /// The best non-adaptive sampler among them.
        other: String,
    },
    /// A non-adaptive sampler is best and every adaptive image is significantly worse.
    NotLowest {
        /// The best sampler.
        best: String,
    },
    /// No adaptive image (or no image at all).
    NoAdaptive,
}

impl AdaptiveVerdict {
    /// The verdict of ranked images (`rows` lowest error first, as [`rank_pixel_errors`]).
    pub fn of(rows: &[SphereError]) -> Self {
        let tied = || rows.iter().filter(|r| r.tied_with_best);
        let adaptive = tied().find(|r| crate::is_adaptive(&r.sampler));
        let other = tied().find(|r| !crate::is_adaptive(&r.sampler));
        match (adaptive, other, rows.first()) {
            (Some(a), None, _) => Self::Lowest(a.sampler.clone()),
            (Some(a), Some(o), _) => Self::Tied {
                adaptive: a.sampler.clone(),
                other: o.sampler.clone(),
            },
            (None, _, Some(b)) if rows.iter().any(|r| crate::is_adaptive(&r.sampler)) => {
                Self::NotLowest {
                    best: b.sampler.clone(),
                }
            }
            _ => Self::NoAdaptive,
        }
    }

    /// One word for tables: `lowest`, `tied`, `not lowest`, `—`.
    pub fn word(&self) -> &'static str {
        match self {
            Self::Lowest(_) => "lowest",
            Self::Tied { .. } => "tied",
            Self::NotLowest { .. } => "not lowest",
            Self::NoAdaptive => "—",
        }
    }
}

/// The images of a study.
#[derive(Debug, Clone)]
pub struct Render {
    /// The settings.
    pub config: RenderConfig,
    /// The light spec.
    pub light: String,
    /// The BRDFs, left to right.
    pub brdfs: Vec<String>,
    /// How the reference was made.
    pub reference_method: String,
    /// The reference.
    pub reference: Image,
    /// The reference's own error, estimated from its samples, and its weights.
    pub reference_error: ReferenceError,
    /// One equal-samples and one equal-time image per sampler that could be built, each
    /// followed by its two MIS images when there are MIS images.
    pub images: Vec<Image>,
    /// Measured ns per pixel sample per sampler on the render's path (coherent ωo; timings):
    /// the equal-time budget.
    pub ns_per_sample: Vec<(String, f64)>,
    /// The equal-time budget: ns per pixel sample of the budget's sampler (`adaptive`, BRDF
    /// sampling alone); every equal-time image gets `spp × budget_ns` per pixel.
    pub budget_ns: f64,
    /// The light's sampler in the MIS images (`None`: no MIS images).
    pub mis_light: Option<String>,
    /// Time and BRDF evaluations per sample with coherent and with random ωo, per sampler.
    pub sample_costs: Vec<SampleCost>,
    /// The adaptive product estimator's cost (`None`: no product images).
    pub product_cost: Option<ProductCost>,
}

/// The adaptive product estimator's cost per pixel: `T(n) = setup + n · per_sample`, fitted
/// from the timings at 8 and 24 samples per pixel (coherent rows, one thread, the median of the
/// interleaved runs), so that its equal-time images get `(spp · budget − setup) / per_sample`
/// samples ([`product_equal_time_spp`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProductCost {
    /// ns per pixel of the cut (`T(8) − 8 · per_sample`).
    pub setup_ns: f64,
    /// ns per sample (`(T(24) − T(8)) / 16`).
    pub per_sample_ns: f64,
    /// ns per pixel sample at 8 samples per pixel, `T(8) / 8`.
    pub at8_ns: f64,
    /// BRDF evaluations per pixel at 8 samples per pixel (the cut's and the samples').
    pub evals_per_pixel8: f64,
}

/// Samples per pixel of an estimator with a per-pixel setup at equal time:
/// `(spp · budget_ns − setup_ns) / per_sample_ns` rounded, at least 1 (1 when the cost is not a
/// positive number).
pub fn product_equal_time_spp(
    spp: usize,
    budget_ns: f64,
    setup_ns: f64,
    per_sample_ns: f64,
) -> usize {
    let x = (spp as f64 * budget_ns - setup_ns.max(0.0)) / per_sample_ns;
    if x.is_finite() && x > 0.0 {
        (x.round() as usize).max(1)
    } else {
        1
    }
}

/// One sampler's cost per pixel sample on the batch path (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleCost {
    /// The sampler.
    pub sampler: String,
    /// ns per sample, a row of pixels × spp per batch call (median of the timing runs).
    pub coherent_ns: f64,
    /// ns per sample, each query at a random pixel of the same sphere, same batch sizes.
    pub random_ns: f64,
    /// BRDF evaluations per sample on the render's path, coherent queries: the sampler's and
    /// the estimator's (a fused `f` is not evaluated again).
    pub coherent_evals: f64,
    /// The same, random queries.
    pub random_evals: f64,
    /// ns per MIS pixel sample (one BRDF and one light sample, the other technique's pdf at
    /// each, the integrand at each), coherent queries as rendered (median of the timing runs);
    /// `None` without MIS images.
    #[serde(default)]
    pub mis_ns: Option<f64>,
    /// BRDF evaluations per MIS pixel sample (one BRDF and one light sample), all of the path's
    /// (the sampler's trials, the integrand's `f` at the light sample, the BRDF pdf at it);
    /// `None` without MIS images.
    #[serde(default)]
    pub mis_evals: Option<f64>,
}

/// The light's own sampler for the reference.
enum LightSampler {
    Map(Box<EnvMapSampler>),
    Cone { axis: Vec3, cos_radius: f64 },
    None,
}

impl LightSampler {
    fn new(light: &Light) -> Result<Self, StudyError> {
        Ok(match light {
            Light::Map { map, .. } => {
                let s = samplers::find("envmap-adaptive")?
                    .build_envmap(map, &AdaptiveOptions::default())?;
                LightSampler::Map(Box::new(s))
            }
            Light::Area { axis, radius, .. } => LightSampler::Cone {
                axis: *axis,
                cos_radius: radius.cos(),
            },
            Light::Constant { .. } => LightSampler::None,
        })
    }
}

impl LightTechnique for LightSampler {
    /// A world direction and its solid-angle pdf (`None` under constant light: nothing to
    /// sample, so MIS is BRDF sampling alone).
    fn sample_world(&self, u: &mut dyn UniformSource) -> Option<(Vec3, f64)> {
        match self {
            LightSampler::Map(s) => s.sample_world(u),
            LightSampler::Cone { axis, cos_radius } => {
                let c = 1.0 - u.next_uniform() * (1.0 - cos_radius);
                let phi = std::f64::consts::TAU * u.next_uniform();
                let (t1, t2) = frame_of(axis);
                let s = (1.0 - c * c).max(0.0).sqrt();
                let d = axis * c + t1 * (s * phi.cos()) + t2 * (s * phi.sin());
                Some((d, self.pdf_world(&d)))
            }
            LightSampler::None => None,
        }
    }

    fn pdf_world(&self, d: &Vec3) -> f64 {
        match self {
            LightSampler::Map(s) => s.pdf_world(d),
            LightSampler::Cone { axis, cos_radius } => {
                if d.dot(axis) >= *cos_radius {
                    1.0 / (std::f64::consts::TAU * (1.0 - cos_radius))
                } else {
                    0.0
                }
            }
            LightSampler::None => 0.0,
        }
    }
}

/// The BRDF handed to `sample_eval_batch` for a coloured BRDF ([`Brdf::rgb_scale`] `None`):
/// `f = 1` everywhere. The renderer needs the RGB value `eval_rgb`, which it evaluates itself,
/// so the batch's own (luminance) evaluation would be wasted: every sampler pays its sampling
/// and one RGB evaluation per sample.
struct NoEval;

impl Brdf for NoEval {
    fn eval(&self, _wo: &Vec3, _wi: &Vec3) -> f64 {
        1.0
    }
}

/// Two unit vectors completing `n` to an orthonormal frame.
fn frame_of(n: &Vec3) -> (Vec3, Vec3) {
    let up = Vec3::new(0.0, 0.0, 1.0);
    let t = up.cross(n);
    let t = if t.norm() > 1e-9 {
        t.normalize()
    } else {
        Vec3::new(1.0, 0.0, 0.0)
    };
    (t, n.cross(&t))
}

/// A visible sphere pixel.
#[derive(Debug, Clone, Copy)]
struct Hit {
    /// Pixel index.
    pixel: usize,
    /// Sphere (BRDF) index.
    sphere: usize,
    /// `ωo` in the shading frame and the frame (tangent `t`, bitangent `b`, normal `n`).
    query: Query,
}

impl Hit {
    fn world_of(&self, l: &Vec3) -> Vec3 {
        self.query.frame.to_world(l)
    }

    #[cfg(test)]
    fn local_of(&self, w: &Vec3) -> Vec3 {
        self.query.frame.to_local(w)
    }
}

/// The visible sphere pixels of a `count`-sphere row.
fn hits(count: usize, px: usize) -> Vec<Hit> {
    let width = count * px;
    let view = Vec3::new(0.0, -1.0, 0.0); // towards the camera
    let mut out = Vec::new();
    for iy in 0..px {
        for ix in 0..width {
            let x = ((ix % px) as f64 + 0.5) / px as f64 * 2.0 - 1.0;
            let z = 1.0 - (iy as f64 + 0.5) / px as f64 * 2.0;
            let r2 = x * x + z * z;
            if r2 >= 1.0 {
                continue;
            }
            let n = Vec3::new(x, -(1.0 - r2).sqrt(), z).normalize();
            let (t, b) = frame_of(&n);
            // `frame_of` gives unit `t ⊥ n` and `b = n × t`, so `t × b = n`: never refused.
            let Ok(frame) = LocalFrame::from_axes(t, b, n) else {
                continue;
            };
            let wo = frame.to_local(&view).normalize();
            if wo.z > 0.0 {
                out.push(Hit {
                    pixel: iy * width + ix,
                    sphere: ix / px,
                    query: Query { wo, frame },
                });
            }
        }
    }
    out
}

/// `f ⊙ L · cos` (RGB) for a local `wi` (0 below the horizon).
#[inline]
fn integrand(brdf: &dyn Brdf, light: &Light, h: &Hit, wi: &Vec3) -> [f64; 3] {
    if !(wi.z > 0.0) {
        return [0.0; 3];
    }
    lit(brdf.eval_rgb(&h.query.wo, wi), light, h, wi)
}

/// `f ⊙ L · cos` (RGB) for a local `wi` above the horizon and its RGB BRDF value `f`.
#[inline]
fn lit(f: [f64; 3], light: &Light, h: &Hit, wi: &Vec3) -> [f64; 3] {
    let l = light.radiance(&h.world_of(wi));
    [f[0] * l[0] * wi.z, f[1] * l[1] * wi.z, f[2] * l[2] * wi.z]
}

/// [`integrand`] of a BRDF whose RGB value is `c ⊙ f` ([`Brdf::rgb_scale`]), given its scalar
/// value `f` at `wi` (the sampler's fused one, or one evaluation).
#[inline]
fn integrand_scaled(c: [f64; 3], f: f64, light: &Light, h: &Hit, wi: &Vec3) -> [f64; 3] {
    if !(wi.z > 0.0) {
        return [0.0; 3];
    }
    lit(c.map(|k| k * f), light, h, wi)
}

/// A stable per-name number for seeds.
fn name_hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

impl StudyPlan {
    /// Renders the sphere images (see the module docs) for every sampler of the study.
    ///
    /// Errors: a light index outside the study, or the light's sampler failing to build.
    pub fn render(
        &self,
        cfg: &RenderConfig,
        progress: crate::ProgressFn<'_>,
    ) -> Result<Render, StudyError> {
        let all: Vec<usize> = (0..self.brdfs.len()).collect();
        self.render_brdfs(cfg, &all, progress)
    }

    /// [`StudyPlan::render`] of some of the study's BRDFs (`specs`, each one of the config's,
    /// left to right in this order), with the samplers the plan built for them (a study's
    /// sphere sheet reuses its statistics' builds instead of building them again).
    ///
    /// Errors: a spec that is not one of the study's BRDFs, and [`StudyPlan::render`]'s.
    pub fn render_subset(
        &self,
        cfg: &RenderConfig,
        specs: &[String],
        progress: crate::ProgressFn<'_>,
    ) -> Result<Render, StudyError> {
        let chosen = specs
            .iter()
            .map(|spec| {
                self.brdfs
                    .iter()
                    .position(|b| &b.spec == spec)
                    .ok_or_else(|| StudyError::NotInStudy {
                        what: "BRDFs",
                        name: crate::names::short_brdf(spec),
                    })
            })
            .collect::<Result<Vec<usize>, _>>()?;
        if chosen.is_empty() {
            return Err(StudyError::EmptyGrid("sphere BRDFs"));
        }
        self.render_brdfs(cfg, &chosen, progress)
    }

    fn render_brdfs(
        &self,
        cfg: &RenderConfig,
        chosen: &[usize],
        progress: crate::ProgressFn<'_>,
    ) -> Result<Render, StudyError> {
        let light = self
            .lights
            .get(cfg.light)
            .ok_or(StudyError::EmptyGrid("light to render under"))?;
        let px = cfg.sphere_px.max(4);
        let (width, height) = (chosen.len() * px, px);
        let hits = hits(chosen.len(), px);
        // The objects the samplers were built with (the study's counting wrappers), so that a
        // sampler recognises its own BRDF and hands back its accepted trial's `f`.
        let brdfs: Vec<&dyn Brdf> = chosen
            .iter()
            .map(|&b| self.brdfs[b].counted.as_ref())
            .collect();
        // Samplers per (sampler, BRDF), built on every core first (cached: those the study's
        // statistics built are reused); the reference sampler is `adaptive`.
        let pairs: Vec<(usize, usize)> = (0..self.entries.len())
            .flat_map(|s| chosen.iter().map(move |&b| (s, b)))
            .collect();
        self.build_all(&pairs, &|_| {});
        let built: Vec<Vec<Option<std::sync::Arc<dyn DirectionSampler>>>> = (0..self.entries.len())
            .map(|s| {
                chosen
                    .iter()
                    .map(|&b| self.build(s, b).ok().map(|(d, _)| d.sampler))
                    .collect()
            })
            .collect();
        let reference_entry = samplers::find("adaptive")?;
        let reference_samplers: Vec<std::sync::Arc<dyn DirectionSampler>> = match self
            .entries
            .iter()
            .position(|e| e.name == reference_entry.name)
        {
            Some(s) if built[s].iter().all(Option::is_some) => {
                built[s].iter().flatten().cloned().collect()
            }
            _ => {
                let options = brdf_sampling::SetOptions {
                    slices: self.config.slices,
                    ..Default::default()
                };
                chosen
                    .iter()
                    .map(|&b| &self.brdfs[b])
                    .map(|b| {
                        reference_entry
                            .build_direction(&samplers::DirectionRequest::new(
                                std::sync::Arc::clone(&b.counted),
                                &options,
                            ))
                            .map(|d| d.sampler)
                    })
                    .collect::<Result<_, _>>()?
            }
        };
        let light_sampler = LightSampler::new(light)?;
        let segments = segments(&hits, width);
        let mis_light = match (&light_sampler, cfg.mis) {
            (LightSampler::None, _) | (_, false) => None,
            (l, true) => Some(l),
        };
        let timed: Vec<usize> = (0..self.entries.len())
            .filter(|&s| built[s].iter().all(Option::is_some))
            .collect();
        let timed_samplers: Vec<Vec<&dyn DirectionSampler>> = timed
            .iter()
            .map(|&s| built[s].iter().flatten().map(|b| b.as_ref()).collect())
            .collect();
        // The adaptive product images: under a map, with MIS images, when `adaptive-exact`
        // was built for every sphere.
        let pyramid = match (light.as_ref(), mis_light) {
            (Light::Map { map, .. }, Some(_)) => Some(PowerPyramid::new(map)),
            _ => None,
        };
        let product = pyramid.as_ref().and_then(|p| {
            timed
                .iter()
                .position(|&s| self.entries[s].name == PRODUCT_DEFENSIVE)
                .map(|d| (d, p))
        });
        // The reference (see `ReferenceError`): each part as two independent halves; with the
        // product, weights per sphere from independent pilots.
        let start = Instant::now();
        let ref_mis = |spp: usize, tag: &str| {
            render_segments(
                &hits,
                &segments,
                width * height,
                |seg, rng| {
                    let sphere = seg[0].sphere;
                    mis_row(
                        brdfs[sphere],
                        light,
                        seg,
                        reference_samplers[sphere].as_ref(),
                        &light_sampler,
                        spp,
                        rng,
                    )
                },
                cfg.seed ^ name_hash(tag),
            )
        };
        let ref_product = |d: usize, pyramid: &PowerPyramid, spp: usize, tag: &str| {
            let s = timed[d];
            render_segments(
                &hits,
                &segments,
                width * height,
                |seg, rng| {
                    let sphere = seg[0].sphere;
                    match built[s][sphere].as_deref() {
                        None => vec![[0.0; 3]; seg.len()],
                        Some(smp) => product_row(brdfs[sphere], light, seg, smp, pyramid, spp, rng),
                    }
                },
                cfg.seed ^ name_hash(tag),
            )
        };
        let sphere_pixels = |j: usize| -> Vec<usize> {
            (0..width * height)
                .filter(|p| (p % width) / px == j)
                .collect()
        };
        let (mis_spp, product_spp) = match product {
            Some(_) => (
                (cfg.reference_spp / REFERENCE_MIS_DIVISOR).max(2),
                (cfg.reference_spp * 3 / 2).max(2),
            ),
            None => (cfg.reference_spp.max(2), 0),
        };
        let cpu = crate::machine::process_cpu_seconds;
        let mut cpu_parts = [0.0; 3];
        let c0 = cpu();
        let m1 = ref_mis(mis_spp / 2, "reference");
        let m2 = ref_mis(mis_spp - mis_spp / 2, "reference half 2");
        let c1 = cpu();
        if let (Some(a), Some(b)) = (c0, c1) {
            cpu_parts[0] = b - a;
        }
        let (ref_rgb, ref_d, mis_weight, pilot_rel_var) = match product {
            Some((d, pyramid)) => {
                let pm = [
                    ref_mis(REFERENCE_PILOT_SPP, "reference pilot mis 1"),
                    ref_mis(REFERENCE_PILOT_SPP, "reference pilot mis 2"),
                ];
                let pk = [
                    ref_product(d, pyramid, REFERENCE_PILOT_SPP, "reference pilot product 1"),
                    ref_product(d, pyramid, REFERENCE_PILOT_SPP, "reference pilot product 2"),
                ];
                let fitted: Vec<(f64, f64, f64)> = (0..chosen.len())
                    .map(|j| {
                        reference_mis_weight(
                            [&pm[0], &pm[1]],
                            [&pk[0], &pk[1]],
                            &sphere_pixels(j),
                            REFERENCE_PILOT_SPP,
                            mis_spp,
                            product_spp,
                        )
                    })
                    .collect();
                let c2 = cpu();
                if let (Some(a), Some(b)) = (c1, c2) {
                    cpu_parts[1] = b - a;
                }
                let k1 = ref_product(d, pyramid, product_spp / 2, "reference product 1");
                let k2 = ref_product(
                    d,
                    pyramid,
                    product_spp - product_spp / 2,
                    "reference product 2",
                );
                if let (Some(a), Some(b)) = (c2, cpu()) {
                    cpu_parts[2] = b - a;
                }
                let w: Vec<f64> = fitted.iter().map(|f| f.0).collect();
                let (rgb, dd) = combine_reference([&m1, &m2], Some([&k1, &k2]), |p| {
                    let w = w[(p % width) / px];
                    (w, 1.0 - w)
                });
                (rgb, dd, w, fitted.iter().map(|f| (f.1, f.2)).collect())
            }
            None => {
                let (rgb, dd) = combine_reference([&m1, &m2], None, |_| (1.0, 0.0));
                (
                    rgb,
                    dd,
                    vec![1.0; chosen.len()],
                    vec![(0.0, 0.0); chosen.len()],
                )
            }
        };
        let all_pixels: Vec<usize> = (0..width * height).collect();
        let reference_error = ReferenceError {
            per_sphere: (0..chosen.len())
                .map(|j| reference_self_error(&ref_rgb, &ref_d, &sphere_pixels(j)))
                .collect(),
            whole: reference_self_error(&ref_rgb, &ref_d, &all_pixels),
            mis_weight,
            pilot_rel_var,
            cpu_seconds: c0.map(|_| cpu_parts),
        };
        progress(1);
        let reference = Image {
            sampler: "reference".into(),
            kind: "reference".into(),
            spp: cfg.reference_spp,
            width,
            height,
            rgb: ref_rgb,
            rel_error: None,
            seconds: start.elapsed().as_secs_f64(),
        };
        // Time per pixel sample, one thread, on every 11th row segment: median of
        // `TIMING_REPEATS` interleaved runs, coherent (the render's path) and random ωo, and
        // MIS (coherent) when there are MIS images.
        let (timed_costs, product_cost) = sample_costs(
            &hits,
            &segments,
            &brdfs,
            light,
            mis_light,
            &timed_samplers,
            product,
            cfg.seed,
        );
        let costs: Vec<(usize, SampleCost)> = timed
            .iter()
            .zip(timed_costs)
            .map(|(&s, cost)| {
                (
                    s,
                    SampleCost {
                        sampler: self.entries[s].name.to_string(),
                        ..cost
                    },
                )
            })
            .collect();
        let ns_per_sample: Vec<(usize, f64)> =
            costs.iter().map(|(s, c)| (*s, c.coherent_ns)).collect();
        let budget_ns = ns_per_sample
            .iter()
            .find(|(s, _)| self.entries[*s].name == "adaptive")
            .map(|x| x.1)
            .unwrap_or_else(|| {
                ns_per_sample.iter().map(|x| x.1).sum::<f64>() / ns_per_sample.len().max(1) as f64
            });
        let mut images = Vec::new();
        for (s, cost) in &costs {
            let s = *s;
            let name = self.entries[s].name;
            let mut kinds = vec![
                (IMAGE_KINDS[0], cfg.spp, false),
                (
                    IMAGE_KINDS[1],
                    equal_time_spp(cfg.spp, budget_ns, cost.coherent_ns),
                    false,
                ),
            ];
            if let (Some(_), Some(mis_ns)) = (mis_light, cost.mis_ns) {
                kinds.push((IMAGE_KINDS[2], cfg.spp, true));
                kinds.push((
                    IMAGE_KINDS[3],
                    equal_time_spp(cfg.spp, budget_ns, mis_ns),
                    true,
                ));
            }
            for (kind, spp, mis) in kinds {
                let start = Instant::now();
                let rgb = render_segments(
                    &hits,
                    &segments,
                    width * height,
                    |seg, rng| {
                        let sphere = seg[0].sphere;
                        match (built[s][sphere].as_deref(), mis_light) {
                            (None, _) => vec![[0.0; 3]; seg.len()],
                            (Some(smp), Some(l)) if mis => {
                                mis_row(brdfs[sphere], light, seg, smp, l, spp, rng)
                            }
                            (Some(smp), _) => brdf_row(brdfs[sphere], light, seg, smp, spp, rng),
                        }
                    },
                    cfg.seed ^ name_hash(name) ^ name_hash(kind),
                );
                images.push(Image {
                    sampler: name.to_string(),
                    kind: kind.to_string(),
                    spp,
                    width,
                    height,
                    rel_error: Some(relative_error(&rgb, &reference.rgb)),
                    rgb,
                    seconds: start.elapsed().as_secs_f64(),
                });
                progress(1);
            }
        }
        if let (Some((d, pyramid)), Some(pc)) = (product, &product_cost) {
            let s = timed[d];
            for (kind, spp) in [
                (PRODUCT_KINDS[0], cfg.spp),
                (
                    PRODUCT_KINDS[1],
                    product_equal_time_spp(cfg.spp, budget_ns, pc.setup_ns, pc.per_sample_ns),
                ),
            ] {
                let start = Instant::now();
                let rgb = render_segments(
                    &hits,
                    &segments,
                    width * height,
                    |seg, rng| {
                        let sphere = seg[0].sphere;
                        match built[s][sphere].as_deref() {
                            None => vec![[0.0; 3]; seg.len()],
                            Some(smp) => {
                                product_row(brdfs[sphere], light, seg, smp, pyramid, spp, rng)
                            }
                        }
                    },
                    cfg.seed ^ name_hash(PRODUCT_NAME) ^ name_hash(kind),
                );
                images.push(Image {
                    sampler: PRODUCT_NAME.to_string(),
                    kind: kind.to_string(),
                    spp,
                    width,
                    height,
                    rel_error: Some(relative_error(&rgb, &reference.rgb)),
                    rgb,
                    seconds: start.elapsed().as_secs_f64(),
                });
            }
        }
        let light_method = match light_sampler {
            LightSampler::Map(_) => "the envmap-adaptive map sampler",
            LightSampler::Cone { .. } => "uniform sampling of the area light's cone",
            LightSampler::None => "nothing (constant light: BRDF sampling alone)",
        };
        Ok(Render {
            config: cfg.clone(),
            light: self.config.lights[cfg.light].clone(),
            brdfs: chosen.iter().map(|&b| self.brdfs[b].spec.clone()).collect(),
            reference_method: if product_spp > 0 {
                format!(
                    "w × MIS (balance heuristic) of the adaptive BRDF sampler and {light_method} at {mis_spp} samples of each per pixel + (1 − w) × the adaptive product at {product_spp} samples per pixel (own seeds), w per sphere from independent pilots at {REFERENCE_PILOT_SPP} spp (inverse relative variance): {}",
                    reference_error
                        .mis_weight
                        .iter()
                        .map(|w| format!("{w:.3}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            } else {
                format!(
                    "MIS (balance heuristic) of the adaptive BRDF sampler and {light_method}, {mis_spp} samples of each per pixel"
                )
            },
            reference,
            reference_error,
            images,
            ns_per_sample: ns_per_sample
                .iter()
                .map(|(s, ns)| (self.entries[*s].name.to_string(), *ns))
                .collect(),
            sample_costs: costs.into_iter().map(|(_, c)| c).collect(),
            product_cost,
            budget_ns,
            mis_light: mis_light.map(|_| light_method.to_string()),
        })
    }
}

/// The hits cut into row segments: the consecutive visible pixels of one image row on one
/// sphere (one batch call each).
fn segments(hits: &[Hit], width: usize) -> Vec<std::ops::Range<usize>> {
    let mut out: Vec<std::ops::Range<usize>> = Vec::new();
    for (i, h) in hits.iter().enumerate() {
        match out.last_mut() {
            Some(r)
                if hits[r.start].sphere == h.sphere
                    && hits[r.start].pixel / width == h.pixel / width =>
            {
                r.end = i + 1;
            }
            _ => out.push(i..i + 1),
        }
    }
    out
}

/// Renders every row segment with `shade(segment, rng)` (one value per hit) in parallel;
/// the segment whose first pixel is `p` draws from a generator seeded from `(seed, p)`.
fn render_segments(
    hits: &[Hit],
    segments: &[std::ops::Range<usize>],
    pixels: usize,
    shade: impl Fn(&[Hit], &mut Xoshiro256PlusPlus) -> Vec<[f64; 3]> + Sync,
    seed: u64,
) -> Vec<[f64; 3]> {
    let values: Vec<(usize, Vec<[f64; 3]>)> = segments
        .par_iter()
        .map(|r| {
            let seg = &hits[r.clone()];
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, seg[0].pixel as u64));
            (r.start, shade(seg, &mut rng))
        })
        .collect();
    let mut rgb = vec![[0.0; 3]; pixels];
    for (first, v) in values {
        for (h, c) in hits[first..].iter().zip(v) {
            rgb[h.pixel] = c;
        }
    }
    rgb
}

/// The BRDF-sampling estimates of a row segment: one batch call, `spp` samples per pixel.
/// `brdf` is the object `sampler` was built with. A BRDF of constant colour
/// ([`Brdf::rgb_scale`]) is passed to the batch and its `f` ([`brdf_sampling::EvalSample::f`]:
/// a rejection sampler's accepted trial) times the colour is the RGB value (the *fused f*) when
/// the sampler fuses ([`DirectionSampler::fuses_eval`]); otherwise [`NoEval`] and one
/// `eval_rgb` per sample.
fn brdf_row(
    brdf: &dyn Brdf,
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    match brdf.rgb_scale() {
        Some(c) if sampler.fuses_eval() => brdf_row_fused(brdf, c, light, seg, sampler, spp, rng),
        _ => brdf_row_rgb(brdf, light, seg, sampler, spp, rng),
    }
}

/// [`brdf_row`] with the fused `f` of a BRDF whose RGB value is `c ⊙ f`.
#[inline(never)]
fn brdf_row_fused(
    brdf: &dyn Brdf,
    c: [f64; 3],
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    let points: Vec<Query> = seg.iter().map(|h| h.query).collect();
    Batch { sampler, brdf, spp }.brdf(
        &points,
        |k, s| integrand_scaled(c, s.f, light, &seg[k], &s.wi),
        rng,
    )
}

/// [`brdf_row`] with one `eval_rgb` per sample (the batch evaluates nothing).
#[inline(never)]
fn brdf_row_rgb(
    brdf: &dyn Brdf,
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    let points: Vec<Query> = seg.iter().map(|h| h.query).collect();
    Batch {
        sampler,
        brdf: &NoEval,
        spp,
    }
    .brdf(&points, |k, s| integrand(brdf, light, &seg[k], &s.wi), rng)
}

/// The MIS (balance heuristic, `spp` samples of each technique) estimates of a row segment;
/// `brdf` as in [`brdf_row`] (the fused `f` at the BRDF samples of a constant-colour BRDF,
/// one scalar evaluation times the colour at its light samples).
fn mis_row<L: LightTechnique + ?Sized>(
    brdf: &dyn Brdf,
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    light_sampler: &L,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    match brdf.rgb_scale() {
        Some(c) if sampler.fuses_eval() => {
            mis_row_fused(brdf, c, light, seg, sampler, light_sampler, spp, rng)
        }
        _ => mis_row_rgb(brdf, light, seg, sampler, light_sampler, spp, rng),
    }
}

/// [`mis_row`] with the fused `f` of a BRDF whose RGB value is `c ⊙ f`: at a light sample the
/// batch evaluates `f` once ([`Batch::mis_given_f`]) and the sampler's pdf there takes that
/// `f` ([`DirectionSampler::pdf_many_given_f`]: no second evaluation for `adaptive-exact`).
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn mis_row_fused<L: LightTechnique + ?Sized>(
    brdf: &dyn Brdf,
    c: [f64; 3],
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    light_sampler: &L,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    let points: Vec<Query> = seg.iter().map(|h| h.query).collect();
    Batch { sampler, brdf, spp }.mis_given_f(
        &points,
        light_sampler,
        MisHeuristic::Balance,
        |k, wi, f| integrand_scaled(c, f, light, &seg[k], wi),
        rng,
    )
}

/// [`mis_row`] with one `eval_rgb` per sample (the batch evaluates nothing).
#[inline(never)]
fn mis_row_rgb<L: LightTechnique + ?Sized>(
    brdf: &dyn Brdf,
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    light_sampler: &L,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    let points: Vec<Query> = seg.iter().map(|h| h.query).collect();
    Batch {
        sampler,
        brdf: &NoEval,
        spp,
    }
    .mis(
        &points,
        light_sampler,
        MisHeuristic::Balance,
        |k, wi, _| integrand(brdf, light, &seg[k], wi),
        rng,
    )
}

/// Each sampler's cost per pixel sample (`samplers[i][sphere]`), one thread: every 11th row
/// segment, 8 samples per pixel per batch call (coherent); then, with the same batch sizes,
/// each query at a pixel of the same sphere drawn at random (random ωo, one sample each); and,
/// with a light sampler, MIS on the coherent segments (8 pairs per pixel). Median of
/// [`TIMING_REPEATS`] runs of each (sampler, path), the runs interleaved (repeat `r` of every
/// sampler and path before repeat `r + 1`), timed on the thread's CPU clock where there is
/// one; and the BRDF evaluations per sample, the sampler's and the estimator's (counted on this
/// thread by the study's [`crate::CountingBrdf`], the object the samplers were built with).
/// With `product = Some((i, pyramid))`, sampler `i` also times the adaptive product at 8 and 24
/// samples per pixel ([`ProductCost`]).
#[allow(
    clippy::too_many_arguments,
    reason = "the render's parts, passed as they are"
)]
fn sample_costs(
    hits: &[Hit],
    segments: &[std::ops::Range<usize>],
    brdfs: &[&dyn Brdf],
    light: &Light,
    light_sampler: Option<&LightSampler>,
    samplers: &[Vec<&dyn DirectionSampler>],
    product: Option<(usize, &PowerPyramid)>,
    seed: u64,
) -> (Vec<SampleCost>, Option<ProductCost>) {
    let spp = 8;
    let subset: Vec<&[Hit]> = segments
        .iter()
        .step_by(11)
        .map(|r| &hits[r.clone()])
        .collect();
    // Random ωo: per subset segment, `len × spp` hits of the same sphere drawn uniformly.
    let mut pick = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, u64::MAX));
    let by_sphere: Vec<Vec<Hit>> = (0..brdfs.len())
        .map(|b| hits.iter().filter(|h| h.sphere == b).copied().collect())
        .collect();
    let random: Vec<Vec<Hit>> = subset
        .iter()
        .map(|seg| {
            let pool = &by_sphere[seg[0].sphere];
            (0..seg.len() * spp)
                .map(|_| {
                    pool[((pick.next_uniform() * pool.len() as f64) as usize).min(pool.len() - 1)]
                })
                .collect()
        })
        .collect();
    let random_refs: Vec<&[Hit]> = random.iter().map(Vec::as_slice).collect();
    let samples = (subset.iter().map(|s| s.len()).sum::<usize>() * spp).max(1) as f64;
    let pixels = subset.iter().map(|s| s.len()).sum::<usize>().max(1) as f64;
    // Paths: 0 coherent BRDF sampling, 1 random ωo, 2 coherent MIS; for the product's
    // defensive sampler also 3, 4: the adaptive product at 8 and 24 samples per pixel.
    let paths = if light_sampler.is_some() { 3 } else { 2 };
    let paths_of = |i: usize| match product {
        Some((d, _)) if d == i => 5,
        _ => paths,
    };
    let mut times: Vec<Vec<Vec<f64>>> = (0..samplers.len())
        .map(|i| vec![Vec::with_capacity(TIMING_REPEATS); paths_of(i)])
        .collect();
    let mut evals: Vec<Vec<f64>> = (0..samplers.len())
        .map(|i| vec![0.0; paths_of(i)])
        .collect();
    let mut rngs: Vec<Vec<Xoshiro256PlusPlus>> = (0..samplers.len())
        .map(|i| {
            (0..paths_of(i))
                .map(|p| {
                    let stream = if p < 3 {
                        i * 3 + p
                    } else {
                        3 * samplers.len() + p
                    };
                    Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, stream as u64))
                })
                .collect()
        })
        .collect();
    for r in 0..TIMING_REPEATS {
        for (i, smp) in samplers.iter().enumerate() {
            for (path, rng) in rngs[i].iter_mut().enumerate() {
                let (batches, per_point) = match path {
                    1 => (&random_refs[..], 1),
                    4 => (&subset[..], 3 * spp),
                    _ => (&subset[..], spp),
                };
                let before = crate::thread_evaluations();
                let (cpu, wall) = (crate::machine::thread_cpu_seconds(), Instant::now());
                let mut sink = 0.0;
                for seg in batches {
                    let sphere = seg[0].sphere;
                    let v = match (path, light_sampler, product) {
                        (2, Some(l), _) => {
                            mis_row(brdfs[sphere], light, seg, smp[sphere], l, per_point, rng)
                        }
                        (3 | 4, _, Some((_, pyramid))) => product_row(
                            brdfs[sphere],
                            light,
                            seg,
                            smp[sphere],
                            pyramid,
                            per_point,
                            rng,
                        ),
                        _ => brdf_row(brdfs[sphere], light, seg, smp[sphere], per_point, rng),
                    };
                    sink += v.iter().map(|c| c[1]).sum::<f64>();
                }
                std::hint::black_box(sink);
                let seconds = match (cpu, crate::machine::thread_cpu_seconds()) {
                    (Some(a), Some(b)) => b - a,
                    _ => wall.elapsed().as_secs_f64(),
                };
                // Product paths: ns and evaluations per pixel; the others per sample.
                let per = if path >= 3 { pixels } else { samples };
                times[i][path].push(seconds * 1e9 / per);
                if r == 0 {
                    evals[i][path] = (crate::thread_evaluations() - before) as f64 / per;
                }
            }
        }
    }
    let median = |t: &mut Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    let product_cost = product.and_then(|(d, _)| {
        let t = times.get_mut(d)?;
        let (t8, t24) = (median(t.get_mut(3)?), median(t.get_mut(4)?));
        let per_sample_ns = (t24 - t8) / (2.0 * spp as f64);
        Some(ProductCost {
            setup_ns: t8 - spp as f64 * per_sample_ns,
            per_sample_ns,
            at8_ns: t8 / spp as f64,
            evals_per_pixel8: evals[d][3],
        })
    });
    let costs = times
        .iter_mut()
        .zip(&evals)
        .map(|(t, e)| SampleCost {
            sampler: String::new(),
            coherent_ns: median(&mut t[0]),
            random_ns: median(&mut t[1]),
            coherent_evals: e[0],
            random_evals: e[1],
            mis_ns: (paths > 2).then(|| median(&mut t[2])),
            mis_evals: (paths > 2).then(|| e[2]),
        })
        .collect();
    (costs, product_cost)
}

/// The adaptive product estimates of a row segment ([`estimators::ProductBatch`], `spp`
/// samples per pixel of both techniques, `sampler` the defensive one): the batch's BRDF is
/// `brdf` (the object `sampler` was built with, so `adaptive-exact` fuses its `f` and its pdf at
/// the product samples takes their `f`); the RGB value is the colour times `f` for a BRDF of
/// constant colour, one `eval_rgb` per sample otherwise.
fn product_row(
    brdf: &dyn Brdf,
    light: &Light,
    seg: &[Hit],
    sampler: &dyn DirectionSampler,
    pyramid: &PowerPyramid,
    spp: usize,
    rng: &mut dyn UniformSource,
) -> Vec<[f64; 3]> {
    let points: Vec<Query> = seg.iter().map(|h| h.query).collect();
    let batch = ProductBatch {
        sampler,
        brdf,
        pyramid,
        spp,
        options: ProductOptions::default(),
    };
    match brdf.rgb_scale() {
        Some(c) => batch.estimate(
            &points,
            |k, wi, f| integrand_scaled(c, f, light, &seg[k], wi),
            rng,
        ),
        None => batch.estimate(&points, |k, wi, _| integrand(brdf, light, &seg[k], wi), rng),
    }
}

/// Mean over pixels with non-null reference luminance of `|Y − Y_ref| / Y_ref`.
pub fn relative_error(image: &[[f64; 3]], reference: &[[f64; 3]]) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for (i, r) in image.iter().zip(reference) {
        let yr = colour::luminance(*r);
        if yr > 0.0 {
            sum += (colour::luminance(*i) - yr).abs() / yr;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { sum / count as f64 }
}

impl Image {
    /// The exposure that maps the 99th percentile of `reference`'s non-zero luminances to 0.9.
    pub fn exposure_of(reference: &Image) -> f64 {
        let mut ys: Vec<f64> = reference
            .rgb
            .iter()
            .map(|c| colour::luminance(*c))
            .filter(|y| *y > 0.0)
            .collect();
        if ys.is_empty() {
            return 1.0;
        }
        ys.sort_by(f64::total_cmp);
        let p = ys[((ys.len() - 1) as f64 * 0.99) as usize];
        if p > 0.0 { 0.9 / p } else { 1.0 }
    }

    /// Tone-mapped 8-bit sRGB (exposure, clamp, sRGB transfer curve).
    pub fn to_rgb8(&self, exposure: f64) -> image::RgbImage {
        let mut img = image::RgbImage::new(self.width as u32, self.height as u32);
        for (i, p) in img.pixels_mut().enumerate() {
            let c = self.rgb[i];
            *p =
                image::Rgb(c.map(|x| (srgb((x * exposure).clamp(0.0, 1.0)) * 255.0).round() as u8));
        }
        img
    }

    /// The PNG bytes of [`Image::to_rgb8`].
    pub fn png(&self, exposure: f64) -> Result<Vec<u8>, StudyError> {
        encode_png(&self.to_rgb8(exposure), &self.sampler)
    }

    /// The raw linear image as PFM (colour, little endian, bottom row first).
    pub fn pfm(&self) -> Vec<u8> {
        let mut out = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        for y in (0..self.height).rev() {
            for x in 0..self.width {
                for c in self.rgb[y * self.width + x] {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
        out
    }
}

/// PNG bytes of an 8-bit image.
pub fn encode_png(img: &image::RgbImage, name: &str) -> Result<Vec<u8>, StudyError> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| StudyError::Plot {
            name: name.to_string(),
            reason: e.to_string(),
        })?;
    Ok(out.into_inner())
}

/// Stacks images vertically with a 4-pixel gap (the report's contact sheet).
pub fn stack(images: &[image::RgbImage]) -> image::RgbImage {
    let w = images.iter().map(image::RgbImage::width).max().unwrap_or(1);
    let h = images.iter().map(|i| i.height() + 4).sum::<u32>().max(1);
    let mut out = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let mut y0 = 0;
    for img in images {
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(x, y0 + y, *p);
        }
        y0 += img.height() + 4;
    }
    out
}

/// The sRGB transfer curve.
fn srgb(x: f64) -> f64 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

impl Render {
    /// The images of `kind` (one of [`IMAGE_KINDS`]), lowest relative error first.
    pub fn ranked(&self, kind: &str) -> Vec<&Image> {
        let mut ranked: Vec<&Image> = self.images.iter().filter(|i| i.kind == kind).collect();
        ranked.sort_by(|a, b| {
            a.rel_error
                .unwrap_or(f64::MAX)
                .total_cmp(&b.rel_error.unwrap_or(f64::MAX))
        });
        ranked
    }

    /// Per sphere (its BRDF, left to right): the images of `kind` ranked, lowest relative
    /// error of that sphere's pixels first, with intervals and verdicts ([`SphereError`]).
    pub fn sphere_ranking(&self, kind: &str) -> Vec<(String, Vec<SphereError>)> {
        let w = self.reference.width;
        let px = (w / self.brdfs.len().max(1)).max(1);
        self.brdfs
            .iter()
            .enumerate()
            .map(|(b, spec)| {
                let idx: Vec<usize> = (0..self.reference.rgb.len())
                    .filter(|p| p % w / px == b)
                    .collect();
                (spec.clone(), self.ranking_on(kind, &idx))
            })
            .collect()
    }

    /// The images of `kind` ranked over the whole row of spheres (every pixel), with
    /// intervals and verdicts ([`SphereError`]).
    pub fn row_ranking(&self, kind: &str) -> Vec<SphereError> {
        let idx: Vec<usize> = (0..self.reference.rgb.len()).collect();
        self.ranking_on(kind, &idx)
    }

    fn ranking_on(&self, kind: &str, idx: &[usize]) -> Vec<SphereError> {
        self.ranking_named(idx, |i| (i.kind == kind).then(|| i.sampler.clone()))
    }

    /// The images that `name` names (`None`: left out), ranked on the pixels `idx`.
    fn ranking_named(
        &self,
        idx: &[usize],
        name: impl Fn(&Image) -> Option<String>,
    ) -> Vec<SphereError> {
        rank_pixel_errors(
            self.images
                .iter()
                .filter_map(|i| {
                    name(i).map(|n| (n, i.spp, pixel_errors(&i.rgb, &self.reference.rgb, idx)))
                })
                .collect(),
        )
    }

    /// The name of an equal-time image among every estimator: the sampler (BRDF sampling
    /// alone), `sampler+MIS`, or [`PRODUCT_NAME`] (`None` for other kinds).
    pub fn equal_time_name(image: &Image) -> Option<String> {
        match image.kind.as_str() {
            k if k == IMAGE_KINDS[1] => Some(image.sampler.clone()),
            k if k == IMAGE_KINDS[3] => Some(format!("{}+MIS", image.sampler)),
            k if k == PRODUCT_KINDS[1] => Some(image.sampler.clone()),
            _ => None,
        }
    }

    /// Per sphere, every estimator's equal-time image ranked together — BRDF sampling alone,
    /// MIS (`sampler+MIS`) and the adaptive product — with the intervals and verdicts of
    /// [`SphereError`] (Šidák over all the comparisons with the best).
    pub fn sphere_ranking_all(&self) -> Vec<(String, Vec<SphereError>)> {
        let w = self.reference.width;
        let px = (w / self.brdfs.len().max(1)).max(1);
        self.brdfs
            .iter()
            .enumerate()
            .map(|(b, spec)| {
                let idx: Vec<usize> = (0..self.reference.rgb.len())
                    .filter(|p| p % w / px == b)
                    .collect();
                (
                    spec.clone(),
                    self.ranking_named(&idx, Self::equal_time_name),
                )
            })
            .collect()
    }

    /// "At equal time, BRDF only: best **X** (e ± ci %, spp; tied: …); with MIS: …" over the
    /// whole row of spheres, then per sphere how often an adaptive sampler is significantly
    /// lowest ([`Render::goal_summary`]) (`None` without equal-time images; the MIS part only
    /// with MIS images).
    pub fn equal_time_verdict(&self) -> Option<String> {
        let best = |kind: &str| {
            let r = self.row_ranking(kind);
            r.first().map(|i| {
                let tied: Vec<&str> = r[1..]
                    .iter()
                    .filter(|x| x.tied_with_best)
                    .map(|x| x.sampler.as_str())
                    .collect();
                format!(
                    "best **{}** ({:.2} ± {:.2} %, {} spp; tied with it: {})",
                    i.sampler,
                    100.0 * i.error,
                    100.0 * i.ci95,
                    i.spp,
                    if tied.is_empty() {
                        "none".to_string()
                    } else {
                        tied.join(", ")
                    }
                )
            })
        };
        let brdf_only = best(IMAGE_KINDS[1])?;
        let head = match best(IMAGE_KINDS[3]) {
            Some(mis) => format!("At equal time, BRDF only: {brdf_only}; with MIS: {mis}."),
            None => format!("At equal time, BRDF only: {brdf_only}; with MIS: no MIS images."),
        };
        Some(format!("{head} {}", self.goal_summary()))
    }

    /// Per sphere at equal time, whether an adaptive sampler is lowest ([`AdaptiveVerdict`]):
    /// "An adaptive sampler significantly lowest at equal time: BRDF only on k of n spheres
    /// (t tied); with MIS on …".
    pub fn goal_summary(&self) -> String {
        // (lowest, tied, spheres) of the per-sphere rankings.
        let tally = |rankings: &[(String, Vec<SphereError>)]| {
            let v: Vec<AdaptiveVerdict> = rankings
                .iter()
                .filter(|(_, r)| !r.is_empty())
                .map(|(_, r)| AdaptiveVerdict::of(r))
                .collect();
            let lowest = v
                .iter()
                .filter(|x| matches!(x, AdaptiveVerdict::Lowest(_)))
                .count();
            let tied = v
                .iter()
                .filter(|x| matches!(x, AdaptiveVerdict::Tied { .. }))
                .count();
            (lowest, tied, v.len())
        };
        let count = |kind: &str| tally(&self.sphere_ranking(kind));
        let (l, t, n) = count(IMAGE_KINDS[1]);
        let mut s = format!(
            "An adaptive sampler significantly lowest at equal time (95 %, Šidák over the comparisons with the best): BRDF only on {l} of {n} spheres ({t} tied)"
        );
        let (l, t, n) = count(IMAGE_KINDS[3]);
        if n > 0 {
            s.push_str(&format!("; with MIS on {l} of {n} ({t} tied)"));
        }
        if self.images.iter().any(|i| i.kind == PRODUCT_KINDS[1]) {
            let (l, t, n) = tally(&self.sphere_ranking_all());
            s.push_str(&format!(
                "; over every estimator (BRDF only, MIS, adaptive product) on {l} of {n} ({t} tied)"
            ));
        }
        s.push('.');
        s
    }

    /// The report's section on the images: the setup, the reference, and per sampler the
    /// samples per pixel and relative error at equal samples and at equal time. `sheets` are
    /// `(caption, path)` of the images to embed.
    pub fn markdown(&self, sheets: &[(String, String)]) -> String {
        use std::fmt::Write as _;
        let mut s = String::from("## Sphere images\n\n");
        let _ = writeln!(
            s,
            "Spheres, left to right: {}; under `{}`; {}×{} pixels per sphere, orthographic camera, direct lighting, no shadows. Reference: {} ({:.1} s †); its own relative error, estimated from its two independent halves (mean over pixels of |d_p| / Y_ref, see `ReferenceError`), {:.2} % (per sphere: {}). Relative error = mean over pixels with non-null reference luminance of |Y − Y_ref| / Y_ref. Equal time: samples per pixel scaled by the measured time per sample (†) to the `adaptive` sampler's budget of {} spp.\n",
            self.brdfs
                .iter()
                .map(|b| format!("`{}`", crate::names::short_brdf(b)))
                .collect::<Vec<_>>()
                .join(", "),
            crate::names::short_light(&self.light),
            self.config.sphere_px,
            self.config.sphere_px,
            self.reference_method,
            self.reference.seconds,
            100.0 * self.reference_error.whole,
            self.reference_error
                .per_sphere
                .iter()
                .map(|e| format!("{:.2} %", 100.0 * e))
                .collect::<Vec<_>>()
                .join(", "),
            self.config.spp,
        );
        s.push_str("| sampler | ns / sample † | spp (equal samples) | rel. error | spp (equal time †) | rel. error |\n|---|---|---|---|---|---|\n");
        for (name, ns) in &self.ns_per_sample {
            let find = |kind: &str| {
                self.images
                    .iter()
                    .find(|i| &i.sampler == name && i.kind == kind)
            };
            let cell = |i: Option<&Image>| {
                i.map_or("— | —".to_string(), |i| {
                    format!("{} | {:.2} %", i.spp, 100.0 * i.rel_error.unwrap_or(0.0))
                })
            };
            let _ = writeln!(
                s,
                "| {name} | {ns:.0} | {} | {} |",
                cell(find("equal samples")),
                cell(find("equal time"))
            );
        }
        s.push('\n');
        if !self.sample_costs.is_empty() {
            s.push_str("Cost per pixel sample on the batch path (one thread; every 11th row segment, 8 samples per pixel): *coherent* = one `sample_eval_batch` call per row of pixels of a sphere, as the images are rendered; *random ωo* = the same number of queries per call, each at a pixel of the same sphere drawn at random. BRDF evaluations per sample are all of the path's, the sampler's and the estimator's (a sampler's fused f, e.g. `adaptive-exact`'s accepted trial on a grey BRDF, is not evaluated again); they do not depend on the machine's load.\n\n| sampler | ns / sample, coherent † | ns / sample, random ωo † | random / coherent | BRDF evals / sample, coherent | random |\n|---|---|---|---|---|---|\n");
            for c in &self.sample_costs {
                let _ = writeln!(
                    s,
                    "| {} | {:.0} | {:.0} | {:.2} | {:.2} | {:.2} |",
                    c.sampler,
                    c.coherent_ns,
                    c.random_ns,
                    c.random_ns / c.coherent_ns,
                    c.coherent_evals,
                    c.random_evals
                );
            }
            s.push('\n');
        }
        if let Some(method) = &self.mis_light {
            let _ = writeln!(
                s,
                "**With MIS.** Each sampler combined with {method} by MIS (balance heuristic), one BRDF sample and one light sample per spp (the reference's estimator). ns / MIS sample † = both samples, the other technique's pdf at each and the integrand at each, on the coherent path. Equal time = the same time per pixel as the BRDF-only equal-time images ({} spp × {:.0} ns), so the two tables compare at equal time too.\n",
                self.config.spp, self.budget_ns
            );
            s.push_str("| sampler | ns / MIS sample † | BRDF evals / MIS sample | spp (equal samples) | rel. error | spp (equal time †) | rel. error |\n|---|---|---|---|---|---|---|\n");
            for c in &self.sample_costs {
                let find = |kind: &str| {
                    self.images
                        .iter()
                        .find(|i| i.sampler == c.sampler && i.kind == kind)
                };
                let (Some(es), Some(et), Some(ns)) =
                    (find(IMAGE_KINDS[2]), find(IMAGE_KINDS[3]), c.mis_ns)
                else {
                    continue;
                };
                let _ = writeln!(
                    s,
                    "| {} | {ns:.0} | {} | {} | {:.2} % | {} | {:.2} % |",
                    c.sampler,
                    c.mis_evals.map_or("—".to_string(), |e| format!("{e:.2}")),
                    es.spp,
                    100.0 * es.rel_error.unwrap_or(0.0),
                    et.spp,
                    100.0 * et.rel_error.unwrap_or(0.0)
                );
            }
            s.push('\n');
        }
        for kind in IMAGE_KINDS {
            let ranked = self.row_ranking(kind);
            let best = ranked.first();
            let best_adaptive = ranked.iter().find(|i| crate::is_adaptive(&i.sampler));
            let at = match kind.strip_prefix("MIS ") {
                Some(k) => format!("With MIS at {k}"),
                None => format!("At {kind}"),
            };
            if let (Some(b), Some(a)) = (best, best_adaptive) {
                let tied: Vec<&str> = ranked[1..]
                    .iter()
                    .filter(|x| x.tied_with_best)
                    .map(|x| x.sampler.as_str())
                    .collect();
                let _ = write!(
                    s,
                    "{at}, **{}** has the lowest image error ({:.2} ± {:.2} %); tied with it: {}",
                    b.sampler,
                    100.0 * b.error,
                    100.0 * b.ci95,
                    if tied.is_empty() {
                        "none".to_string()
                    } else {
                        tied.join(", ")
                    }
                );
                if !crate::is_adaptive(&b.sampler) {
                    let _ = write!(
                        s,
                        "; the best adaptive sampler, {}, has {:.2} ± {:.2} % ({:.2}× the error, {} by {:.2} ± {:.2} points)",
                        a.sampler,
                        100.0 * a.error,
                        100.0 * a.ci95,
                        if b.error > 0.0 {
                            a.error / b.error
                        } else {
                            f64::INFINITY
                        },
                        if a.tied_with_best { "tied" } else { "worse" },
                        100.0 * a.above_best,
                        100.0 * a.above_best_hw
                    );
                }
                let _ = writeln!(s, ".");
            }
        }
        s.push('\n');
        if let Some(v) = self.equal_time_verdict() {
            let _ = writeln!(s, "{v}\n");
        }
        let brdf_only = self.sphere_ranking(IMAGE_KINDS[1]);
        let mis = self.sphere_ranking(IMAGE_KINDS[3]);
        if brdf_only.iter().any(|(_, r)| !r.is_empty()) {
            let with_mis = mis.iter().any(|(_, r)| !r.is_empty());
            s.push_str("Per sphere at equal time (relative error of that sphere's pixels ± its 95 % interval; the best sampler, the samplers tied with it — difference from the best not significant at the 95 % family level, Šidák over the comparisons with the best —, and the best adaptive one when it is not the best; **lowest**: an adaptive sampler is best and every other sampler significantly worse, **tied**: an adaptive and a non-adaptive sampler among the best and those tied with it):\n\n");
            s.push_str(if with_mis {
                "| sphere | BRDF only | adaptive | with MIS | adaptive |\n|---|---|---|---|---|\n"
            } else {
                "| sphere | BRDF only | adaptive |\n|---|---|---|\n"
            });
            let cell = |r: &[SphereError]| -> String {
                let Some(b) = r.first() else {
                    return "— | —".into();
                };
                let mut c = format!(
                    "**{}** {:.2} ± {:.2} %",
                    b.sampler,
                    100.0 * b.error,
                    100.0 * b.ci95
                );
                let tied: Vec<&str> = r[1..]
                    .iter()
                    .filter(|x| x.tied_with_best)
                    .map(|x| x.sampler.as_str())
                    .collect();
                if !tied.is_empty() {
                    let _ = write!(c, "; tied: {}", tied.join(", "));
                }
                if let (false, Some(a)) = (
                    crate::is_adaptive(&b.sampler),
                    r.iter().find(|x| crate::is_adaptive(&x.sampler)),
                ) {
                    let _ = write!(
                        c,
                        " (adaptive best: {} {:.2} ± {:.2} %)",
                        a.sampler,
                        100.0 * a.error,
                        100.0 * a.ci95
                    );
                }
                let _ = write!(c, " | {}", AdaptiveVerdict::of(r).word());
                c
            };
            for (k, (brdf, r)) in brdf_only.iter().enumerate() {
                let _ = write!(s, "| `{}` | {} |", crate::names::short_brdf(brdf), cell(r));
                if with_mis {
                    let _ = write!(s, " {} |", cell(&mis[k].1));
                }
                s.push('\n');
            }
        }
        s.push('\n');
        if let Some(pc) = &self.product_cost {
            let find = |kind: &str| {
                self.images
                    .iter()
                    .find(|i| i.sampler == PRODUCT_NAME && i.kind == kind)
            };
            if let (Some(es), Some(et)) = (find(PRODUCT_KINDS[0]), find(PRODUCT_KINDS[1])) {
                let _ = writeln!(
                    s,
                    "**Adaptive product** (`{PRODUCT_NAME}`: per pixel, cells of the map's power pyramid weighted by f·cos at the cell's power-weighted mean direction × the cell's power, refined where that weight is largest; exact sampling ∝ radiance inside a cell; a quarter of the samples from `{PRODUCT_DEFENSIVE}`, balance heuristic). Cost per pixel (one thread, coherent rows, fitted from 8 and 24 spp †): setup {:.0} ns + {:.0} ns per sample ({:.0} ns per pixel sample at 8 spp; {:.1} BRDF evaluations per pixel at 8 spp). Equal samples: {} spp, {:.2} %; equal time ({} spp × {:.0} ns per pixel): {} spp, {:.2} %.\n",
                    pc.setup_ns,
                    pc.per_sample_ns,
                    pc.at8_ns,
                    pc.evals_per_pixel8,
                    es.spp,
                    100.0 * es.rel_error.unwrap_or(0.0),
                    self.config.spp,
                    self.budget_ns,
                    et.spp,
                    100.0 * et.rel_error.unwrap_or(0.0)
                );
                s.push_str("Per sphere at equal time over every estimator (BRDF only: the sampler; MIS: `sampler+MIS`; the adaptive product), Šidák over all comparisons with the best:\n\n| sphere | best | tied with it | verdict |\n|---|---|---|---|\n");
                for (brdf, r) in self.sphere_ranking_all() {
                    let Some(b) = r.first() else { continue };
                    let tied: Vec<String> = r[1..]
                        .iter()
                        .filter(|x| x.tied_with_best)
                        .map(|x| format!("{} {:.2} %", x.sampler, 100.0 * x.error))
                        .collect();
                    let _ = writeln!(
                        s,
                        "| `{}` | **{}** {:.2} ± {:.2} % ({} spp) | {} | {} |",
                        crate::names::short_brdf(&brdf),
                        b.sampler,
                        100.0 * b.error,
                        100.0 * b.ci95,
                        b.spp,
                        if tied.is_empty() {
                            "none".to_string()
                        } else {
                            tied.join(", ")
                        },
                        AdaptiveVerdict::of(&r).word()
                    );
                }
                s.push('\n');
            }
        }
        for (caption, path) in sheets {
            let _ = writeln!(s, "**{caption}**\n\n![{caption}]({path})\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_ignores_black_reference_pixels() {
        let r = [[1.0; 3], [0.0; 3], [2.0; 3]];
        let i = [[1.5; 3], [5.0; 3], [2.0; 3]];
        assert!((relative_error(&i, &r) - 0.25).abs() < 1e-12);
    }

    #[test]
    fn sphere_pixels_face_the_camera() {
        let hs = hits(2, 16);
        assert!(!hs.is_empty());
        for h in &hs {
            assert!(h.query.wo.z > 0.0 && (h.query.wo.norm() - 1.0).abs() < 1e-12);
            assert!(
                (h.world_of(&h.local_of(&Vec3::new(0.3, 0.4, 0.5))) - Vec3::new(0.3, 0.4, 0.5))
                    .norm()
                    < 1e-12
            );
        }
        assert!(hs.iter().any(|h| h.sphere == 1));
    }

    /// The pre-batch pixel estimator: `spp` calls of `sample` at the pixel, one value each.
    fn one_query_values(
        brdf: &dyn Brdf,
        light: &Light,
        h: &Hit,
        sampler: &dyn DirectionSampler,
        spp: usize,
        rng: &mut dyn UniformSource,
    ) -> Vec<[f64; 3]> {
        (0..spp)
            .map(|_| {
                let s = sampler.sample(&h.query.wo, rng);
                if s.pdf > 0.0 {
                    integrand(brdf, light, h, &s.wi).map(|c| c / s.pdf)
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }

    fn mean(v: &[[f64; 3]]) -> [f64; 3] {
        let n = v.len() as f64;
        v.iter()
            .fold([0.0; 3], |a, c| [a[0] + c[0], a[1] + c[1], a[2] + c[2]])
            .map(|a| a / n)
    }

    /// Where the batch path draws uniforms in the same order as the one-query path (a
    /// sampler without its own batch path: `cosine`), a row segment's batch estimates equal
    /// the pre-batch per-pixel estimator run pixel after pixel on one generator, to rounding
    /// (the batch multiplies by `1/p` where that code divided by `p`).
    #[test]
    fn a_row_batch_equals_the_per_pixel_estimator_where_the_stream_is_the_same() {
        let light = Light::parse("area:theta=30,phi=180,radius=40").unwrap();
        let brdf = brdf::parse_spec("phong:n=20").unwrap();
        let sampler = samplers::find("cosine")
            .unwrap()
            .build_direction(&samplers::DirectionRequest::new(
                std::sync::Arc::from(brdf::parse_spec("phong:n=20").unwrap()),
                &brdf_sampling::SetOptions::default(),
            ))
            .unwrap()
            .sampler;
        let hs = hits(1, 16);
        let segs = segments(&hs, 16);
        assert!(segs.len() > 10 && segs.iter().all(|r| r.len() <= 16));
        let mut lit = 0;
        for r in segs.iter().step_by(3) {
            let seg = &hs[r.clone()];
            let mut a = Xoshiro256PlusPlus::seed_from_u64(3);
            let batch = brdf_row(brdf.as_ref(), &light, seg, sampler.as_ref(), 7, &mut a);
            let mut b = Xoshiro256PlusPlus::seed_from_u64(3);
            let one: Vec<[f64; 3]> = seg
                .iter()
                .map(|h| {
                    mean(&one_query_values(
                        brdf.as_ref(),
                        &light,
                        h,
                        sampler.as_ref(),
                        7,
                        &mut b,
                    ))
                })
                .collect();
            assert_eq!(batch.len(), one.len());
            for (a, b) in batch.iter().zip(&one) {
                for c in 0..3 {
                    approx::assert_relative_eq!(a[c], b[c], max_relative = 1e-12);
                }
            }
            lit += one.iter().filter(|c| c[1] > 0.0).count();
        }
        assert!(lit > 20, "{lit} lit pixels");
    }

    /// Two spheres of `px` pixels (`lambert`, `phong:n=20`, `adaptive-exact` built for each)
    /// under a 64 × 32 procedural sky: the scene of the product and reference tests.
    struct SkyScene {
        light: Light,
        brdfs: Vec<std::sync::Arc<dyn Brdf>>,
        built: Vec<std::sync::Arc<dyn DirectionSampler>>,
        light_sampler: LightSampler,
        pyramid: PowerPyramid,
        hs: Vec<Hit>,
        segs: Vec<std::ops::Range<usize>>,
    }

    fn sky_scene(px: usize) -> SkyScene {
        let map = envmap::procedural_sky(64, 32).unwrap();
        let pyramid = PowerPyramid::new(&map);
        let light = Light::Map {
            map,
            label: "sky".into(),
        };
        let (brdfs, built) = lambert_and_phong_built("adaptive-exact", false);
        let light_sampler = LightSampler::new(&light).unwrap();
        let hs = hits(2, px);
        let segs = segments(&hs, 2 * px);
        SkyScene {
            light,
            brdfs,
            built,
            light_sampler,
            pyramid,
            hs,
            segs,
        }
    }

    /// `lambert` and `phong:n=20` with `sampler` built for each (8 slices where it has them);
    /// with `counted`, each BRDF wrapped in the study's evaluation counter and the sampler built
    /// **with that wrapped object** (as the study builds them).
    #[allow(clippy::type_complexity)]
    fn lambert_and_phong_built(
        sampler: &str,
        counted: bool,
    ) -> (
        Vec<std::sync::Arc<dyn Brdf>>,
        Vec<std::sync::Arc<dyn DirectionSampler>>,
    ) {
        let brdfs: Vec<std::sync::Arc<dyn Brdf>> = ["lambert", "phong:n=20"]
            .iter()
            .map(|s| {
                let raw: std::sync::Arc<dyn Brdf> =
                    std::sync::Arc::from(brdf::parse_spec(s).unwrap());
                if counted {
                    std::sync::Arc::new(crate::CountingBrdf(raw)) as std::sync::Arc<dyn Brdf>
                } else {
                    raw
                }
            })
            .collect();
        let options = brdf_sampling::SetOptions {
            slices: 8,
            ..Default::default()
        };
        let built = brdfs
            .iter()
            .map(|b| {
                samplers::build_direction(
                    sampler,
                    &samplers::DirectionRequest::new(std::sync::Arc::clone(b), &options),
                )
                .unwrap()
                .sampler
            })
            .collect();
        (brdfs, built)
    }

    /// Each hit's `spp` one-query MIS values (balance heuristic), its generator seeded from
    /// `(seed, pixel)`: the judge of the batched MIS rows.
    fn one_query_mis(
        hs: &[Hit],
        brdfs: &[std::sync::Arc<dyn Brdf>],
        built: &[std::sync::Arc<dyn DirectionSampler>],
        light: &Light,
        light_sampler: &LightSampler,
        spp: usize,
        seed: u64,
    ) -> Vec<Vec<[f64; 3]>> {
        hs.iter()
            .map(|h| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, h.pixel as u64));
                let pair = estimators::MisPair {
                    brdf_sampler: built[h.sphere].as_ref(),
                    light_sampler,
                    frame: h.query.frame,
                    heuristic: MisHeuristic::Balance,
                };
                let g = |wi: &Vec3| integrand(brdfs[h.sphere].as_ref(), light, h, wi);
                (0..spp)
                    .map(|_| pair.value(&h.query.wo, g, &mut rng))
                    .collect()
            })
            .collect()
    }

    fn chi2(a: &[[f64; 3]], b: &[Vec<[f64; 3]>]) -> (f64, usize) {
        let (mut x, mut k) = (0.0, 0);
        for (a, vs) in a.iter().zip(b) {
            let n = vs.len() as f64;
            let m = mean(vs)[1];
            let var = vs.iter().map(|v| (v[1] - m).powi(2)).sum::<f64>() / (n - 1.0);
            if var == 0.0 {
                if a[1] != m {
                    return (f64::INFINITY, k);
                }
                continue;
            }
            x += (a[1] - m).powi(2) / (2.0 * var / n);
            k += 1;
        }
        (x, k)
    }

    /// The batch path keeps the law where it reorders the uniforms: MIS of `adaptive-exact`
    /// (whose batch path groups queries by interval) and the area light, row segments of two
    /// spheres, against the one-query MIS (`estimators::MisPair`, the study's MIS cells'
    /// estimator) per pixel: `Σ z²` below the χ²(k) quantile at α = 10⁻³ (fixed seeds; measured
    /// 94.9 over 96 pixels, limit ≈ 141). A batch whose outputs are handed to the pixels in the
    /// wrong order (each segment reversed), or whose queries all carry one pixel's ωo, fails.
    #[test]
    fn the_batched_mis_render_has_the_law_of_the_per_pixel_one_and_a_misordered_batch_fails() {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let light = Light::parse("area:theta=30,phi=180,radius=10").unwrap();
        let (brdfs, built) = lambert_and_phong_built("adaptive-exact", false);
        let light_sampler = LightSampler::new(&light).unwrap();
        let px = 10;
        let hs = hits(2, px);
        let segs = segments(&hs, 2 * px);
        let spp = 400;
        // 0: the batch path; 1: outputs handed out in reverse; 2: every query of a segment at
        // the ωo of its middle pixel (each pixel keeps its own frame).
        let render = |variant: u8| -> Vec<[f64; 3]> {
            let mut out = Vec::new();
            for r in &segs {
                let mut seg = hs[r.clone()].to_vec();
                if variant == 2 {
                    let wo = seg[seg.len() / 2].query.wo;
                    seg.iter_mut().for_each(|h| h.query.wo = wo);
                }
                let seg = &seg[..];
                let b = seg[0].sphere;
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(17, r.start as u64));
                let mut v = mis_row(
                    brdfs[b].as_ref(),
                    &light,
                    seg,
                    built[b].as_ref(),
                    &light_sampler,
                    spp,
                    &mut rng,
                );
                if variant == 1 {
                    v.reverse();
                }
                out.extend(v);
            }
            out
        };
        let one = one_query_mis(&hs, &brdfs, &built, &light, &light_sampler, spp, 29);
        let (x, k) = chi2(&render(0), &one);
        assert!(k > 60, "{k} lit pixels");
        let limit = ChiSquared::new(k as f64).unwrap().inverse_cdf(1.0 - 1e-3);
        assert!(
            x < limit,
            "batch vs one-query: Σz² = {x:.1} over {k} pixels (limit {limit:.1})"
        );
        for broken in [1, 2] {
            let (x, _) = chi2(&render(broken), &one);
            assert!(
                x > limit,
                "broken batch {broken} not caught: Σz² = {x:.1} (limit {limit:.1})"
            );
        }
    }

    /// The fused f (issue 29): on grey BRDFs the rows rendered with the batch's `f` equal the
    /// rows rendered with one `eval_rgb` per sample from the same seed — bit for bit for
    /// `cosine` (its `f` is that evaluation), to rounding for `adaptive-exact` (its accepted
    /// trial's `f`, evaluated in its own frame) — BRDF sampling and MIS; and `adaptive-exact`
    /// saves one evaluation per sample (`cosine` none). Shown to fail on broken versions: a
    /// wrong colour (`c = [1, ½, 1]` for a grey BRDF) changes the values, and a BRDF object
    /// other than the one the sampler was built with (the same model, not fused) saves no
    /// evaluation.
    #[test]
    fn the_fused_f_gives_the_rgb_rows_values_and_saves_the_exact_samplers_evaluation() {
        let light = Light::parse("area:theta=30,phi=180,radius=40").unwrap();
        let light_sampler = LightSampler::new(&light).unwrap();
        let hs = hits(2, 10);
        let segs = segments(&hs, 20);
        let spp = 16;
        // (values, evaluations) of every 2nd segment; `variant`: 0 fused, 1 one `eval_rgb`
        // per sample, 2 fused with a wrong colour, 3 fused with another object of the model.
        let rows = |brdfs: &[std::sync::Arc<dyn Brdf>],
                    built: &[std::sync::Arc<dyn DirectionSampler>],
                    mis: bool,
                    variant: u8| {
            let before = crate::thread_evaluations();
            let mut out = Vec::new();
            for r in segs.iter().step_by(2) {
                let seg = &hs[r.clone()];
                let b = seg[0].sphere;
                let (smp, own) = (built[b].as_ref(), brdfs[b].as_ref());
                let other = crate::CountingBrdf(std::sync::Arc::from(
                    brdf::parse_spec(own.name()).unwrap(),
                ));
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(5, r.start as u64));
                let (brdf, c): (&dyn Brdf, [f64; 3]) = match variant {
                    2 => (own, [1.0, 0.5, 1.0]),
                    3 => (&other, [1.0; 3]),
                    _ => (own, own.rgb_scale().unwrap()),
                };
                out.extend(match (mis, variant) {
                    (false, 1) => brdf_row_rgb(own, &light, seg, smp, spp, &mut rng),
                    (false, _) => brdf_row_fused(brdf, c, &light, seg, smp, spp, &mut rng),
                    (true, 1) => mis_row_rgb(own, &light, seg, smp, &light_sampler, spp, &mut rng),
                    (true, _) => {
                        mis_row_fused(brdf, c, &light, seg, smp, &light_sampler, spp, &mut rng)
                    }
                });
            }
            (out, crate::thread_evaluations() - before)
        };
        for sampler in ["cosine", "adaptive-exact"] {
            let (brdfs, built) = lambert_and_phong_built(sampler, true);
            assert_eq!(brdfs[1].rgb_scale(), Some([1.0; 3]));
            // Only a sampler whose `f` is free takes the fused path in the render.
            assert_eq!(built[1].fuses_eval(), sampler == "adaptive-exact");
            for mis in [false, true] {
                let (fused, e_fused) = rows(&brdfs, &built, mis, 0);
                let (rgb, e_rgb) = rows(&brdfs, &built, mis, 1);
                let lit = rgb.iter().filter(|c| c[1] > 0.0).count();
                assert!(lit > 30, "{sampler}: {lit} lit pixels");
                if sampler == "cosine" {
                    assert_eq!(fused, rgb, "cosine, MIS {mis}");
                }
                for (a, b) in fused.iter().zip(&rgb) {
                    for ch in 0..3 {
                        approx::assert_relative_eq!(a[ch], b[ch], max_relative = 1e-9);
                    }
                }
                let samples = (lit * spp) as u64;
                if sampler == "cosine" {
                    assert_eq!(e_fused, e_rgb, "cosine, MIS {mis}");
                } else {
                    assert!(
                        e_rgb >= e_fused + samples,
                        "{sampler}, MIS {mis}: {e_fused} evaluations fused, {e_rgb} unfused"
                    );
                    let (_, e_other) = rows(&brdfs, &built, mis, 3);
                    assert!(
                        e_other >= e_rgb,
                        "a foreign object fused: {e_other} vs {e_rgb}"
                    );
                }
                let (wrong, _) = rows(&brdfs, &built, mis, 2);
                assert!(
                    wrong
                        .iter()
                        .zip(&rgb)
                        .any(|(a, b)| (a[1] - b[1]).abs() > 1e-6 * b[1]),
                    "a wrong colour not caught"
                );
            }
        }
    }

    /// The images' error intervals ([`rank_pixel_errors`]) against independent renders: `K`
    /// pairs of images of two spheres (`lambert`, `phong:n=20`, `cosine` sampling, area light,
    /// 16 spp), each pair two seeds of the same law, the reference one 1024-spp render. The
    /// standard deviation the pixels give (`ci95 / z₉₅`, the successive-difference variance)
    /// matches the spread of `ē` over the `K` renders, and that of the paired difference the
    /// spread of `ē_a − ē_b`: ratios within [0.75, 1.2] (measured 0.88 and 0.89; `K` = 100:
    /// the spread's own relative error ≈ 7 %); two images of one law are tied in ≥ 90 % of the
    /// pairs (measured 95: the decision's false-positive rate is the nominal 5 %; family level
    /// 5 %, one comparison), 64 spp against 4 spp never. Checked broken: the variance without
    /// its `1/2` (ratio 1.25) and the interval without its `√P` fail (docs/benchmarks.md §25.7).
    #[test]
    fn the_pixel_intervals_match_the_spread_of_independent_renders() {
        let light = Light::parse("area:theta=30,phi=180,radius=40").unwrap();
        let (brdfs, built) = lambert_and_phong_built("cosine", false);
        let px = 24;
        let hs = hits(2, px);
        let segs = segments(&hs, 2 * px);
        let pixels = 2 * px * px;
        let render = |spp: usize, seed: u64| {
            render_segments(
                &hs,
                &segs,
                pixels,
                |seg, rng| {
                    let b = seg[0].sphere;
                    brdf_row(brdfs[b].as_ref(), &light, seg, built[b].as_ref(), spp, rng)
                },
                seed,
            )
        };
        let reference = render(1024, 1);
        let idx: Vec<usize> = (0..pixels).collect();
        let errors = |spp: usize, seed: u64| pixel_errors(&render(spp, seed), &reference, &idx);
        let z95 = crate::ranking::two_sided_z(0.05);
        let k = 100;
        let (mut means, mut est, mut diffs, mut est_d) = (vec![], vec![], vec![], vec![]);
        let (mut tied, mut told_apart) = (0, 0);
        for seed in 0..k {
            let a = errors(16, 1000 + seed);
            let b = errors(16, 2000 + seed);
            assert!(a.len() > 600, "{} lit pixels", a.len());
            let r = rank_pixel_errors(vec![("a".into(), 16, a), ("b".into(), 16, b)]);
            let ra = r.iter().find(|x| x.sampler == "a").unwrap();
            let rb = r.iter().find(|x| x.sampler == "b").unwrap();
            means.push(ra.error);
            est.push(ra.ci95 / z95);
            diffs.push(ra.error - rb.error);
            est_d.push(r[1].above_best_hw / z95);
            tied += usize::from(r[1].tied_with_best);
            let r = rank_pixel_errors(vec![
                ("64".into(), 64, errors(64, 3000 + seed)),
                ("4".into(), 4, errors(4, 4000 + seed)),
            ]);
            told_apart += usize::from(r[0].sampler == "64" && !r[1].tied_with_best);
        }
        let sd = |v: &[f64]| {
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0)).sqrt()
        };
        let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let ratio = avg(&est) / sd(&means);
        let centre = avg(&means);
        let covered = means
            .iter()
            .zip(&est)
            .filter(|(m, e)| (*m - centre).abs() <= z95 * *e)
            .count();
        eprintln!("95 % intervals covering the mean over renders: {covered}/{k}");
        let ratio_d = avg(&est_d) / sd(&diffs);
        eprintln!(
            "error {:.4}: sd from pixels {:.5}, over renders {:.5} (ratio {ratio:.3}); difference: {:.5} vs {:.5} (ratio {ratio_d:.3}); tied {tied}/{k}, told apart {told_apart}/{k}",
            avg(&means),
            avg(&est),
            sd(&means),
            avg(&est_d),
            sd(&diffs)
        );
        assert!((0.75..=1.2).contains(&ratio), "error's sd ratio {ratio:.3}");
        assert!(
            (0.75..=1.2).contains(&ratio_d),
            "difference's sd ratio {ratio_d:.3}"
        );
        assert!(tied >= 90, "one law tied in {tied} of {k} pairs");
        assert_eq!(told_apart as u64, k, "64 spp against 4 spp");
    }

    /// The verdicts of [`AdaptiveVerdict`] from ranked rows.
    #[test]
    fn the_adaptive_verdict_reads_the_ties() {
        let row = |name: &str, tied: bool| SphereError {
            sampler: name.into(),
            spp: 1,
            error: 0.5,
            ci95: 0.01,
            above_best: 0.0,
            above_best_hw: 0.0,
            tied_with_best: tied,
        };
        let v = AdaptiveVerdict::of;
        assert_eq!(
            v(&[row("adaptive-exact", true), row("cosine", false)]),
            AdaptiveVerdict::Lowest("adaptive-exact".into())
        );
        assert_eq!(
            v(&[
                row("adaptive-exact", true),
                row("adaptive", true),
                row("cosine", false)
            ]),
            AdaptiveVerdict::Lowest("adaptive-exact".into())
        );
        assert_eq!(
            v(&[row("cosine", true), row("adaptive", true)]),
            AdaptiveVerdict::Tied {
                adaptive: "adaptive".into(),
                other: "cosine".into()
            }
        );
        assert_eq!(
            v(&[row("adaptive", true), row("uniform", true)]).word(),
            "tied"
        );
        assert_eq!(
            v(&[row("cosine", true), row("adaptive", false)]),
            AdaptiveVerdict::NotLowest {
                best: "cosine".into()
            }
        );
        assert_eq!(v(&[row("cosine", true)]), AdaptiveVerdict::NoAdaptive);
    }

    /// Paired costs per pixel sample of the fused f and of the `eval_rgb` path (the renderer
    /// before issue 29's item 1), every quick sampler on the quick BRDFs under the Grace probe,
    /// on [`sample_costs`]'s subset (every 11th row segment of 80-pixel spheres, 8 samples per
    /// pixel, θo as rendered), the two paths interleaved in each of [`TIMING_REPEATS`] rounds
    /// (their order alternating between rounds), the same uniforms for both, medians; with the
    /// BRDF evaluations per sample. docs/benchmarks.md §24.7:
    /// `cargo test --release -p study --lib fused_f_costs -- --ignored --nocapture`.
    /// `FUSED_COSTS_SAMPLERS`, `FUSED_COSTS_BRDFS` (comma-separated), `FUSED_COSTS_REPEATS`
    /// and `FUSED_COSTS_LIGHT` (a light spec instead of the probe) narrow the run (e.g. one sampler under valgrind, whose inclusive
    /// instruction counts of `brdf_row_fused`, `brdf_row_rgb`, `mis_row_fused` and
    /// `mis_row_rgb` are then the four paths').
    #[test]
    #[ignore = "a measurement (about a minute): docs/benchmarks.md §24.7"]
    fn fused_f_costs_under_the_grace_probe() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let map = root.join("../shared/data/envmaps/grace_probe_latlong.hdr");
        if !map.exists() {
            eprintln!("skipped: {} is absent", map.display());
            return;
        }
        let list = |var: &str| -> Option<Vec<String>> {
            std::env::var(var)
                .ok()
                .map(|v| v.split(',').map(str::to_string).collect())
        };
        let brdf_specs = list("FUSED_COSTS_BRDFS")
            .unwrap_or_else(|| crate::QUICK_BRDFS.iter().map(|s| s.to_string()).collect());
        let samplers = list("FUSED_COSTS_SAMPLERS")
            .unwrap_or_else(|| crate::StudyConfig::quick(None).0.samplers);
        let repeats = std::env::var("FUSED_COSTS_REPEATS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(TIMING_REPEATS);
        let config = crate::StudyConfig::new(
            samplers,
            brdf_specs,
            vec![30.0],
            vec![
                std::env::var("FUSED_COSTS_LIGHT")
                    .unwrap_or_else(|_| format!("envmap:{}", map.display())),
            ],
        );
        let plan = StudyPlan::new(config, Vec::new()).unwrap();
        let nb = plan.brdfs.len();
        let pairs: Vec<(usize, usize)> = (0..plan.entries.len())
            .flat_map(|s| (0..nb).map(move |b| (s, b)))
            .collect();
        plan.build_all(&pairs, &|_| {});
        let built: Vec<(usize, Vec<std::sync::Arc<dyn DirectionSampler>>)> =
            (0..plan.entries.len())
                .filter_map(|s| {
                    let v: Option<Vec<_>> = (0..nb)
                        .map(|b| plan.build(s, b).ok().map(|(d, _)| d.sampler))
                        .collect();
                    v.map(|v| (s, v))
                })
                .collect();
        let light = plan.lights[0].as_ref();
        let light_sampler = LightSampler::new(light).unwrap();
        let brdfs: Vec<&dyn Brdf> = plan.brdfs.iter().map(|b| b.counted.as_ref()).collect();
        let px = 80;
        let hs = hits(nb, px);
        let segs = segments(&hs, nb * px);
        let subset: Vec<&[Hit]> = segs.iter().step_by(11).map(|r| &hs[r.clone()]).collect();
        let spp = 8;
        let samples = (subset.iter().map(|s| s.len()).sum::<usize>() * spp) as f64;
        // [sampler][variant: 0 fused BRDF, 1 eval_rgb BRDF, 2 fused MIS, 3 eval_rgb MIS]
        let mut ns = vec![vec![Vec::new(); 4]; built.len()];
        let mut evals = vec![[0.0; 4]; built.len()];
        println!("{samples} pixel samples per path and round");
        for r in 0..repeats {
            for (i, (_, smp)) in built.iter().enumerate() {
                // Odd rounds run the eval_rgb path first (no position bias).
                let order = if r % 2 == 0 {
                    [0, 1, 2, 3]
                } else {
                    [1, 0, 3, 2]
                };
                for v in order {
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(7, r as u64));
                    let before = crate::thread_evaluations();
                    let t0 = crate::machine::thread_cpu_seconds().unwrap_or(0.0);
                    let mut sink = 0.0;
                    for seg in &subset {
                        let b = seg[0].sphere;
                        let (f, s) = (brdfs[b], smp[b].as_ref());
                        let l = &light_sampler;
                        let out = match v {
                            0 => brdf_row(f, light, seg, s, spp, &mut rng),
                            1 => brdf_row_rgb(f, light, seg, s, spp, &mut rng),
                            2 => mis_row(f, light, seg, s, l, spp, &mut rng),
                            _ => mis_row_rgb(f, light, seg, s, l, spp, &mut rng),
                        };
                        sink += out.iter().map(|c| c[1]).sum::<f64>();
                    }
                    std::hint::black_box(sink);
                    let t1 = crate::machine::thread_cpu_seconds().unwrap_or(0.0);
                    ns[i][v].push((t1 - t0) * 1e9 / samples);
                    evals[i][v] = (crate::thread_evaluations() - before) as f64 / samples;
                }
            }
        }
        let median = |t: &mut Vec<f64>| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        };
        println!(
            "| sampler | ns fused | ns eval_rgb | ratio | evals fused | evals eval_rgb | MIS ns fused | MIS ns eval_rgb | ratio | MIS evals fused | MIS evals eval_rgb |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|");
        for (i, (s, _)) in built.iter().enumerate() {
            let m: Vec<f64> = ns[i].iter_mut().map(median).collect();
            let e = evals[i];
            println!(
                "| {} | {:.0} | {:.0} | {:.3} | {:.2} | {:.2} | {:.0} | {:.0} | {:.3} | {:.2} | {:.2} |",
                plan.entries[*s].name,
                m[0],
                m[1],
                m[0] / m[1],
                e[0],
                e[1],
                m[2],
                m[3],
                m[2] / m[3],
                e[2],
                e[3]
            );
        }
    }

    /// A light technique that reports twice its density (a broken MIS: the weights and the
    /// light term are then biased).
    struct DoubledPdf<'a>(&'a LightSampler);

    impl LightTechnique for DoubledPdf<'_> {
        fn sample_world(&self, u: &mut dyn UniformSource) -> Option<(Vec3, f64)> {
            self.0.sample_world(u).map(|(d, p)| (d, 2.0 * p))
        }
        fn pdf_world(&self, d: &Vec3) -> f64 {
            2.0 * self.0.pdf_world(d)
        }
    }

    /// The MIS images' law under a map, the light technique of the Grace images (the
    /// `envmap-adaptive` sampler of a small procedural sky with a sun): the row segments'
    /// batched MIS of `adaptive` and the map sampler, as the `MIS …` images are rendered, against
    /// the one-query MIS (`estimators::MisPair`) per pixel, two spheres: `Σ z²` below the χ²(k)
    /// quantile at α = 10⁻³ (fixed seeds; docs/benchmarks.md §23.8 gives the measured value). A
    /// light technique reporting twice its density fails, and so does a batch whose outputs
    /// reach the pixels in the wrong order.
    #[test]
    fn the_mis_images_under_a_map_have_the_law_of_the_per_pixel_mis_and_a_wrong_light_pdf_fails() {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let light = Light::Map {
            map: envmap::procedural_sky(64, 32).unwrap(),
            label: "sky".into(),
        };
        let (brdfs, built) = lambert_and_phong_built("adaptive", false);
        let light_sampler = LightSampler::new(&light).unwrap();
        assert!(matches!(light_sampler, LightSampler::Map(_)));
        let doubled = DoubledPdf(&light_sampler);
        let px = 10;
        let hs = hits(2, px);
        let segs = segments(&hs, 2 * px);
        let spp = 300;
        // 0: as rendered; 1: the doubled density; 2: outputs handed out in reverse.
        let render = |variant: u8| -> Vec<[f64; 3]> {
            let mut out = Vec::new();
            for r in &segs {
                let seg = &hs[r.clone()];
                let b = seg[0].sphere;
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(41, r.start as u64));
                let (brdf, smp) = (brdfs[b].as_ref(), built[b].as_ref());
                let mut v = if variant == 1 {
                    mis_row(brdf, &light, seg, smp, &doubled, spp, &mut rng)
                } else {
                    mis_row(brdf, &light, seg, smp, &light_sampler, spp, &mut rng)
                };
                if variant == 2 {
                    v.reverse();
                }
                out.extend(v);
            }
            out
        };
        let one = one_query_mis(&hs, &brdfs, &built, &light, &light_sampler, spp, 43);
        let (x, k) = chi2(&render(0), &one);
        assert!(k > 100, "{k} lit pixels");
        let limit = ChiSquared::new(k as f64).unwrap().inverse_cdf(1.0 - 1e-3);
        eprintln!("MIS under a map: Σz² = {x:.1} over {k} pixels (limit {limit:.1})");
        assert!(
            x < limit,
            "batch vs one-query: Σz² = {x:.1} over {k} pixels (limit {limit:.1})"
        );
        for broken in [1, 2] {
            let (x, _) = chi2(&render(broken), &one);
            eprintln!("broken {broken}: Σz² = {x:.1}");
            assert!(
                x > limit,
                "broken MIS {broken} not caught: Σz² = {x:.1} (limit {limit:.1})"
            );
        }
    }

    /// The adaptive product rows have the per-pixel law of the MIS estimator (the same mean):
    /// `adaptive-exact` as the defensive sampler, the pyramid of a 64 × 32 procedural sky, two
    /// spheres of 10 px, 300 samples per pixel against the one-query MIS per pixel, `Σ z²`
    /// (with the MIS samples' variance, the larger of the two here) below the χ²(k) quantile at
    /// α = 10⁻³ (measured 124.6 over 160 pixels, limit 221.0). Broken: the outputs handed to
    /// the pixels in reverse fail. (A pyramid of another map — a poor product density — is
    /// checked against the quadrature in `estimators`, with its own variance: here its larger
    /// variance breaks the MIS-variance yardstick, Σz² = 8882.)
    #[test]
    fn the_product_rows_have_the_law_of_the_per_pixel_mis_and_a_misordered_row_fails() {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let px = 10;
        let sc = sky_scene(px);
        let spp = 300;
        let render = |pyr: &PowerPyramid, reverse: bool| -> Vec<[f64; 3]> {
            let mut out = Vec::new();
            for r in &sc.segs {
                let seg = &sc.hs[r.clone()];
                let b = seg[0].sphere;
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(47, r.start as u64));
                let mut v = product_row(
                    sc.brdfs[b].as_ref(),
                    &sc.light,
                    seg,
                    sc.built[b].as_ref(),
                    pyr,
                    spp,
                    &mut rng,
                );
                if reverse {
                    v.reverse();
                }
                out.extend(v);
            }
            out
        };
        let one = one_query_mis(
            &sc.hs,
            &sc.brdfs,
            &sc.built,
            &sc.light,
            &sc.light_sampler,
            spp,
            43,
        );
        let limit = |k: usize| ChiSquared::new(k as f64).unwrap().inverse_cdf(1.0 - 1e-3);
        let (x, k) = chi2(&render(&sc.pyramid, false), &one);
        assert!(k > 100, "{k} lit pixels");
        eprintln!(
            "product rows: Σz² = {x:.1} over {k} pixels (limit {:.1})",
            limit(k)
        );
        assert!(x < limit(k), "Σz² = {x:.1} over {k} pixels");
        let (x, k) = chi2(&render(&sc.pyramid, true), &one);
        eprintln!("reversed product rows: Σz² = {x:.1}");
        assert!(x > limit(k), "reversed rows not caught: Σz² = {x:.1}");
    }

    /// The reference's error estimate ([`ReferenceError`]: `|d_p| / Y(R_p)` from the parts'
    /// independent halves) against its actual error over `K` = 40 independent references of a
    /// small scene (`lambert`, `phong:n=20`, 10 px, a 64 × 32 procedural sky; `adaptive-exact`
    /// for the MIS part and as the product's defensive sampler; MIS 8 + 8 pairs, product 8 + 8
    /// samples, weights per sphere from pilots at 16 spp, as the render makes it), the truth an
    /// independent product render at 16 384 spp: the mean estimate over the mean actual error
    /// `mean_p |Y(R_p) − Y_true,p| / Y_true,p` within [0.85, 1.15] (docs/benchmarks.md §26.7 gives
    /// the measured ratio). Broken: weights summing to 1.1 (`w_K = 1.1 − w`: a biased reference,
    /// its estimate blind to the bias) and halves drawn with one seed (not independent: `d = 0`)
    /// fail.
    #[test]
    fn the_reference_error_estimate_matches_its_error_over_independent_references() {
        let px = 10;
        let width = 2 * px;
        let sc = sky_scene(px);
        let pixels = width * px;
        let mis = |spp: usize, seed: u64| {
            render_segments(
                &sc.hs,
                &sc.segs,
                pixels,
                |seg, rng| {
                    let b = seg[0].sphere;
                    let (brdf, smp) = (sc.brdfs[b].as_ref(), sc.built[b].as_ref());
                    mis_row(brdf, &sc.light, seg, smp, &sc.light_sampler, spp, rng)
                },
                seed,
            )
        };
        let product = |spp: usize, seed: u64| {
            render_segments(
                &sc.hs,
                &sc.segs,
                pixels,
                |seg, rng| {
                    let b = seg[0].sphere;
                    let (brdf, smp) = (sc.brdfs[b].as_ref(), sc.built[b].as_ref());
                    product_row(brdf, &sc.light, seg, smp, &sc.pyramid, spp, rng)
                },
                seed,
            )
        };
        let sphere_pixels =
            |j: usize| -> Vec<usize> { (0..pixels).filter(|p| (p % width) / px == j).collect() };
        let truth = product(16384, 99);
        let idx: Vec<usize> = (0..pixels)
            .filter(|&p| colour::luminance(truth[p]) > 0.0)
            .collect();
        assert!(idx.len() > 100, "{} lit pixels", idx.len());
        // 0: as rendered; 1: weights summing to 1.1; 2: halves of one seed.
        let reference = |seed: u64, variant: u8| -> (f64, f64) {
            let s = 1000 * seed;
            let pm = [mis(16, s + 1), mis(16, s + 2)];
            let pk = [product(16, s + 3), product(16, s + 4)];
            let w: Vec<f64> = (0..2)
                .map(|j| {
                    reference_mis_weight(
                        [&pm[0], &pm[1]],
                        [&pk[0], &pk[1]],
                        &sphere_pixels(j),
                        16,
                        16,
                        16,
                    )
                    .0
                })
                .collect();
            let second = if variant == 2 { 0 } else { 10 };
            let (m1, m2) = (mis(8, s + 5), mis(8, s + 5 + second));
            let (k1, k2) = (product(8, s + 6), product(8, s + 6 + second));
            let (rgb, d) = combine_reference([&m1, &m2], Some([&k1, &k2]), |p| {
                let w = w[(p % width) / px];
                (w, if variant == 1 { 1.1 - w } else { 1.0 - w })
            });
            let actual = idx
                .iter()
                .map(|&p| {
                    let t = colour::luminance(truth[p]);
                    (colour::luminance(rgb[p]) - t).abs() / t
                })
                .sum::<f64>()
                / idx.len() as f64;
            (reference_self_error(&rgb, &d, &idx), actual)
        };
        let k = 40;
        let ratio = |variant: u8| {
            let (mut est, mut act) = (0.0, 0.0);
            for seed in 0..k {
                let (e, a) = reference(seed, variant);
                est += e;
                act += a;
            }
            let r = est / act;
            eprintln!(
                "variant {variant}: estimated {:.5}, actual {:.5} (ratio {r:.3})",
                est / k as f64,
                act / k as f64
            );
            r
        };
        let r = ratio(0);
        assert!((0.85..=1.15).contains(&r), "estimate / actual = {r:.3}");
        for broken in [1, 2] {
            let r = ratio(broken);
            assert!(
                !(0.85..=1.15).contains(&r),
                "broken {broken} not caught: estimate / actual = {r:.3}"
            );
        }
    }

    /// Equal time with a per-pixel setup: `(spp · budget − setup) / per_sample`, at least 1.
    #[test]
    fn the_product_equal_time_budget_pays_the_setup_once_per_pixel() {
        assert_eq!(product_equal_time_spp(64, 400.0, 6400.0, 300.0), 64);
        assert_eq!(product_equal_time_spp(64, 400.0, 0.0, 400.0), 64);
        assert_eq!(product_equal_time_spp(64, 400.0, 1e9, 300.0), 1);
        assert_eq!(product_equal_time_spp(64, 400.0, 10.0, f64::NAN), 1);
    }
}
