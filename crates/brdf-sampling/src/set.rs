//! [`QuadTreeSet`]: one adaptive quadtree per outgoing-direction slice of a BRDF, sampled
//! through [`DirectionSampler`].

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use brdf::{Brdf, Vec3};
use partition_sampler::diagnostics::AuditedDraws;
use partition_sampler::{
    AllocationMode, Audit, AuditCounters, Density, GridOptions, QuadTreeBuilder, QuadTreeSampler,
    Sample2, Sampler2D, TreeParams, UniformSource,
};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::direction_sampler::{DirSample, DirectionSampler, SamplerDiagnostics};
use crate::disc::{DiscBrdf, DiscMap, SliceDensity, thread_evaluations};
use crate::error::SetError;
use crate::image_map::{Counted, EvalCounter, SliceImageMap};
use crate::layout::{SliceChoice, SliceLayout, SliceLocator};
use crate::normalisation::{Grading, per_leaf_quadrature};
use crate::options::{SetOptions, Variant};
use crate::report::{CostMeasurement, SetReport};

/// Progress callback: `(slices done, total)`, called from the building threads after each
/// slice is built. `total` starts at the number of slices and grows by the number of slices
/// chosen for refinement at each refinement level ([`SetOptions::refine_levels`]).
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A set of adaptive quadtrees over outgoing-direction slices of one BRDF (seed 000 §3.4,
/// seed 003 §3.1), sampled as a [`DirectionSampler`].
///
/// Slice `(θ_j, φ_k)` holds a [`QuadTreeSampler`] of the disc density `x ↦ f_r(ωo_jk, h⁻¹(x))`
/// (see [`crate::disc`]), built from the image map of [`crate::SetOptions::grid`]² cells plus a
/// rim band (see the crate docs). For an outgoing direction `ωo`, the nearest slice is sampled
/// and its sample rotated about the normal by `φo − φ_k` (see [`SliceLayout`]); with
/// [`SetOptions::mixture`], the two θ-neighbouring slices are mixed with linear weights in θ.
///
/// **pdf** (with respect to solid angle): nearest slice `c`,
/// `p(ωi | ωo) = f_r(ωo_c, R⁻¹ωi) cos θi / Î_c` for `R⁻¹ωi` in a sampleable leaf of tree `c`,
/// 0 elsewhere and below the horizon; with the mixture `Σ_k w_k p_k(ωi)`. The slice choice
/// depends only on `ωo`, so `(1/N) Σ f_r(ωo, ωi) L cos θi / p` is unbiased wherever `p > 0`
/// covers the support of `f_r(ωo, ·)`.
pub struct QuadTreeSet {
    pub(crate) brdf: Arc<dyn Brdf>,
    pub(crate) spec: String,
    pub(crate) variant: Variant,
    pub(crate) options: SetOptions,
    /// The layout, with the θ-edge cosines of the nearest-slice rule.
    pub(crate) locator: SliceLocator,
    pub(crate) trees: Vec<QuadTreeSampler<SliceDensity>>,
    /// One per tree.
    pub(crate) norms: Vec<SliceNorm>,
    pub(crate) build_time: Duration,
    pub(crate) grid_evaluations: u64,
    /// Trials, samples and violations of the set's own `sample` calls (the trees' counters
    /// hold those of direct tree calls and of [`QuadTreeSet::measure_cost`]).
    pub(crate) counters: AuditCounters,
}

impl std::fmt::Debug for QuadTreeSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QuadTreeSet")
            .field("variant", &self.variant)
            .field("spec", &self.spec)
            .field("layout", &self.locator.layout())
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// The slice layout a BRDF needs under `options`.
pub fn layout_for(brdf: &dyn Brdf, options: &SetOptions) -> SliceLayout {
    if brdf.is_isotropic() {
        SliceLayout {
            theta: options.slices,
            phi: 1,
            half_turn: false,
        }
    } else {
        let [theta, phi] = options.anisotropic_slices;
        // Half-turn symmetry: the same azimuth step over [0, π) (an even count is halved).
        let half_turn =
            options.symmetries && brdf.is_half_turn_symmetric() && phi.is_multiple_of(2);
        SliceLayout {
            theta,
            phi: if half_turn { phi / 2 } else { phi },
            half_turn,
        }
    }
}

/// Normalisation of one slice's pdf: the tree's pdf `f / Î_grid` is multiplied by `factor`
/// (`Î_grid / Î_leaves`, see [`crate::normalisation`]; 1 for the papers' variant, whose leaf
/// probabilities are the grid integrals themselves).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct SliceNorm {
    pub(crate) factor: f64,
    /// Estimated relative error of the integral the pdf is normalised with.
    pub(crate) rel_err: Option<f64>,
}

