//! `adaptive-exact`: samples exactly ∝ `f_r(ωo, ·) cos θi` at **every** outgoing direction,
//! with interval-bounded trees (issue 14).
//!
//! # Math
//! The outgoing angles are partitioned into θ intervals `[θ_a, θ_b]` (for anisotropic BRDFs,
//! rectangles `[θ_a, θ_b] × [δ_a, δ_b]` of azimuth cells with centres `φ_k`, offsets
//! `δ ∈ [−h, h]`, [`ExactOptions::initial_phi_cells`] of them before splitting;
//! half-turn-symmetric BRDFs store `[0, π)`). Each interval holds one quadtree
//! on the unit disc of its [`DiscMap`] (equal-area when `θ_b` reaches
//! [`SetOptions::equal_area_from_deg`] or the BRDF is unbounded at the horizon), built with the
//! set's image map, rim band, safety factor and tree parameters from the **envelope**
//! `F(x) = max_n g_n(x)` of the query densities at the interval's bound nodes (a uniform grid
//! of [`ExactOptions::bound_nodes`] θ values × [`ExactOptions::phi_bound_nodes`] δ values of
//! the interval).
//! The leaf bounds `M_i` thus hold for every outgoing direction of the interval (between the
//! nodes, the safety factor covers the envelope's dips; every trial above its bound is counted
//! by the audit, [`crate::DirectionSampler::bound_violations`]).
//!
//! For a query `ωo = (θo, φo)`: the cell `k` with the nearest `φ_k`, the rotation
//! `r = φo − φ_k` (`δ = r` reduced to `[−h, h]`; one cell and `r = φo` for isotropic BRDFs),
//! the interval containing `(θo, δ)` (a guide table over the cell's θ strips, then the strip's
//! δ edges), and the query density `g(x) = f_r(ωo, R_r h⁻¹(x))`
//! (projected) or `2 f_r(ωo, R_r h_e⁻¹(x)) cos θi` (equal-area). A leaf is chosen ∝
//! `V_i = area_i · M_i`, a point `x` uniformly in it and accepted when `z · M_i < g(x)`; the
//! accepted `x` has density `g / ∫ g` exactly, and `ωi = R_r h⁻¹(x)`.
//!
//! **pdf** (w.r.t. solid angle): `p(ωi | ωo) = f_r(ωo, ωi) cos θi / A(θo, δ)`, with
//! `A = ∫_Ω f_r(ωo, ·) cos θi dσ` (the disc integral of `g`), tabulated per interval at
//! Chebyshev–Lobatto nodes ([`ExactOptions::normaliser_nodes`] × [`ExactOptions::phi_normaliser_nodes`]),
//! each node integrated with the leaf quadrature of the interval's tree (`normalisation.rs`;
//! a MERL table over its own bins instead, 5 nodes per interval, `tabulated.rs`, issue 27);
//! the δ nodes are doubled (Lobatto-nested, up to 17) while the δ tail exceeds the same floor;
//! `A · cos θo` is interpolated ([`chebyshev`]): it stays smooth up to grazing angles for models
//! whose `f_r` has a `1/cos θo` factor (Beard–Maxwell, Ward), where `A` itself diverges. The
//! table's variable is `cos θo` for isotropic BRDFs (`A` is even in `θo`, so smooth in
//! `cos θo`; a query then needs no `acos`) and `θo` for anisotropic cells ([`TableVar`]). The
//! reported normaliser error is the quadrature's estimate plus the interpolation's (the
//! Chebyshev tail).
//!
//! **Adaptive intervals.** An interval is halved while its tree would need more than
//! [`ExactOptions::max_trials`] mean trials at one of its normaliser nodes (`Σ V_i / A`) or its
//! θ (δ) interpolation tail exceeds [`ExactOptions::normaliser_tol`] (or the quadrature's own
//! error estimate, if larger: below it the tail is quadrature noise), down to
//! [`ExactOptions::min_width_deg`]: sharp lobes and grazing angles get narrow intervals, smooth
//! models keep the initial ones. The initial intervals are also cut at the BRDF's known
//! **kinks in θo** ([`theta_kinks`]: the θo slices of an RGL table, linear in θo between
//! them), so that no interval's Chebyshev table has to follow a kink of `A(θo)` (on the RGL
//! fixture `|A/Â − 1|` went from 2.1e-3 next to a slice to below 1e-4 up to 85°, issue 27).
//! Too many trials halve θ, or δ when the bound nodes'
//! densities overlap clearly less along δ than along θ and the azimuth loss alone explains the
//! excess (`split_axis`): an anisotropic lobe far from the normal gets narrow azimuth cells, the
//! rest of the hemisphere wide ones. The layout is reported by [`ExactSet::report`].
//!
//! **Build cost.** Interval edges and bound nodes are exact rationals of `π/2` (one
//! denominator for the set), so a halved interval's ends and midpoint are bound nodes of its
//! children too, with the same bits; for isotropic BRDFs slower than [`CACHE_ABOVE_NS`] per
//! evaluation, a child looks up the values its parent's nodes took at the same incident
//! directions of the image-map lattice instead of evaluating them again (bit-identical; with
//! 3 nodes a child evaluates one node afresh). The normaliser nodes are integrated ends and
//! middle first: the first whose `ΣV/A` exceeds the cap decides the split, and the others are
//! not integrated. A child takes the normaliser at the end it shares with its parent from the
//! parent's quadrature (same node bits), and a doubled δ grid keeps the nodes it already has;
//! each quadrature uses the graded rule (`normalisation::Grading::Graded`: orders 5 and 3
//! first, order 8 only on the pieces that need it).

mod batch;
mod chebyshev;
mod density;
mod fused;
mod probe;
mod tabulated;
mod walk;

use std::sync::Arc;
use std::time::{Duration, Instant};

use brdf::{Brdf, Vec3, direction_from_radians, rotate_z};
use partition_sampler::{
    Audit, AuditCounters, GridOptions, LeafChoice, QuadTreeBuilder, QuadTreeSampler, Sampler2D,
    Scheme, TreeParams, UniformSource,
};
use rayon::prelude::*;

use crate::direction_sampler::{DirSample, DirectionSampler, EvalSample};
use crate::disc::{DiscBrdf, DiscMap, SliceDensity};
use crate::error::SetError;
use crate::image_map::{Counted, EvalCounter, SliceImageMap};
use crate::layout::Turn;
use crate::options::{OptionsError, SetOptions};
use crate::set::layout_for;

use chebyshev::{ChebyshevTable, lobatto_nodes};
use density::{EnvelopeNode, IntervalEnvelope, NodeKey, NodeValues, QueryDensity};

/// The largest outgoing polar angle the nodes use (degrees): `f_r` at exactly 90° is 0 or
/// undefined. A query above it is served as the direction of the same azimuth at this angle
/// (samples ∝ `f_r(ωo', ·) cos θi`, pdf normalised, bounds valid; `f_r` may diverge there).
pub const THETA_TOP_DEG: f64 = 89.99;

/// Settings of [`ExactSet`]. `set` supplies the tree parameters, image map, safety factor,
/// disc-map policy and symmetries (its slice counts are unused: the intervals and azimuth cells
/// adapt).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactOptions {
    /// The quadtree settings shared with the other adaptive sets.
    pub set: SetOptions,
    /// θ intervals before splitting (equal widths over `[0°, 90°]`).
    pub initial_intervals: usize,
    /// Azimuth cells per full turn before splitting (anisotropic BRDFs; an even count is halved
    /// over `[0, π)` for half-turn-symmetric ones, as the sets' `anisotropic_slices`).
    pub initial_phi_cells: usize,
    /// θ nodes of the bound envelope per interval (uniform, ends included; ≥ 2).
    pub bound_nodes: usize,
    /// δ nodes of the bound envelope per interval (anisotropic BRDFs; ≥ 2), more where the
    /// interval is wider in azimuth than this many nodes [`MAX_DELTA_NODE_SPACING_DEG`] apart.
    pub phi_bound_nodes: usize,
    /// Chebyshev–Lobatto θ nodes of the normaliser table (3 ..= 32).
    pub normaliser_nodes: usize,
    /// Chebyshev–Lobatto δ nodes of the normaliser table (anisotropic BRDFs; 3 ..= 32).
    pub phi_normaliser_nodes: usize,
    /// Split an interval whose mean trials `Σ V_i / A` exceed this at a normaliser node (> 1).
    pub max_trials: f64,
    /// Split an interval whose relative interpolation tail exceeds this (> 0).
    pub normaliser_tol: f64,
    /// Narrowest interval, in θ and in azimuth (degrees, > 0).
    pub min_width_deg: f64,
}

