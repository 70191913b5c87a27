//! `adaptive-exact`: samples exactly ∝ `f_r(ωo, ·) cos θi` at **every** outgoing direction,
//! with interval-bounded trees (issue 14).
//!
//! # Math
//! The outgoing angles are partitioned into θ intervals `[θ_a, θ_b]` (for anisotropic BRDFs,
//! rectangles `[θ_a, θ_b] × [δ_a, δ_b]` of azimuth cells with centres `φ_k`, offsets
//! `δ ∈ [−h, h]`, [`ExactOptions::initial_phi_cells`] of them before splitting;
//! half-turn-symmetric BRDFs store `[0, π)`). Each interval holds one quadtree
//! on the unit disc of its [`DiscMap`](crate::disc::DiscMap) (equal-area when `θ_b` reaches
//! [`SetOptions::equal_area_from_deg`](crate::options::SetOptions::equal_area_from_deg) or the BRDF is unbounded at the horizon), built with the
//! set's image map, rim band, safety factor and tree parameters from the **envelope**
//! `F(x) = max_n g_n(x)` of the query densities at the interval's bound nodes (a uniform grid
//! of [`ExactOptions::bound_nodes`] θ values × [`ExactOptions::phi_bound_nodes`] δ values of
//! the interval).
//! The leaf bounds `M_i` thus hold for every outgoing direction of the interval (between the
//! nodes, the safety factor covers the envelope's dips; every trial above its bound is counted
//! by the audit, [`crate::SamplerDiagnostics::bound_violations`]).
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
//! a MERL table over its own bins instead, 5 nodes per interval, `tabulated.rs`; Cornell data
//! from one table of `A(θo)` per set, `set_table.rs`; issue 27);
//! the δ nodes are doubled (Lobatto-nested, up to 17) while the δ tail exceeds the same floor;
//! `A · cos θo` is interpolated ([`chebyshev`]): it stays smooth up to grazing angles for models
//! whose `f_r` has a `1/cos θo` factor (Beard–Maxwell, Ward), where `A` itself diverges. The
//! table's variable is `cos θo` for isotropic BRDFs (`A` is even in `θo`, so smooth in
//! `cos θo`; a query then needs no `acos`) and `θo` for anisotropic cells ([`TableVar`](grid::TableVar)). The
//! reported normaliser error is the quadrature's estimate plus the interpolation's (the
//! Chebyshev tail).
//!
//! **Adaptive intervals.** An interval is halved while its tree would need more than
//! [`ExactOptions::max_trials`] mean trials at one of its normaliser nodes (`Σ V_i / A`) or its
//! θ (δ) interpolation tail exceeds [`ExactOptions::normaliser_tol`] (or the quadrature's own
//! error estimate, if larger: below it the tail is quadrature noise), down to
//! [`ExactOptions::min_width_deg`]: sharp lobes and grazing angles get narrow intervals, smooth
//! models keep the initial ones. The initial intervals are also cut at the BRDF's known
//! **kinks in θo** ([`theta_kinks`](grid::theta_kinks): the θo slices of an RGL table, linear in θo between
//! them), so that no interval's Chebyshev table has to follow a kink of `A(θo)` (on the RGL
//! fixture `|A/Â − 1|` went from 2.1e-3 next to a slice to below 1e-4 up to 85°, issue 27).
//! Too many trials halve θ, or δ when the bound nodes'
//! densities overlap clearly less along δ than along θ and the azimuth loss alone explains the
//! excess (`split_axis`): an anisotropic lobe far from the normal gets narrow azimuth cells, the
//! rest of the hemisphere wide ones. The layout is reported by [`ExactSet::report`].
//!
//! **Build cost.** Interval edges and bound nodes are exact rationals of `π/2` (one
//! denominator for the set), so a halved interval's ends and midpoint are bound nodes of its
//! children too, with the same bits; for isotropic BRDFs slower than [`CACHE_ABOVE_NS`](build::CACHE_ABOVE_NS) per
//! evaluation, a child looks up the values its parent's nodes took at the same incident
//! directions of the image-map lattice instead of evaluating them again (bit-identical; with
//! 3 nodes a child evaluates one node afresh). The normaliser nodes are integrated ends and
//! middle first: the first whose `ΣV/A` exceeds the cap decides the split, and the others are
//! not integrated. A child takes the normaliser at the end it shares with its parent from the
//! parent's quadrature (same node bits), and a doubled δ grid keeps the nodes it already has;
//! each quadrature uses the graded rule (`normalisation::Grading::Graded`: orders 5 and 3
//! first, order 8 only on the pieces that need it).

mod aniso_record;
mod batch;
mod batch_aniso;
mod build;
mod build_interval;
mod chebyshev;
mod density;
mod error;
mod fused;
mod grid;
mod interval;
mod iso_record;
mod jobs;
mod lanes;
mod layout;
mod lookup;
mod options;
mod persist;
mod phases;
mod probe;
mod report;
mod rgl_bound;
mod sampler;
mod set;
mod set_table;
mod table;
mod tabulated;
mod walk;
mod wave_aniso;
mod wave_iso;

pub use error::ExactError;
pub use options::{
    ExactOptions, MAX_DELTA_NODE_SPACING_DEG, RGL_MAX_DEPTH, RGL_N_MAX, RGL_VOLUME_TOLERANCE,
    THETA_TOP_DEG, envelope_grid, envelope_tree_params,
};
pub use persist::EXACT_FORMAT_VERSION;
pub use phases::{BuildPhases, PhaseCounts};
pub use report::{CellLayout, ExactReport};
pub use set::ExactSet;

use interval::Query;

#[cfg(test)]
mod tests;