/// Probes a declared mirror symmetry on 64 fixed points of the slice's disc (a Fibonacci
/// spiral in the half `y < 0`, radii up to 0.999): the first `(x, y, f(x, y), f(x, −y))` whose
/// values differ by more than `10⁻¹² · max(1, |f|)`.
fn mirror_asymmetry(f: &DiscBrdf) -> Option<(f64, f64, f64, f64)> {
    const PROBES: usize = 64;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..PROBES).find_map(|i| {
        let r = 0.999 * ((i as f64 + 0.5) / PROBES as f64).sqrt();
        // Angles in (π, 2π): y < 0.
        let t =
            std::f64::consts::PI * (1.0 + ((i as f64 * golden) / std::f64::consts::TAU).fract());
        let (x, y) = (r * t.cos(), r * t.sin());
        let (a, b) = (f.eval([x, y]), f.eval([x, -y]));
        ((a - b).abs() > 1e-12 * a.abs().max(1.0)).then_some((x, y, a, b))
    })
}

/// Relative zero floor of every slice's density: a slice built at `ωo_j` samples
/// `g = f_r(ωo_j, ·)` where that is non-zero and `SUPPORT_FLOOR · f̄_j` where it is exactly 0
/// (`f̄_j`: the mean of the slice's disc density over [`FLOOR_PROBES`] fixed points; see
/// [`DiscBrdf::with_zero_floor`]).
///
/// Why. A slice serves every `ωo` of its θ bin, and its pdf is `g / ∫ g`. Without the floor the
/// pdf vanishes wherever `f_r(ωo_j, ·) = 0`, but the support of `f_r(ωo, ·)` can move with θo:
/// the RGL fixture (`paper_white`) is exactly 0 at `θo = 80.5°` for `θi ≳ 88°` near
/// `φi ≈ ±164°` (the tables' zero region beyond the measured range, reached by the warp
/// interpolated between the file's slices at 78.5° and 90°) but positive there at
/// `θo = 80°`, so the slice at 80.5° left `1.6·10⁻⁶` of the target mass at 80° uncovered
/// (a biased estimator; found by the validation suite's support test). With the floor the
/// pdf is positive on the whole open disc for every BRDF. It costs nothing where `f_r > 0`
/// (there `g = f_r` exactly; only `∫ g` grows, by at most `SUPPORT_FLOOR` of `∫ f_r` times
/// the zero region's share of the disc), and BRDFs positive everywhere are unchanged.
pub const SUPPORT_FLOOR: f64 = 1e-3;

/// Fixed points (a Fibonacci spiral over the disc) whose mean density scales the zero floor.
pub const FLOOR_PROBES: usize = 256;

/// The zero floor of `f` ([`SUPPORT_FLOOR`] × the mean of `f` over [`FLOOR_PROBES`] points of a
/// Fibonacci spiral covering the disc, radii up to `√(1 − ½/FLOOR_PROBES)`). 0 when every
/// probe is 0 (then the slice keeps its plain support).
fn zero_floor(f: &Counted<'_>) -> f64 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let n = FLOOR_PROBES as f64;
    let sum: f64 = (0..FLOOR_PROBES)
        .map(|i| {
            let r = ((i as f64 + 0.5) / n).sqrt();
            let t = i as f64 * golden;
            let v = f.eval([r * t.cos(), r * t.sin()]);
            if v.is_finite() { v.max(0.0) } else { 0.0 }
        })
        .sum();
    SUPPORT_FLOOR * sum / n
}

/// A built slice: its tree, the BRDF evaluations spent and its normalisation.
type BuiltSlice = (QuadTreeSampler<SliceDensity>, u64, SliceNorm);

