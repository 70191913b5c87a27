//! A study's results: per-cell numbers, the JSON and CSV forms, and merging shards.
//!
//! # `results.json` schema (`"schema": "brdf-lab-study/3"`)
//!
//! ```text
//! {
//!   "schema": "brdf-lab-study/3",
//!   "config": { preset, samplers[], brdfs[], theta_o_deg[], lights[], n_grid[], repetitions,
//!               batch_repetitions, variance_samples, timing_samples, timing_repeats, slices,
//!               seed },
//!   "shard": null | { "index": K, "count": N },      // K from 1
//!   "total_cells": number of cells of the whole grid,
//!   "notes": [ "…" ],                                 // e.g. a missing map file
//!   "lights": [ { "spec", "description" } ],
//!   "cells": [ {
//!       "index", "sampler", "mode" ("one-sample" | "batch"), "brdf", "theta_o_deg", "light",
//!       "estimator" ("brdf" | "light" | "mis-balance" | "mis-power"),
//!       "light_sampler": null | map sampler of a MIS cell (a light cell's is its `sampler`),
//!       "status": null | "why the cell could not run",
//!       "reference": { "value", "abs_err", "method" },   // L_r(ωo), luminance
//!       "bytes": memory of the sampler's structures,
//!       "evaluations_per_sample": BRDF evaluations by the sampler per sample,
//!       "variance": { "value", "ci95" },   // per-sample variance of the estimator
//!       "zero_variance": bool,             // exact f·cos·L sampler (constant light)
//!       "mse": { "n", "value", "ci95", "reference_err" },  // N·E[(L̂_N − L)²] at the budget N
//!       "tail_share": largest share of Σ(y − ȳ)² held by one value,
//!       "warnings": [ "…" ],               // why the spread estimate is unreliable
//!       "errors": [ { "n", "mean_rel_err", "ci95", "rms_rel_err", "variance_per_sample" } ],
//!       "timing": { "clock" ("thread-cpu" | "wall"), "build_seconds", "sample_ns",
//!                   "estimator_ns", "estimator_ns_min", "estimator_ns_max",
//!                   "estimator_log_sd", "estimator_wall_ns", "estimator_wall_log_sd",
//!                   "repeats", "efficiency" }                           // TIMINGS
//!   } ],
//!   "runs": [ { "commit", "cpu_model", "logical_cpus", "threads", "load_start": [1, 5, 15 min],
//!               "load_end", "wall_seconds", "cpu_seconds" } ],        // one per run / shard
//!   "rankings": [ {                                   // empty for a shard; module `ranking`
//!       "brdf", "theta_o", "light", "estimator" ("brdf", "light", "mis-balance", "mis-power"),
//!       "light_sampler" (MIS only: the map sampler every ranked BRDF sampler is paired with),
//!       "best": label, "tied": [label], "worse": [label],   // label: `sampler` or `sampler (batch)`
//!       "alpha", "rule" ("sidak"), "comparisons" (m), "level" (of each interval),
//!       "entries": [ { "sampler", "cell" (the cell's index), "verdict", "efficiency",
//!                      "se_log_efficiency", "se_log_mse", "se_log_time", "ratio", "ratio_lo",
//!                      "ratio_hi", "by_time", "unreliable", "evaluations_per_sample" } ],
//!       "excluded": [ { "sampler", "cell", "reason" } ]
//!   } ]
//! }
//! ```
//!
//! Everything outside `timing`, `runs` and `rankings` depends only on the config (seed included): equal on rerun, for
//! any thread count, and between one run and merged shards. `timing` holds the only measured
//! times: build time, time per sample of the sampler alone and of the whole estimator
//! (single-threaded, median of the repeats) and the efficiency 1 / (variance × estimator time
//! per sample in seconds), the MSE at the budget N standing in for the variance.
//!
//! ## Changes from `brdf-lab-study/2`
//!
//! * new `rankings` and `runs`; `config.batch_repetitions` (batch-mode cells use
//!   `max(repetitions, batch_repetitions)` estimates per N);
//! * `timing`: times are on the timing thread's CPU clock where the platform has one (`clock`),
//!   the wall-clock median beside; the repeats are interleaved across cells and their spread
//!   recorded (`estimator_ns_min`, `estimator_ns_max`, `estimator_log_sd`, …, `repeats`).
//!   Version 2 files are refused by `study merge`.
//!
//! ## Changes from `brdf-lab-study/1`
//!
//! * new `mse`, `tail_share`, `warnings` per cell (crate docs of `dispersion`);
//! * `variance` (one-sample mode) is now over every one-sample value the cell drew (the
//!   error-curve repetitions plus `variance_samples` more), not over `variance_samples` alone;
//! * `timing.efficiency` is `1 / (mse.value × estimator time)`, no longer `1 / (variance × …)`:
//!   a heavy-tailed sampler whose sample variance misses its rare large values, or a biased
//!   one, no longer ranks first. Version 1 files are refused by `study merge`.