impl ExactOptions {
    /// Default initial interval count.
    pub const DEFAULT_INITIAL_INTERVALS: usize = 6;
    /// Default azimuth cells per turn before splitting.
    pub const DEFAULT_INITIAL_PHI_CELLS: usize = 8;
    /// Default θ bound nodes.
    pub const DEFAULT_BOUND_NODES: usize = 3;
    /// Default δ bound nodes.
    pub const DEFAULT_PHI_BOUND_NODES: usize = 3;
    /// Default θ normaliser nodes.
    pub const DEFAULT_NORMALISER_NODES: usize = 9;
    /// Default δ normaliser nodes.
    pub const DEFAULT_PHI_NORMALISER_NODES: usize = 5;
    /// Default trial cap.
    pub const DEFAULT_MAX_TRIALS: f64 = 2.0;
    /// Default interpolation tolerance.
    pub const DEFAULT_NORMALISER_TOL: f64 = 1e-6;
    /// Default narrowest interval (degrees).
    pub const DEFAULT_MIN_WIDTH_DEG: f64 = 0.25;

    /// The defaults around `set`.
    pub fn with_set(set: SetOptions) -> Self {
        Self {
            set,
            initial_intervals: Self::DEFAULT_INITIAL_INTERVALS,
            initial_phi_cells: Self::DEFAULT_INITIAL_PHI_CELLS,
            bound_nodes: Self::DEFAULT_BOUND_NODES,
            phi_bound_nodes: Self::DEFAULT_PHI_BOUND_NODES,
            normaliser_nodes: Self::DEFAULT_NORMALISER_NODES,
            phi_normaliser_nodes: Self::DEFAULT_PHI_NORMALISER_NODES,
            max_trials: Self::DEFAULT_MAX_TRIALS,
            normaliser_tol: Self::DEFAULT_NORMALISER_TOL,
            min_width_deg: Self::DEFAULT_MIN_WIDTH_DEG,
        }
    }

    /// Checks every field (and `set`).
    pub fn validate(&self) -> Result<(), ExactError> {
        self.set.validate()?;
        let bad = |what: &'static str, value: f64| Err(ExactError::Invalid { what, value });
        if !(1..=90).contains(&self.initial_intervals) {
            return bad(
                "initial_intervals (1 ..= 90)",
                self.initial_intervals as f64,
            );
        }
        if !(1..=64).contains(&self.initial_phi_cells) {
            return bad(
                "initial_phi_cells (1 ..= 64)",
                self.initial_phi_cells as f64,
            );
        }
        if !(2..=64).contains(&self.bound_nodes) {
            return bad("bound_nodes (2 ..= 64)", self.bound_nodes as f64);
        }
        if !(2..=64).contains(&self.phi_bound_nodes) {
            return bad("phi_bound_nodes (2 ..= 64)", self.phi_bound_nodes as f64);
        }
        if !(3..=32).contains(&self.normaliser_nodes) {
            return bad("normaliser_nodes (3 ..= 32)", self.normaliser_nodes as f64);
        }
        if !(3..=32).contains(&self.phi_normaliser_nodes) {
            return bad(
                "phi_normaliser_nodes (3 ..= 32)",
                self.phi_normaliser_nodes as f64,
            );
        }
        if !(self.max_trials > 1.0 && self.max_trials.is_finite()) {
            return bad("max_trials (> 1)", self.max_trials);
        }
        if !(self.normaliser_tol > 0.0 && self.normaliser_tol.is_finite()) {
            return bad("normaliser_tol (> 0)", self.normaliser_tol);
        }
        if !(self.min_width_deg > 0.0 && self.min_width_deg <= 90.0) {
            return bad("min_width_deg (0, 90]", self.min_width_deg);
        }
        Ok(())
    }
}

impl Default for ExactOptions {
    fn default() -> Self {
        Self::with_set(SetOptions::default())
    }
}

/// Why an [`ExactSet`] could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ExactError {
    /// Invalid quadtree settings.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// An exact-sampler setting out of range.
    #[error("adaptive-exact: {what} = {value} is out of range")]
    Invalid {
        /// The setting and its range.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// An interval's image map or tree failed (the slice number is the interval's).
    #[error(transparent)]
    Set(#[from] SetError),
    /// An interval's normaliser is not positive and finite (the BRDF is zero or not finite
    /// there).
    #[error("adaptive-exact: ∫ f cos = {value} at θo = {theta_deg:.3}°, φo = {phi_deg:.3}°")]
    Normaliser {
        /// The integral found.
        value: f64,
        /// Where.
        theta_deg: f64,
        /// Where.
        phi_deg: f64,
    },
}

/// One built interval.
struct Interval {
    /// Its θ range (radians).
    theta: [f64; 2],
    /// Its azimuth offsets from the cell's centre (radians; `[0, 0]` for isotropic BRDFs).
    delta: [f64; 2],
    tree: QuadTreeSampler<SliceDensity>,
    map: DiscMap,
    /// `A · cos θo` over the table variable `v` (`cos θo` for isotropic BRDFs, `θo` otherwise,
    /// see [`TableVar`]) and `δ`.
    table: ChebyshevTable,
    /// Largest `Σ V_i / A` over the normaliser nodes.
    worst_trials: f64,
    /// Quadrature + interpolation relative error estimate of `A`.
    norm_err: f64,
    /// The quadrature's part of it.
    quad_err: f64,
    evaluations: u64,
}

impl Interval {
    /// `A(θo, δ)`: the table holds `A · cos θo` (smooth at grazing angles also for BRDFs with
    /// a `1/cos θo` factor), its variable (the set's `var`) clamped to the table's nodes.
    #[inline]
    fn normaliser(&self, var: TableVar, q: &Query) -> f64 {
        let t = &self.table.theta;
        let v = q.var.clamp(t[t.len() - 1], t[0]);
        let cos = if v == q.var { q.cos } else { var.cos(v) };
        self.table.eval(v, q.delta) / cos
    }
}

/// The variable of an interval's normaliser table and of its search.
///
/// Isotropic BRDFs use `v = cos θo`: `A` is then an even function of `θo` (`ωo` at `−θo` is
/// `ωo` at `θo` turned by π), hence a smooth function of `cos θo` up to normal incidence, and
/// a query needs no `acos` — unless the BRDF is a table linear in θo (see [`table_var`]). Anisotropic cells keep `v = θo` (without half-turn symmetry `A`
/// is not even in `θo` at a fixed azimuth, and `cos θo` would put a square-root singularity at
/// normal incidence).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TableVar {
    Cos,
    Theta,
}

impl TableVar {
    /// `v` of the outgoing polar angle `θ`.
    fn of(self, theta: f64) -> f64 {
        match self {
            Self::Cos => theta.cos(),
            Self::Theta => theta,
        }
    }
    /// `θ` of `v`.
    fn theta(self, v: f64) -> f64 {
        match self {
            Self::Cos => v.clamp(-1.0, 1.0).acos(),
            Self::Theta => v,
        }
    }
    /// `cos θ` of `v`.
    #[inline]
    fn cos(self, v: f64) -> f64 {
        match self {
            Self::Cos => v,
            Self::Theta => cos_not_speculated(v),
        }
    }
    /// The search key of `v`, increasing with θ over `[0, key_range]`: `1 − cos θ` or `θ`.
    #[inline]
    fn key(self, v: f64) -> f64 {
        match self {
            Self::Cos => 1.0 - v,
            Self::Theta => v,
        }
    }
    fn key_range(self) -> f64 {
        match self {
            Self::Cos => 1.0,
            Self::Theta => std::f64::consts::FRAC_PI_2,
        }
    }
}

/// `cos v` behind a call the optimiser cannot hoist: inlined, `libm`'s `cos` (which it treats
/// as pure) was computed on every query of an isotropic set and the result discarded (5 % of
/// the sampling loop of `ward` in `perf`).
#[inline(never)]
fn cos_not_speculated(v: f64) -> f64 {
    v.cos()
}

/// One azimuth cell: its centre and its intervals. The cell is cut into θ **strips** at every
/// interval's θ edges; a strip holds the intervals that cover it, ordered by δ (one, unless
/// the cell was split in azimuth there).
struct Cell {
    phi: f64,
    /// `(cos, sin)` of `phi`: a query's rotation from the cell's frame without trigonometry.
    phi_turn: Turn,
    /// Upper θ edges of the strips (radians), increasing; the last is π/2.
    upper: Vec<f64>,
    /// The same edges as search keys ([`TableVar::key`]), increasing.
    keys: Vec<f64>,
    /// Guide table over the keys `[0, range]`: `guide[g]` is the strip of the key
    /// `g · range / GUIDE_LEN`, where the search for any key of bucket `g` starts (see
    /// [`Cell::interval_of`]).
    guide: Vec<u32>,
    range: f64,
    /// Strip `s` holds the intervals `members[strips[s]..strips[s + 1]]`; empty when every
    /// strip holds one interval, the strip's own index (no azimuth split in the cell).
    strips: Vec<u32>,
    /// Upper δ edge of each strip entry, increasing within a strip.
    delta_upper: Vec<f64>,
    /// The interval of each strip entry.
    members: Vec<u32>,
    /// The intervals, ordered by θ, then δ.
    intervals: Vec<Interval>,
}

/// An interval with its θ and δ numerators ([`Grid`]).
type Placed = ([u64; 2], [u64; 2], Interval);

/// Buckets of a cell's guide table.
const GUIDE_LEN: usize = 256;