/// Builds the tree of slice `index`; returns it with the number of BRDF evaluations spent and
/// its normalisation.
fn build_slice(
    brdf: &Arc<dyn Brdf>,
    layout: SliceLayout,
    index: usize,
    options: &SetOptions,
    variant: Variant,
) -> Result<BuiltSlice, SetError> {
    let (t, p) = layout.angles_of(index);
    let (theta_deg, phi_deg) = (t.to_degrees(), p.to_degrees());
    let disc_map = options
        .disc_map
        .map_for(brdf.as_ref(), theta_deg, options.equal_area_from_deg);
    let f = DiscBrdf::with_map(Arc::clone(brdf), layout.direction_of(index), disc_map);
    let counter = EvalCounter::new();
    let floor = zero_floor(&Counted {
        f: &f,
        counter: &counter,
    });
    let f = f.with_zero_floor(floor);
    let mirror_y = options.symmetries && brdf.is_mirror_symmetric() && layout.phi == 1 && p == 0.0;
    if mirror_y && let Some((x, y, a, b)) = mirror_asymmetry(&f) {
        return Err(SetError::MirrorAsymmetry {
            slice: index,
            theta_deg,
            x,
            y,
            a,
            b,
        });
    }
    let grid_options = GridOptions {
        refinement: match variant {
            Variant::Adaptive => options.grid_refinement,
            Variant::Paper => None,
        },
        mirror_y,
        ..GridOptions::default()
    };
    let map = SliceImageMap::new(
        Counted {
            f: &f,
            counter: &counter,
        },
        options.grid,
        options.safety_factor,
        options.dilation_for(brdf.as_ref()),
        &grid_options,
    )
    .map_err(|source| SetError::Density {
        slice: index,
        theta_deg,
        phi_deg,
        source,
    })?;
    let tree_error = |source| SetError::Tree {
        slice: index,
        theta_deg,
        phi_deg,
        source,
    };
    let params = TreeParams {
        scheme: variant.scheme(),
        leaf_choice: variant.leaf_choice(),
        ..options.tree
    };
    let mut tree = QuadTreeBuilder::from_params(params)
        .build_tree(&map)
        .map_err(tree_error)?;
    drop(map);
    // Both variants check the image map's integrals against the same per-leaf quadrature (the
    // papers' variant without the mirror symmetry: its leaf values become the leaf
    // probabilities).
    let q = per_leaf_quadrature(
        &Counted {
            f: &f,
            counter: &counter,
        },
        tree.leaves(),
        tree.integral(),
        mirror_y && variant == Variant::Adaptive,
        Grading::Fixed,
    );
    let grid_err = tree.integral_rel_err().unwrap_or(f64::INFINITY);
    let norm = match variant {
        Variant::Adaptive => {
            let (i_leaves, rel_err) = (q.total, q.rel_err);
            // Keep the grid's Î when its own error estimate is the smaller one and is not
            // contradicted by the leaf rule: when the two integrals differ by more than the
            // grid claims, the grid's estimate is wrong and the (higher-order, adaptive) leaf
            // rule's value is kept — its estimate `|I₈ − I₅|` is the low order's error, so it
            // is pessimistic on rough data such as the Cornell interpolant (acryl_blue at
            // 45.5°: grid 2.0e-3 off claiming 1.0e-3, leaves 4e-5 off claiming 1.1e-3).
            let disagreement = ((i_leaves - tree.integral()) / i_leaves).abs();
            if i_leaves.is_finite()
                && i_leaves > 0.0
                && (rel_err <= grid_err || disagreement > grid_err)
            {
                SliceNorm {
                    factor: tree.integral() / i_leaves,
                    // The choice above uses the worst-case estimate; the pdf declares the
                    // tighter one (`LeafIntegrals::declared_rel_err`, issue 27).
                    rel_err: Some(q.declared_rel_err()),
                }
            } else {
                SliceNorm {
                    factor: 1.0,
                    rel_err: None,
                }
            }
        }
        Variant::Paper => {
            // The papers' scheme picks leaves ∝ I_i, so its pdf f/Î is exact only when every
            // I_i is: replace the image map's I_i by the leaf quadrature's when that is the
            // more accurate (the leaves, bounds and sampling procedure are the papers').
            // Only the estimates decide here: the leaf rule's per-leaf values also set the
            // leaf probabilities, and on the Cornell fixture the disagreement rule of the
            // adaptive variant made this variant's `|∫pdf − 1|` worse (1.1e-3 → 1.6e-3).
            if q.total.is_finite() && q.total > 0.0 && q.rel_err <= grid_err {
                tree = tree
                    .with_leaf_integrals(q.per_leaf, Some(q.rel_err))
                    .map_err(tree_error)?;
            }
            SliceNorm {
                factor: 1.0,
                rel_err: None,
            }
        }
    };
    // A clone holds its arrays with exact capacities (the builder grows them amortised).
    let tree = tree.clone();
    let shape = *tree.shape();
    let sampler =
        QuadTreeSampler::from_parts(tree, SliceDensity { f, shape }).map_err(|source| {
            SetError::Attach {
                slice: index,
                source,
            }
        })?;
    let norm = SliceNorm {
        rel_err: norm.rel_err.or(sampler.stats().integral_rel_err),
        ..norm
    };
    Ok((sampler, counter.total(), norm))
}

