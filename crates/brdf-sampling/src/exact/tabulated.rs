//! Normaliser nodes of tabulated BRDFs integrated in the table's own cells (issue 27).
//!
//! The MERL layout's nearest-bin lookup is piecewise constant with edges everywhere in `ωi`:
//! the leaf quadrature of an interval's tree (a Gauss rule, 16 000 evaluations) was 10⁻³ off
//! at a node, and no interpolation in θo can repair that. [`brdf::MerlBrdf::albedo_in_bins`]
//! integrates the table over its bins instead (exact rings of constant half-vector angle, an
//! adaptive rule across them), to [`MERL_REL_TOL`] within [`MERL_BUDGET`] lookups.
//!
//! The Cornell interpolant (k nearest scattered samples with cut Gaussian weights) has kinks on
//! surfaces no coordinate follows, everywhere in `ωi`: the leaf quadrature of an interval's
//! tree was up to 7·10⁻⁴ off at 16 000 evaluations. Its nodes are now the reference rule at
//! `ωo` itself ([`crate::reference_albedo_with_budget`], the leaves refined around the mirror
//! direction, [`CORNELL_NODE_BUDGET`] evaluations), integrated for one table of `A(θo)` per
//! set (`set_table.rs`) from which the intervals take their nodes. The MERL nodes are kept
//! once per build ([`NodeCache`]: an interval's ends are its neighbours' ends).
//!
//! The RGL tables' bilinear interpolants have kinks along the cells of the warped square and
//! of the `ndf` grid, which no leaf follows: the leaf quadrature of an interval's tree was up
//! to 1.1·10⁻⁴ off at a node even at 48 000 evaluations (`colodur_napoli_4f` at 37.03°), and
//! the reference rule at `ωo` (100 000 evaluations, docs/benchmarks.md §13.12) up to 5·10⁻⁴
//! on `cc_ibiza_sunset` above 88°. Their nodes are now integrated over the interpolant's own
//! cells ([`crate::rgl_albedo_in_cells`] at [`RGL_CELL_NODE_ORDER`] points per piece: every
//! kink and the horizon followed, ~10⁻⁷ at fewer evaluations), kept per build in the
//! [`NodeCache`]; docs/benchmarks.md §13.13.
//!
//! The other nodes keep the leaf quadrature of the interval's tree ([`node_quadrature`]; RGL
//! data with `follow_kinks: false` at [`RGL_NODE_BUDGET`]).

use std::collections::HashMap;
use std::sync::Mutex;

use brdf::measured::cornell::Interpolation;
use brdf::{Brdf, CornellBrdf, MerlBrdf, RglBrdf, direction_from_radians};
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

/// Evaluations of one Cornell normaliser node (the reference rule's budget; its default is
/// 4·10⁶). Measured on the three shared files at 11 angles from 2.8° to 89.9° against the
/// same rule at 10⁶ evaluations: docs/benchmarks.md §13.11.
pub(crate) const CORNELL_NODE_BUDGET: u64 = 150_000;

/// Gauss points per piece and axis of an RGL normaliser node ([`crate::rgl_albedo_in_cells`];
/// its error estimate is the same rule at 1 point). Replaces the reference rule at 100 000
/// evaluations, which was up to 5·10⁻⁴ off on `cc_ibiza_sunset` at 88.5–89.9°
/// (docs/benchmarks.md §13.13).
pub(crate) const RGL_CELL_NODE_ORDER: usize = 2;

/// Largest interpolation tail a Cornell interval keeps (relative). The tail test of the
/// build stops at the nodes' own error estimate (below it the tail is quadrature noise), but
/// the reference rule's estimate (`Σ |I₈ − I₅|`) is 3–10 × its actual error here, so the
/// tail is held to this instead when it is smaller.
pub(crate) const CORNELL_TAIL_CAP: f64 = 2e-5;

/// `(A, relative error estimate)` at the outgoing polar angle `theta` (radians) by a rule
/// that does not depend on the interval (the MERL layout's integral in its own cells; the
/// reference rule for Cornell data); `None` for every other BRDF (the caller integrates on
/// the tree's leaves). The evaluations are counted as evaluations of the build (on the
/// calling thread's [`crate::thread_evaluations`]).
pub(crate) fn table_normaliser(brdf: &dyn Brdf, theta: f64) -> Option<(f64, f64)> {
    let (value, rel, evaluations) = table_normaliser_uncounted(brdf, theta)?;
    count_evaluations(evaluations);
    Some((value, rel))
}