impl Cell {
    /// The cell of centre `phi` tiled by `members` (θ numerators, δ numerators and interval,
    /// ordered by θ then δ; see [`Grid`]).
    fn new(phi: f64, members: Vec<Placed>, grid: &Grid, var: TableVar) -> Self {
        let mut edges: Vec<u64> = members.iter().map(|(num, _, _)| num[1]).collect();
        edges.sort_unstable();
        edges.dedup();
        let upper: Vec<f64> = edges.iter().map(|&e| grid.edge(e)).collect();
        let mut keys: Vec<f64> = upper.iter().map(|&t| var.key(var.of(t))).collect();
        // Monotone despite rounding (the search needs sorted keys).
        for i in 1..keys.len() {
            keys[i] = keys[i].max(keys[i - 1]);
        }
        let range = var.key_range();
        let guide = interval_guide(&keys, range);
        let (mut strips, mut delta_upper, mut entries) = (vec![0u32], Vec::new(), Vec::new());
        let mut lower = 0u64;
        for &e in &edges {
            let mut strip: Vec<(u64, usize)> = members
                .iter()
                .enumerate()
                .filter(|(_, (num, _, _))| num[0] <= lower && num[1] >= e)
                .map(|(i, (_, dnum, _))| (dnum[1], i))
                .collect();
            strip.sort_unstable();
            for (d, i) in strip {
                delta_upper.push(grid.delta(d));
                entries.push(i as u32);
            }
            strips.push(entries.len() as u32);
            lower = e;
        }
        let plain = entries.len() == edges.len();
        let intervals = members.into_iter().map(|(_, _, iv)| iv).collect();
        Self {
            phi,
            phi_turn: Turn::from_angle(phi),
            upper,
            keys,
            guide,
            range,
            strips: if plain { Vec::new() } else { strips },
            delta_upper: if plain { Vec::new() } else { delta_upper },
            members: if plain { Vec::new() } else { entries },
            intervals,
        }
    }

    /// The interval of the search key `key` and azimuth offset `delta`.
    #[inline]
    fn interval_of(&self, key: f64, delta: f64) -> usize {
        let s = guided_interval(&self.keys, &self.guide, self.range, key);
        if self.strips.is_empty() {
            return s;
        }
        let (mut j, last) = (self.strips[s] as usize, self.strips[s + 1] as usize - 1);
        while j < last && self.delta_upper[j] < delta {
            j += 1;
        }
        self.members[j] as usize
    }

    /// The intervals of strip `s`, ordered by δ.
    fn strip(&self, s: usize) -> Vec<usize> {
        if self.strips.is_empty() {
            return vec![s];
        }
        (self.strips[s]..self.strips[s + 1])
            .map(|j| self.members[j as usize] as usize)
            .collect()
    }

    /// Per strip, its intervals' azimuth edges (degrees, absolute).
    fn phi_edges_deg(&self) -> Vec<Vec<f64>> {
        (0..self.upper.len())
            .map(|s| {
                let ivs = self.strip(s);
                let deg = |d: f64| (self.phi + d).to_degrees();
                let mut e = vec![deg(self.intervals[ivs[0]].delta[0])];
                e.extend(ivs.iter().map(|&i| deg(self.intervals[i].delta[1])));
                e
            })
            .collect()
    }
}

/// The guide table of the interval edges `upper` (increasing, not empty) over `[0, range]`:
/// entry `g` is the interval of `g · range / GUIDE_LEN`.
fn interval_guide(upper: &[f64], range: f64) -> Vec<u32> {
    let step = range / GUIDE_LEN as f64;
    let last = upper.len().saturating_sub(1);
    (0..GUIDE_LEN)
        .map(|g| upper.partition_point(|&u| u < g as f64 * step).min(last) as u32)
        .collect()
}

/// The first interval whose upper edge is ≥ `x` (the last one when none is): the binary search
/// `upper.partition_point(|u| u < x)`, by a scan from the guide table's bucket of `x` (usually
/// zero or one step; down only if rounding put `x` in the bucket above its own).
#[inline]
fn guided_interval(upper: &[f64], guide: &[u32], range: f64, x: f64) -> usize {
    let last = upper.len() - 1;
    let g = ((x * (GUIDE_LEN as f64 / range)) as usize).min(GUIDE_LEN - 1);
    let mut i = (guide[g] as usize).min(last);
    while i > 0 && upper[i - 1] >= x {
        i -= 1;
    }
    while i < last && upper[i] < x {
        i += 1;
    }
    i
}

/// The intervals of one azimuth cell of an [`ExactSet`]: θ strips cut at every interval's θ
/// edges, each strip split in azimuth where its intervals were.
#[derive(Debug, Clone, PartialEq)]
pub struct CellLayout {
    /// The cell's centre azimuth (degrees).
    pub phi_deg: f64,
    /// The strips' θ edges (degrees, from 0 to 90).
    pub theta_edges_deg: Vec<f64>,
    /// Per strip, the azimuth edges of its intervals (degrees, increasing, from the cell's lower
    /// edge to its upper one); empty for isotropic BRDFs.
    pub phi_edges_deg: Vec<Vec<f64>>,
}

/// The layout and statistics of an [`ExactSet`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExactReport {
    /// BRDF name.
    pub brdf: String,
    /// Azimuth cells before their splits (1 for isotropic BRDFs).
    pub cells: usize,
    /// Per azimuth cell: its θ strips and their intervals' azimuth edges.
    pub layout: Vec<CellLayout>,
    /// Trees (= intervals over all cells).
    pub trees: usize,
    /// Trees on the equal-area disc.
    pub equal_area_trees: usize,
    /// Sampleable leaves over all trees.
    pub leaves: usize,
    /// Mean over trees of the worst `Σ V_i / A` at their normaliser nodes.
    pub mean_worst_trials: f64,
    /// Largest `Σ V_i / A` at any normaliser node.
    pub worst_trials: f64,
    /// Largest estimated relative error of the tabulated normaliser `A`.
    pub max_normaliser_rel_err: f64,
    /// Bound violations counted so far by sampling.
    pub bound_violations: u64,
    /// Samples drawn so far (flushed counts).
    pub samples: u64,
    /// Trials so far (flushed counts).
    pub trials: u64,
    /// BRDF evaluations of the build (envelopes count one per node).
    pub build_evaluations: u64,
    /// Wall-clock build time.
    pub build_time: Duration,
    /// Bytes of the set.
    pub memory_bytes: usize,
}

impl std::fmt::Display for ExactReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "intervals  {} in {} azimuth cell(s) ({} equal-area)",
            self.trees, self.cells, self.equal_area_trees
        )?;
        let list = |v: &[f64]| -> String {
            let e: Vec<String> = v.iter().map(|t| format!("{t:.2}")).collect();
            e.join(", ")
        };
        for c in &self.layout {
            let (phi, edges) = (c.phi_deg, &c.theta_edges_deg);
            writeln!(f, "  φ {phi:7.2}°  θ edges [{}]", list(edges))?;
            for (s, phis) in c.phi_edges_deg.iter().enumerate() {
                if phis.len() > 2 {
                    let (a, b) = (edges[s], edges[s + 1]);
                    writeln!(f, "    θ {a:.2}–{b:.2}°  φ edges [{}]", list(phis))?;
                }
            }
        }
        writeln!(f, "leaves     {}", self.leaves)?;
        writeln!(
            f,
            "trials     mean worst ΣV/A {:.3}, largest {:.3}",
            self.mean_worst_trials, self.worst_trials
        )?;
        writeln!(
            f,
            "A error    {:.2e} (relative, estimated)",
            self.max_normaliser_rel_err
        )?;
        writeln!(
            f,
            "audit      {} violations in {} trials, {} samples",
            self.bound_violations, self.trials, self.samples
        )?;
        writeln!(f, "evals      {} (build)", self.build_evaluations)?;
        writeln!(f, "build      {:.3} s", self.build_time.as_secs_f64())?;
        write!(f, "memory     {:.1} KiB", self.memory_bytes as f64 / 1024.0)
    }
}

/// The exact sampler (see the module docs).
pub struct ExactSet {
    brdf: Arc<dyn Brdf>,
    options: ExactOptions,
    isotropic: bool,
    /// Azimuth period of the cells (2π, or π for half-turn-symmetric BRDFs).
    period: f64,
    cells: Vec<Cell>,
    /// The variable of the normaliser tables and of the interval search.
    var: TableVar,
    /// `cos` of [`THETA_TOP_DEG`]: queries below it are served there.
    top_cos: f64,
    build_time: Duration,
    /// Trials, samples and violations of the set's own `sample` calls, counted set-wide (one
    /// thread-local buffer for every tree: at random θo consecutive samples use different
    /// trees); `measure_cost` records into the trees.
    counters: AuditCounters,
}

impl std::fmt::Debug for ExactSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExactSet")
            .field("brdf", &self.brdf.name())
            .field("options", &self.options)
            .field("trees", &self.len())
            .finish_non_exhaustive()
    }
}

/// A request to build one interval `θ ∈ [θ(num[0]), θ(num[1])]` (see [`Grid`]), with what its
/// parent already evaluated.
#[derive(Clone)]
struct Job {
    cell: usize,
    num: [u64; 2],
    /// The azimuth offsets `δ ∈ [δ(dnum[0]), δ(dnum[1])]` of the cell (see [`Grid::delta`]).
    dnum: [u64; 2],
    inherited: Arc<Inheritance>,
}