impl QuadTreeSet {
    /// Builds the set of `brdf` for `variant` (all slices in parallel with rayon; the result
    /// does not depend on the thread count). The spec recorded for persistence is
    /// `brdf.name()`; set another with [`QuadTreeSet::with_spec`].
    pub fn build(
        brdf: Arc<dyn Brdf>,
        variant: Variant,
        options: &SetOptions,
    ) -> Result<Self, SetError> {
        Self::build_with_progress(brdf, variant, options, None)
    }

    /// [`QuadTreeSet::build`] reporting `(done, total)` after each slice.
    pub fn build_with_progress(
        brdf: Arc<dyn Brdf>,
        variant: Variant,
        options: &SetOptions,
        progress: Option<Progress<'_>>,
    ) -> Result<Self, SetError> {
        options.validate()?;
        let start = Instant::now();
        let layout = layout_for(brdf.as_ref(), options);
        let total = AtomicUsize::new(layout.len());
        let done = AtomicUsize::new(0);
        let tick = || {
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            if let Some(p) = progress {
                p(d, total.load(Ordering::Relaxed));
            }
        };
        let mut built: Vec<BuiltSlice> = (0..layout.len())
            .into_par_iter()
            .map(|i| {
                let r = build_slice(&brdf, layout, i, options, variant);
                tick();
                r
            })
            .collect::<Result<_, _>>()?;
        // Refinement of the worst slices (grazing lobes squeezed against the rim).
        let cap = layout.len().div_ceil(10);
        let mut level_opts = *options;
        for _ in 0..options.refine_levels {
            let mut worst: Vec<(f64, usize)> = built
                .iter()
                .enumerate()
                .map(|(i, (t, _, _))| (t.tree().expected_mean_trials(), i))
                .filter(|&(e, _)| e > options.refine_threshold)
                .collect();
            if worst.is_empty() {
                break;
            }
            worst.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            worst.truncate(cap);
            level_opts = level_opts.with_depth(level_opts.tree.max_depth + 1);
            let opts = level_opts;
            total.fetch_add(worst.len(), Ordering::Relaxed);
            let redone: Vec<(usize, BuiltSlice)> = worst
                .par_iter()
                .map(|&(_, i)| {
                    let r = build_slice(&brdf, layout, i, &opts, variant).map(|b| (i, b));
                    tick();
                    r
                })
                .collect::<Result<_, _>>()?;
            for (i, (tree, evals, norm)) in redone {
                let old = &mut built[i];
                let better =
                    tree.tree().expected_mean_trials() < old.0.tree().expected_mean_trials();
                old.1 += evals;
                if better {
                    old.0 = tree;
                    old.2 = norm;
                }
            }
        }
        let grid_evaluations = built.iter().map(|b| b.1).sum();
        let norms = built.iter().map(|b| b.2).collect();
        let trees = built.into_iter().map(|b| b.0).collect();
        let spec = brdf.name().to_string();
        Ok(Self {
            brdf,
            spec,
            variant,
            options: *options,
            locator: SliceLocator::new(layout),
            trees,
            norms,
            build_time: start.elapsed(),
            grid_evaluations,
            counters: AuditCounters::new(),
        })
    }

