//! [`QuadTreeSampler`]: rejection sampling on the leaves of a built [`QuadTree`].

use std::sync::Arc;

use crate::allocate::{AllocationMode, allocate, stratum_weights};
use crate::audit::{Audit, Counters, flush_local, record_one};
use crate::contract::{Point2, Sample2, Sampler2D, UniformSource};
use crate::density::{IntegralSource, RegionStats};
use crate::error::AttachError;
use crate::index::{floor_index, index_to_f64};
use crate::leaf::{Frame, Leaf};
use crate::rect::Domain;
use crate::tree::{EMPTY, LEAF, LeafChoice, QuadTree, Scheme};

/// `sample_envelope_of`: rejection against another density under this tree's bounds.
mod envelope_of;

/// A sample is abandoned (returned with pdf 0 and counted as exhausted) after this many
/// rejection trials. Only reachable when the bounds or integrals badly contradict `f`.
pub const MAX_TRIALS_PER_SAMPLE: u64 = 1 << 20;

/// Trials generated ahead per block by the batch path of [`Sampler2D::sample_into`].
const TRIAL_BLOCK: usize = 64;

/// The adaptive-partition sampler of a density `D` (seed 003 §3, seed 000 §3).
///
/// **pdf.** Both [`Sampler2D::sample`] and [`Sampler2D::pdf`] report
/// `p(x) = f(x) / Î` with respect to area on the domain, where `Î = Σ I_i` is the tree's
/// integral estimate ([`SamplerStats::integral`], with its source and estimated relative
/// error), for `x` in a sampleable leaf, and 0 elsewhere (outside the domain, in dropped
/// cells, in leaves of zero weight).
/// * [`Scheme::Envelope`] (default): the samples' true density is exactly `f / ∫_D f` when the
///   bounds hold, so `p` is exact up to the global factor `∫_D f / Î` (1 for tabulated data).
/// * [`Scheme::Paper`]: the true density is `(I_i / Î) · f(x) / ∫_{leaf i} f`; `p` equals it
///   when the `I_i` are exact, and is otherwise off by the per-leaf factor
///   `I_i / ∫_{leaf i} f`.
///
/// There is no inverse: rejection sampling is not a warp of the unit square.
pub struct QuadTreeSampler<D> {
    tree: QuadTree,
    density: D,
    counters: Arc<Counters>,
    disc: bool,
    inv_integral: f64,
    /// The tree's map from stored leaf coordinates to the domain.
    frame: Frame,
    /// Scale of the leaves' `f32` bounds.
    bound_scale: f64,
    /// The frame is the identity (roots `[0, 1]²`, `[−1, 1]²`, …): the hot loop skips the map.
    identity: bool,
}

impl<D> std::fmt::Debug for QuadTreeSampler<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("QuadTreeSampler")
            .field("params", &self.tree.params)
            .field("counts", &self.tree.counts)
            .field("integral", &self.tree.integral)
            .field("density", &std::any::type_name::<D>())
            .finish_non_exhaustive()
    }
}

/// Summary of a sampler: structure, cost and accuracy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplerStats {
    /// Nodes visited by the builder (internal + leaves).
    pub nodes: usize,
    /// Leaves (sampleable or not).
    pub leaves: usize,
    /// Leaves with positive selection weight.
    pub active_leaves: usize,
    /// Deepest leaf (root = 0).
    pub depth: u32,
    /// `Σ V_i / Σ I_i`: expected rejection trials per sample.
    pub expected_mean_trials: f64,
    /// Trials per sample measured so far (flushed counts only), if any sample was drawn.
    pub measured_mean_trials: Option<f64>,
    /// Samples counted so far.
    pub samples: u64,
    /// Trials with `f(x) > M_i` counted so far.
    pub bound_violations: u64,
    /// Samples abandoned after [`MAX_TRIALS_PER_SAMPLE`] trials (returned with pdf 0).
    pub exhausted: u64,
    /// Bytes of the tree and the density ([`Sampler2D::bytes_used`]).
    pub bytes: usize,
    /// `Î = Σ I_i`, the normaliser of the pdf.
    pub integral: f64,
    /// How `Î` was obtained.
    pub integral_source: IntegralSource,
    /// Estimated relative error of `Î`, when known.
    pub integral_rel_err: Option<f64>,
}

