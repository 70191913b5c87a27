//! The built quadtree: flat arrays of leaves (rejection rectangles, bounds, alias entries; see
//! [`crate::leaf`]), internal nodes (child codes) and, only for [`LeafChoice::Descent`], the
//! per-node CDFs of the papers' descent. Serialisable.

use serde::{Deserialize, Serialize};

use crate::contract::Point2;
use crate::density::{DensityShape, IntegralSource};
use crate::leaf::{Frame, Leaf};
use crate::rect::{Domain, Rect};

/// How a leaf is chosen for a rejection trial, and what the pdf is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Scheme {
    /// **Default, exact with approximate integrals.** A leaf is chosen ∝ `V_i = area(rect_i) · M_i`,
    /// a point uniform in its rejection rectangle and a height uniform in `[0, M_i)`; on
    /// rejection the whole trial restarts from the leaf choice. Accepted points have density
    /// exactly `f(x) / ∫_D f` whenever every `M_i` bounds `f` on its leaf; mean trials per
    /// sample `Σ V_i / Σ I_i ≤ n_max` (up to leaves capped by the maximum depth).
    #[default]
    Envelope,
    /// The papers' scheme: a leaf is chosen ∝ `I_i`, then rejection is repeated inside that
    /// leaf. The true density is `(I_i / Σ I) · f(x) / ∫_{leaf i} f`, which equals `f(x) / Σ I`
    /// only when every `I_i` is exact (tabulated densities).
    Paper,
}

/// How the leaf of a trial is selected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum LeafChoice {
    /// **Default.** Flattened leaves with a Vose alias table: one uniform, O(1).
    #[default]
    Alias,
    /// The papers' walk from the root with the per-node CDFs `F_ik`: one uniform per level.
    Descent,
}

/// Every sampling configuration: both [`Scheme`]s with both [`LeafChoice`]s (envelope first,
/// alias first).
pub const SAMPLING_CONFIGS: [(Scheme, LeafChoice); 4] = [
    (Scheme::Envelope, LeafChoice::Alias),
    (Scheme::Envelope, LeafChoice::Descent),
    (Scheme::Paper, LeafChoice::Alias),
    (Scheme::Paper, LeafChoice::Descent),
];

/// Parameters a tree was built with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TreeParams {
    /// Split threshold: a cell is split while `n_max · I_i / V_i < 1`.
    pub n_max: f64,
    /// Maximum depth (root = 0).
    pub max_depth: u32,
    /// Cells are not split into children narrower or lower than this (domain units).
    pub min_leaf_size: f64,
    /// Cells with `V_i ≤ volume_tolerance · I_root` are not split (they cannot add more than
    /// `volume_tolerance` trials per sample each); 0 disables the rule.
    pub volume_tolerance: f64,
    /// Sampling scheme.
    pub scheme: Scheme,
    /// Leaf selection.
    pub leaf_choice: LeafChoice,
}

impl TreeParams {
    /// Generic default split threshold: the papers' `n_max = 2`. Uses with their own
    /// measured default name it for their use (BRDF sets, environment maps).
    pub const DEFAULT_N_MAX: f64 = 2.0;

    /// Generic default maximum depth.
    ///
    /// The papers used 5 for BRDF lobes on the disc. Measured with `examples/nmax_sweep.rs`
    /// (`n_max = 2`): a Phong lobe of exponent 1000 needs ≈ 3.9 trials per sample at depth 5,
    /// 1.72 at depth 7 and 1.62 from depth 8 on (the criterion then stops by itself at depth
    /// 9); a 1024 × 512 map with a sun of a few texels needs 30 trials at depth 5, 2.2 at depth
    /// 7 and 1.10 at depth 10 (texel-sized cells). Since the split criterion stops early
    /// wherever the bound is already tight, a deeper cap costs nothing there; 12 resolves
    /// texels of maps up to 4096 wide. Beyond it trees only grow where bounds stay loose.
    pub const DEFAULT_MAX_DEPTH: u32 = 12;