/// [`table_normaliser`] with its BRDF evaluations returned, `(A, relative error estimate,
/// evaluations)`, and not added to the thread's counter (the node cache charges them to an
/// interval by a rule that does not depend on the build's schedule, [`NodeCache::get`]).
fn table_normaliser_uncounted(brdf: &dyn Brdf, theta: f64) -> Option<(f64, f64, u64)> {
    let any = brdf.as_any()?;
    let (value, abs_err, evaluations) = if let Some(merl) = any.downcast_ref::<MerlBrdf>() {
        let a = merl.albedo_in_bins(theta, MERL_REL_TOL, MERL_BUDGET);
        (a.value, a.abs_err, a.evaluations)
    } else if let Some(rgl) = any.downcast_ref::<RglBrdf>() {
        // Evaluated through `brdf` (a counting wrapper counts them).
        match crate::reference::albedo_in_cells_of(brdf, rgl, theta, RGL_CELL_NODE_ORDER) {
            Ok(a) => (a.value, a.abs_err, a.evaluations),
            Err(_) => (f64::NAN, f64::INFINITY, 0),
        }
    } else if let Some((value, abs_err)) = any
        .downcast_ref::<CornellBrdf>()
        .filter(|c| c.interpolation() == Interpolation::Grid)
        .and_then(|c| c.grid_albedo(theta))
    {
        // The tabulated interpolant's albedo, exact up to rounding (docs/benchmarks.md §24.6).
        (value, abs_err, 0)
    } else if let Some(cornell) = any.downcast_ref::<CornellBrdf>() {
        // The reference rule on the material's quadrature evaluator, its bound declared
        // (docs/benchmarks.md §27.3).
        let wo = direction_from_radians(theta, 0.0);
        match crate::reference::cornell_node_albedo(cornell, &wo, CORNELL_NODE_BUDGET) {
            Ok(a) => (a.value, a.abs_err, a.evaluations),
            Err(_) => (f64::NAN, f64::INFINITY, 0),
        }
    } else {
        return None;
    };
    let rel = if value > 0.0 {
        abs_err / value
    } else {
        f64::INFINITY
    };
    Some((value, rel, evaluations))
}

/// Whether [`table_normaliser`] serves `brdf`.
pub(crate) fn table_normaliser_exists(brdf: &dyn Brdf) -> bool {
    brdf.as_any()
        .is_some_and(|a| a.is::<MerlBrdf>() || a.is::<CornellBrdf>() || a.is::<RglBrdf>())
}

/// Whether `brdf`'s set tabulates `A` over `θo` rather than `cos θo`: the Cornell interpolant
/// depends on `sin θo` (its first remapped coordinate), so `A` is linear in `θo` at normal
/// incidence, a square root of `1 − cos θo`.
pub(crate) fn tabulates_over_theta(brdf: &dyn Brdf) -> bool {
    brdf.as_any().is_some_and(|a| a.is::<CornellBrdf>())
}

/// The largest interpolation tail a set of `brdf` keeps, whatever its nodes' error estimate
/// (`f64::INFINITY`: the estimate decides, see [`CORNELL_TAIL_CAP`]).
pub(crate) fn tail_cap(brdf: &dyn Brdf) -> f64 {
    if tabulates_over_theta(brdf) {
        CORNELL_TAIL_CAP
    } else {
        f64::INFINITY
    }
}

/// The [`table_normaliser`] values a build has integrated, by the bits of `θo`: shared by
/// its intervals (adjacent intervals share their ends, a split interval's middle is its
/// children's end). The values depend on `θo` alone, so the set does not depend on which
/// interval integrated a node first. Each entry also keeps the node's evaluation count `E(θo)`
/// (a function of `θo` alone too), so that a build can charge it to an interval by a fixed
/// rule rather than to whichever interval asked first (docs/benchmarks.md §32.2).
#[derive(Default)]
pub(crate) struct NodeCache(Mutex<HashMap<u64, (f64, f64, u64)>>);