/// Bytes per structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryReport {
    /// Leaf array: rejection rectangles, bounds, alias entries, leaf integrals.
    pub leaves: usize,
    /// Internal nodes: child codes and descent CDFs.
    pub nodes: usize,
    /// The density provider (grid values, pyramids).
    pub density: usize,
    /// Everything, including the inline struct sizes.
    pub total: usize,
}

/// The result of [`QuadTreeSampler::sample_batch`].
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    /// The samples, grouped by leaf; `pdf` is the one-sample pdf `f(x) / Î`.
    pub samples: Vec<Sample2>,
    /// Per-sample stratum weights `N p_i / n_i` ([`AllocationMode::Hamilton`] only): the
    /// estimator is `(1/N) Σ w_k g(x_k) / pdf(x_k)`.
    pub weights: Option<Vec<f64>>,
    /// Samples per leaf `n_i` (leaf storage order).
    pub counts: Vec<usize>,
}

impl<D: RegionStats> QuadTreeSampler<D> {
    pub(crate) fn from_valid_parts(tree: QuadTree, density: D) -> Self {
        let disc = matches!(tree.shape.domain, Domain::UnitDisc);
        let inv_integral = 1.0 / tree.integral;
        let frame = tree.frame();
        let bound_scale = tree.bound_scale;
        Self {
            tree,
            density,
            counters: Arc::new(Counters::default()),
            disc,
            inv_integral,
            frame,
            bound_scale,
            identity: frame.is_identity(),
        }
    }

    /// Re-attaches a density to a stored tree, checking that the density's
    /// [`crate::DensityShape`] (provider kind, domain, dimensions, data fingerprint) is the
    /// one the tree was built for and that the tree is structurally sound.
    pub fn from_parts(tree: QuadTree, density: D) -> Result<Self, AttachError> {
        tree.validate().map_err(AttachError::Corrupt)?;
        let found = density.shape();
        if found != tree.shape {
            return Err(AttachError::ShapeMismatch {
                expected: Box::new(tree.shape),
                found: Box::new(found),
            });
        }
        Ok(Self::from_valid_parts(tree, density))
    }

    /// Splits into the tree and the density.
    pub fn into_parts(self) -> (QuadTree, D) {
        (self.tree, self.density)
    }

    /// The tree.
    pub fn tree(&self) -> &QuadTree {
        &self.tree
    }

    /// The density.
    pub fn density(&self) -> &D {
        &self.density
    }

    /// The same sampler with another leaf-selection method. The leaves and nodes are
    /// unchanged; [`LeafChoice::Descent`] (re)builds the per-node CDFs from the leaf weights
    /// exactly as the builder does (bit-identical), [`LeafChoice::Alias`] frees them.
    pub fn with_leaf_choice(mut self, choice: LeafChoice) -> Self {
        self.tree.set_leaf_choice(choice);
        self
    }

    /// `Î`, the pdf normaliser.
    pub fn integral(&self) -> f64 {
        self.tree.integral
    }

    /// Bytes per structure.
    pub fn memory(&self) -> MemoryReport {
        let density = self.density.bytes_used();
        MemoryReport {
            leaves: self.tree.leaf_bytes(),
            nodes: self.tree.node_bytes(),
            density,
            total: self.tree.bytes_used() + density + std::mem::size_of::<Self>()
                - std::mem::size_of::<QuadTree>(),
        }
    }

    /// Structure, cost and accuracy figures. Flushes the calling thread's buffered counts.
    pub fn stats(&self) -> SamplerStats {
        flush_local(&self.counters);
        let a = self.counters.snapshot();
        let c = self.tree.counts;
        SamplerStats {
            nodes: c.nodes,
            leaves: c.leaves,
            active_leaves: c.active_leaves,
            depth: c.depth,
            expected_mean_trials: self.tree.expected_mean_trials(),
            measured_mean_trials: (a.samples > 0).then(|| a.trials as f64 / a.samples as f64),
            samples: a.samples,
            bound_violations: a.violations,
            exhausted: a.exhausted,
            bytes: self.bytes_used(),
            integral: self.tree.integral,
            integral_source: self.tree.integral_source,
            integral_rel_err: self.tree.integral_rel_err,
        }
    }

    /// Zeroes the shared counters (buffered counts of other threads may arrive later).
    pub fn reset_stats(&self) {
        flush_local(&self.counters);
        self.counters.reset();
    }