use serde::{Deserialize, Serialize};

use crate::dispersion::BudgetMse;
use crate::machine::RunInfo;
use crate::verdict::Ranking;
use crate::{Mode, Reference, Shard, StudyConfig, StudyError};

/// Version tag of [`StudyResults`]' JSON form.
pub const SCHEMA: &str = "brdf-lab-study/3";

/// A value with the half-width of its 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WithCi {
    /// The estimate.
    pub value: f64,
    /// Half-width of the 95 % confidence interval.
    pub ci95: f64,
}

/// Relative error of the estimator at one sample count.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorAtN {
    /// Samples per estimate.
    pub n: usize,
    /// Mean over the repetitions of `|L̂_N − L_ref| / L_ref`.
    pub mean_rel_err: f64,
    /// Half-width of its 95 % confidence interval (1.96 · sd / √R).
    pub ci95: f64,
    /// Root mean square of the relative errors.
    pub rms_rel_err: f64,
    /// `N · Var(L̂_N)` over the repetitions: the per-sample variance this N achieves (equal
    /// to the one-sample variance for independent samples, lower for stratified batches).
    pub variance_per_sample: f64,
}

/// The clock of a cell's per-sample times.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clock {
    /// The timing thread's CPU time (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`).
    ThreadCpu,
    /// Wall time (platforms without a thread CPU clock).
    Wall,
}

/// Measured times of a cell (the only time-dependent numbers of a study).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The clock of the per-sample times: `thread-cpu` (the timing thread's CPU time, which
    /// does not count the time other processes hold the core) where the platform gives it,
    /// else `wall`.
    pub clock: Clock,
    /// Time to build the sampler for this BRDF (s); 0 for samplers without a structure.
    pub build_seconds: f64,
    /// Time per sample of the sampler alone (ns), single-threaded, median of the repeats.
    pub sample_ns: f64,
    /// Time per sample of the whole estimator: sampling, `f_r`, `L`, `cos / pdf` (ns), median
    /// of the repeats.
    pub estimator_ns: f64,
    /// Fastest repeat of the estimator (ns per sample).
    pub estimator_ns_min: f64,
    /// Slowest repeat of the estimator (ns per sample).
    pub estimator_ns_max: f64,
    /// Sample standard deviation of `ln(estimator ns)` over the repeats (the timing spread
    /// the rankings carry; 0 with one repeat).
    pub estimator_log_sd: f64,
    /// Wall-clock time per sample of the whole estimator (ns), median of the repeats (equal to
    /// [`Self::estimator_ns`] when `clock` is `wall`).
    pub estimator_wall_ns: f64,
    /// Sample standard deviation of `ln(wall ns)` over the repeats.
    pub estimator_wall_log_sd: f64,
    /// Timing repeats (interleaved with the other cells').
    pub repeats: usize,
    /// `1 / (MSE per sample at the budget N × estimator time per sample in s)` (the cell's
    /// [`CellResult::mse`]); `None` when it is 0.
    pub efficiency: Option<f64>,
}

