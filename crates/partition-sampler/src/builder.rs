//! Top-down construction of the adaptive quadtree (seed 003 §3.1, seed 000 §3.1).

use crate::alias::build_alias;
use crate::density::RegionStats;
use crate::error::BuildError;
use crate::leaf::{Frame, Leaf, encode_axis, encode_bound, pow2_floor};
use crate::quadtree_sampler::QuadTreeSampler;
use crate::rect::{Domain, Rect};
use crate::tree::{
    EMPTY, LEAF, LeafChoice, Node, QuadTree, Scheme, TreeCounts, TreeParams, cell_rect,
};

pub use crate::limits::MAX_DEPTH_LIMIT;

/// Builds a [`QuadTreeSampler`] from a [`RegionStats`] provider.
///
/// A cell `i` with rejection rectangle `r_i` (the cell, or the bounding box of cell ∩ disc),
/// bound `M_i` and integral `I_i` is split into four equal quadrants while
/// `n_max · I_i / V_i < 1` with `V_i = area(r_i) · M_i`, `depth < max_depth`, and the children
/// are no smaller than `min_leaf_size` (and than the provider's smallest useful cell), and
/// `V_i > volume_tolerance · I_root`. Cells that do not meet the domain are dropped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadTreeBuilder {
    params: TreeParams,
}

impl Default for QuadTreeBuilder {
    fn default() -> Self {
        Self::from_params(TreeParams::default())
    }
}