    /// Records the BRDF spec string (checked by [`QuadTreeSet::from_bytes`]).
    pub fn with_spec(mut self, spec: impl Into<String>) -> Self {
        self.spec = spec.into().trim().to_string();
        self
    }

    /// Switches between the nearest slice and the two-slice mixture (the trees are unchanged).
    pub fn with_mixture(mut self, mixture: bool) -> Self {
        self.options.mixture = mixture;
        self
    }

    /// The BRDF.
    pub fn brdf(&self) -> &Arc<dyn Brdf> {
        &self.brdf
    }

    /// The recorded BRDF spec.
    pub fn spec(&self) -> &str {
        &self.spec
    }

    /// The variant.
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// The options the set was built with (and its current mixture flag).
    pub fn options(&self) -> &SetOptions {
        &self.options
    }

    /// The slice layout.
    pub fn layout(&self) -> SliceLayout {
        self.locator.layout()
    }

    /// The tree of slice `index` (area pdf on the disc, see [`QuadTreeSampler`]).
    pub fn tree(&self, index: usize) -> Option<&QuadTreeSampler<SliceDensity>> {
        self.trees.get(index)
    }

    /// Number of trees.
    pub fn len(&self) -> usize {
        self.trees.len()
    }

    /// `true` when the set has no trees (never for a built set).
    pub fn is_empty(&self) -> bool {
        self.trees.is_empty()
    }

    /// Wall-clock build time (zero for a loaded set).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// BRDF evaluations spent building (image maps and rim bands).
    pub fn grid_evaluations(&self) -> u64 {
        self.grid_evaluations
    }

    /// The slice(s) serving `wo` with their weights; `None` below the horizon.
    pub fn choices(&self, wo: &Vec3) -> Option<[SliceChoice; 2]> {
        if self.options.mixture {
            self.locator.layout().neighbours(wo)
        } else {
            self.locator
                .nearest(wo)
                .map(|c| [c, SliceChoice { weight: 0.0, ..c }])
        }
    }

    /// Density of `wi` under slice choice `c` alone, w.r.t. solid angle.
    #[inline]
    fn slice_pdf(&self, c: &SliceChoice, wi: &Vec3) -> f64 {
        match self.trees.get(c.index) {
            Some(tree) if wi.z > 0.0 => tree
                .density()
                .map()
                .area_to_solid_angle(self.slice_area_pdf(c, wi), wi),
            _ => 0.0,
        }
    }

    /// The factor turning tree `index`'s pdf `f / Î_grid` into the set's `f / Î_leaves`.
    #[inline]
    fn norm_factor(&self, index: usize) -> f64 {
        self.norms.get(index).map_or(1.0, |n| n.factor)
    }

    /// Density of `wi` under slice choice `c` alone, w.r.t. area on the disc of that slice
    /// (the tree's own pdf `f / Î`, under the slice's [`DiscMap`]).
    pub fn slice_area_pdf(&self, c: &SliceChoice, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let Some(tree) = self.trees.get(c.index) else {
            return 0.0;
        };
        let map = tree.density().map();
        let v = c.rotation.undo(wi);
        tree.pdf(map.to_disc(&v)) * self.norm_factor(c.index)
    }

    /// The mixture pdf `Σ w_k p_k` given the pdf of the component that drew `wi`.
    #[inline]
    fn combine(&self, cs: &[SliceChoice; 2], drawn: usize, drawn_pdf: f64, wi: &Vec3) -> f64 {
        let mut p = 0.0;
        for (k, c) in cs.iter().enumerate() {
            if c.weight > 0.0 {
                let pk = if k == drawn || c.index == cs[drawn].index {
                    drawn_pdf
                } else {
                    self.slice_pdf(c, wi)
                };
                p += c.weight * pk;
            }
        }
        p
    }

    /// [`Self::sample_with`] for the nearest-slice rule (the same draws, without the mixture's
    /// bookkeeping), counting into `a`.
    #[inline]
    fn sample_nearest(&self, wo: &Vec3, u: &mut dyn UniformSource, a: &mut Audit) -> DirSample {
        let Some((c, tree)) = self
            .locator
            .nearest(wo)
            .and_then(|c| Some((c, self.trees.get(c.index)?)))
        else {
            return DirSample {
                wi: Vec3::new(0.0, 0.0, 1.0),
                pdf: 0.0,
            };
        };
        self.to_direction_sample(&c, tree, tree.sample_audited(u, a))
    }