/// What a split interval hands to its children: its caching bound nodes' values, and the
/// normalisers it integrated, keyed by the bits of the node's table variable and of `δ` (a
/// child's end is its parent's end with the same bits, so its quadrature is not repeated).
#[derive(Default)]
struct Inheritance {
    nodes: Vec<(NodeKey, Arc<NodeValues>)>,
    normalisers: Vec<(NormaliserKey, Normaliser)>,
}

/// A normaliser node: the bits of its table variable and of `δ`.
type NormaliserKey = (u64, u64);

/// One normaliser node's quadrature: `A` and its relative error estimate.
#[derive(Clone, Copy)]
struct Normaliser {
    total: f64,
    rel_err: f64,
}

impl Job {
    /// Whether halving θ keeps the interval at least `min_width` (radians) wide.
    fn can_split_theta(&self, grid: &Grid, min_width: f64) -> bool {
        let even = (self.num[1] - self.num[0]).is_multiple_of(2);
        even && 0.5 * (grid.edge(self.num[1]) - grid.edge(self.num[0])) >= min_width
    }
    /// Whether halving δ keeps the interval at least `min_width` (radians of azimuth) wide
    /// (never for isotropic BRDFs, whose one cell has `δ = 0`).
    fn can_split_delta(&self, grid: &Grid, min_width: f64) -> bool {
        let even = (self.dnum[1] - self.dnum[0]).is_multiple_of(2);
        grid.half > 0.0
            && even
            && 0.5 * (grid.delta(self.dnum[1]) - grid.delta(self.dnum[0])) >= min_width
    }
    /// `axis` (`true`: δ) if the interval can be halved along it.
    fn can_split_along(&self, grid: &Grid, min_width: f64, delta: bool) -> Option<bool> {
        let can = if delta {
            self.can_split_delta(grid, min_width)
        } else {
            self.can_split_theta(grid, min_width)
        };
        can.then_some(delta)
    }
    /// The two halves along the chosen axis (`delta`: split δ).
    fn halves(&self, delta: bool) -> [([u64; 2], [u64; 2]); 2] {
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

/// Exact interval edges and bound nodes: a θ numerator `num` over `2^EDGE_BITS` (or a node's
/// `k` over `m · 2^EDGE_BITS`) names a point of the initial interval `i = ⌊num / 2^EDGE_BITS⌋`,
/// at the fraction `rem / 2^EDGE_BITS` of it. One rational for every point of the set, so that
/// a node shared by a split interval and its children is the same rational, hence the same
/// `f64` (one correctly rounded quotient) and the same `ωo` bits.
///
/// The initial intervals are uniform (`θ = (π/2) · num / den`, `den = n0 · 2^EDGE_BITS`), or,
/// when the BRDF has kinks in θo ([`theta_kinks`]), cut at those kinks as well
/// (`θ = b_i + (b_{i+1} − b_i) · rem / 2^EDGE_BITS` over the breaks `b`): every interval is then
/// a range where `A(θo)` is smooth, and its Chebyshev table converges.
#[derive(Debug, Clone, Copy)]
struct Grid {
    /// Denominator of the interval edges: `initial intervals · 2^EDGE_BITS`.
    den: u64,
    /// `bound_nodes − 1`: node `n` of `[a, b]` is `(a·m + (b − a)·n) / (den·m)`.
    m: u64,
    /// Half-width of the azimuth cells (0: isotropic); `δ = h · (2 · num / 2^EDGE_BITS − 1)`.
    half: f64,
    /// The initial intervals' edges (radians, `breaks[0..=n0]`) when they are not uniform.
    breaks: Option<[f64; MAX_BREAKS + 1]>,
}

/// Halvings an initial interval can take (far below any useful `min_width_deg`).
const EDGE_BITS: u32 = 40;

/// Most initial intervals a set can start from when they are cut at the BRDF's kinks (a BRDF
/// with more kinks than fit keeps the uniform intervals).
const MAX_BREAKS: usize = 128;

impl Grid {
    /// The θ of the rational `k / (m · 2^EDGE_BITS)` (in initial intervals).
    fn angle(&self, k: u64, m: u64) -> f64 {
        match &self.breaks {
            None => std::f64::consts::FRAC_PI_2 * (k as f64 / (self.den * m) as f64),
            Some(b) => {
                let unit = m << EDGE_BITS;
                let n0 = (self.den >> EDGE_BITS) as usize;
                let (i, rem) = ((k / unit) as usize, k % unit);
                if i >= n0 {
                    b[n0]
                } else if rem == 0 {
                    b[i]
                } else {
                    b[i] + (b[i + 1] - b[i]) * (rem as f64 / unit as f64)
                }
            }
        }
    }
    fn edge(&self, num: u64) -> f64 {
        self.angle(num, 1)
    }
    /// The azimuth offset of the numerator `num` (over `2^EDGE_BITS`).
    fn delta(&self, num: u64) -> f64 {
        self.delta_of(num, 1)
    }
    /// The azimuth offset of `num / (2^EDGE_BITS · m)`: one correctly rounded quotient, so
    /// equal rationals give the same bits.
    fn delta_of(&self, num: u64, m: u64) -> f64 {
        self.half * (2.0 * (num as f64 / ((1u64 << EDGE_BITS) * m) as f64) - 1.0)
    }
    /// Numerator (over `den · m`) and angle of bound node `n` of the interval `num`.
    fn node(&self, num: [u64; 2], n: u64) -> (u64, f64) {
        let k = num[0] * self.m + (num[1] - num[0]) * n;
        (k, self.angle(k, self.m))
    }
}

/// Outgoing polar angles (radians, inside `(0, π/2)`, increasing) where `A(θo)` is known to
/// have a kink: the θo slices of an RGL table, which is linear in θo between them
/// ([`brdf::RglBrdf::theta_slices`]). Empty for every other BRDF.
pub(crate) fn theta_kinks(brdf: &dyn Brdf) -> Vec<f64> {
    let Some(rgl) = brdf
        .as_any()
        .and_then(|a| a.downcast_ref::<brdf::RglBrdf>())
    else {
        return Vec::new();
    };
    let eps = 1e-6;
    let mut k: Vec<f64> = rgl
        .theta_kinks() // the slices, and σ's nodes above the last one (issue 27)
        .into_iter()
        .filter(|t| t.is_finite() && *t > eps && *t < std::f64::consts::FRAC_PI_2 - eps)
        .collect();
    k.sort_by(f64::total_cmp);
    k.dedup_by(|a, b| (*a - *b).abs() <= eps);
    k
}

/// Uniform edges closer to a kink than this (degrees) are dropped: the kink replaces them.
const KINK_MERGE_DEG: f64 = 2.0;

/// The initial intervals' edges: `n0` uniform ones, cut at the `kinks` too (a uniform edge
/// within [`KINK_MERGE_DEG`] of a kink gives way to it); `None` without kinks, or with more
/// than [`MAX_BREAKS`] intervals.
fn initial_breaks(n0: usize, kinks: &[f64]) -> Option<Vec<f64>> {
    if kinks.is_empty() {
        return None;
    }
    let merge = KINK_MERGE_DEG.to_radians();
    let mut b: Vec<f64> = (0..=n0)
        .map(|i| std::f64::consts::FRAC_PI_2 * (i as f64 / n0 as f64))
        .filter(|&t| {
            let end = t == 0.0 || t == std::f64::consts::FRAC_PI_2;
            end || kinks.iter().all(|k| (k - t).abs() >= merge)
        })
        .collect();
    b.extend_from_slice(kinks);
    b.sort_by(f64::total_cmp);
    b.dedup();
    (b.len() <= MAX_BREAKS + 1).then_some(b)
}

/// BRDFs slower than this per evaluation (nanoseconds) keep their bound nodes' values for the
/// children of a split interval (measured break-even: beckmann at ~140 ns per evaluation
/// builds as fast with the cache as without).
const CACHE_ABOVE_NS: f64 = 250.0;

/// Mean time of one evaluation of `brdf` (a few thousand directions, one thread).
fn eval_cost_ns(brdf: &dyn Brdf) -> f64 {
    let n = 2048;
    let wo = direction_from_radians(0.6, 0.3);
    let start = Instant::now();
    let mut sink = 0.0;
    for k in 0..n {
        let t = 1.5 * (k as f64 + 0.5) / n as f64;
        let wi = direction_from_radians(t, 2.399 * k as f64);
        sink += brdf.eval(&wo, &wi);
    }
    std::hint::black_box(sink);
    start.elapsed().as_secs_f64() * 1e9 / n as f64
}

/// Where a query lands.
#[derive(Debug, Clone, Copy)]
struct Query {
    cell: usize,
    interval: usize,
    /// The outgoing direction served: the query's, or above [`THETA_TOP_DEG`] the direction of
    /// the same azimuth at that angle.
    wo: Vec3,
    /// The table variable ([`TableVar`]) of the served direction.
    var: f64,
    /// `cos θo`.
    cos: f64,
    delta: f64,
    /// The rotation about the normal from the tree's frame to the world's.
    turn: Turn,
}

impl ExactSet {
    /// Builds the set of `brdf` (intervals in parallel with rayon; the result does not depend
    /// on the thread count). `progress` is called with `(intervals built, intervals queued)`.
    pub fn build(
        brdf: Arc<dyn Brdf>,
        options: &ExactOptions,
        progress: Option<crate::Progress<'_>>,
    ) -> Result<Self, ExactError> {
        Self::build_with(brdf, options, progress, None, true)
    }

    /// [`ExactSet::build`]; `cache` forces the node-value cache on or off (`None`: on for
    /// isotropic BRDFs slower than [`CACHE_ABOVE_NS`] per evaluation). The set is the same
    /// either way. `follow_kinks: false` keeps the uniform initial intervals also for a BRDF
    /// with kinks in θo (the behaviour before issue 27, for comparisons).
    fn build_with(
        brdf: Arc<dyn Brdf>,
        options: &ExactOptions,
        progress: Option<crate::Progress<'_>>,
        cache: Option<bool>,
        follow_kinks: bool,
    ) -> Result<Self, ExactError> {
        options.validate()?;
        let start = Instant::now();
        let isotropic = brdf.is_isotropic();
        let kinks = if follow_kinks {
            theta_kinks(brdf.as_ref())
        } else {
            Vec::new()
        };
        let var = table_var(isotropic, !kinks.is_empty());
        // `follow_kinks: false` also keeps the leaf quadrature for the MERL layout (before
        // issue 27).
        let table_nodes =
            follow_kinks && isotropic && tabulated::table_normaliser_exists(brdf.as_ref());
        // Azimuth cells: the sets' rule (half-turn symmetry halves an even count over [0, π)).
        let layout = layout_for(
            brdf.as_ref(),
            &SetOptions {
                anisotropic_slices: [1, options.initial_phi_cells],
                ..options.set
            },
        );
        let (period, n_cells) = (layout.phi_period(), layout.phi);
        let phi_of = |k: usize| layout.phi_of(k);
        let min_width = options.min_width_deg.to_radians();
        let breaks = initial_breaks(options.initial_intervals, &kinks).map(|b| {
            let mut a = [std::f64::consts::FRAC_PI_2; MAX_BREAKS + 1];
            a[..b.len()].copy_from_slice(&b);
            (b.len() - 1, a)
        });
        let n0 = breaks.map_or(options.initial_intervals, |(n, _)| n) as u64;
        let grid = Grid {
            den: n0 << EDGE_BITS,
            m: options.bound_nodes as u64 - 1,
            half: if isotropic {
                0.0
            } else {
                0.5 * period / n_cells as f64
            },
            breaks: breaks.map(|(_, a)| a),
        };
        // Bit-identical results either way; the cache only pays for expensive isotropic
        // BRDFs. Anisotropic intervals spend most of their evaluations on the normaliser
        // nodes: on poulin-fournier the cache cut the build's evaluations by 16 % and its CPU
        // time by 10 %, for a peak of 280 MB instead of 16 MB (it stays off by default).
        let cache = match cache {
            Some(forced) => forced,
            None => isotropic && eval_cost_ns(brdf.as_ref()) > CACHE_ABOVE_NS,
        };
        let none = Arc::new(Inheritance::default());
        let mut jobs: Vec<Job> = (0..n_cells)
            .flat_map(|cell| {
                let none = &none;
                (0..n0).map(move |i| Job {
                    cell,
                    num: [i << EDGE_BITS, (i + 1) << EDGE_BITS],
                    dnum: [0, 1 << EDGE_BITS],
                    inherited: Arc::clone(none),
                })
            })
            .collect();
        let mut done: Vec<(usize, Placed)> = Vec::new();
        let (mut built, mut queued) = (0usize, jobs.len());
        // Depth first, a few intervals at a time: a split parent's node values are released
        // once its children are built (the set does not depend on the order).
        jobs.reverse();
        let batch_len = 2 * rayon::current_num_threads().max(1);
        while !jobs.is_empty() {
            let batch = jobs.split_off(jobs.len().saturating_sub(batch_len));
            let results: Vec<Result<(Job, Built), ExactError>> = batch
                .par_iter()
                .map(|job| {
                    let ctx = IntervalContext {
                        grid,
                        phi_k: phi_of(job.cell),
                        delta: [grid.delta(job.dnum[0]), grid.delta(job.dnum[1])],
                        var,
                        cache,
                        min_width,
                        table_nodes,
                    };
                    build_interval(&brdf, options, job, &ctx).map(|b| (job.clone(), b))
                })
                .collect();
            let mut next = Vec::new();
            for r in results {
                let (
                    job,
                    Built {
                        interval: iv,
                        inheritance,
                        axis: trials_axis,
                    },
                ) = r?;
                built += 1;
                // The axis to halve (`Some(true)`: δ), if any: too many trials (either axis),
                // or an interpolation tail above the tolerance (or the quadrature's own error,
                // if larger: below it the tail is quadrature noise) along θ or δ.
                let floor = |iv: &Interval| options.normaliser_tol.max(iv.quad_err);
                let axis = match &iv {
                    // `None` only comes from an interval that can be split.
                    None => trials_axis,
                    Some(iv) if iv.worst_trials > options.max_trials && trials_axis.is_some() => {
                        trials_axis
                    }
                    Some(iv)
                        if iv.table.rel_tail_theta() > floor(iv)
                            && job.can_split_theta(&grid, min_width) =>
                    {
                        Some(false)
                    }
                    Some(iv)
                        if iv.table.rel_tail_delta() > floor(iv)
                            && job.can_split_delta(&grid, min_width) =>
                    {
                        Some(true)
                    }
                    Some(_) => None,
                };
                if let Some(delta) = axis {
                    let inheritance = Arc::new(inheritance);
                    for (num, dnum) in job.halves(delta) {
                        next.push(Job {
                            cell: job.cell,
                            num,
                            dnum,
                            inherited: Arc::clone(&inheritance),
                        });
                    }
                    queued += 2;
                } else if let Some(iv) = iv {
                    // Only the edges are kept (the node values go with `job`).
                    done.push((job.cell, (job.num, job.dnum, iv)));
                }
                if let Some(p) = progress {
                    p(built, queued);
                }
            }
            // Children on top of the stack, the left one first.
            jobs.extend(next.into_iter().rev());
        }
        done.sort_by_key(|(cell, (num, dnum, _))| (*cell, num[0], dnum[0]));
        let mut per_cell: Vec<Vec<Placed>> = (0..n_cells).map(|_| Vec::new()).collect();
        for (cell, placed) in done {
            per_cell[cell].push(placed);
        }
        let cells: Vec<Cell> = per_cell
            .into_iter()
            .enumerate()
            .map(|(k, members)| Cell::new(phi_of(k), members, &grid, var))
            .collect();
        Ok(Self {
            brdf,
            options: *options,
            isotropic,
            period,
            cells,
            var,
            top_cos: THETA_TOP_DEG.to_radians().cos(),
            build_time: start.elapsed(),
            counters: AuditCounters::new(),
        })
    }

    /// Number of trees (intervals over all cells).
    pub fn len(&self) -> usize {
        self.cells.iter().map(|c| c.intervals.len()).sum()
    }

    /// `true` when the set has no trees (never for a built set).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The BRDF.
    pub fn brdf(&self) -> &Arc<dyn Brdf> {
        &self.brdf
    }

    /// The options the set was built with.
    pub fn options(&self) -> &ExactOptions {
        &self.options
    }

    /// The tabulated normaliser `A(θo, δ) = ∫ f_r(ωo, ·) cos θi dσ` used by the pdf at `wo`
    /// (`None` below the horizon).
    pub fn normaliser(&self, wo: &Vec3) -> Option<f64> {
        let q = self.locate(wo)?;
        Some(self.interval(&q).normaliser(self.var, &q))
    }

    /// The layout of every azimuth cell: its θ strips and, per strip, its intervals' azimuth
    /// edges.
    pub fn layout(&self) -> Vec<CellLayout> {
        self.cells
            .iter()
            .map(|c| {
                let mut theta_edges_deg = vec![0.0];
                theta_edges_deg.extend(c.upper.iter().map(|t| t.to_degrees()));
                CellLayout {
                    phi_deg: c.phi.to_degrees(),
                    theta_edges_deg,
                    phi_edges_deg: if self.isotropic {
                        Vec::new()
                    } else {
                        c.phi_edges_deg()
                    },
                }
            })
            .collect()
    }

    /// Layout, cost and audit figures.
    pub fn report(&self) -> ExactReport {
        let all = || self.cells.iter().flat_map(|c| c.intervals.iter());
        let own = self.counters.snapshot();
        let (mut violations, mut samples, mut trials) = (own.violations, own.samples, own.trials);
        for iv in all() {
            let s = iv.tree.stats();
            violations += s.bound_violations;
            samples += s.samples;
            trials += s
                .measured_mean_trials
                .map_or(0, |m| (m * s.samples as f64).round() as u64);
        }
        let n = self.len().max(1) as f64;
        ExactReport {
            brdf: self.brdf.name().to_string(),
            cells: self.cells.len(),
            layout: self.layout(),
            trees: self.len(),
            equal_area_trees: all().filter(|iv| iv.map == DiscMap::EqualArea).count(),
            leaves: all().map(|iv| iv.tree.tree().counts().active_leaves).sum(),
            mean_worst_trials: all().map(|iv| iv.worst_trials).sum::<f64>() / n,
            worst_trials: all().map(|iv| iv.worst_trials).fold(0.0, f64::max),
            max_normaliser_rel_err: all().map(|iv| iv.norm_err).fold(0.0, f64::max),
            bound_violations: violations,
            samples,
            trials,
            build_evaluations: all().map(|iv| iv.evaluations).sum(),
            build_time: self.build_time,
            memory_bytes: self.bytes_used(),
        }
    }

    fn interval(&self, q: &Query) -> &Interval {
        &self.cells[q.cell].intervals[q.interval]
    }

    /// Cell, interval, θo, δ and rotation of `wo`; `None` at or below the horizon.
    #[inline]
    fn locate(&self, wo: &Vec3) -> Option<Query> {
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite()) {
            return None;
        }
        let mut served = *wo;
        if wo.z < self.top_cos {
            // f_r at grazing θo may diverge (1/cos θo factors) where no bound node was put:
            // serve the direction at `top` (same azimuth) instead, so that the bounds hold and
            // the pdf stays normalised; the law differs from f_r(ωo, ·) cos θi only there.
            let top = THETA_TOP_DEG.to_radians();
            let (s, r) = (top.sin(), (wo.x * wo.x + wo.y * wo.y).sqrt());
            served = Vec3::new(wo.x / r * s, wo.y / r * s, self.top_cos);
        }
        let wo = &served;
        let cos = wo.z.min(1.0);
        let (cell, turn, delta) = if self.isotropic {
            // The rotation that takes the frame's ωo (at φ = 0) to the query's, without
            // trigonometry: (cos φo, sin φo) = (x, y)/r.
            let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
            let turn = if r > 0.0 {
                Turn {
                    cos: wo.x / r,
                    sin: wo.y / r,
                }
            } else {
                Turn::IDENTITY
            };
            (0, turn, 0.0)
        } else {
            let phi = wo.y.atan2(wo.x);
            let n = self.cells.len();
            let step = self.period / n as f64;
            let k = ((phi.rem_euclid(self.period) / step).round() as usize) % n;
            let rot = phi - self.cells[k].phi;
            let mut delta = rot.rem_euclid(self.period);
            if delta > 0.5 * self.period {
                delta -= self.period;
            }
            (k, walk::turn_from_cell(wo, self.cells[k].phi_turn), delta)
        };
        let var = match self.var {
            TableVar::Cos => cos,
            TableVar::Theta => cos.acos(),
        };
        let interval = self.cells[cell].interval_of(self.var.key(var), delta);
        Some(Query {
            cell,
            interval,
            wo: served,
            var,
            cos,
            delta,
            turn,
        })
    }

    /// One direction; `audit` receives the trials.
    #[inline]
    fn draw(&self, wo: &Vec3, u: &mut dyn UniformSource, audit: &mut Audit) -> Option<DirSample> {
        self.draw_with_f(wo, u, audit).map(|(s, _)| s)
    }

    /// [`ExactSet::draw`] and the `f_r` of the accepted trial, evaluated in the interval's
    /// frame at the served `ωo` (`None` when no trial was accepted or the query was served
    /// at another `ωo`, above [`THETA_TOP_DEG`]).
    #[inline]
    fn draw_with_f(
        &self,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> Option<(DirSample, Option<f64>)> {
        let q = self.locate(wo)?;
        Some(self.draw_located(&q, wo, u, audit))
    }

    /// [`ExactSet::draw_with_f`] at a query already located (`q = self.locate(wo)`).
    #[inline]
    fn draw_located(
        &self,
        q: &Query,
        wo: &Vec3,
        u: &mut dyn UniformSource,
        audit: &mut Audit,
    ) -> (DirSample, Option<f64>) {
        let q = *q;
        let iv = self.interval(&q);
        let g = QueryDensity::in_frame(self.brdf.as_ref(), self.isotropic, &q.wo, q.turn, iv.map);
        let drawn = iv.tree.sample_envelope_of(&|p| g.at(p), u, audit);
        match drawn {
            Some((x, gx)) => {
                let a = iv.normaliser(self.var, &q);
                let v = iv.map.to_direction(x);
                let s = DirSample {
                    wi: q.turn.apply(&v),
                    pdf: iv.map.area_to_solid_angle(gx / a, &v),
                };
                // `g` is `f` (projected map) or `2 f cos θi` (equal-area map, `v.z > 0` where
                // a trial is accepted: `g > 0`).
                let f = match iv.map {
                    DiscMap::Projected => gx,
                    DiscMap::EqualArea => gx / (2.0 * v.z),
                };
                let served = q.wo == *wo;
                (s, (served && f.is_finite()).then_some(f))
            }
            None => (
                DirSample {
                    wi: Vec3::new(0.0, 0.0, 1.0),
                    pdf: 0.0,
                },
                None,
            ),
        }
    }

    /// Draws `per_interval` samples at outgoing directions uniform in every interval (θ
    /// and φ uniform in the interval's ranges) on the calling thread, and counts trials,
    /// BRDF evaluations, violations and exhausted samples (also added to the trees' counts).
    pub fn measure_cost(&self, per_interval: usize, seed: u64) -> crate::CostMeasurement {
        use rand::SeedableRng;
        let before = crate::disc::thread_evaluations();
        let mut total = Audit::default();
        let mut index = 0u64;
        for c in &self.cells {
            for iv in &c.intervals {
                let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(
                    partition_sampler::chunk_seed(seed, index),
                );
                index += 1;
                let ([lo, hi], [da, db]) = (iv.theta, iv.delta);
                let mut a = Audit::default();
                for _ in 0..per_interval {
                    let theta = lo + rng.next_uniform() * (hi - lo);
                    let phi = if self.isotropic {
                        0.0
                    } else {
                        c.phi + da + rng.next_uniform() * (db - da)
                    };
                    let wo = direction_from_radians(theta, phi);
                    let _ = self.draw(&wo, &mut rng, &mut a);
                }
                iv.tree.record_audit(&a);
                total.merge(&a);
            }
        }
        crate::CostMeasurement {
            samples: total.samples,
            trials: total.trials,
            evaluations: crate::disc::thread_evaluations() - before,
            violations: total.violations,
            exhausted: total.exhausted,
        }
    }
}

/// Outgoing polar angles per interval whose peaks bound the interval's envelope near its
/// moving mirror direction (see [`peak_track`]).
const PEAK_TRACK_THETAS: usize = 65;

/// Azimuth offsets per anisotropic interval for the same track (at least; 4 per bound node
/// spacing).
const PEAK_TRACK_DELTAS: usize = 9;

/// Largest azimuth spacing of an interval's δ bound nodes (degrees): an anisotropic lobe turns
/// with δ, and the envelope of nodes farther apart dips below the densities between them (a
/// 90° cell with 3 nodes let 3 trials in 10⁶ exceed their bound on `ward` with
/// `alpha_x = 0.1, alpha_y = 0.3`).
pub const MAX_DELTA_NODE_SPACING_DEG: f64 = 11.25;

/// The peak track of an interval `[ta, tb]` of cell `phi_k` (azimuth offsets `deltas`): for
/// every outgoing direction `(θ, φ_k + δ)` of a fine grid, its mirror direction's point in the
/// interval's frame and disc map, and the member density there (`QueryDensity`).
fn peak_track<'a>(
    brdf: &'a dyn Brdf,
    ta: f64,
    tb: f64,
    phi_k: f64,
    deltas: &[f64],
    map: DiscMap,
) -> Vec<crate::image_map::TrackPoint<'a>> {
    let mut track = Vec::new();
    for n in 0..PEAK_TRACK_THETAS {
        let t = ta + (tb - ta) * n as f64 / (PEAK_TRACK_THETAS - 1) as f64;
        for &d in deltas {
            let wo = direction_from_radians(t, phi_k + d);
            let g = QueryDensity::new(brdf, wo, d, map);
            // `g` evaluates f(ωo, R_d v): its peak is at v = R_{−d} mirror(ωo).
            let at = map.to_disc(&rotate_z(&brdf::mirror(&wo), -d));
            track.push(crate::image_map::TrackPoint {
                at,
                density: Box::new(move |p| g.at(p)),
            });
        }
    }
    track
}

