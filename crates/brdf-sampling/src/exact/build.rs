//! [`ExactSet::build`]: the intervals, built in parallel and halved until they meet the caps.

use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, direction_from_radians};
use partition_sampler::AuditCounters;
use rayon::prelude::*;

use crate::options::SetOptions;
use crate::set::layout_for;

use super::build_interval::{Built, IntervalContext, build_interval};
use super::error::ExactError;
use super::grid::{EDGE_BITS, Grid, MAX_BREAKS, TableVar, initial_breaks, table_var, theta_kinks};
use super::interval::Interval;
use super::jobs::{Inheritance, Job};
use super::layout::{Cell, Placed};
use super::options::{ExactOptions, THETA_TOP_DEG};
use super::phases::{BuildPhases, Lap};
use super::set::ExactSet;
use super::set_table::SetTable;
use super::tabulated;

/// BRDFs slower than this per evaluation (nanoseconds) keep their bound nodes' values for the
/// children of a split interval (measured break-even: beckmann at ~140 ns per evaluation
/// builds as fast with the cache as without).
pub(super) const CACHE_ABOVE_NS: f64 = 250.0;

/// Mean time of one evaluation of `brdf` (a few thousand directions, one thread).
pub(super) fn eval_cost_ns(brdf: &dyn Brdf) -> f64 {
    let n = 2048;
    let wo = direction_from_radians(0.6, 0.3);
    let start = Instant::now();
    let mut sink = 0.0;
    for k in 0..n {
        let t = 1.5 * (k as f64 + 0.5) / n as f64;
        let wi = direction_from_radians(t, 2.399 * k as f64);
        sink += brdf.eval(&wo, &wi);
    }
    std::hint::black_box(sink);
    start.elapsed().as_secs_f64() * 1e9 / n as f64
}

/// Whether `brdf` is an RGL material (or a wrapper that exposes one).
fn is_rgl(brdf: &dyn Brdf) -> bool {
    brdf.as_any().is_some_and(|a| a.is::<brdf::RglBrdf>())
}

impl ExactSet {
    /// Builds the set of `brdf` (intervals in parallel with rayon; the result does not depend
    /// on the thread count). `progress` is called with `(intervals built, intervals queued)`.
    pub fn build(
        brdf: Arc<dyn Brdf>,
        options: &ExactOptions,
        progress: Option<crate::Progress<'_>>,
    ) -> Result<Self, ExactError> {
        Self::build_phased(brdf, options, progress, None, true).map(|(set, _)| set)
    }

    /// [`ExactSet::build`] with its evaluations per phase (those of [`brdf::CountingBrdf`] on
    /// the threads that built the intervals: exact on a pool of one thread, see
    /// [`ExactSet::build_counted`]); `cache` forces the node-value cache on or off (`None`: on
    /// for isotropic BRDFs slower than [`CACHE_ABOVE_NS`] per evaluation). The set is the same
    /// either way. `follow_kinks: false` keeps the uniform initial intervals also for a BRDF
    /// with kinks in θo (the behaviour before issue 27, for comparisons).
    pub(super) fn build_phased(
        brdf: Arc<dyn Brdf>,
        options: &ExactOptions,
        progress: Option<crate::Progress<'_>>,
        cache: Option<bool>,
        follow_kinks: bool,
    ) -> Result<(Self, BuildPhases), ExactError> {
        options.validate()?;
        let start = Instant::now();
        let mut phases = BuildPhases::default();
        let mut lap = Lap::start();
        let mut plan = Plan::new(brdf.as_ref(), options, cache, follow_kinks);
        if plan.table_nodes && tabulated::tabulates_over_theta(brdf.as_ref()) {
            let breaks: Vec<f64> = (1..plan.n0)
                .map(|i| plan.grid.edge(i << EDGE_BITS))
                .collect();
            plan.set_table =
                SetTable::build(brdf.as_ref(), 0.0, THETA_TOP_DEG.to_radians(), &breaks)
                    .map(Arc::new);
        }
        phases.plan = lap.take();
        let done = run_jobs(&brdf, options, &plan, progress, &mut phases)?;
        let cells = assemble_cells(done, &plan);
        let set = Self {
            brdf,
            options: *options,
            isotropic: plan.isotropic,
            period: plan.period,
            cells,
            var: plan.var,
            top_cos: THETA_TOP_DEG.to_radians().cos(),
            build_time: start.elapsed(),
            counters: AuditCounters::new(),
        };
        Ok((set, phases))
    }
}

