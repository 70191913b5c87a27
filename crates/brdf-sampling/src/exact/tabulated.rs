//! Normaliser nodes of tabulated BRDFs integrated in the table's own cells (issue 27).
//!
//! The MERL layout's nearest-bin lookup is piecewise constant with edges everywhere in `ωi`:
//! the leaf quadrature of an interval's tree (a Gauss rule, 16 000 evaluations) was 10⁻³ off
//! at a node, and no interpolation in θo can repair that. [`brdf::MerlBrdf::albedo_in_bins`]
//! integrates the table over its bins instead (exact rings of constant half-vector angle, an
//! adaptive rule across them), to [`MERL_REL_TOL`] within [`MERL_BUDGET`] lookups.

use brdf::{Brdf, MerlBrdf};

use crate::disc::count_evaluations;

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