/// Builder setters: `name(arg: T)` sets the parameter `name` to `arg` and returns the builder.
macro_rules! setters {
    ($($(#[$doc:meta])* $name:ident($arg:ident: $ty:ty);)*) => {
        $(
            $(#[$doc])*
            pub fn $name(mut self, $arg: $ty) -> Self {
                self.params.$name = $arg;
                self
            }
        )*
    };
}

impl QuadTreeBuilder {
    /// The generic defaults ([`TreeParams::default`]): `n_max = 2`, `max_depth = 12`, no
    /// minimum leaf size, [`Scheme::Envelope`], [`LeafChoice::Alias`].
    pub fn new() -> Self {
        Self::default()
    }

    /// A builder with every parameter given (validated by [`QuadTreeBuilder::build`]).
    pub fn from_params(params: TreeParams) -> Self {
        Self { params }
    }

    setters! {
        /// Split threshold `n_max ≥ 1` (the bound on mean trials per leaf).
        n_max(n_max: f64);
        /// Maximum depth (root = 0), at most [`MAX_DEPTH_LIMIT`].
        max_depth(max_depth: u32);
        /// Minimum child width and height in domain units (0 = no limit).
        min_leaf_size(size: f64);
        /// Cells whose envelope volume is at most `tol · I_root` (`I_root` = the root's integral
        /// estimate) are not split: their trials cost at most `tol` per sample each, while
        /// splitting the far tails of a peaked density (values like 1e-300) would only spend
        /// memory. 0 gives the papers' pure criterion.
        volume_tolerance(tol: f64);
        /// Sampling scheme.
        scheme(scheme: Scheme);
        /// Leaf selection method.
        leaf_choice(choice: LeafChoice);
    }

    /// The parameters as set.
    pub fn params(&self) -> TreeParams {
        self.params
    }

    /// Builds the tree and attaches `density` to it.
    pub fn build<D: RegionStats>(&self, density: D) -> Result<QuadTreeSampler<D>, BuildError> {
        let tree = self.build_tree(&density)?;
        Ok(QuadTreeSampler::from_valid_parts(tree, density))
    }

    /// Builds only the tree (e.g. to persist it), borrowing the density.
    pub fn build_tree<D: RegionStats + ?Sized>(&self, density: &D) -> Result<QuadTree, BuildError> {
        let p = self.params;
        p.validate()?;
        let domain = density.domain();
        if !domain.is_valid() {
            return Err(BuildError::InvalidDomain(domain));
        }
        let root = domain.bounding_rect();
        let [mw, mh] = density.min_cell_size().unwrap_or([0.0, 0.0]);
        let mut b = Walker {
            density,
            domain,
            root,
            params: p,
            min_size: [mw.max(p.min_leaf_size), mh.max(p.min_leaf_size)],
            leaves: Vec::new(),
            leaf_integral: Vec::new(),
            nodes: Vec::new(),
            counts: TreeCounts::default(),
            abs_err: Some(0.0),
            split_floor: 0.0,
        };
        let root_code = b.visit(0, 0, 0)?;
        // Every stored leaf has M_i > 0 (else its weight was 0); scale the bounds by a power
        // of two so that the largest is in [1, 2) as an f32.
        let max_m = b.leaves.iter().map(|r| r.m).fold(0.0f64, f64::max);
        if !(max_m > 0.0 && max_m.is_finite()) {
            return Err(BuildError::ZeroMass);
        }
        let bound_scale = pow2_floor(max_m);
        let frame = Frame::of_root(&root);
        let leaves: Vec<Leaf> = b
            .leaves
            .iter()
            .map(|r| r.encode(&root, &frame, bound_scale))
            .collect();
        let integral: f64 = b.leaf_integral.iter().sum();
        if !(integral > 0.0 && integral.is_finite()) {
            return Err(BuildError::ZeroMass);
        }
        let integral_rel_err = density.total_rel_err().or(b.abs_err.map(|e| e / integral));
        b.counts.active_leaves = leaves.len();
        b.leaf_integral.shrink_to_fit();
        b.nodes.shrink_to_fit();
        let mut tree = QuadTree {
            params: p,
            shape: density.shape(),
            root,
            leaves,
            leaf_integral: b.leaf_integral,
            bound_scale,
            nodes: b.nodes,
            cdf: Vec::new(),
            root_code,
            counts: b.counts,
            integral,
            volume: 0.0,
            integral_source: density.integral_source(),
            integral_rel_err,
        };
        // Selection weights, volumes and CDFs from the stored (rounded) values, so that they
        // are exactly what the sampler realises.
        let weights = tree.leaf_weights();
        let total_weight: f64 = weights.iter().sum();
        if !(total_weight > 0.0 && total_weight.is_finite()) {
            return Err(BuildError::ZeroMass);
        }
        for (leaf, (prob, a)) in tree.leaves.iter_mut().zip(build_alias(&weights)) {
            leaf.prob = prob;
            leaf.alias = a;
        }
        let extent = frame.extent;
        tree.volume = tree
            .leaves
            .iter()
            .map(|l| l.volume(extent, bound_scale))
            .sum();
        if !(tree.volume > 0.0 && tree.volume.is_finite()) {
            return Err(BuildError::ZeroMass);
        }
        tree.set_leaf_choice(p.leaf_choice);
        Ok(tree)
    }
}

/// A leaf as found by the walk, before encoding.
struct RawLeaf {
    /// Rejection rectangle (f64, domain units).
    rej: Rect,
    /// `M_i`.
    m: f64,
    /// Cell depth and indices.
    d: u32,
    ix: u64,
    iy: u64,
}

impl RawLeaf {
    /// The stored form: rectangle in the frame's coordinates, rounded outward within the
    /// cell, bound rounded up (see [`crate::leaf`]).
    fn encode(&self, root: &Rect, frame: &Frame, bound_scale: f64) -> Leaf {
        // Axis `k` (0 = x, 1 = y): the rejection interval `[lo, hi]` in the cell `i` of the
        // root's range `start + [0, size]` at depth `d`.
        let axis = |k: usize, [lo, hi]: [f64; 2], [start, size]: [f64; 2], i: u64| {
            let cell = frame.cell_edges(start, size, self.d, i);
            encode_axis(lo, hi, cell, frame.origin[k], frame.extent[k])
        };
        let (u0, du) = axis(
            0,
            [self.rej.x0, self.rej.x1],
            [root.x0, root.width()],
            self.ix,
        );
        let (v0, dv) = axis(
            1,
            [self.rej.y0, self.rej.y1],
            [root.y0, root.height()],
            self.iy,
        );
        Leaf {
            u0,
            v0,
            du,
            dv,
            m: encode_bound(self.m, bound_scale),
            alias: 0,
            prob: 1.0,
        }
    }
}

/// Recursive builder state: flat output arrays grown amortised (no per-node allocation).
struct Walker<'a, D: ?Sized> {
    density: &'a D,
    domain: Domain,
    root: Rect,
    params: TreeParams,
    min_size: [f64; 2],
    leaves: Vec<RawLeaf>,
    leaf_integral: Vec<f64>,
    nodes: Vec<Node>,
    counts: TreeCounts,
    abs_err: Option<f64>,
    /// Cells with `V_i` at or below this are not split.
    split_floor: f64,
}

impl<D: RegionStats + ?Sized> Walker<'_, D> {
    /// Visits cell `(ix, iy)` at depth `d`; returns its child code.
    ///
    /// Split decisions and the choice of leaves of zero weight use the unrounded `f64`
    /// values; a leaf of positive `f64` weight keeps a positive weight once stored (its
    /// rectangle and bound only grow).
    fn visit(&mut self, d: u32, ix: u64, iy: u64) -> Result<u32, BuildError> {
        let cell = cell_rect(&self.root, d, ix, iy);
        let Some(rej) = self.domain.rejection_rect(&cell) else {
            self.counts.dropped += 1;
            return Ok(EMPTY);
        };
        let est = self.density.region(&cell);
        let (m, i) = (est.max_bound, est.integral);
        if !(m.is_finite() && m >= 0.0 && i.is_finite() && i >= 0.0) {
            return Err(BuildError::InvalidRegionEstimate {
                cell,
                max_bound: m,
                integral: i,
            });
        }
        self.counts.nodes += 1;
        if d == 0 {
            self.split_floor = self.params.volume_tolerance * i;
        }
        let v = rej.area() * m;
        let child = 0.5f64.powi(d as i32 + 1);
        let can_split = d < self.params.max_depth
            && self.root.width() * child >= self.min_size[0]
            && self.root.height() * child >= self.min_size[1];
        if can_split && v > self.split_floor && self.params.n_max * i < v {
            let idx = self.nodes.len();
            if idx >= (LEAF - 1) as usize {
                return Err(BuildError::TooManyNodes);
            }
            self.nodes.push(Node {
                children: [EMPTY; 4],
            });
            self.counts.internal += 1;
            let mut children = [EMPTY; 4];
            for (k, c) in (0..4u64).zip(children.iter_mut()) {
                *c = self.visit(d + 1, 2 * ix + (k & 1), 2 * iy + (k >> 1))?;
            }
            self.nodes[idx] = Node { children };
            return Ok(idx as u32);
        }
        self.counts.leaves += 1;
        self.counts.depth = self.counts.depth.max(d);
        let weight = match self.params.scheme {
            Scheme::Envelope => v,
            Scheme::Paper if m > 0.0 && rej.area() > 0.0 => i,
            Scheme::Paper => 0.0,
        };
        if weight.is_nan() || weight <= 0.0 {
            return Ok(EMPTY);
        }
        if self.leaves.len() >= (LEAF - 1) as usize {
            return Err(BuildError::TooManyNodes);
        }
        self.abs_err = match (self.abs_err, est.integral_rel_err) {
            (Some(a), Some(r)) => Some(a + r.abs() * i),
            _ => None,
        };
        let code = LEAF | self.leaves.len() as u32;
        self.leaves.push(RawLeaf { rej, m, d, ix, iy });
        self.leaf_integral.push(i);
        Ok(code)
    }
}