    /// The direction of a disc sample `s` of slice `c`'s tree, turned by the slice's rotation,
    /// with its pdf w.r.t. solid angle (the set's normalisation) under that slice alone.
    #[inline]
    fn to_direction_sample(
        &self,
        c: &SliceChoice,
        tree: &QuadTreeSampler<SliceDensity>,
        s: Sample2,
    ) -> DirSample {
        let map = tree.density().map();
        let v = map.to_direction(s.point);
        DirSample {
            wi: c.rotation.apply(&v),
            pdf: map.area_to_solid_angle(s.pdf * self.norm_factor(c.index), &v),
        }
    }

    /// One direction, drawing the disc point with `draw`.
    #[inline]
    fn sample_with(
        &self,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        mut draw: impl FnMut(&QuadTreeSampler<SliceDensity>, &mut dyn UniformSource) -> Sample2,
    ) -> DirSample {
        let up = DirSample {
            wi: Vec3::new(0.0, 0.0, 1.0),
            pdf: 0.0,
        };
        let Some(cs) = self.choices(wo) else {
            return up;
        };
        let drawn = usize::from(cs[1].weight > 0.0 && u.next_uniform() < cs[1].weight);
        let c = cs[drawn];
        let Some(tree) = self.trees.get(c.index) else {
            return up;
        };
        let DirSample { wi, pdf: p } = self.to_direction_sample(&c, tree, draw(tree, u));
        let pdf = if cs[1 - drawn].weight > 0.0 {
            self.combine(&cs, drawn, p, &wi)
        } else {
            p
        };
        DirSample { wi, pdf }
    }

    /// Samples `per_slice` directions for outgoing directions spread over every slice's θ bin
    /// (φ uniform) on the calling thread, and counts trials, BRDF evaluations (including the
    /// second component of a mixture), bound violations and exhausted samples. The counts are
    /// also added to the trees' statistics ([`QuadTreeSet::report`]).
    pub fn measure_cost(&self, per_slice: usize, seed: u64) -> CostMeasurement {
        let mut audit = Audit::default();
        let before = thread_evaluations();
        let mut samples = 0u64;
        let layout = self.locator.layout();
        let dt = std::f64::consts::FRAC_PI_2 / layout.theta as f64;
        let dp = layout.phi_period() / layout.phi as f64;
        for i in 0..self.trees.len() {
            let mut rng =
                Xoshiro256PlusPlus::seed_from_u64(partition_sampler::chunk_seed(seed, i as u64));
            let (t, p) = layout.angles_of(i);
            for _ in 0..per_slice {
                let theta = t + (rng.next_uniform() - 0.5) * dt;
                let phi = p + (rng.next_uniform() - 0.5) * dp;
                let wo = brdf::direction_from_radians(theta, phi);
                let _ = self.sample_with(&wo, &mut rng, |tree, u| {
                    let mut a = Audit::default();
                    let s = tree.sample_audited(u, &mut a);
                    tree.record_audit(&a);
                    audit.merge(&a);
                    s
                });
                samples += 1;
            }
        }
        CostMeasurement {
            samples,
            trials: audit.trials,
            evaluations: thread_evaluations() - before,
            violations: audit.violations,
            exhausted: audit.exhausted,
        }
    }

