//! One built interval (its tree and normaliser table) and where a query lands.

use brdf::Vec3;
use partition_sampler::QuadTreeSampler;

use crate::disc::{DiscMap, SliceDensity};
use crate::layout::Turn;

use super::chebyshev::ChebyshevTable;
use super::grid::TableVar;
use super::table::SubBounds;

/// One built interval.
pub(super) struct Interval {
    /// Its θ and δ numerators ([`Grid`](super::grid::Grid); kept for saving the set).
    pub(super) num: [u64; 2],
    pub(super) dnum: [u64; 2],
    /// Its θ range (radians).
    pub(super) theta: [f64; 2],
    /// Its azimuth offsets from the cell's centre (radians; `[0, 0]` for isotropic BRDFs).
    pub(super) delta: [f64; 2],
    pub(super) tree: QuadTreeSampler<SliceDensity>,
    pub(super) map: DiscMap,
    /// `A · cos θo` over the table variable `v` (`cos θo` for isotropic BRDFs, `θo` otherwise,
    /// see [`TableVar`]) and `δ`.
    pub(super) table: ChebyshevTable,
    /// Largest `Σ V_i / A` over the normaliser nodes.
    pub(super) worst_trials: f64,
    /// Quadrature + interpolation relative error estimate of `A`.
    pub(super) norm_err: f64,
    /// The quadrature's part of it.
    pub(super) quad_err: f64,
    pub(super) evaluations: u64,
    /// The leaves' thinning bounds (RGL materials; [`SubBounds`]), in the tree's leaf order.
    pub(super) sub_bounds: Option<SubBounds>,
}

impl Interval {
    /// `A(θo, δ)`: the table holds `A · cos θo` (smooth at grazing angles also for BRDFs with
    /// a `1/cos θo` factor), its variable (the set's `var`) clamped to the table's nodes.
    #[inline]
    pub(super) fn normaliser(&self, var: TableVar, q: &Query) -> f64 {
        let t = &self.table.theta;
        let v = q.var.clamp(t[t.len() - 1], t[0]);
        let cos = if v == q.var { q.cos } else { var.cos(v) };
        self.table.eval(v, q.delta) / cos
    }
}

/// Where a query lands.
#[derive(Debug, Clone, Copy)]
pub(super) struct Query {
    pub(super) cell: usize,
    pub(super) interval: usize,
    /// The outgoing direction served: the query's, or above [`THETA_TOP_DEG`](super::options::THETA_TOP_DEG) the direction of
    /// the same azimuth at that angle.
    pub(super) wo: Vec3,
    /// The table variable ([`TableVar`]) of the served direction (NaN for an anisotropic
    /// query located for drawing only: [`ExactSet::locate_keys`](super::ExactSet::locate_keys)).
    pub(super) var: f64,
    /// `cos θo`.
    pub(super) cos: f64,
    /// The offset `δ` from the cell's centre (NaN as [`Query::var`]).
    pub(super) delta: f64,
    /// Anisotropic sets: the normaliser grid's keys `w = √(1 − cos θo)` and the strip key
    /// (`tan δ` or `δ`, [`Cell::by_tan`](super::layout::Cell::by_tan)); see
    /// [`AnisoRecord`](super::aniso_record::AnisoRecord). Unused for isotropic sets.
    pub(super) keys: [f64; 2],
    /// The rotation about the normal from the tree's frame to the world's.
    pub(super) turn: Turn,
}