    /// Adds locally gathered counts to the sampler's statistics
    /// ([`crate::diagnostics::AuditedDraws::record_audit`]).
    pub(crate) fn add_audit(&self, audit: &Audit) {
        self.counters.record(audit);
    }

    /// Leaf selection probabilities `p_i = I_i / Î` of batch mode (leaf storage order).
    pub fn leaf_probabilities(&self) -> Vec<f64> {
        self.tree
            .leaf_integral
            .iter()
            .map(|i| i * self.inv_integral)
            .collect()
    }

    /// The papers' batch mode (seed 000 §3.6): `n` samples split over the leaves with
    /// `n_i ≈ n · I_i / Î` by [`allocate`], then `n_i` samples drawn by rejection inside leaf
    /// `i`. Each sample's `pdf` is the one-sample pdf `f(x)/Î` (= `p_i f(x) / I_i`).
    ///
    /// Unbiasedness: with [`AllocationMode::RandomizedRemainder`] `E[n_i] = n p_i`, so
    /// `(1/n) Σ g/pdf` is unbiased whenever the `I_i` are exact (for estimated `I_i` the
    /// per-leaf factor `I_i / ∫_leaf f` remains, as in [`Scheme::Paper`]). With
    /// [`AllocationMode::Hamilton`] use the returned weights; leaves with `n p_i < 1` may get
    /// no sample, which biases the estimate (their mass is missed).
    pub fn sample_batch<U: UniformSource + ?Sized>(
        &self,
        n: usize,
        mode: AllocationMode,
        u: &mut U,
    ) -> Batch {
        let counts = allocate(n, &self.tree.leaf_integral, mode, u)
            .unwrap_or_else(|_| vec![0; self.tree.leaves.len()]);
        let mut samples = Vec::with_capacity(n);
        let mut a = Audit::default();
        for (leaf, &k) in self.tree.leaves.iter().zip(&counts) {
            for _ in 0..k {
                samples.push(if self.identity {
                    self.draw_in_leaf::<false, U>(leaf, u, &mut a)
                } else {
                    self.draw_in_leaf::<true, U>(leaf, u, &mut a)
                });
            }
        }
        self.counters.record(&a);
        let weights = match mode {
            AllocationMode::Hamilton => {
                let w = stratum_weights(n, &self.tree.leaf_integral, &counts);
                Some(
                    counts
                        .iter()
                        .zip(w)
                        .flat_map(|(&k, wi)| std::iter::repeat_n(wi, k))
                        .collect(),
                )
            }
            AllocationMode::RandomizedRemainder => None,
        };
        Batch {
            samples,
            weights,
            counts,
        }
    }

    /// `n` samples drawn in parallel: [`crate::sample_par`] (fixed chunks of
    /// [`crate::PAR_CHUNK`], one generator per chunk seeded from `(seed, chunk)`), so the output
    /// depends only on `seed` and `n`, never on the thread count. Trials are counted once per
    /// chunk.
    pub fn sample_par(&self, n: usize, seed: u64) -> Vec<Sample2> {
        crate::sample_par(self, n, seed)
    }

    /// The alias table's leaf index for the uniform `u0`: column `i = ⌊u0·n⌋`, kept when the
    /// fraction `u0·n − i` is below its probability, else its alias (`i` if the alias is out
    /// of range). `leaves` must not be empty.
    #[inline(always)]
    fn alias_index(&self, u0: f64) -> usize {
        let leaves = &self.tree.leaves;
        let n = leaves.len();
        let s = u0 * index_to_f64(n);
        let i = floor_index(s, n - 1);
        let first = &leaves[i];
        let alias = first.alias as usize;
        if s - index_to_f64(i) < first.prob || alias >= n {
            i
        } else {
            alias
        }
    }

    /// The leaf of [`Self::alias_index`].
    #[inline(always)]
    fn alias_leaf(&self, u0: f64) -> &Leaf {
        &self.tree.leaves[self.alias_index(u0)]
    }