    /// Structure and statistics of the set (counts gathered so far by all sampling calls).
    pub fn report(&self) -> SetReport {
        let mut r = SetReport {
            variant: self.variant,
            mixture: self.options.mixture,
            brdf: self.brdf.name().to_string(),
            spec: self.spec.clone(),
            layout: self.locator.layout(),
            trees: self.trees.len(),
            equal_area_trees: self
                .trees
                .iter()
                .filter(|t| t.density().map() == DiscMap::EqualArea)
                .count(),
            build_time: self.build_time,
            memory_bytes: self.bytes_used(),
            nodes: 0,
            leaves: 0,
            max_depth: 0,
            expected_mean_trials: 0.0,
            worst_expected_mean_trials: 0.0,
            measured_mean_trials: None,
            samples: 0,
            bound_violations: 0,
            exhausted: 0,
            grid_evaluations: self.grid_evaluations,
            evaluations_per_sample: None,
            max_integral_rel_err: None,
        };
        let mut trials = 0.0;
        for t in &self.trees {
            let s = t.stats();
            r.nodes += s.nodes;
            r.leaves += s.active_leaves;
            r.max_depth = r.max_depth.max(s.depth);
            r.expected_mean_trials += s.expected_mean_trials;
            r.worst_expected_mean_trials = r.worst_expected_mean_trials.max(s.expected_mean_trials);
            r.samples += s.samples;
            trials += s.measured_mean_trials.unwrap_or(0.0) * s.samples as f64;
            r.bound_violations += s.bound_violations;
            r.exhausted += s.exhausted;
        }
        let own = self.counters.snapshot();
        r.samples += own.samples;
        trials += own.trials as f64;
        r.bound_violations += own.violations;
        r.exhausted += own.exhausted;
        for n in &self.norms {
            if let Some(e) = n.rel_err {
                r.max_integral_rel_err = Some(r.max_integral_rel_err.unwrap_or(0.0).max(e));
            }
        }
        r.expected_mean_trials /= self.trees.len().max(1) as f64;
        r.measured_mean_trials = (r.samples > 0).then(|| trials / r.samples as f64);
        r
    }

    /// [`QuadTreeSet::report`] after a [`QuadTreeSet::measure_cost`] run of `per_slice`
    /// samples per slice, which fills [`SetReport::evaluations_per_sample`].
    pub fn report_with_cost(&self, per_slice: usize, seed: u64) -> SetReport {
        let cost = self.measure_cost(per_slice, seed);
        let mut r = self.report();
        r.evaluations_per_sample = cost.evaluations_per_sample();
        r
    }
}

impl DirectionSampler for QuadTreeSet {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let mut a = Audit::default();
        let s = if self.options.mixture {
            self.sample_with(wo, u, |t, u| t.sample_audited(u, &mut a))
        } else {
            self.sample_nearest(wo, u, &mut a)
        };
        self.counters.record(&a);
        s
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        let Some(cs) = self.choices(wo) else {
            return 0.0;
        };
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let mut p = 0.0;
        for c in &cs {
            if c.weight > 0.0 {
                p += c.weight * self.slice_pdf(c, wi);
            }
        }
        p
    }

    fn sample_batch(&self, wo: &Vec3, n: usize, u: &mut dyn UniformSource) -> Vec<DirSample> {
        let nearest = (!self.options.mixture)
            .then(|| self.locator.nearest(wo))
            .flatten();
        match (self.variant, nearest) {
            (Variant::Paper, Some(c)) => {
                let Some(tree) = self.trees.get(c.index) else {
                    return Vec::new();
                };
                let batch = tree.sample_batch(n, AllocationMode::RandomizedRemainder, u);
                batch
                    .samples
                    .iter()
                    .map(|s| self.to_direction_sample(&c, tree, *s))
                    .collect()
            }
            _ => (0..n).map(|_| self.sample(wo, u)).collect(),
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.trees.iter().map(Sampler2D::bytes_used).sum::<usize>()
            + (self.trees.capacity() - self.trees.len())
                * std::mem::size_of::<QuadTreeSampler<SliceDensity>>()
            + self.spec.capacity()
    }
}

impl SamplerDiagnostics for QuadTreeSet {
    fn bound_violations(&self) -> Option<u64> {
        Some(self.report().bound_violations)
    }

    fn normaliser_rel_err(&self, wo: &Vec3) -> Option<f64> {
        let cs = self.choices(wo)?;
        cs.iter()
            .filter(|c| c.weight > 0.0)
            .filter_map(|c| {
                // The error of the integral the pdf is normalised with: the leaf quadrature's
                // when it replaced the grid's, else the grid's.
                match self.norms.get(c.index).and_then(|n| n.rel_err) {
                    Some(e) => Some(e),
                    None => self.tree(c.index)?.stats().integral_rel_err,
                }
            })
            .reduce(f64::max)
    }
}