/// What one interval's build needs besides its [`Job`].
struct IntervalContext {
    grid: Grid,
    /// The cell's centre azimuth.
    phi_k: f64,
    /// The interval's azimuth offsets `[δ_a, δ_b]` from the cell's centre (`[0, 0]`:
    /// isotropic).
    delta: [f64; 2],
    /// The set's table variable.
    var: TableVar,
    /// Keep the bound nodes' values for the children.
    cache: bool,
    /// Narrowest interval (radians, θ and azimuth).
    min_width: f64,
    /// Integrate the normaliser nodes in the BRDF's own table cells (the MERL layout,
    /// `tabulated.rs`) instead of on the tree's leaves.
    table_nodes: bool,
}

/// One interval's build: the interval (`None`: to be split) and what its children can reuse.
struct Built {
    interval: Option<Interval>,
    inheritance: Inheritance,
    /// The axis to halve should its mean trials exceed the cap (`Some(true)`: δ; `None`: that
    /// axis is at its narrowest), see [`split_axis`].
    axis: Option<bool>,
}

/// The table variable of a set (`isotropic`: the BRDF's, i.e. one azimuth cell; `tabulated`:
/// the BRDF has kinks in θo, [`theta_kinks`]). A table interpolated linearly in θo (RGL) makes
/// `A` a function of `|θo|` with a kink at normal incidence, i.e. a square root of `1 − cos θo`:
/// its sets keep `v = θo` (on `cc_ibiza_sunset` the `cos θo` table was 4e-4 off at 1.1°).
fn table_var(isotropic: bool, tabulated: bool) -> TableVar {
    if isotropic && !tabulated {
        TableVar::Cos
    } else {
        TableVar::Theta
    }
}