/// What every interval of a build shares: the grid of edges, the azimuth cells, the table
/// variable and the build's switches.
pub(super) struct Plan {
    pub(super) isotropic: bool,
    pub(super) grid: Grid,
    /// Initial intervals per cell.
    pub(super) n0: u64,
    /// Azimuth period of the cells (2π, or π for half-turn-symmetric BRDFs).
    pub(super) period: f64,
    /// The cells' centre azimuths (radians).
    pub(super) phis: Vec<f64>,
    pub(super) var: TableVar,
    /// Keep the bound nodes' values for the children.
    pub(super) cache: bool,
    /// Narrowest interval (radians, θ and azimuth).
    pub(super) min_width: f64,
    /// Integrate the normaliser nodes by a rule of their own, not on the interval's tree
    /// (the MERL layout's cells, the Cornell reference rule: `tabulated.rs`).
    pub(super) table_nodes: bool,
    /// Those nodes, integrated once per build.
    pub(super) node_cache: Arc<tabulated::NodeCache>,
    /// The set's table of `A(θo)` the intervals take their nodes from (Cornell data,
    /// `set_table.rs`; filled by the build, not by a load).
    pub(super) set_table: Option<Arc<SetTable>>,
    /// The largest interpolation tail an interval keeps whatever its nodes' error estimate
    /// ([`tabulated::tail_cap`]).
    pub(super) tail_cap: f64,
    /// Intervals split for their mean trials hand their normaliser tables down
    /// (`jobs::InheritedTable`): RGL sets, whose nodes cost ~9·10⁴ evaluations each.
    pub(super) inherit_tables: bool,
}

impl Plan {
    /// The plan of `brdf`'s set (see [`ExactSet::build_phased`] for `cache` and `follow_kinks`).
    pub(super) fn new(
        brdf: &dyn Brdf,
        options: &ExactOptions,
        cache: Option<bool>,
        follow_kinks: bool,
    ) -> Self {
        let isotropic = brdf.is_isotropic();
        let kinks = if follow_kinks {
            theta_kinks(brdf)
        } else {
            Vec::new()
        };
        // `follow_kinks: false` also keeps the leaf quadrature and the `cos θo` table for the
        // MERL layout and Cornell data (before issue 27).
        let table_nodes = follow_kinks && isotropic && tabulated::table_normaliser_exists(brdf);
        let over_theta = follow_kinks && tabulated::tabulates_over_theta(brdf);
        let var = table_var(isotropic, !kinks.is_empty() || over_theta);
        // Azimuth cells: the sets' rule (half-turn symmetry halves an even count over [0, π)).
        let layout = layout_for(
            brdf,
            &SetOptions {
                anisotropic_slices: [1, options.initial_phi_cells],
                ..options.set
            },
        );
        let (period, n_cells) = (layout.phi_period(), layout.phi);
        let breaks = initial_breaks(options.initial_intervals, &kinks).map(|b| {
            let mut a = [std::f64::consts::FRAC_PI_2; MAX_BREAKS + 1];
            a[..b.len()].copy_from_slice(&b);
            (b.len() - 1, a)
        });
        let n0 = breaks.map_or(options.initial_intervals, |(n, _)| n) as u64;
        let grid = Grid {
            den: n0 << EDGE_BITS,
            m: options.bound_nodes as u64 - 1,
            half: if isotropic {
                0.0
            } else {
                0.5 * period / n_cells as f64
            },
            breaks: breaks.map(|(_, a)| a),
        };
        // Bit-identical results either way; the cache only pays for expensive isotropic
        // BRDFs. Anisotropic intervals spend most of their evaluations on the normaliser
        // nodes: on poulin-fournier the cache cut the build's evaluations by 16 % and its CPU
        // time by 10 %, for a peak of 280 MB instead of 16 MB (it stays off by default).
        // RGL materials always cache (issue 29): at ~300 ns per evaluation they sat next to the
        // threshold, so a loaded host's probe could turn the cache off and multiply the
        // envelopes' evaluations by ~2.3 (`cc_ibiza_sunset`: 13.6 M → 30.1 M).
        let cache = match cache {
            Some(forced) => forced,
            None => isotropic && (is_rgl(brdf) || eval_cost_ns(brdf) > CACHE_ABOVE_NS),
        };
        Self {
            isotropic,
            grid,
            n0,
            period,
            phis: (0..n_cells).map(|k| layout.phi_of(k)).collect(),
            var,
            cache,
            min_width: options.min_width_deg.to_radians(),
            table_nodes,
            node_cache: Arc::default(),
            set_table: None,
            tail_cap: if table_nodes {
                tabulated::tail_cap(brdf)
            } else {
                f64::INFINITY
            },
            inherit_tables: table_nodes && is_rgl(brdf),
        }
    }

    /// The context of `job`'s build.
    pub(super) fn context(&self, job: &Job) -> IntervalContext {
        let grid = self.grid;
        IntervalContext {
            grid,
            phi_k: self.phis[job.cell],
            delta: [grid.delta(job.dnum[0]), grid.delta(job.dnum[1])],
            var: self.var,
            cache: self.cache,
            min_width: self.min_width,
            tail_cap: self.tail_cap,
            table_nodes: self.table_nodes,
            node_cache: Arc::clone(&self.node_cache),
            set_table: self.set_table.clone(),
            inherit_tables: self.inherit_tables,
        }
    }

    /// The initial intervals of every cell, in the order they are built.
    fn initial_jobs(&self) -> Vec<Job> {
        let none = Arc::new(Inheritance::default());
        (0..self.phis.len())
            .flat_map(|cell| {
                let none = &none;
                (0..self.n0).map(move |i| Job {
                    cell,
                    num: [i << EDGE_BITS, (i + 1) << EDGE_BITS],
                    dnum: [0, 1 << EDGE_BITS],
                    inherited: Arc::clone(none),
                })
            })
            .collect()
    }
}