    #[inline(always)]
    fn pick_leaf<U: UniformSource + ?Sized>(&self, u: &mut U) -> Option<&Leaf> {
        let leaves = &self.tree.leaves;
        match self.tree.params.leaf_choice {
            LeafChoice::Alias => {
                if leaves.is_empty() {
                    let _ = u.next_uniform();
                    return None;
                }
                Some(self.alias_leaf(u.next_uniform()))
            }
            LeafChoice::Descent => {
                let mut code = self.tree.root_code;
                loop {
                    if code == EMPTY {
                        return None;
                    }
                    if code & LEAF != 0 {
                        return leaves.get((code & !LEAF) as usize);
                    }
                    let node = self.tree.nodes.get(code as usize)?;
                    let cdf = self.tree.cdf.get(code as usize)?;
                    let r = u.next_uniform();
                    let k = if r < cdf[0] {
                        0
                    } else if r < cdf[1] {
                        1
                    } else if r < cdf[2] {
                        2
                    } else {
                        3
                    };
                    code = node.children[k];
                }
            }
        }
    }

    /// One rejection trial in `leaf`: `Some((x, f(x)))` when accepted. The point is uniform
    /// in the leaf's stored rectangle mapped by the frame, `x = origin + u · extent` (the map
    /// whose Jacobian the leaf areas and weights use, see [`Leaf::area`]). `MAP = false` skips
    /// the map for the identity frame (where it is `0 + u · 1 = u` anyway).
    #[inline(always)]
    fn trial<const MAP: bool, U: UniformSource + ?Sized>(
        &self,
        leaf: &Leaf,
        u: &mut U,
        a: &mut Audit,
    ) -> (Point2, Option<f64>) {
        let us = [u.next_uniform(), u.next_uniform(), u.next_uniform()];
        self.trial_with::<MAP>(leaf, us, a)
    }

    /// [`Self::trial`] with its three uniforms (`x`, `y`, height) given.
    #[inline(always)]
    fn trial_with<const MAP: bool>(
        &self,
        leaf: &Leaf,
        us: [f64; 3],
        a: &mut Audit,
    ) -> (Point2, Option<f64>) {
        let s = f64::from(leaf.u0) + us[0] * f64::from(leaf.du);
        let t = f64::from(leaf.v0) + us[1] * f64::from(leaf.dv);
        let (x, y) = if MAP {
            (self.frame.domain_coord(0, s), self.frame.domain_coord(1, t))
        } else {
            (s, t)
        };
        let m = leaf.bound(self.bound_scale);
        let z = us[2] * m;
        a.trials += 1;
        if self.disc && x * x + y * y > 1.0 {
            return ([x, y], None);
        }
        let f = self.density.eval([x, y]);
        if f > m {
            a.violations += 1;
        }
        ([x, y], (z < f).then_some(f))
    }

    /// After an envelope trial at `p` (`acc`: the density when accepted): the sample when it
    /// was accepted, the exhausted sample when the trials since `start` reached the cap, else
    /// `None` (try again).
    #[inline(always)]
    fn settle(&self, p: Point2, acc: Option<f64>, start: u64, a: &mut Audit) -> Option<Sample2> {
        if let Some(f) = acc {
            a.samples += 1;
            return Some(Sample2 {
                point: p,
                pdf: f * self.inv_integral,
            });
        }
        (a.trials - start >= MAX_TRIALS_PER_SAMPLE).then(|| self.exhausted(p, a))
    }

    fn exhausted(&self, p: Point2, a: &mut Audit) -> Sample2 {
        a.exhausted += 1;
        a.samples += 1;
        Sample2 { point: p, pdf: 0.0 }
    }

    /// Rejection inside one leaf until acceptance (batch mode and [`Scheme::Paper`]); counts
    /// the sample in `a`.
    #[inline(always)]
    fn draw_in_leaf<const MAP: bool, U: UniformSource + ?Sized>(
        &self,
        leaf: &Leaf,
        u: &mut U,
        a: &mut Audit,
    ) -> Sample2 {
        let start = a.trials;
        loop {
            let (p, acc) = self.trial::<MAP, U>(leaf, u, a);
            if let Some(f) = acc {
                a.samples += 1;
                return Sample2 {
                    point: p,
                    pdf: f * self.inv_integral,
                };
            }
            if a.trials - start >= MAX_TRIALS_PER_SAMPLE {
                return self.exhausted(p, a);
            }
        }
    }