/// Builds the tree and normaliser table of one interval (`None`: its mean trials exceed the cap
/// at a normaliser node, and it can be split), and returns its bound nodes' values (empty
/// unless `ctx.cache`) for its children should it be split.
fn build_interval(
    brdf: &Arc<dyn Brdf>,
    options: &ExactOptions,
    job: &Job,
    ctx: &IntervalContext,
) -> Result<Built, ExactError> {
    let (grid, phi_k, [da, db]) = (ctx.grid, ctx.phi_k, ctx.delta);
    let isotropic = grid.half == 0.0;
    let top = THETA_TOP_DEG.to_radians();
    let theta_b = grid.edge(job.num[1]);
    let (ta, tb) = (grid.edge(job.num[0]).min(top), theta_b.min(top));
    let set = &options.set;
    let map = set
        .disc_map
        .map_for(brdf.as_ref(), theta_b.to_degrees(), set.equal_area_from_deg);
    // δ nodes as exact rationals (see `Grid::delta_of`): a node a split interval shares with
    // its child is the same `f64`, whatever the two node counts.
    let deltas = |n: usize| -> Vec<f64> {
        if isotropic {
            vec![0.0]
        } else {
            let (a, b, m) = (job.dnum[0], job.dnum[1], n as u64 - 1);
            (0..n as u64)
                .map(|k| grid.delta_of(a * m + (b - a) * k, m))
                .collect()
        }
    };
    // Bound nodes at most MAX_DELTA_NODE_SPACING_DEG apart in azimuth.
    let n_delta = options
        .phi_bound_nodes
        .max(((db - da).to_degrees() / MAX_DELTA_NODE_SPACING_DEG - 1e-9).ceil() as usize + 1);
    let mut nodes = Vec::new();
    for n in 0..=grid.m {
        let (num, t) = grid.node(job.num, n);
        // Nodes past the top angle sit at it (no longer the shared rational: not cached).
        let (t, cacheable) = if t > top {
            (top, false)
        } else {
            (t, ctx.cache)
        };
        for d in deltas(n_delta) {
            let key = (num, d.to_bits());
            let inherited = job
                .inherited
                .nodes
                .iter()
                .find(|(k, _)| *k == key && cacheable)
                .map(|(_, v)| Arc::clone(v));
            let wo = direction_from_radians(t, phi_k + d);
            nodes.push(EnvelopeNode::new(
                key,
                brdf.prepare(&wo),
                d,
                inherited,
                cacheable,
            ));
        }
    }
    let n_nodes = nodes.len() as u64;
    let mirror_y = set.symmetries && brdf.is_mirror_symmetric() && isotropic;
    let envelope = Arc::new(IntervalEnvelope {
        brdf: Arc::clone(brdf),
        nodes,
        evaluations: Default::default(),
    });
    let centre = direction_from_radians(0.5 * (ta + tb), phi_k);
    let f = DiscBrdf::with_map(Arc::clone(&envelope) as Arc<dyn Brdf>, centre, map);
    let counter = EvalCounter::new();
    let (theta_deg, phi_deg) = (0.5 * (ta + tb).to_degrees(), phi_k.to_degrees());
    let slice = (ta.to_degrees() * 1000.0) as usize;
    let grid_options = GridOptions {
        refinement: set.grid_refinement,
        mirror_y,
        ..GridOptions::default()
    };
    let image = SliceImageMap::new(
        Counted {
            f: &f,
            counter: &counter,
        },
        set.grid,
        set.safety_factor,
        set.dilation_for(brdf.as_ref()),
        &grid_options,
    )
    .map_err(|source| SetError::Density {
        slice,
        theta_deg,
        phi_deg,
        source,
    })?;
    // The members' peaks: the mirror direction of every outgoing direction of the interval
    // moves with θo (and δ), and a cusp there (Beard–Maxwell) falls between the bound nodes'.
    let image = image.with_track(peak_track(
        brdf.as_ref(),
        ta,
        tb,
        phi_k,
        &deltas(PEAK_TRACK_DELTAS.max(4 * n_delta - 3)),
        map,
    ));
    let params = TreeParams {
        scheme: Scheme::Envelope,
        leaf_choice: LeafChoice::Alias,
        ..set.tree
    };
    let tree = QuadTreeBuilder::from_params(params)
        .build_tree(&image)
        .map_err(|source| SetError::Tree {
            slice,
            theta_deg,
            phi_deg,
            source,
        })?;
    drop(image);
    let axis_from = crate::disc::thread_evaluations();
    let axis = split_axis(
        brdf.as_ref(),
        job,
        ctx,
        &envelope.nodes,
        &tree,
        map,
        options.max_trials,
    );
    let axis_evals = crate::disc::thread_evaluations() - axis_from;
    // Node evaluations: the cached nodes counted their misses, the others every point.
    let cached = envelope.nodes.iter().filter(|n| n.caches()).count() as u64;
    let build_evals = counter.total() * (n_nodes - cached)
        + envelope
            .evaluations
            .load(std::sync::atomic::Ordering::Relaxed);
    // The sampler keeps the envelope without its node values; they go to the children.
    let plain = Arc::new(IntervalEnvelope {
        brdf: Arc::clone(brdf),
        nodes: envelope
            .nodes
            .iter()
            .map(|n| EnvelopeNode::new(n.key, n.wo, n.delta, None, false))
            .collect(),
        evaluations: Default::default(),
    });
    drop(f);
    let f = DiscBrdf::with_map(plain, centre, map);
    // The normaliser at the Chebyshev nodes, by the leaf quadrature of this tree; the δ nodes
    // double (Lobatto-nested) while their tail exceeds the tolerance.
    let var = ctx.var;
    let (va, vb) = (var.of(ta), var.of(tb));
    // Nodes integrated in the table's cells are exact to ~1e-6 but cost ~10⁵ lookups each;
    // `A(θo)` of the MERL layout interpolates to < 1e-5 on 5 of them (`tabulated.rs`).
    let n_theta = if ctx.table_nodes {
        options.normaliser_nodes.min(tabulated::TABLE_NODES)
    } else {
        options.normaliser_nodes
    };
    let theta_nodes = lobatto_nodes(va.min(vb), va.max(vb), n_theta);
    let before = crate::disc::thread_evaluations();
    let volume = tree.volume();
    // The ends and the middle first: a node whose mean trials `ΣV/A` exceed the cap decides a
    // split, and the other nodes' quadratures are not needed.
    let nt = theta_nodes.len();
    let merl_nodes = ctx.table_nodes;
    let mut normalisers: Vec<(NormaliserKey, Normaliser)> = Vec::new();
    let mut nd = options.phi_normaliser_nodes;
    let (table, quad_err) = loop {
        let delta_nodes = if isotropic {
            vec![0.0]
        } else {
            lobatto_nodes(da, db, nd)
        };
        // The nodes the parent integrated first (the split test costs nothing there), then the
        // ends and the middle.
        let known = |own: &[(NormaliserKey, Normaliser)], i: usize, d: f64| {
            let key = (theta_nodes[i].to_bits(), d.to_bits());
            job.inherited
                .normalisers
                .iter()
                .chain(own)
                .find(|(k, _)| *k == key)
                .map(|(_, n)| *n)
        };
        let mut order: Vec<(usize, usize)> = [0, nt - 1, nt / 2]
            .into_iter()
            .chain((1..nt - 1).filter(|&i| i != nt / 2))
            .flat_map(|i| (0..delta_nodes.len()).map(move |j| (i, j)))
            .collect();
        order.sort_by_key(|&(i, j)| known(&normalisers, i, delta_nodes[j]).is_none());
        let mut values = vec![0.0; nt * delta_nodes.len()];
        let mut quad_err = 0.0f64;
        for (i, j) in order {
            let (t, cos, d) = (
                var.theta(theta_nodes[i]),
                var.cos(theta_nodes[i]),
                delta_nodes[j],
            );
            let r = match known(&normalisers, i, d) {
                Some(r) => r,
                None if merl_nodes => {
                    // The MERL layout: integrated over its own bins (`tabulated.rs`).
                    let (total, rel_err) =
                        tabulated::table_normaliser(brdf.as_ref(), t).unwrap_or((f64::NAN, 0.0));
                    let r = Normaliser { total, rel_err };
                    normalisers.push(((theta_nodes[i].to_bits(), d.to_bits()), r));
                    r
                }
                None => {
                    let q = QueryDensity::new(
                        brdf.as_ref(),
                        direction_from_radians(t, phi_k + d),
                        d,
                        map,
                    );
                    // The graded leaf quadrature, its budget by the BRDF (`tabulated.rs`).
                    let r = tabulated::node_quadrature(
                        brdf.as_ref(),
                        &q,
                        tree.leaves(),
                        tree.integral(),
                        mirror_y,
                    );
                    let r = Normaliser {
                        total: r.total,
                        rel_err: r.rel_err,
                    };
                    normalisers.push(((theta_nodes[i].to_bits(), d.to_bits()), r));
                    r
                }
            };
            if !(r.total.is_finite() && r.total > 0.0) {
                return Err(ExactError::Normaliser {
                    value: r.total,
                    theta_deg: t.to_degrees(),
                    phi_deg: (phi_k + d).to_degrees(),
                });
            }
            if axis.is_some() && volume / r.total > options.max_trials {
                return Ok(Built {
                    axis,
                    interval: None,
                    inheritance: Inheritance {
                        nodes: values_of(envelope),
                        normalisers,
                    },
                });
            }
            quad_err = quad_err.max(r.rel_err);
            values[i * delta_nodes.len() + j] = r.total * cos;
        }
        let table = ChebyshevTable::new(theta_nodes.clone(), delta_nodes, values);
        // Interpolation below the quadrature's own error is noise: no refinement past it.
        let floor = options.normaliser_tol.max(quad_err);
        if isotropic || table.rel_tail_delta() <= floor || 2 * nd - 1 > 17 {
            break (table, quad_err);
        }
        nd = 2 * nd - 1;
    };
    let quad_evals = crate::disc::thread_evaluations() - before;
    // The table holds A · cos θ.
    let worst_trials = table
        .values
        .iter()
        .enumerate()
        .map(|(k, ac)| volume * var.cos(table.theta[k / table.delta.len()]) / ac)
        .fold(0.0, f64::max);
    let norm_err = quad_err + table.rel_tail();
    let tree = tree.clone();
    let shape = *tree.shape();
    let sampler = QuadTreeSampler::from_parts(tree, SliceDensity { f, shape })
        .map_err(|source| SetError::Attach { slice, source })?;
    Ok(Built {
        axis,
        interval: Some(Interval {
            theta: [grid.edge(job.num[0]), theta_b],
            delta: ctx.delta,
            tree: sampler,
            map,
            table,
            worst_trials,
            norm_err,
            quad_err,
            evaluations: build_evals + axis_evals + quad_evals,
        }),
        inheritance: Inheritance {
            nodes: values_of(envelope),
            normalisers,
        },
    })
}

