//! Per-set figures: build cost, memory, structure, trials and bound audits.

use std::time::Duration;

use crate::layout::SliceLayout;

/// Cost of a sampling run measured by [`crate::QuadTreeSet::measure_cost`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CostMeasurement {
    /// Directions drawn.
    pub samples: u64,
    /// Rejection trials (points drawn in a rejection rectangle, inside the disc or not).
    pub trials: u64,
    /// BRDF evaluations (trials inside the disc, plus the second component's pdf of a mixture).
    pub evaluations: u64,
    /// Trials where the BRDF exceeded the leaf bound.
    pub violations: u64,
    /// Samples abandoned after the trial cap (returned with pdf 0).
    pub exhausted: u64,
}

impl CostMeasurement {
    /// Trials per sample.
    pub fn mean_trials(&self) -> Option<f64> {
        (self.samples > 0).then(|| self.trials as f64 / self.samples as f64)
    }

    /// BRDF evaluations per accepted sample.
    pub fn evaluations_per_sample(&self) -> Option<f64> {
        (self.samples > 0).then(|| self.evaluations as f64 / self.samples as f64)
    }
}

/// Summary of a [`crate::QuadTreeSet`] (sums over its slices unless stated).
#[derive(Debug, Clone, PartialEq)]
pub struct SetReport {
    /// The partition-sampler scheme of the trees.
    pub variant: crate::Variant,
    /// Whether the two θ-neighbouring slices are mixed.
    pub mixture: bool,
    /// BRDF model name.
    pub brdf: String,
    /// Recorded BRDF spec.
    pub spec: String,
    /// Slice grid.
    pub layout: SliceLayout,
    /// Number of trees.
    pub trees: usize,
    /// Trees on the equal-area disc ([`crate::DiscMap::EqualArea`]); the rest are projected.
    pub equal_area_trees: usize,
    /// Wall-clock build time (zero for a loaded set).
    pub build_time: Duration,
    /// Bytes of all trees, their attached densities and the set itself.
    pub memory_bytes: usize,
    /// Tree nodes (internal + leaves).
    pub nodes: usize,
    /// Sampleable leaves.
    pub leaves: usize,
    /// Deepest leaf over all trees.
    pub max_depth: u32,
    /// Mean over slices of the expected trials per sample `Σ V_i / Σ I_i`.
    pub expected_mean_trials: f64,
    /// Largest per-slice expected trials.
    pub worst_expected_mean_trials: f64,
    /// Trials per sample measured so far over all slices (`None` before any sample).
    pub measured_mean_trials: Option<f64>,
    /// Samples counted so far.
    pub samples: u64,
    /// Trials with `f > M_i` counted so far (the validation suite requires 0).
    pub bound_violations: u64,
    /// Samples abandoned after the trial cap.
    pub exhausted: u64,
    /// BRDF evaluations spent building (image maps and rim bands).
    pub grid_evaluations: u64,
    /// BRDF evaluations per accepted sample, from [`crate::QuadTreeSet::report_with_cost`].
    pub evaluations_per_sample: Option<f64>,
    /// Largest estimated relative error of a slice's integral `Î` (grid Richardson estimate).
    pub max_integral_rel_err: Option<f64>,
}

impl std::fmt::Display for SetReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let opt = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |v| format!("{v:.3}"));
        writeln!(
            f,
            "variant            {:?}{}",
            self.variant,
            if self.mixture {
                ", two-slice mixture"
            } else {
                ""
            }
        )?;
        writeln!(f, "brdf               {} (spec `{}`)", self.brdf, self.spec)?;
        writeln!(
            f,
            "slices             {} θ × {} φ{} = {} trees ({} on the equal-area disc)",
            self.layout.theta,
            self.layout.phi,
            if self.layout.half_turn {
                " over [0°, 180°) (half-turn symmetry)"
            } else {
                ""
            },
            self.trees,
            self.equal_area_trees
        )?;
        writeln!(
            f,
            "build time         {:.3} s",
            self.build_time.as_secs_f64()
        )?;
        writeln!(
            f,
            "memory             {:.1} KiB",
            self.memory_bytes as f64 / 1024.0
        )?;
        writeln!(
            f,
            "nodes / leaves     {} / {} (max depth {})",
            self.nodes, self.leaves, self.max_depth
        )?;
        writeln!(
            f,
            "trials / sample    expected {:.3} (worst slice {:.3}), measured {}",
            self.expected_mean_trials,
            self.worst_expected_mean_trials,
            opt(self.measured_mean_trials)
        )?;
        writeln!(f, "BRDF evals/sample  {}", opt(self.evaluations_per_sample))?;
        writeln!(f, "build evaluations  {}", self.grid_evaluations)?;
        writeln!(
            f,
            "samples            {} (bound violations {}, exhausted {})",
            self.samples, self.bound_violations, self.exhausted
        )?;
        write!(
            f,
            "integral rel. err. {}",
            self.max_integral_rel_err
                .map_or_else(|| "-".to_string(), |v| format!("{v:.2e}"))
        )
    }
}
