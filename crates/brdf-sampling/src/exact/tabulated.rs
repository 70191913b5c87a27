//! Normaliser nodes of tabulated BRDFs integrated in the table's own cells (issue 27).
//!
//! The MERL layout's nearest-bin lookup is piecewise constant with edges everywhere in `ωi`:
//! the leaf quadrature of an interval's tree (a Gauss rule, 16 000 evaluations) was 10⁻³ off
//! at a node, and no interpolation in θo can repair that. [`brdf::MerlBrdf::albedo_in_bins`]
//! integrates the table over its bins instead (exact rings of constant half-vector angle, an
//! adaptive rule across them), to [`MERL_REL_TOL`] within [`MERL_BUDGET`] lookups.
//!
//! The other nodes keep the leaf quadrature of the interval's tree ([`node_quadrature`]), with
//! a larger budget for the RGL tables ([`RGL_NODE_BUDGET`]): their bilinear interpolants have
//! kinks along the cells of the warped square and of the `ndf` grid, which no leaf follows.

use brdf::{Brdf, MerlBrdf, RglBrdf};
use partition_sampler::{Density, LeafInfo};

use crate::disc::count_evaluations;
use crate::normalisation::{EVALUATION_BUDGET, Grading, LeafIntegrals, TOL, adaptive_quadrature};

/// Evaluation budget of one RGL normaliser node (the leaf quadrature's default is
/// [`EVALUATION_BUDGET`]). At 16 000 the nodes of `paper_white` and `colodur_napoli_4f` were
/// up to 1.0·10⁻⁴ and 8.9·10⁻⁵ off (the rule run at the query itself against two independent
/// references that agree to 10⁻⁶; docs/benchmarks.md §13.10): the kinks of the interpolant
/// cross the leaves everywhere, and the rule's error falls about like `1/budget`.
pub(crate) const RGL_NODE_BUDGET: u64 = 48_000;

/// The evaluation budget of a leaf-quadrature normaliser node of `brdf`.
pub(crate) fn node_budget(brdf: &dyn Brdf) -> u64 {
    if brdf.as_any().is_some_and(|a| a.is::<RglBrdf>()) {
        RGL_NODE_BUDGET
    } else {
        EVALUATION_BUDGET
    }
}

/// A normaliser node by the graded leaf quadrature of the interval's tree: `f` (the slice's
/// density of `brdf`) over `leaves`, to `TOL · scale` within [`node_budget`] evaluations.
pub(crate) fn node_quadrature(
    brdf: &dyn Brdf,
    f: &dyn Density,
    leaves: impl Iterator<Item = LeafInfo>,
    scale: f64,
    mirror: bool,
) -> LeafIntegrals {
    adaptive_quadrature(
        f,
        leaves,
        TOL * scale,
        mirror,
        node_budget(brdf),
        Grading::Graded,
    )
}

/// Relative error target of a MERL normaliser node. Its estimate is the 2-point Gauss rule's
/// difference from the midpoint rule, summed over the pieces: conservative, the actual error
/// measured 10–100 × smaller on the MERL layout of `phong:n=50` (1e-6 at this target up to
/// 85°, 6e-6 at 89°, against the same rule at 1e-8).
pub(crate) const MERL_REL_TOL: f64 = 1e-4;

/// Chebyshev nodes per interval of a set whose nodes are integrated in the table's cells
/// (at most the options' count): with exact node values the MERL layout's interpolation tails
/// stay below 1e-5 on the default layout, and each node costs ~10⁵ lookups.
pub(crate) const TABLE_NODES: usize = 5;

/// Most table lookups of one MERL normaliser node (about 10⁵ reach [`MERL_REL_TOL`] up to
/// 85°; 89.5° needs 5 · 10⁶, and stops at this budget with its estimate declared).
pub(crate) const MERL_BUDGET: u64 = 1_000_000;

/// `(A, relative error estimate)` at the outgoing polar angle `theta` (radians) integrated in
/// the table's own cells, for BRDFs that have such an integral (the MERL layout); `None` for
/// every other BRDF (the caller integrates on the tree's leaves). The lookups are counted as
/// evaluations of the build.
pub(crate) fn table_normaliser(brdf: &dyn Brdf, theta: f64) -> Option<(f64, f64)> {
    let merl = brdf.as_any()?.downcast_ref::<MerlBrdf>()?;
    let a = merl.albedo_in_bins(theta, MERL_REL_TOL, MERL_BUDGET);
    count_evaluations(a.evaluations);
    let rel = if a.value > 0.0 {
        a.abs_err / a.value
    } else {
        f64::INFINITY
    };
    Some((a.value, rel))
}

/// Whether [`table_normaliser`] serves `brdf`.
pub(crate) fn table_normaliser_exists(brdf: &dyn Brdf) -> bool {
    brdf.as_any().is_some_and(|a| a.is::<MerlBrdf>())
}