    /// The batch path of [`Sampler2D::sample_into`] (envelope scheme, alias leaf choice,
    /// rectangular domain). The one-sample loop is a sequence of trials, each consuming the
    /// same uniforms (leaf pick, then `x`, `y`, `z` when a leaf is found) whatever the
    /// outcome, and a sample is the first accepted trial after the previous one (or the
    /// exhausted one after [`MAX_TRIALS_PER_SAMPLE`]). So the trials can be generated ahead in
    /// blocks, their densities evaluated together, and the accept pass run after, with the
    /// same result. A block never holds more trials than samples still missing, so no uniform
    /// is consumed that the one-sample loop would not consume.
    #[inline(always)]
    fn fill_blocks<const MAP: bool, U: UniformSource + ?Sized>(
        &self,
        u: &mut U,
        out: &mut [Sample2],
        a: &mut Audit,
    ) {
        let leaves = &self.tree.leaves;
        let centre = self.tree.root.center();
        let mut points = [centre; TRIAL_BLOCK];
        let mut zs = [0.0f64; TRIAL_BLOCK];
        let mut bounds = [0.0f64; TRIAL_BLOCK];
        let mut fs = [0.0f64; TRIAL_BLOCK];
        let mut us = [[0.0f64; 4]; TRIAL_BLOCK];
        let mut picks = [0usize; TRIAL_BLOCK];
        let mut filled = 0;
        let mut since = 0u64;
        while filled < out.len() {
            let k = (out.len() - filled).min(TRIAL_BLOCK);
            // Three passes, each free of data-dependent branches so that the cache misses of
            // a block overlap: the uniforms of every trial and its alias column (pick_leaf's
            // alias branch, chosen by a select), then the picked leaf's point and height
            // (trial's), then the densities.
            for j in 0..k {
                us[j] = u.next_uniform4();
                picks[j] = self.alias_index(us[j][0]);
            }
            for j in 0..k {
                let leaf = &leaves[picks[j]];
                let s = f64::from(leaf.u0) + us[j][1] * f64::from(leaf.du);
                let t = f64::from(leaf.v0) + us[j][2] * f64::from(leaf.dv);
                points[j] = if MAP {
                    [self.frame.domain_coord(0, s), self.frame.domain_coord(1, t)]
                } else {
                    [s, t]
                };
                let m = leaf.bound(self.bound_scale);
                bounds[j] = m;
                zs[j] = us[j][3] * m;
            }
            self.density.eval_block(&points[..k], &mut fs[..k]);
            // The accept pass without a data-dependent branch (its outcome is random, ≈ one
            // trial in six rejected: a mispredicted branch each time): every trial's sample is
            // written to `out[filled]` and `filled` advances only when it was accepted, so a
            // rejected trial's write is overwritten by the next one. In bounds: trial `j` of
            // the block finds `filled ≤ filled₀ + j < filled₀ + k ≤ out.len()`. The exhausted
            // case (`since` reaching the cap) stays a branch: it is never taken in practice.
            a.trials += k as u64;
            for j in 0..k {
                let f = fs[j];
                let accept = zs[j] < f;
                a.violations += u64::from(f > bounds[j]);
                out[filled] = Sample2 {
                    point: points[j],
                    pdf: f * self.inv_integral,
                };
                filled += usize::from(accept);
                a.samples += u64::from(accept);
                since = if accept { 0 } else { since + 1 };
                if since >= MAX_TRIALS_PER_SAMPLE {
                    out[filled] = self.exhausted(points[j], a);
                    filled += 1;
                    since = 0;
                }
            }
        }
    }

    /// One sample of the configured scheme (counts the sample in `a`).
    #[inline]
    pub(crate) fn draw<U: UniformSource + ?Sized>(&self, u: &mut U, a: &mut Audit) -> Sample2 {
        if self.identity {
            self.draw_with::<false, U>(u, a)
        } else {
            let (s, local) = self.draw_mapped(u);
            a.merge(&local);
            s
        }
    }

    /// [`Self::draw`] for a non-identity frame, kept out of line so that only one copy of the
    /// loop is inlined into callers. It counts into its own [`Audit`], returned by value: a
    /// caller's `&mut Audit` escaping into an out-of-line call would keep the caller's counts in
    /// memory on the inlined path too (measurably slower).
    #[inline(never)]
    fn draw_mapped<U: UniformSource + ?Sized>(&self, u: &mut U) -> (Sample2, Audit) {
        let mut a = Audit::default();
        let s = self.draw_with::<true, U>(u, &mut a);
        (s, a)
    }