impl NodeCache {
    /// `(A, relative error, E)` at `theta`: [`table_normaliser`]'s value and error, and the
    /// evaluations `E` its rule makes at `theta` — whether this call integrated the node or
    /// found it integrated (nothing is added to the thread's counter: the caller charges `E`).
    /// Integrated once per build (two calls racing on a new node may both integrate it; they
    /// store the same bits).
    pub(crate) fn get(&self, brdf: &dyn Brdf, theta: f64) -> Option<(f64, f64, u64)> {
        let key = theta.to_bits();
        if let Some(v) = self.0.lock().ok().and_then(|m| m.get(&key).copied()) {
            return Some(v);
        }
        let v = table_normaliser_uncounted(brdf, theta)?;
        if let Ok(mut m) = self.0.lock() {
            m.insert(key, v);
        }
        Some(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 27 (docs/benchmarks.md §13.12, §13.13): RGL normaliser nodes agree with the
    /// reference rule at 2·10⁶ evaluations (an independent rule; its own error ~10⁻⁶ on this
    /// file) inside a slice and grazing, within 3·10⁻⁵ and within the node's error estimate.
    /// Before §13.12, RGL nodes were the leaf quadrature of the interval's tree
    /// ([`table_normaliser`] gave `None`), up to 1.1·10⁻⁴ off (`colodur_napoli_4f` at 37.03°,
    /// a node of the 28.45–40.86° interval).
    #[test]
    fn rgl_nodes_agree_with_the_reference_rule() {
        let Some(rgl) = super::super::tests::paper_white_fixture() else {
            return;
        };
        assert!(table_normaliser_exists(&rgl));
        for deg in [37.03f64, 88.3] {
            let theta = deg.to_radians();
            let (a, rel) = table_normaliser(&rgl, theta).expect("an RGL node");
            let wo = direction_from_radians(theta, 0.0);
            let reference =
                crate::reference::reference_albedo_with_budget(&rgl, &wo, 2_000_000).unwrap();
            let gap = (a / reference.value - 1.0).abs();
            assert!(
                gap <= 3e-5,
                "θo {deg}°: node {a} vs {}: {gap:e}",
                reference.value
            );
            assert!(
                gap <= rel,
                "θo {deg}°: gap {gap:e} above the estimate {rel:e}"
            );
        }
    }

    /// Issue 27 item 4 (docs/benchmarks.md §13.13): at grazing angles of `cc_ibiza_sunset`
    /// the RGL nodes are within 10⁻⁵ of the albedo integrated over the interpolant's cells at
    /// [`crate::RGL_CELL_ORDER`] (its own error ≤ 6·10⁻⁸ there, and within 4·10⁻⁶ of the
    /// 4·10⁶-evaluation reference rule) and within their own estimate. The nodes of §13.12 (the
    /// reference rule at 100 000 evaluations) were 2.1·10⁻⁴ and 5.1·10⁻⁴ off at 88.5° and
    /// 89.5°. Skipped without the team's data beside the repository.
    #[test]
    fn rgl_nodes_follow_the_cells_at_grazing_angles() {
        let Some(rgl) = crate::reference::rgl_tests_ibiza() else {
            return;
        };
        for deg in [88.5f64, 89.5] {
            let theta = deg.to_radians();
            let (a, rel) = table_normaliser(&rgl, theta).expect("an RGL node");
            let c = crate::rgl_reference_albedo(&rgl, theta).expect("cells");
            let gap = (a / c.value - 1.0).abs();
            assert!(gap <= 1e-5, "θo {deg}°: node {a} vs cells {c:?}: {gap:e}");
            assert!(
                gap <= rel,
                "θo {deg}°: gap {gap:e} above the estimate {rel:e}"
            );
        }
    }

    /// The whole `adaptive-exact` normaliser of `cc_ibiza_sunset` against the cell rule up to
    /// 89.9° (issue 27 item 4's goal, `|A/Â − 1| ≤ 10⁻⁴`). A build of ~15 CPU-s: run with
    /// `cargo test --release -p brdf-sampling -- --ignored ibiza_normaliser`.
    #[test]
    #[ignore = "builds a full set (~15 CPU-s); docs/benchmarks.md §13.13"]
    fn ibiza_normaliser_meets_1e4_up_to_89_9() {
        let Some(rgl) = crate::reference::rgl_tests_ibiza() else {
            return;
        };
        let set = crate::ExactSet::build(
            std::sync::Arc::new(rgl.clone()),
            &crate::ExactOptions::with_set(crate::SetOptions::default()),
            None,
        )
        .expect("build");
        for deg in [30.0f64, 84.6, 87.6, 88.0, 88.5, 89.0, 89.5, 89.9] {
            let theta = deg.to_radians();
            let a_hat = set
                .normaliser(&direction_from_radians(theta, 0.0))
                .expect("normaliser");
            let c = crate::rgl_reference_albedo(&rgl, theta).expect("cells");
            let gap = (c.value / a_hat - 1.0).abs();
            assert!(gap <= 1e-4, "θo {deg}°: Â {a_hat} vs cells {c:?}: {gap:e}");
        }
    }
}
