//! The layout and statistics of a built set ([`ExactReport`]).

use std::time::Duration;

use crate::direction_sampler::DirectionSampler;
use crate::disc::DiscMap;

use super::set::ExactSet;

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

impl ExactSet {
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
}