/// The results of one cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellResult {
    /// Position in the full grid.
    pub index: usize,
    /// Sampler name.
    pub sampler: String,
    /// How samples were drawn.
    pub mode: Mode,
    /// BRDF spec.
    pub brdf: String,
    /// Outgoing polar angle (degrees, φo = 0).
    pub theta_o_deg: f64,
    /// Light spec.
    pub light: String,
    /// The estimator: `brdf` (the sampler alone), `light` (the map sampler alone; `sampler`
    /// names it), `mis-balance` or `mis-power` (the BRDF sampler `sampler` with the map
    /// sampler `light_sampler`, one draw of each per sample).
    #[serde(default = "brdf_estimator")]
    pub estimator: String,
    /// The map sampler of a MIS cell.
    #[serde(default)]
    pub light_sampler: Option<String>,
    /// Why the cell could not run (e.g. the sampler does not apply to this BRDF).
    pub status: Option<String>,
    /// The reference `L_r(ωo)`.
    pub reference: Reference,
    /// Memory of the sampler's structures (bytes).
    pub bytes: usize,
    /// BRDF evaluations made by the sampler per sample (the estimator's own excluded).
    pub evaluations_per_sample: f64,
    /// Per-sample variance of the estimator: the sample variance of `f L cos / p` over every
    /// one-sample value the cell drew (one-sample mode) or `N · Var(L̂_N)` at the largest N
    /// (batch mode).
    pub variance: WithCi,
    /// The variance is zero to rounding (an exact `f·cos·L` sampler, e.g. under constant light).
    pub zero_variance: bool,
    /// Per-sample mean squared error against the reference at the budget (largest) N,
    /// `N · E[(L̂_N − L)²] = σ² + N b²`: what efficiency divides by (module `dispersion`).
    pub mse: BudgetMse,
    /// Largest share of `Σ (y − ȳ)²` held by one value (one-sample values, or the batch
    /// estimates at the budget N).
    pub tail_share: f64,
    /// Why the cell's spread estimate is unreliable (a heavy tail, an uncertain variance, a
    /// mean off the reference); empty when none applies.
    pub warnings: Vec<String>,
    /// Relative errors along the N grid.
    pub errors: Vec<ErrorAtN>,
    /// Measured times.
    pub timing: Option<Timing>,
}

impl CellResult {
    /// Whether the cell ran.
    pub fn ok(&self) -> bool {
        self.status.is_none()
    }

    /// The relative error at the largest N.
    pub fn final_error(&self) -> Option<&ErrorAtN> {
        self.errors.last()
    }

    /// `sampler` or `sampler (batch)` (the ranked name inside a comparison).
    pub fn label(&self) -> String {
        match self.mode {
            Mode::OneSample => self.sampler.clone(),
            Mode::Batch => format!("{} (batch)", self.sampler),
        }
    }

    /// A copy without timings (for comparisons that must be exact).
    pub fn without_timing(&self) -> Self {
        Self {
            timing: None,
            ..self.clone()
        }
    }
}

fn brdf_estimator() -> String {
    crate::verdict::ESTIMATOR_BRDF.to_string()
}

/// A light of the study and its description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LightInfo {
    /// The spec.
    pub spec: String,
    /// What it is.
    pub description: String,
}

/// The results of a study (or of one shard of it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyResults {
    /// [`SCHEMA`].
    pub schema: String,
    /// The study.
    pub config: StudyConfig,
    /// The shard these results cover, `None` for a whole study.
    pub shard: Option<Shard>,
    /// Cells of the whole grid.
    pub total_cells: usize,
    /// Notes for the report (e.g. a missing map file and what replaced it).
    pub notes: Vec<String>,
    /// Warnings of the samplers' builds (e.g. `srbf` fits stopped at the L-BFGS iteration cap),
    /// one per sampler and BRDF; a merge keeps the union of its shards', sorted.
    #[serde(default)]
    pub build_warnings: Vec<String>,
    /// The lights.
    pub lights: Vec<LightInfo>,
    /// The cells run, by index.
    pub cells: Vec<CellResult>,
    /// Where and how it ran (one per run; a merged study lists its shards').
    pub runs: Vec<RunInfo>,
    /// One ranking per comparison (module [`crate::ranking`]); empty for a shard (`study
    /// merge` ranks the whole grid).
    pub rankings: Vec<Ranking>,
}