/// Builds every interval, halving those that miss the caps, and returns the kept ones with
/// their cells (in the order they were built).
fn run_jobs(
    brdf: &Arc<dyn Brdf>,
    options: &ExactOptions,
    plan: &Plan,
    progress: Option<crate::Progress<'_>>,
    phases: &mut BuildPhases,
) -> Result<Vec<(usize, Placed)>, ExactError> {
    let mut jobs = plan.initial_jobs();
    let mut done: Vec<(usize, Placed)> = Vec::new();
    let (mut built, mut queued) = (0usize, jobs.len());
    // Depth first, a few intervals at a time: a split parent's node values are released
    // once its children are built (the set does not depend on the order).
    jobs.reverse();
    let batch_len = 2 * rayon::current_num_threads().max(1);
    while !jobs.is_empty() {
        let batch = jobs.split_off(jobs.len().saturating_sub(batch_len));
        let results: Vec<Result<(Job, Built), ExactError>> = batch
            .par_iter()
            .map(|job| {
                build_interval(brdf, options, job, &plan.context(job)).map(|b| (job.clone(), b))
            })
            .collect();
        let mut next = Vec::new();
        for r in results {
            let (
                job,
                Built {
                    interval: iv,
                    inheritance,
                    axis: trials_axis,
                    phases: counts,
                },
            ) = r?;
            built += 1;
            phases.built += 1;
            if let Some(delta) = next_axis(options, plan, &job, iv.as_ref(), trials_axis) {
                // Too many trials (found early, or at a node of the full table), or a
                // table's interpolation tail.
                let by_trials = iv
                    .as_ref()
                    .is_none_or(|iv| iv.worst_trials > options.max_trials && trials_axis.is_some());
                if by_trials {
                    phases.split.add(&counts);
                } else {
                    phases.split_tail.add(&counts);
                }
                phases.record(
                    &plan.grid,
                    &job,
                    iv.as_ref(),
                    &counts,
                    Some((by_trials, delta)),
                );
                // Split for its tail: its tree bounds the halves too (`Inheritance`).
                let mut inheritance = inheritance;
                if let (false, Some(iv)) = (by_trials, iv) {
                    inheritance.tree = Some((iv.tree.into_parts().0, iv.map));
                }
                let inheritance = Arc::new(inheritance);
                for (num, dnum) in job.halves(delta) {
                    next.push(Job {
                        cell: job.cell,
                        num,
                        dnum,
                        inherited: Arc::clone(&inheritance),
                    });
                }
                queued += 2;
            } else if let Some(iv) = iv {
                phases.kept.add(&counts);
                phases.kept_intervals += 1;
                phases.record(&plan.grid, &job, Some(&iv), &counts, None);
                // Only the edges are kept (the node values go with `job`).
                done.push((job.cell, (job.num, job.dnum, iv)));
            }
            if let Some(p) = progress {
                p(built, queued);
            }
        }
        // Children on top of the stack, the left one first.
        jobs.extend(next.into_iter().rev());
    }
    Ok(done)
}

/// The axis to halve (`Some(true)`: δ), if any: too many trials (either axis, `trials_axis`
/// from the build; `iv` is `None` only for an interval that can be split), or an
/// interpolation tail above the tolerance (or the quadrature's own error, if larger: below it
/// the tail is quadrature noise; at most the plan's `tail_cap`) along θ or δ.
fn next_axis(
    options: &ExactOptions,
    plan: &Plan,
    job: &Job,
    iv: Option<&Interval>,
    trials_axis: Option<bool>,
) -> Option<bool> {
    let (grid, min_width) = (&plan.grid, plan.min_width);
    let floor = |iv: &Interval| options.normaliser_tol.max(iv.quad_err.min(plan.tail_cap));
    match iv {
        None => trials_axis,
        Some(iv) if iv.worst_trials > options.max_trials && trials_axis.is_some() => trials_axis,
        Some(iv)
            if iv.table.rel_tail_theta() > floor(iv) && job.can_split_theta(grid, min_width) =>
        {
            Some(false)
        }
        Some(iv)
            if iv.table.rel_tail_delta() > floor(iv) && job.can_split_delta(grid, min_width) =>
        {
            Some(true)
        }
        Some(_) => None,
    }
}

/// The cells of the kept intervals (sorted by cell, θ and δ: the same set whatever the
/// order they were built in).
fn assemble_cells(mut done: Vec<(usize, Placed)>, plan: &Plan) -> Vec<Cell> {
    done.sort_by_key(|(cell, (num, dnum, _))| (*cell, num[0], dnum[0]));
    let mut per_cell: Vec<Vec<Placed>> = plan.phis.iter().map(|_| Vec::new()).collect();
    for (cell, placed) in done {
        per_cell[cell].push(placed);
    }
    per_cell
        .into_iter()
        .zip(&plan.phis)
        .map(|(members, &phi)| Cell::new(phi, members, &plan.grid, plan.var))
        .collect()
}