    /// Generic default [`TreeParams::volume_tolerance`].
    pub const DEFAULT_VOLUME_TOLERANCE: f64 = 1e-6;

    /// Checks every field: `n_max` finite and ≥ 1, `max_depth ≤ MAX_DEPTH_LIMIT`, sizes and
    /// tolerances finite and ≥ 0.
    pub fn validate(&self) -> Result<(), crate::BuildError> {
        use crate::BuildError;
        if !(self.n_max.is_finite() && self.n_max >= 1.0) {
            return Err(BuildError::InvalidNMax(self.n_max));
        }
        if self.max_depth > crate::limits::MAX_DEPTH_LIMIT {
            return Err(BuildError::MaxDepthTooLarge(self.max_depth));
        }
        if !(self.min_leaf_size.is_finite() && self.min_leaf_size >= 0.0) {
            return Err(BuildError::InvalidMinLeafSize(self.min_leaf_size));
        }
        if !(self.volume_tolerance.is_finite() && self.volume_tolerance >= 0.0) {
            return Err(BuildError::InvalidVolumeTolerance(self.volume_tolerance));
        }
        Ok(())
    }
}

impl Default for TreeParams {
    /// The generic defaults: `n_max = 2`, `max_depth = 12`, no minimum leaf size, volume
    /// tolerance `1e-6`, [`Scheme::Envelope`], [`LeafChoice::Alias`].
    fn default() -> Self {
        Self {
            n_max: Self::DEFAULT_N_MAX,
            max_depth: Self::DEFAULT_MAX_DEPTH,
            min_leaf_size: 0.0,
            volume_tolerance: Self::DEFAULT_VOLUME_TOLERANCE,
            scheme: Scheme::Envelope,
            leaf_choice: LeafChoice::Alias,
        }
    }
}

/// A CDF entry larger than any uniform in `[0, 1)`: the walk stops at this child at the latest.
pub(crate) const CDF_SKIP: f64 = 2.0;

/// Child code: no sampleable content.
pub(crate) const EMPTY: u32 = u32::MAX;
/// Child code flag: the low 31 bits index `leaves`.
pub(crate) const LEAF: u32 = 1 << 31;

/// An internal node: four child codes (quadrants x-major: 0 = (lo, lo), 1 = (hi, lo),
/// 2 = (lo, hi), 3 = (hi, hi)). The descent CDFs live in [`QuadTree`]'s separate `cdf` array.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct Node {
    pub(crate) children: [u32; 4],
}

/// Counts describing a tree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct TreeCounts {
    /// All nodes visited by the builder (internal + leaves, dropped cells excluded).
    pub nodes: usize,
    /// Internal nodes.
    pub internal: usize,
    /// Leaves (sampleable or not).
    pub leaves: usize,
    /// Leaves with positive selection weight.
    pub active_leaves: usize,
    /// Cells dropped because they do not meet the domain (disc).
    pub dropped: usize,
    /// Deepest leaf (root = 0).
    pub depth: u32,
}

/// Geometry and statistics of one sampleable leaf, as stored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeafInfo {
    /// Rejection rectangle: the cell, or the bounding box of cell ∩ disc with its edges
    /// rounded outward to `f32` precision (never beyond the cell).
    pub rect: Rect,
    /// `M_i`, rounded up to `f32` precision (never below the provider's bound).
    pub max_bound: f64,
    /// `I_i`.
    pub integral: f64,
    /// `V_i = area(rect) · M_i` (the envelope scheme's selection weight).
    pub volume: f64,
}

