//! The settings of an [`ExactSet`](crate::ExactSet)(crate::ExactSet) and its public constants.

use crate::options::SetOptions;

use super::error::ExactError;

/// The largest outgoing polar angle the nodes use (degrees): `f_r` at exactly 90° is 0 or
/// undefined. A query above it is served as the direction of the same azimuth at this angle
/// (samples ∝ `f_r(ωo', ·) cos θi`, pdf normalised, bounds valid; `f_r` may diverge there).
pub const THETA_TOP_DEG: f64 = 89.99;

/// Largest azimuth spacing of an interval's δ bound nodes (degrees): an anisotropic lobe turns
/// with δ, and the envelope of nodes farther apart dips below the densities between them (a
/// 90° cell with 3 nodes let 3 trials in 10⁶ exceed their bound on `ward` with
/// `alpha_x = 0.1, alpha_y = 0.3`).
pub const MAX_DELTA_NODE_SPACING_DEG: f64 = 11.25;

/// Settings of [`ExactSet`](crate::ExactSet). `set` supplies the tree parameters, image map, safety factor,
/// disc-map policy and symmetries (its slice counts are unused: the intervals and azimuth cells
/// adapt).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
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
