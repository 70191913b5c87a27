//! What building a factored sampler reports, and why it can fail.

use std::fmt;

use crate::factored::nmf::{NmfError, NmfStats};
use crate::options::{FactoredOptionsError, NmfCost, Reparam};

/// The build report of a [`crate::FactoredSampler`]: the factorisation's fit and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct FactoredReport {
    /// Half-angle or spherical.
    pub reparam: Reparam,
    /// The factorisation's cost.
    pub cost: NmfCost,
    /// Whether rows are `θo` only (isotropic variant, frame turned by `φo`) or `θo × φo`.
    pub rows_theta_only: bool,
    /// Rows of the data matrix (outgoing cells).
    pub rows: usize,
    /// Columns of the data matrix (`θp × φp` cells).
    pub cols: usize,
    /// Outer terms `J`.
    pub outer_terms: usize,
    /// Inner terms `K`.
    pub inner_terms: usize,
    /// The first level, `Y ≈ F G`: iterations, convergence, cost and
    /// `‖Y − FG‖_F / ‖Y‖_F`.
    pub outer: NmfStats,
    /// The second level, one per `j`: `G_j ≈ U_j V_j` on the `θp × φp` grid.
    pub inner: Vec<NmfStats>,
    /// `‖G − Ĝ‖_F / ‖G‖_F` over all `j` (`Ĝ_j = U_j V_j`).
    pub inner_relative_error: f64,
    /// `‖Y − F Ĝ‖_F / ‖Y‖_F`: how well the sampled representation fits the data.
    pub total_relative_error: f64,
    /// The defensive cosine weight `α`.
    pub defensive_alpha: f64,
    /// Wall-clock seconds of the build (data matrix and both factorisations).
    pub build_seconds: f64,
    /// Bytes of the sampling tables.
    pub bytes: usize,
}

impl FactoredReport {
    /// Whether every factorisation met its tolerance before the iteration cap.
    pub fn converged(&self) -> bool {
        self.outer.converged && self.inner.iter().all(|s| s.converged)
    }
}

impl fmt::Display for FactoredReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let inner_iters: usize = self.inner.iter().map(|s| s.iterations).sum();
        let inner_converged = self.inner.iter().all(|s| s.converged);
        write!(
            f,
            "factored   {} rows ({}) × {} cols ({}), J = {}, K = {}, {} cost, α = {}\n\
             outer NMF  {} iterations, {}, relative error {:.4e}\n\
             inner NMF  {} iterations over {} factorisations, {}, relative error {:.4e}\n\
             total      relative error ‖Y − FĜ‖/‖Y‖ = {:.4e}; build {:.3} s, {} bytes",
            self.rows,
            if self.rows_theta_only {
                "θo only, turned by φo"
            } else {
                "θo × φo"
            },
            self.cols,
            self.reparam.name(),
            self.outer_terms,
            self.inner_terms,
            self.cost.name(),
            self.defensive_alpha,
            self.outer.iterations,
            converged_word(self.outer.converged),
            self.outer.relative_error,
            inner_iters,
            self.inner.len(),
            converged_word(inner_converged),
            self.inner_relative_error,
            self.total_relative_error,
            self.build_seconds,
            self.bytes
        )
    }
}

fn converged_word(c: bool) -> &'static str {
    if c {
        "converged"
    } else {
        "NOT converged (iteration cap; residual above)"
    }
}

/// A factored sampler could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FactoredError {
    /// An option is outside its range.
    #[error(transparent)]
    Options(#[from] FactoredOptionsError),
    /// The BRDF returned a negative or non-finite value.
    #[error(
        "factored: the BRDF is {value} at ωo = ({:.4}, {:.4}, {:.4}), ωi = ({:.4}, {:.4}, {:.4}); expected a finite value ≥ 0",
        wo[0], wo[1], wo[2], wi[0], wi[1], wi[2]
    )]
    BadBrdfValue {
        /// The value.
        value: f64,
        /// Outgoing direction.
        wo: [f64; 3],
        /// Incoming direction.
        wi: [f64; 3],
    },
    /// The factorisation could not start (e.g. the BRDF is zero on every cell).
    #[error("factored: {0}")]
    Nmf(#[from] NmfError),
}