/// A built adaptive partition, without its density: what is persisted.
///
/// Re-attach a density with [`crate::QuadTreeSampler::from_parts`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuadTree {
    pub(crate) params: TreeParams,
    pub(crate) shape: DensityShape,
    pub(crate) root: Rect,
    pub(crate) leaves: Vec<Leaf>,
    /// `I_i` per leaf. Kept in `f64`: `Î = Σ I_i` is exact for tabulated densities, which the
    /// [`Scheme::Paper`] pdf and batch mode rely on.
    pub(crate) leaf_integral: Vec<f64>,
    /// Power of two scaling the leaves' `f32` bounds (`M_i = m · bound_scale`), so that bounds
    /// of any finite magnitude fit.
    pub(crate) bound_scale: f64,
    pub(crate) nodes: Vec<Node>,
    /// Per internal node, the cumulative child probabilities `F_i0..F_i2` ([`CDF_SKIP`] from the
    /// last child of positive weight on); empty unless `params.leaf_choice` is
    /// [`LeafChoice::Descent`] (see [`QuadTree::descent_cdfs`]).
    pub(crate) cdf: Vec<[f64; 3]>,
    pub(crate) root_code: u32,
    pub(crate) counts: TreeCounts,
    /// `Î = Σ I_i` over sampleable leaves.
    pub(crate) integral: f64,
    /// `Σ V_i` over sampleable leaves.
    pub(crate) volume: f64,
    pub(crate) integral_source: IntegralSource,
    pub(crate) integral_rel_err: Option<f64>,
}

/// `[x0, x1) × [y0, y1)` of cell `(ix, iy)` at depth `d` (the same arithmetic everywhere, so
/// neighbouring cells share bit-identical edges).
#[inline]
pub(crate) fn cell_rect(root: &Rect, d: u32, ix: u64, iy: u64) -> Rect {
    let sw = root.width() * 0.5f64.powi(d as i32);
    let sh = root.height() * 0.5f64.powi(d as i32);
    Rect {
        x0: root.x0 + ix as f64 * sw,
        x1: root.x0 + (ix + 1) as f64 * sw,
        y0: root.y0 + iy as f64 * sh,
        y1: root.y0 + (iy + 1) as f64 * sh,
    }
}

impl QuadTree {
    /// Build parameters.
    pub fn params(&self) -> &TreeParams {
        &self.params
    }

    /// Shape of the density the tree was built for.
    pub fn shape(&self) -> &DensityShape {
        &self.shape
    }

    /// The domain.
    pub fn domain(&self) -> Domain {
        self.shape.domain
    }

    /// Node and leaf counts.
    pub fn counts(&self) -> TreeCounts {
        self.counts
    }

    /// `Î = Σ I_i` over sampleable leaves.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Estimated relative error of [`QuadTree::integral`], when the provider knows one.
    pub fn integral_rel_err(&self) -> Option<f64> {
        self.integral_rel_err
    }

    /// `Σ V_i` over sampleable leaves.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// Expected trials per sample, `Σ V_i / Σ I_i` (both schemes).
    pub fn expected_mean_trials(&self) -> f64 {
        self.volume / self.integral
    }