impl StudyResults {
    /// The JSON form (pretty-printed).
    pub fn to_json(&self) -> String {
        // Serialising plain data with finite floats cannot fail; non-finite floats are never
        // stored (they become `None` or are replaced before).
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    /// Reads the JSON form back.
    pub fn from_json(text: &str, path: &str) -> Result<Self, StudyError> {
        let r: Self = serde_json::from_str(text).map_err(|e| StudyError::ResultsFile {
            path: path.to_string(),
            reason: e.to_string(),
        })?;
        if r.schema != SCHEMA {
            return Err(StudyError::ResultsFile {
                path: path.to_string(),
                reason: format!("schema `{}`, expected `{SCHEMA}`", r.schema),
            });
        }
        Ok(r)
    }

    /// The same results without timings (what must agree bit for bit between runs).
    pub fn without_timing(&self) -> Self {
        Self {
            cells: self.cells.iter().map(CellResult::without_timing).collect(),
            runs: Vec::new(),
            rankings: Vec::new(),
            ..self.clone()
        }
    }

    /// The CSV form: one row per cell and N; timing columns are marked `[timing]` in the
    /// header. Fields are quoted where needed (BRDF specs contain commas). Measured files and
    /// map lights are named by their short names ([`crate::names::short_brdf`],
    /// [`crate::names::short_light`]); the full paths are in `results.json` only.
    pub fn to_csv(&self) -> String {
        let mut out = String::from(
            "index,sampler,mode,brdf,theta_o_deg,light,status,reference,reference_abs_err,n,mean_rel_err,rel_err_ci95,rms_rel_err,variance_per_sample_at_n,variance_per_sample,variance_ci95,zero_variance,mse_per_sample,mse_ci95,mse_reference_err,tail_share,warnings,evaluations_per_sample,bytes,build_seconds[timing],sample_ns[timing],estimator_ns[timing],estimator_ns_min[timing],estimator_ns_max[timing],estimator_log_sd[timing],estimator_wall_ns[timing],efficiency[timing],estimator,light_sampler\n",
        );
        for c in &self.cells {
            let t = c.timing;
            let timing = [
                t.map(|t| t.build_seconds),
                t.map(|t| t.sample_ns),
                t.map(|t| t.estimator_ns),
                t.map(|t| t.estimator_ns_min),
                t.map(|t| t.estimator_ns_max),
                t.map(|t| t.estimator_log_sd),
                t.map(|t| t.estimator_wall_ns),
                t.and_then(|t| t.efficiency),
            ]
            .map(opt);
            let rows: Vec<Option<&ErrorAtN>> = if c.errors.is_empty() {
                vec![None]
            } else {
                c.errors.iter().map(Some).collect()
            };
            for e in rows {
                let fields = [
                    c.index.to_string(),
                    quote(&c.sampler),
                    c.mode.as_str().to_string(),
                    quote(&crate::names::short_brdf(&c.brdf)),
                    num(c.theta_o_deg),
                    quote(&crate::names::short_light(&c.light)),
                    quote(c.status.as_deref().unwrap_or("")),
                    num(c.reference.value),
                    num(c.reference.abs_err),
                    e.map_or(String::new(), |e| e.n.to_string()),
                    opt(e.map(|e| e.mean_rel_err)),
                    opt(e.map(|e| e.ci95)),
                    opt(e.map(|e| e.rms_rel_err)),
                    opt(e.map(|e| e.variance_per_sample)),
                    num(c.variance.value),
                    num(c.variance.ci95),
                    c.zero_variance.to_string(),
                    num(c.mse.value),
                    num(c.mse.ci95),
                    num(c.mse.reference_err),
                    num(c.tail_share),
                    quote(&c.warnings.join("; ")),
                    num(c.evaluations_per_sample),
                    c.bytes.to_string(),
                ];
                out.push_str(&fields.join(","));
                for t in &timing {
                    out.push(',');
                    out.push_str(t);
                }
                out.push(',');
                out.push_str(&quote(&c.estimator));
                out.push(',');
                out.push_str(&quote(c.light_sampler.as_deref().unwrap_or("")));
                out.push('\n');
            }
        }
        out
    }
}

/// Full round-trip precision.
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn opt(x: Option<f64>) -> String {
    x.map_or(String::new(), num)
}

/// Quotes a CSV field when it holds a comma, a quote or a line break.
fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