/// The axis to halve (`Some(true)`: δ) should the interval's mean trials exceed the cap, if it
/// can be halved along it: θ for isotropic BRDFs; for anisotropic cells the axis along which
/// the bound nodes' densities overlap least. With `g_ij` the density at θ node `i` and δ node
/// `j` and `(c, d)` the middle nodes, the losses `∫ max_i g_id / ∫ g_cd` (θ) and
/// `∫ max_j g_cj / ∫ g_cd` (δ) are compared, by the midpoint rule on 2 × 2 points per leaf
/// of the interval's tree. At grazing angles the lobe changes with θo, not with δ: the θ loss
/// wins, and an interval at its narrowest θ is kept rather than cut in azimuth for nothing.
fn split_axis(
    brdf: &dyn Brdf,
    job: &Job,
    ctx: &IntervalContext,
    nodes: &[EnvelopeNode],
    tree: &partition_sampler::QuadTree,
    map: DiscMap,
    max_trials: f64,
) -> Option<bool> {
    let (grid, min_width) = (&ctx.grid, ctx.min_width);
    if grid.half == 0.0 || !job.can_split_delta(grid, min_width) {
        return job.can_split_along(grid, min_width, false);
    }
    let n_theta = grid.m as usize + 1;
    let n_delta = nodes.len() / n_theta;
    let (c, d) = (n_theta / 2, n_delta / 2);
    let g: Vec<QueryDensity> = nodes
        .iter()
        .map(|n| QueryDensity::new(brdf, *n.wo.wo(), n.delta, map))
        .collect();
    let (mut centre, mut theta, mut delta) = (0.0, 0.0, 0.0);
    for leaf in tree.leaves() {
        let r = leaf.rect;
        let w = 0.25 * (r.x1 - r.x0) * (r.y1 - r.y0);
        for (a, b) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
            let p = [r.x0 + a * (r.x1 - r.x0), r.y0 + b * (r.y1 - r.y0)];
            let at = |i: usize, j: usize| g[i * n_delta + j].at(p);
            let mid = at(c, d);
            let others = |n: usize, skip: usize, f: &dyn Fn(usize) -> f64| {
                (0..n).filter(|&k| k != skip).map(f).fold(mid, f64::max)
            };
            centre += w * mid;
            theta += w * others(n_theta, c, &|i| at(i, d));
            delta += w * others(n_delta, d, &|j| at(c, j));
        }
    }
    // θ unless the azimuth loses clearly more (the axis of the isotropic sets; near grazing
    // the mean trials of a single node exceed the cap, and only θ splits take the interval
    // away from the top angle where the bounds cannot follow the lobe).
    let by_delta = centre > 0.0
        && delta > theta
        && delta > (1.0 + MIN_DELTA_LOSS) * centre
        && tree.volume() / delta <= max_trials;
    job.can_split_along(grid, min_width, by_delta)
}