    /// The sampleable leaves in storage order.
    pub fn leaves(&self) -> impl ExactSizeIterator<Item = LeafInfo> + '_ {
        let frame = self.frame();
        self.leaves
            .iter()
            .zip(&self.leaf_integral)
            .map(move |(l, &i)| LeafInfo {
                rect: l.rect(&frame),
                max_bound: l.bound(self.bound_scale),
                integral: i,
                volume: l.volume(frame.extent, self.bound_scale),
            })
    }

    /// Bytes of the leaf arrays: 32 per leaf (`f32` rectangle and bound, alias entry) plus 8
    /// for its integral.
    pub fn leaf_bytes(&self) -> usize {
        self.leaves.capacity() * std::mem::size_of::<Leaf>()
            + self.leaf_integral.capacity() * std::mem::size_of::<f64>()
    }

    /// Bytes of the internal nodes: 16 per node (child codes), plus 24 per node for the descent
    /// CDFs when [`LeafChoice::Descent`] is selected.
    pub fn node_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
            + self.cdf.capacity() * std::mem::size_of::<[f64; 3]>()
    }

    /// Total bytes of the tree.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.leaf_bytes() + self.node_bytes()
    }

    /// The map from stored leaf coordinates to the domain.
    pub(crate) fn frame(&self) -> Frame {
        Frame::of_root(&self.root)
    }

    /// Selection weights of the leaves under the tree's scheme, from the stored values:
    /// `V_i = area_i · M_i` ([`Scheme::Envelope`]) or `I_i` ([`Scheme::Paper`]).
    pub(crate) fn leaf_weights(&self) -> Vec<f64> {
        match self.params.scheme {
            Scheme::Envelope => {
                let extent = self.frame().extent;
                self.leaves
                    .iter()
                    .map(|l| l.volume(extent, self.bound_scale))
                    .collect()
            }
            Scheme::Paper => self.leaf_integral.clone(),
        }
    }

    /// The papers' per-node CDFs, bottom-up from the leaf weights ([`QuadTree::leaf_weights`]):
    /// a node's weight is the sum of its children's (empty children weigh 0), and
    /// `F_ik = Σ_{j ≤ k} w_j / Σ_j w_j`. The builder and
    /// [`crate::QuadTreeSampler::with_leaf_choice`] both use this function, so their results
    /// are bit-identical. Relies on child nodes having larger indices than their parent.
    pub(crate) fn descent_cdfs(&self) -> Vec<[f64; 3]> {
        let weights = self.leaf_weights();
        let mut total = vec![0.0f64; self.nodes.len()];
        let mut cdfs = vec![[CDF_SKIP; 3]; self.nodes.len()];
        for k in (0..self.nodes.len()).rev() {
            let mut w = [0.0f64; 4];
            for (wc, &c) in w.iter_mut().zip(&self.nodes[k].children) {
                *wc = if c == EMPTY {
                    0.0
                } else if c & LEAF != 0 {
                    weights.get((c & !LEAF) as usize).copied().unwrap_or(0.0)
                } else {
                    total.get(c as usize).copied().unwrap_or(0.0)
                };
            }
            let t: f64 = w.iter().sum();
            total[k] = t;
            if let Some(last) = (0..4).rev().find(|&j| w[j] > 0.0) {
                let mut acc = 0.0;
                for j in 0..last.min(3) {
                    acc += w[j];
                    cdfs[k][j] = acc / t;
                }
            }
        }
        cdfs
    }

    /// The same tree with its leaf integrals `I_i` replaced (leaf storage order), e.g. by a
    /// quadrature more accurate than the provider's estimate, with that value's relative error.
    /// `Î = Σ I_i` follows, and under [`Scheme::Paper`] so do the selection weights (alias
    /// table, descent CDFs): the papers' scheme then picks leaves with the new probabilities and
    /// its pdf `f/Î` is exact up to their accuracy. Leaves and bounds are unchanged.
    ///
    /// Errors ([`crate::BuildError::InvalidLeafIntegrals`]): a length other than the number of
    /// leaves, a value that is not finite and `≥ 0`, or a zero total.
    pub fn with_leaf_integrals(
        mut self,
        integrals: Vec<f64>,
        rel_err: Option<f64>,
    ) -> Result<Self, crate::error::BuildError> {
        use crate::error::BuildError::InvalidLeafIntegrals;
        if integrals.len() != self.leaves.len() {
            return Err(InvalidLeafIntegrals("one value per leaf needed"));
        }
        if !integrals.iter().all(|i| i.is_finite() && *i >= 0.0) {
            return Err(InvalidLeafIntegrals("values must be finite and ≥ 0"));
        }
        let total: f64 = integrals.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(InvalidLeafIntegrals(
                "the total must be positive and finite",
            ));
        }
        self.leaf_integral = integrals;
        self.integral = total;
        self.integral_rel_err = rel_err;
        if self.params.scheme == Scheme::Paper {
            let weights = self.leaf_weights();
            for (leaf, (prob, a)) in self
                .leaves
                .iter_mut()
                .zip(crate::alias::build_alias(&weights))
            {
                leaf.prob = prob;
                leaf.alias = a;
            }
            self.set_leaf_choice(self.params.leaf_choice);
        }
        Ok(self)
    }

    /// Selects the leaf choice, building the descent CDFs for [`LeafChoice::Descent`] and
    /// freeing them for [`LeafChoice::Alias`].
    pub(crate) fn set_leaf_choice(&mut self, choice: LeafChoice) {
        self.params.leaf_choice = choice;
        self.cdf = match choice {
            LeafChoice::Descent => self.descent_cdfs(),
            LeafChoice::Alias => Vec::new(),
        };
    }

    /// Index of the sampleable leaf whose cell contains `p`, if any.
    pub(crate) fn locate(&self, p: Point2) -> Option<usize> {
        let (rw, rh) = (self.root.width(), self.root.height());
        let (mut ix, mut iy, mut d) = (0u64, 0u64, 0i32);
        let mut code = self.root_code;
        loop {
            if code == EMPTY {
                return None;
            }
            if code & LEAF != 0 {
                return Some((code & !LEAF) as usize);
            }
            let node = self.nodes.get(code as usize)?;
            if d >= 62 {
                return None;
            }
            d += 1;
            let s = 0.5f64.powi(d);
            let hx = u64::from(p[0] >= self.root.x0 + (2 * ix + 1) as f64 * (rw * s));
            let hy = u64::from(p[1] >= self.root.y0 + (2 * iy + 1) as f64 * (rh * s));
            ix = 2 * ix + hx;
            iy = 2 * iy + hy;
            code = node.children[(hy << 1 | hx) as usize];
        }
    }

    /// Structural checks (so decoded bytes can never make sampling index out of range or loop).
    pub(crate) fn validate(&self) -> Result<(), &'static str> {
        let p = &self.params;
        if !(p.n_max.is_finite() && p.n_max >= 1.0) || p.max_depth > crate::limits::MAX_DEPTH_LIMIT
        {
            return Err("invalid parameters");
        }
        let finite_nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !finite_nonneg(p.min_leaf_size) || !finite_nonneg(p.volume_tolerance) {
            return Err("invalid parameters");
        }
        if !self.root.is_valid() || self.root != self.shape.domain.bounding_rect() {
            return Err("invalid root rectangle");
        }
        let n = self.leaves.len();
        if n == 0
            || n >= LEAF as usize
            || self.nodes.len() >= LEAF as usize
            || self.leaf_integral.len() != n
        {
            return Err("leaf array sizes");
        }
        if !(self.bound_scale.is_finite() && self.bound_scale > 0.0) {
            return Err("invalid bound scale");
        }
        let bounds = self.frame().stored_root(&self.root);
        if !self
            .leaves
            .iter()
            .all(|l| l.is_sound(n, self.bound_scale, &bounds))
        {
            return Err("invalid leaf");
        }
        if !self
            .leaf_integral
            .iter()
            .all(|i| i.is_finite() && *i >= 0.0)
        {
            return Err("invalid leaf integral");
        }
        let code_ok = |c: u32, parent: Option<usize>| -> bool {
            if c == EMPTY {
                true
            } else if c & LEAF != 0 {
                ((c & !LEAF) as usize) < n
            } else {
                (c as usize) < self.nodes.len() && parent.is_none_or(|q| c as usize > q)
            }
        };
        if !code_ok(self.root_code, None) {
            return Err("invalid root code");
        }
        for (k, node) in self.nodes.iter().enumerate() {
            if !node.children.iter().all(|&c| code_ok(c, Some(k))) {
                return Err("invalid child code");
            }
        }
        let cdf_len = match p.leaf_choice {
            LeafChoice::Descent => self.nodes.len(),
            LeafChoice::Alias => 0,
        };
        if self.cdf.len() != cdf_len {
            return Err("descent cdf array size");
        }
        if !self
            .cdf
            .iter()
            .flatten()
            .all(|c| (0.0..=CDF_SKIP).contains(c))
        {
            return Err("invalid cdf");
        }
        if !(self.integral.is_finite()
            && self.integral > 0.0
            && self.volume.is_finite()
            && self.volume > 0.0)
        {
            return Err("invalid totals");
        }
        if self.counts.depth > p.max_depth {
            return Err("depth exceeds max_depth");
        }
        Ok(())
    }
}
