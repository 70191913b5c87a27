//! The [`ExactSet`] itself: its fields and accessors.

use std::sync::Arc;
use std::time::Duration;

use brdf::Brdf;
use partition_sampler::AuditCounters;

use super::grid::TableVar;
use super::layout::Cell;
use super::options::ExactOptions;

/// The exact sampler (see the module docs).
pub struct ExactSet {
    pub(super) brdf: Arc<dyn Brdf>,
    pub(super) options: ExactOptions,
    pub(super) isotropic: bool,
    /// Azimuth period of the cells (2π, or π for half-turn-symmetric BRDFs).
    pub(super) period: f64,
    pub(super) cells: Vec<Cell>,
    /// The variable of the normaliser tables and of the interval search.
    pub(super) var: TableVar,
    /// `cos` of [`THETA_TOP_DEG`](super::options::THETA_TOP_DEG): queries below it are served there.
    pub(super) top_cos: f64,
    pub(super) build_time: Duration,
    /// Trials, samples and violations of the set's own `sample` calls, counted set-wide (one
    /// thread-local buffer for every tree: at random θo consecutive samples use different
    /// trees); `measure_cost` records into the trees.
    pub(super) counters: AuditCounters,
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

impl ExactSet {
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
}
