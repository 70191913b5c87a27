//! The work items of a build: an interval to build and what its parent hands down.

use std::sync::Arc;

use partition_sampler::QuadTree;

use crate::disc::DiscMap;

use super::chebyshev::ChebyshevTable;
use super::density::{NodeKey, NodeValues};
use super::grid::Grid;

/// A request to build one interval `θ ∈ [θ(num[0]), θ(num[1])]` (see [`Grid`]), with what its
/// parent already evaluated.
#[derive(Clone)]
pub(super) struct Job {
    pub(super) cell: usize,
    pub(super) num: [u64; 2],
    /// The azimuth offsets `δ ∈ [δ(dnum[0]), δ(dnum[1])]` of the cell (see [`Grid::delta`]).
    pub(super) dnum: [u64; 2],
    pub(super) inherited: Arc<Inheritance>,
}

/// What a split interval hands to its children: its caching bound nodes' values, and the
/// normalisers it integrated, keyed by the bits of the node's table variable and of `δ` (a
/// child's end is its parent's end with the same bits, so its quadrature is not repeated).
///
/// An interval split for its table's interpolation tail (its mean trials met the cap) also
/// hands down its tree: its leaf bounds hold for every outgoing direction of the interval, so
/// of each half too, and the children only need tables of their own (each child still checks
/// its mean trials at its own nodes, and is split with trees of their own when they exceed the
/// cap).
#[derive(Default)]
pub(super) struct Inheritance {
    pub(super) nodes: Vec<(NodeKey, Arc<NodeValues>)>,
    pub(super) normalisers: Vec<(NormaliserKey, Normaliser)>,
    /// The tree of an interval split for its tail, its disc map and its leaves' thinning
    /// bounds (they hold over the halves as the tree's bounds do).
    pub(super) tree: Option<(QuadTree, DiscMap, Option<super::table::SubBounds>)>,
    /// An ancestor's normaliser table whose interpolation tail met the inheritance test (see
    /// [`InheritedTable`]): the descendants take their nodes from it.
    pub(super) table: Option<Arc<InheritedTable>>,
}

/// The normaliser table of an isotropic interval split for its mean trials, handed to its
/// descendants (RGL sets, issue 29): its tail was at most the tolerance, or its nodes' error
/// estimate capped at [`INHERITED_TAIL_CAP`], so within the interval the table is `A · cos θo`
/// to `rel_err`, and a descendant's nodes are its values there (no quadrature). A
/// descendant's table re-interpolates the same polynomial (its own tail is rounding): its
/// declared error carries `rel_err`.
pub(super) struct InheritedTable {
    /// `A · cos θo` over the ancestor's interval (table variable).
    pub(super) table: ChebyshevTable,
    /// The ancestor's node error estimate plus its table's interpolation tail (relative).
    pub(super) rel_err: f64,
}

/// Largest interpolation tail (relative) of a table that a split interval hands to its
/// descendants, unless the tolerance is larger: the tail test of a kept interval stops at its
/// nodes' own error estimate (up to ~10⁻³ for grazing RGL nodes), but an inherited table
/// serves many narrow intervals, so it is held to this instead when that is smaller (the RGL
/// sets' normaliser goal is 10⁻⁴, `tabulated.rs`).
pub(super) const INHERITED_TAIL_CAP: f64 = 3e-5;

/// A normaliser node: the bits of its table variable and of `δ`.
pub(super) type NormaliserKey = (u64, u64);

/// One normaliser node's quadrature: `A` and its relative error estimate.
#[derive(Clone, Copy)]
pub(super) struct Normaliser {
    pub(super) total: f64,
    pub(super) rel_err: f64,
}

impl Job {
    /// Whether halving θ keeps the interval at least `min_width` (radians) wide.
    pub(super) fn can_split_theta(&self, grid: &Grid, min_width: f64) -> bool {
        let even = (self.num[1] - self.num[0]).is_multiple_of(2);
        even && 0.5 * (grid.edge(self.num[1]) - grid.edge(self.num[0])) >= min_width
    }
    /// Whether halving δ keeps the interval at least `min_width` (radians of azimuth) wide
    /// (never for isotropic BRDFs, whose one cell has `δ = 0`).
    pub(super) fn can_split_delta(&self, grid: &Grid, min_width: f64) -> bool {
        let even = (self.dnum[1] - self.dnum[0]).is_multiple_of(2);
        grid.half > 0.0
            && even
            && 0.5 * (grid.delta(self.dnum[1]) - grid.delta(self.dnum[0])) >= min_width
    }
    /// `axis` (`true`: δ) if the interval can be halved along it.
    pub(super) fn can_split_along(&self, grid: &Grid, min_width: f64, delta: bool) -> Option<bool> {
        let can = if delta {
            self.can_split_delta(grid, min_width)
        } else {
            self.can_split_theta(grid, min_width)
        };
        can.then_some(delta)
    }
    /// The two halves along the chosen axis (`delta`: split δ).
    pub(super) fn halves(&self, delta: bool) -> [([u64; 2], [u64; 2]); 2] {
        if delta {
            let mid = self.dnum[0] + (self.dnum[1] - self.dnum[0]) / 2;
            [
                (self.num, [self.dnum[0], mid]),
                (self.num, [mid, self.dnum[1]]),
            ]
        } else {
            let mid = self.num[0] + (self.num[1] - self.num[0]) / 2;
            [
                ([self.num[0], mid], self.dnum),
                ([mid, self.num[1]], self.dnum),
            ]
        }
    }
}