    /// The loop of [`Self::draw`]; `MAP` as in [`Self::trial`].
    #[inline(always)]
    fn draw_with<const MAP: bool, U: UniformSource + ?Sized>(
        &self,
        u: &mut U,
        a: &mut Audit,
    ) -> Sample2 {
        let start = a.trials;
        let mut last = self.tree.root.center();
        if self.tree.params.scheme == Scheme::Envelope
            && self.tree.params.leaf_choice == LeafChoice::Alias
            && !self.tree.leaves.is_empty()
        {
            // The loop below with the four uniforms of a trial (alias pick, x, y, height)
            // fetched in one call: the same numbers in the same order.
            loop {
                let [u0, u1, u2, u3] = u.next_uniform4();
                let leaf = self.alias_leaf(u0);
                let (p, acc) = self.trial_with::<MAP>(leaf, [u1, u2, u3], a);
                if let Some(s) = self.settle(p, acc, start, a) {
                    return s;
                }
            }
        }
        loop {
            let Some(leaf) = self.pick_leaf(u) else {
                a.trials += 1;
                if a.trials - start >= MAX_TRIALS_PER_SAMPLE {
                    return self.exhausted(last, a);
                }
                continue;
            };
            match self.tree.params.scheme {
                Scheme::Envelope => {
                    let (p, acc) = self.trial::<MAP, U>(leaf, u, a);
                    if let Some(s) = self.settle(p, acc, start, a) {
                        return s;
                    }
                    last = p;
                }
                Scheme::Paper => return self.draw_in_leaf::<MAP, U>(leaf, u, a),
            }
        }
    }
}

impl<D: RegionStats> Sampler2D for QuadTreeSampler<D> {
    /// One sample of the configured scheme and leaf choice; pdf `f(x)/Î` (see the type docs).
    #[inline]
    fn sample<U: UniformSource + ?Sized>(&self, u: &mut U) -> Sample2 {
        let mut a = Audit::default();
        let s = self.draw(u, &mut a);
        record_one(&self.counters, &a);
        s
    }

    /// The draws of [`Sampler2D::sample`] — the same samples and the same uniforms consumed,
    /// bit for bit — counted locally and added to the shared counters once. With
    /// [`Scheme::Envelope`] and [`LeafChoice::Alias`] on a rectangle the trials are run in
    /// blocks ([`Self::fill_blocks`]): candidates first, then their densities in one
    /// [`Density::eval_block`](crate::Density::eval_block) call, then the accept pass — the
    /// whole block path compiled for the best vector extension of this CPU (`pulp`'s runtime
    /// dispatch: AVX2 where present, the x86-64 baseline otherwise; integer and IEEE
    /// operations without fused multiply-adds, so the same samples on every path).
    fn sample_into<U: UniformSource + ?Sized>(&self, u: &mut U, out: &mut [Sample2]) {
        let mut a = Audit::default();
        let blocked = !self.disc
            && !self.tree.leaves.is_empty()
            && self.tree.params.scheme == Scheme::Envelope
            && self.tree.params.leaf_choice == LeafChoice::Alias;
        if blocked && self.identity {
            a = pulp::Arch::new().dispatch(FillBlocks::<false, D, U> {
                sampler: self,
                u,
                out,
            });
        } else if blocked {
            a = pulp::Arch::new().dispatch(FillBlocks::<true, D, U> {
                sampler: self,
                u,
                out,
            });
        } else {
            for s in out.iter_mut() {
                *s = self.draw(u, &mut a);
            }
        }
        self.counters.record(&a);
    }

    /// `f(p)/Î` when `p` is in the domain and in a sampleable leaf, else 0.
    fn pdf(&self, p: Point2) -> f64 {
        if !self.tree.shape.domain.contains(p) || self.tree.locate(p).is_none() {
            return 0.0;
        }
        self.density.eval(p) * self.inv_integral
    }

    fn bytes_used(&self) -> usize {
        self.memory().total
    }
}

/// [`QuadTreeSampler::fill_blocks`] as a `pulp` operation, so that its passes are inlined
/// into (and compiled for) each instruction set `pulp` dispatches to; returns its counts.
struct FillBlocks<'a, const MAP: bool, D, U: ?Sized> {
    sampler: &'a QuadTreeSampler<D>,
    u: &'a mut U,
    out: &'a mut [Sample2],
}