/// Relative overlap loss along δ below which an interval is not cut in azimuth
/// ([`split_axis`]).
const MIN_DELTA_LOSS: f64 = 0.1;

/// The values the caching nodes of a built interval know, for its children.
fn values_of(envelope: Arc<IntervalEnvelope>) -> Vec<(NodeKey, Arc<NodeValues>)> {
    match Arc::try_unwrap(envelope) {
        Ok(env) => env
            .nodes
            .into_iter()
            .filter(|n| n.caches())
            .map(EnvelopeNode::into_values)
            .collect(),
        Err(_) => Vec::new(),
    }
}

impl DirectionSampler for ExactSet {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let mut a = Audit::default();
        match self.draw(wo, u, &mut a) {
            Some(s) => {
                self.counters.record(&a);
                s
            }
            None => DirSample {
                wi: Vec3::new(0.0, 0.0, 1.0),
                pdf: 0.0,
            },
        }
    }

    /// The accepted trial's `f` when `brdf` is the set's own BRDF object and the query was
    /// served at its own `ωo` (θo ≤ [`THETA_TOP_DEG`]); otherwise one evaluation of `brdf`.
    fn sample_eval(&self, brdf: &dyn Brdf, wo: &Vec3, u: &mut dyn UniformSource) -> EvalSample {
        let mut a = Audit::default();
        let Some((s, f)) = self.draw_with_f(wo, u, &mut a) else {
            return EvalSample::NONE;
        };
        self.counters.record(&a);
        self.finish(brdf, wo, s, f)
    }

    /// Queries grouped by interval (a counting sort), each group drawn while its tree is
    /// hot; see [`ExactSet::sample_eval_grouped`].
    fn sample_eval_batch(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn UniformSource,
        out: &mut Vec<EvalSample>,
    ) {
        self.sample_eval_grouped(brdf, wos, u, out);
    }

    /// `f_r(ωo, ωi) cos θi / A(θo, δ)` above the horizon, 0 below.
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let Some(q) = self.locate(wo) else {
            return 0.0;
        };
        let a = self.interval(&q).normaliser(self.var, &q);
        self.brdf.eval(&q.wo, wi) * wi.z / a
    }

    fn bound_violations(&self) -> Option<u64> {
        let trees: u64 = self
            .cells
            .iter()
            .flat_map(|c| c.intervals.iter())
            .map(|iv| iv.tree.stats().bound_violations)
            .sum();
        Some(trees + self.counters.snapshot().violations)
    }

    fn normaliser_rel_err(&self, wo: &Vec3) -> Option<f64> {
        let q = self.locate(wo)?;
        Some(self.interval(&q).norm_err)
    }

    /// The [`ExactReport`]: the interval layout per azimuth cell, trials, normaliser error,
    /// audit, build cost and memory.
    fn build_report(&self) -> Option<String> {
        Some(self.report().to_string())
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + self
                .cells
                .iter()
                .map(|c| {
                    std::mem::size_of::<Cell>()
                        + c.upper.capacity() * 8
                        + c.intervals
                            .iter()
                            .map(|iv| {
                                std::mem::size_of::<Interval>()
                                    + iv.tree.bytes_used()
                                    + iv.table.bytes_used()
                            })
                            .sum::<usize>()
                })
                .sum::<usize>()
    }
}

#[cfg(test)]
mod tests;