impl<const MAP: bool, D: RegionStats, U: UniformSource + ?Sized> pulp::WithSimd
    for FillBlocks<'_, MAP, D, U>
{
    type Output = Audit;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Audit {
        let mut a = Audit::default();
        self.sampler.fill_blocks::<MAP, U>(self.u, self.out, &mut a);
        a
    }
}

#[cfg(test)]
mod block_level_tests {
    //! The block path compiled for every instruction-set level `pulp` can dispatch to on the
    //! machine running the tests (the x86-64 baseline always; AVX2 (`V3`) and AVX-512 (`V4`)
    //! where present), each against the one-sample path: the same samples bit for bit, the same
    //! uniforms consumed. (`sample_into` itself runs only the best level; this runs the others.)
    use super::*;
    use crate::{QuadTreeBuilder, Rect, SinPiRows, TabulatedDensity};
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{Rng, SeedableRng};

    /// The block path's operation on the test density and generator.
    type Op<'a, const MAP: bool> =
        FillBlocks<'a, MAP, TabulatedDensity<SinPiRows>, Xoshiro256PlusPlus>;

    fn sampler(rect: Rect) -> QuadTreeSampler<TabulatedDensity<SinPiRows>> {
        // A sun on a sky gradient: leaves of very different weights, so columns take their
        // aliases often.
        let (w, h) = (96usize, 48usize);
        let vals = (0..w * h)
            .map(|k| {
                let (i, j) = ((k % w) as f64, (k / w) as f64);
                1.0 + j / 8.0 + 400.0 * (-((i - 61.0).powi(2) + (j - 17.0).powi(2)) / 6.0).exp()
            })
            .collect();
        let d = TabulatedDensity::new(w, h, vals, rect)
            .unwrap()
            .with_row_factor(SinPiRows)
            .unwrap();
        QuadTreeBuilder::new().n_max(1.3).build(d).unwrap()
    }

    /// `fill_blocks` at one level (`level(op)` runs the operation), from `seed`: its samples
    /// (as bits) and the generator's next draw after them.
    fn run<const MAP: bool>(
        s: &QuadTreeSampler<TabulatedDensity<SinPiRows>>,
        len: usize,
        seed: u64,
        level: &dyn Fn(Op<'_, MAP>),
    ) -> (Vec<[u64; 3]>, u64) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut out = vec![
            Sample2 {
                point: [f64::NAN; 2],
                pdf: f64::NAN,
            };
            len
        ];
        level(FillBlocks {
            sampler: s,
            u: &mut rng,
            out: &mut out,
        });
        let bits = out
            .iter()
            .map(|x| [x.point[0].to_bits(), x.point[1].to_bits(), x.pdf.to_bits()])
            .collect();
        (bits, rng.next_u64())
    }

    fn check<const MAP: bool>(rect: Rect) {
        let s = sampler(rect);
        assert_eq!(s.identity, !MAP);
        for (len, seed) in [(1usize, 1u64), (63, 2), (64, 3), (65, 4), (2000, 5)] {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            let one: Vec<[u64; 3]> = (0..len)
                .map(|_| {
                    let x = s.sample(&mut rng);
                    [x.point[0].to_bits(), x.point[1].to_bits(), x.pdf.to_bits()]
                })
                .collect();
            let expected = (one, rng.next_u64());
            let baseline = run::<MAP>(&s, len, seed, &|op| {
                let mut a = Audit::default();
                op.sampler.fill_blocks::<MAP, _>(op.u, op.out, &mut a);
            });
            assert_eq!(baseline, expected, "x86-64 baseline, len {len}");
            #[cfg(target_arch = "x86_64")]
            {
                if let Some(v3) = pulp::x86::V3::try_new() {
                    let got = run::<MAP>(&s, len, seed, &|op| {
                        pulp::Simd::vectorize(v3, op);
                    });
                    assert_eq!(got, expected, "AVX2 (V3), len {len}");
                }
                if let Some(v4) = pulp::x86::V4::try_new() {
                    let got = run::<MAP>(&s, len, seed, &|op| {
                        pulp::Simd::vectorize(v4, op);
                    });
                    assert_eq!(got, expected, "AVX-512 (V4), len {len}");
                }
            }
        }
    }

    #[test]
    fn every_level_equals_the_one_sample_path() {
        check::<false>(Rect::UNIT);
        check::<true>(Rect::new(-0.3, 1.0, 2.2, 1.7));
    }
}
