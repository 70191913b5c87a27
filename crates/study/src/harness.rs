//! The estimator harness: resolves a [`StudyConfig`] into a plan (every name checked before
//! any work), builds each `(sampler, BRDF)` once, computes each reference once, and runs the
//! cells.
//!
//! For a cell (sampler, mode, BRDF, θo, light) with `ωo = (sin θo, 0, cos θo)`:
//! * the estimator of `L_r(ωo)` is `(1/N) Σ Y(f_r(ωo, ωk) ⊙ L(ωk)) cos θk / p_σ(ωk)` with the
//!   sampler's solid-angle pdf; samples below the horizon (or with pdf 0) contribute 0;
//! * relative errors: `repetitions` independent estimates at every N of the grid. One-sample
//!   mode: **nested error curves** — each repetition draws one stream of `N_max` values (the
//!   budget, the grid's last N) and its estimate at each N is the mean of the stream's first N
//!   ([`prefix_sums`]); at each N the `R` estimates are independent (different repetitions),
//!   each the mean of N i.i.d. values, so every per-N interval keeps its law, while the
//!   estimates of one repetition at different N are correlated (no interval or figure of the
//!   study needs independence across N: the curves' bands are per N, and nothing is fitted
//!   across N). Values drawn: `repetitions × N_max + variance_samples` (32 × 2 500 + 20 000 =
//!   100 000 with the papers' grid, against 32 × Σ N + 20 000 = 204 032 before). Batch mode:
//!   fresh stratified estimates at each N ([`repetitions_at`]);
//! * per-sample variance: over every one-sample value the cell drew (the repetitions' streams
//!   plus `variance_samples` more; one-sample mode), or `N · Var(L̂_N)` at the largest N (batch
//!   mode, whose samples are not independent);
//! * per-sample MSE at the budget (largest) N against the reference, its tail share and
//!   warnings ([`crate::dispersion`]): efficiency divides by it;
//! * BRDF evaluations per sample: counted on the sampler's calls only ([`CountingBrdf`]);
//! * relative errors and MSE in batch mode rest on `max(repetitions, batch_repetitions)`
//!   estimates at the budget N, `repetitions` at the others ([`repetitions_at`]);
//! * timings: after the statistics, nothing else of the study running, on every rayon thread
//!   at once, each thread with an equal share of the cells (every T-th):
//!   runs of `timing_samples` samples per cell, interleaved across its cells (run 1 of each,
//!   then run 2, …), from 5 up to `timing_repeats` runs by a stated stopping rule
//!   ([`timing_done`]: a cell stops once its median time's standard error is ≤ 5 %), on the
//!   thread's own CPU clock where the platform
//!   has one (and the wall clock beside); the median and the spread are kept. Every cell is
//!   timed under the same condition (the other threads timing too);
//! * the MIS cells of one (BRDF sampler, map sampler, BRDF, θo, light) under the balance and
//!   the power heuristic share their draws (the stream of the first): each cell's values are
//!   exactly those it would get alone from that stream, the heuristic's weights only differ;
//!   the one-sample BRDF-only cell of that BRDF sampler (BRDF, θo, light) joins the group of
//!   its first map sampler and takes the estimator's value `g / p` of each of its BRDF draws
//!   (same law, no draw or evaluation of its own: [`mis_groups`]);
//! * the CPU time of each phase (builds, map samplers, references, statistics, timings,
//!   rankings) is in the run's [`crate::RunInfo::phases`].
//!
//! Builds: each `(sampler, BRDF)` is built once, and samplers that build the same structure
//! (the adaptive sets of one variant, nearest slice or two-slice mixture) share one build;
//! the builds run on every core at once, each alone in a one-thread pool, and a build's time
//! is the CPU time of the thread that ran it (wall time where the platform has no thread
//! clock), so it is neither inflated by the builds beside it nor hidden by parallelism. A
//! shared build's time is reported for every sampler that uses it. Longest first: samplers
//! that need a build before the others, the BRDFs dearest to evaluate first (so that no long
//! build starts last and runs alone while the other cores idle).
//!
//! Reproducibility: cell `i` draws from one `Xoshiro256PlusPlus` seeded with
//! `distributions::chunk_seed(seed, i)` (a power-heuristic MIS cell and a joined BRDF-only
//! cell from their MIS group's balance cell's) and sums in a fixed order, so its numbers do not
//! depend on the thread count or on which shard runs it. A shard `K/N` runs every cell of the
//! BRDFs `b` with `b mod N = K − 1` (not every N-th cell), so its builds are its own.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use brdf::{Brdf, Vec3};
use brdf_sampling::{
    DirSample, DirectionSampler, QuadTreeSet, SamplerDiagnostics, SetOptions, Variant,
};
use envmap::{AdaptiveOptions, EnvMapSampler};
use estimators::{LightTechnique, LocalFrame, MisHeuristic, MisPair};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use samplers::{BuiltDirection, Constructor, DirectionRequest, Registry, SamplerEntry};

use crate::counting::{CountingBrdf, thread_evaluations};
use crate::dispersion::{self, BudgetMse, Z95};
use crate::machine::{PhaseClock, RunClock, thread_cpu_seconds};
use crate::results::{
    CellResult, Clock, ErrorAtN, LightInfo, SCHEMA, StudyResults, Timing, WithCi,
};
use crate::{CellSpec, Light, Mode, Reference, Shard, StudyConfig, StudyError, reference};

/// Relative size (to the reference squared) below which a variance counts as zero.
const ZERO_VARIANCE: f64 = 1e-20;

/// Called with the number of steps just done (parallel workers call it concurrently).
pub type ProgressFn<'a> = &'a (dyn Fn(u64) + Sync);

/// A BRDF of the study: as parsed (for the estimator and references) and wrapped in a
/// counter (for the samplers).
pub(crate) struct StudyBrdf {
    pub(crate) spec: String,
    pub(crate) raw: Arc<dyn Brdf>,
    pub(crate) counted: Arc<dyn Brdf>,
}

/// A built sampler and its build time (s), or why it could not be built.
pub(crate) type BuildOutcome = Result<(samplers::BuiltDirection, f64), String>;

/// The warnings of the built samplers, one note each: the `warning: …` lines of their
/// `build_report` (e.g. `srbf` fits that stopped at the L-BFGS iteration cap), so the report
/// says when a sampler's fit is not converged.
fn build_warnings<'a>(
    built: &[((usize, usize), BuildOutcome)],
    sampler_name: impl Fn(usize) -> &'a str,
    brdf_spec: impl Fn(usize) -> &'a str,
) -> Vec<String> {
    let mut notes = Vec::new();
    for ((s, b), outcome) in built {
        let Ok((d, _)) = outcome else { continue };
        let Some(report) = d.sampler.build_report() else {
            continue;
        };
        for w in report.lines().filter_map(|l| l.strip_prefix("warning: ")) {
            notes.push(format!(
                "sampler {} on {}: {w}",
                sampler_name(*s),
                crate::names::short_brdf(brdf_spec(*b))
            ));
        }
    }
    notes
}

/// The structure a sampler's build shares with others, with its own slice rule: the adaptive
/// sets of one variant (`adaptive` and `adaptive-mixture`, `adaptive-paper` and
/// `adaptive-paper-mixture`) build the same trees and differ only in how a sample picks its
/// slice (nearest or the two-slice mixture), so one build serves all of them.
fn shared_structure(entry: &SamplerEntry) -> Option<(Variant, bool)> {
    match entry.constructor {
        Constructor::AdaptiveSet { variant, mixture } => Some((variant, mixture)),
        _ => None,
    }
}

/// An adaptive set derived from a shared build: the set itself in every respect but its
/// memory, which is that of the set as built (the copy's vectors may hold less spare capacity),
/// so the shared structure reports the same bytes for every sampler that uses it.
struct SharedSet {
    set: Arc<QuadTreeSet>,
    bytes: usize,
}

impl DirectionSampler for SharedSet {
    fn sample(&self, wo: &Vec3, u: &mut dyn distributions::UniformSource) -> DirSample {
        self.set.sample(wo, u)
    }
    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.set.pdf(wo, wi)
    }
    fn sample_eval(
        &self,
        brdf: &dyn Brdf,
        wo: &Vec3,
        u: &mut dyn distributions::UniformSource,
    ) -> brdf_sampling::EvalSample {
        self.set.sample_eval(brdf, wo, u)
    }
    fn sample_eval_batch(
        &self,
        brdf: &dyn Brdf,
        wos: &[Vec3],
        u: &mut dyn distributions::UniformSource,
        out: &mut Vec<brdf_sampling::EvalSample>,
    ) {
        self.set.sample_eval_batch(brdf, wos, u, out);
    }
    fn sample_batch(
        &self,
        wo: &Vec3,
        n: usize,
        u: &mut dyn distributions::UniformSource,
    ) -> Vec<DirSample> {
        self.set.sample_batch(wo, n, u)
    }
    fn sample_many(
        &self,
        wo: &Vec3,
        n: usize,
        u: &mut dyn distributions::UniformSource,
    ) -> Vec<DirSample> {
        self.set.sample_many(wo, n, u)
    }
    fn pdf_many(&self, wo: &Vec3, wi: &[Vec3]) -> Vec<f64> {
        self.set.pdf_many(wo, wi)
    }
    fn pdf_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &Vec3, f: f64) -> f64 {
        self.set.pdf_given_f(brdf, wo, wi, f)
    }
    fn pdf_many_given_f(&self, brdf: &dyn Brdf, wo: &Vec3, wi: &[Vec3], f: &[f64]) -> Vec<f64> {
        self.set.pdf_many_given_f(brdf, wo, wi, f)
    }
    fn prefers_batches(&self) -> bool {
        self.set.prefers_batches()
    }
    fn fuses_eval(&self) -> bool {
        self.set.fuses_eval()
    }
    fn bytes_used(&self) -> usize {
        self.bytes
    }
}

impl SamplerDiagnostics for SharedSet {
    fn bound_violations(&self) -> Option<u64> {
        self.set.bound_violations()
    }

    fn normaliser_rel_err(&self, wo: &Vec3) -> Option<f64> {
        self.set.normaliser_rel_err(wo)
    }

    fn pdf_cells(&self, wo: &Vec3) -> Option<brdf_sampling::PdfCells> {
        self.set.pdf_cells(wo)
    }

    fn build_report(&self) -> Option<String> {
        self.set.build_report()
    }

    fn singular_directions(&self, wo: &Vec3) -> Vec<Vec3> {
        self.set.singular_directions(wo)
    }
}

/// CPU seconds (wall where the platform has no thread clock) of 2 048 evaluations of `brdf`
/// at fixed directions: the build order's estimate of what a build on it costs.
fn evaluation_cost(brdf: &dyn Brdf) -> f64 {
    let (cpu, wall) = (thread_cpu_seconds(), Instant::now());
    let mut sink = 0.0;
    for i in 0..2048_u32 {
        let t = f64::from(i % 64) * (89.0 / 64.0);
        let p = f64::from(i / 64) * (360.0 / 32.0);
        let wo = brdf::direction_from_angles(t, 0.0);
        let wi = brdf::direction_from_angles(89.0 - t, p);
        sink += brdf.eval_rgb(&wo, &wi)[1];
    }
    std::hint::black_box(sink);
    cpu_or_wall(cpu, thread_cpu_seconds(), wall.elapsed().as_secs_f64())
}

/// A rayon pool of one thread (`None` if the platform cannot start one): a build run inside
/// it runs every parallel part on that thread.
fn one_thread_pool() -> Option<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().ok()
}

/// What a cell's estimator samples.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// The BRDF sampler `PlanCell::sampler` alone.
    Brdf,
    /// The map sampler `ls` (index into `StudyPlan::light_entries`) alone.
    Light { ls: usize },
    /// The BRDF sampler `PlanCell::sampler` and the map sampler `ls`, one draw of each.
    Mis { ls: usize, heuristic: MisHeuristic },
}

/// A cell with its indices into the plan.
#[derive(Debug, Clone)]
struct PlanCell {
    spec: CellSpec,
    /// Index into `StudyPlan::entries` (unused by light cells).
    sampler: usize,
    brdf: usize,
    theta: usize,
    light: usize,
    kind: Kind,
}

impl PlanCell {
    fn uses_brdf_sampler(&self) -> bool {
        !matches!(self.kind, Kind::Light { .. })
    }

    fn light_sampler(&self) -> Option<usize> {
        match self.kind {
            Kind::Brdf => None,
            Kind::Light { ls } | Kind::Mis { ls, .. } => Some(ls),
        }
    }
}

/// A map sampler built for a light, or why it could not be.
type LightBuild = Result<Arc<EnvMapSampler>, String>;

/// A study whose names are all resolved: ready to run (whole or by shard).
pub struct StudyPlan {
    pub(crate) config: StudyConfig,
    notes: Vec<String>,
    pub(crate) entries: Vec<SamplerEntry>,
    pub(crate) brdfs: Vec<StudyBrdf>,
    pub(crate) lights: Vec<Arc<Light>>,
    /// The map samplers of the light and MIS estimators.
    light_entries: Vec<&'static SamplerEntry>,
    cells: Vec<PlanCell>,
    /// Samplers built so far, by `(sampler, BRDF)` index (the renderer reuses them).
    built: Mutex<Vec<((usize, usize), BuildOutcome)>>,
    /// Whether samplers sharing a structure share its build (always, but for the test that
    /// compares shared builds with separate ones).
    share_builds: bool,
}

impl std::fmt::Debug for StudyPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyPlan")
            .field("config", &self.config)
            .field("cells", &self.cells.len())
            .finish_non_exhaustive()
    }
}

impl StudyPlan {
    /// Checks the config and resolves every sampler (registered direction samplers only), BRDF
    /// and light, before any sampling work. `notes` are carried into the report.
    ///
    /// Errors: the first bad setting or name.
    pub fn new(config: StudyConfig, notes: Vec<String>) -> Result<Self, StudyError> {
        Self::with_registry(config, notes, &Registry::builtin())
    }

    /// [`StudyPlan::new`] with the samplers of `registry`: a direction sampler added with
    /// [`samplers::Registry::with`] (from a crate outside the workspace, or from Python) is
    /// studied beside the built-in ones, its cost measured as it is.
    ///
    /// Errors: as [`StudyPlan::new`].
    pub fn with_registry(
        config: StudyConfig,
        notes: Vec<String>,
        registry: &Registry,
    ) -> Result<Self, StudyError> {
        config.check()?;
        let entries = config
            .samplers
            .iter()
            .map(|name| {
                let e = registry.find(name)?;
                if !e.is_direction() {
                    return Err(StudyError::from(samplers::RegistryError::WrongKind {
                        name: e.name,
                        expected: "direction",
                        found: e.constructor.kind(),
                        candidates: registry.names_of_kind("direction"),
                    }));
                }
                Ok(e.clone())
            })
            .collect::<Result<Vec<_>, StudyError>>()?;
        let brdfs = config
            .brdfs
            .iter()
            .map(|spec| {
                let raw: Arc<dyn Brdf> =
                    Arc::from(brdf::parse_spec(spec).map_err(|source| StudyError::Brdf {
                        spec: spec.clone(),
                        source,
                    })?);
                Ok(StudyBrdf {
                    spec: spec.clone(),
                    counted: Arc::new(CountingBrdf(Arc::clone(&raw))),
                    raw,
                })
            })
            .collect::<Result<Vec<_>, StudyError>>()?;
        let lights = config
            .lights
            .iter()
            .map(|s| Light::parse(s).map(Arc::new))
            .collect::<Result<Vec<_>, _>>()?;
        let mut cells = Vec::new();
        for (li, light) in config.lights.iter().enumerate() {
            for (bi, b) in config.brdfs.iter().enumerate() {
                for (ti, &theta) in config.theta_o_deg.iter().enumerate() {
                    for (si, e) in entries.iter().enumerate() {
                        let modes: &[Mode] = if e.capabilities.batch_mode {
                            &[Mode::OneSample, Mode::Batch]
                        } else {
                            &[Mode::OneSample]
                        };
                        for &mode in modes {
                            cells.push(PlanCell {
                                spec: CellSpec {
                                    index: cells.len(),
                                    sampler: e.name.to_string(),
                                    mode,
                                    brdf: b.clone(),
                                    theta_o_deg: theta,
                                    light: light.clone(),
                                    estimator: crate::verdict::ESTIMATOR_BRDF.to_string(),
                                    light_sampler: None,
                                },
                                sampler: si,
                                brdf: bi,
                                theta: ti,
                                light: li,
                                kind: Kind::Brdf,
                            });
                        }
                    }
                }
            }
        }
        let light_entries = if config.estimators.is_empty() {
            Vec::new()
        } else {
            config
                .light_samplers
                .iter()
                .map(|name| {
                    let e = samplers::find(name)?;
                    if e.constructor.kind() != "envmap" {
                        return Err(StudyError::from(samplers::RegistryError::WrongKind {
                            name: e.name,
                            expected: "envmap",
                            found: e.constructor.kind(),
                            candidates: samplers::names_of_kind("envmap"),
                        }));
                    }
                    Ok(e)
                })
                .collect::<Result<Vec<_>, StudyError>>()?
        };
        // The other estimators' cells follow every BRDF-only cell (their indices, and so the
        // BRDF-only cells' seeds, do not move), under the map lights only.
        let mis_samplers: Vec<usize> = (0..entries.len())
            .filter(|&si| {
                config.mis_samplers.is_empty()
                    || config.mis_samplers.iter().any(|m| m == entries[si].name)
            })
            .collect();
        for (li, light) in config.lights.iter().enumerate() {
            if !matches!(*lights[li], Light::Map { .. }) {
                continue;
            }
            for (bi, b) in config.brdfs.iter().enumerate() {
                for (ti, &theta) in config.theta_o_deg.iter().enumerate() {
                    for estimator in &config.estimators {
                        let heuristic = MisHeuristic::parse(estimator);
                        let pairs: Vec<(usize, usize)> = match heuristic {
                            None => (0..light_entries.len())
                                .map(|ls| (usize::MAX, ls))
                                .collect(),
                            Some(_) => mis_samplers
                                .iter()
                                .flat_map(|&si| (0..light_entries.len()).map(move |ls| (si, ls)))
                                .collect(),
                        };
                        for (si, ls) in pairs {
                            let (sampler, light_sampler, kind) = match heuristic {
                                None => (light_entries[ls].name, None, Kind::Light { ls }),
                                Some(heuristic) => (
                                    entries[si].name,
                                    Some(light_entries[ls].name.to_string()),
                                    Kind::Mis { ls, heuristic },
                                ),
                            };
                            cells.push(PlanCell {
                                spec: CellSpec {
                                    index: cells.len(),
                                    sampler: sampler.to_string(),
                                    mode: Mode::OneSample,
                                    brdf: b.clone(),
                                    theta_o_deg: theta,
                                    light: light.clone(),
                                    estimator: estimator.clone(),
                                    light_sampler,
                                },
                                sampler: si,
                                brdf: bi,
                                theta: ti,
                                light: li,
                                kind,
                            });
                        }
                    }
                }
            }
        }
        Ok(Self {
            config,
            notes,
            entries,
            brdfs,
            lights,
            light_entries,
            cells,
            built: Mutex::new(Vec::new()),
            share_builds: true,
        })
    }

    /// The sampler `s` built for BRDF `b` (cached), with its build time: derived from a
    /// sibling's build when one shares its structure ([`shared_structure`]), else built alone
    /// in a one-thread pool and timed on that thread's CPU clock ([`Self::build_here`]).
    pub(crate) fn build(&self, s: usize, b: usize) -> BuildOutcome {
        if let Some(r) = self.cached(s, b) {
            return r;
        }
        if let Some(r) = self.derive_from_sibling(s, b) {
            return r;
        }
        match one_thread_pool() {
            Some(pool) => pool.install(|| self.build_here(s, b)),
            None => self.build_here(s, b),
        }
    }

    /// The cached build of `(s, b)`, if any.
    fn cached(&self, s: usize, b: usize) -> Option<BuildOutcome> {
        self.built
            .lock()
            .ok()
            .and_then(|v| v.iter().find(|(k, _)| *k == (s, b)).map(|(_, r)| r.clone()))
    }

    /// Caches `r` as the build of `(s, b)` (the first one stays) and returns it.
    fn remember(&self, s: usize, b: usize, r: BuildOutcome) -> BuildOutcome {
        if let Ok(mut v) = self.built.lock() {
            if let Some((_, first)) = v.iter().find(|(k, _)| *k == (s, b)) {
                return first.clone();
            }
            v.push(((s, b), r.clone()));
        }
        r
    }

    /// Builds `(s, b)` on the calling thread and caches it. Its time is the calling thread's
    /// CPU time (the wall time where the platform has no thread clock): run inside a
    /// one-thread rayon pool, every parallel part of the build runs on this thread, so the
    /// figure is the build's whole CPU cost, not inflated by builds running beside it.
    fn build_here(&self, s: usize, b: usize) -> BuildOutcome {
        let options = SetOptions {
            slices: self.config.slices,
            ..SetOptions::default()
        };
        let brdf = &self.brdfs[b];
        let request =
            DirectionRequest::new(Arc::clone(&brdf.counted), &options).with_spec(&brdf.spec);
        let (cpu, wall) = (thread_cpu_seconds(), Instant::now());
        let entry = &self.entries[s];
        let r = if let Err(na) = entry.applicability(brdf.counted.as_ref()) {
            Err(format!("does not apply to this BRDF: {}", na.reason))
        } else {
            entry
                .build_direction(&request)
                .map(|d| {
                    let wall = wall.elapsed().as_secs_f64();
                    (d, cpu_or_wall(cpu, thread_cpu_seconds(), wall))
                })
                .map_err(|e| format!("cannot build: {e}"))
        };
        self.remember(s, b, r)
    }

    /// `(s, b)` from the cached build of a sampler that shares its structure, if there is
    /// one: the same trees (a copy with `s`'s slice rule), the same outcome when that build
    /// failed, and the same build time (what `s` alone would have cost).
    fn derive_from_sibling(&self, s: usize, b: usize) -> Option<BuildOutcome> {
        if !self.share_builds {
            return None;
        }
        let (variant, mixture) = shared_structure(&self.entries[s])?;
        let (sibling, outcome) = (0..self.entries.len())
            .filter(|&o| o != s && shared_structure(&self.entries[o]).map(|v| v.0) == Some(variant))
            .find_map(|o| Some((o, self.cached(o, b)?)))?;
        let r = match outcome {
            Err(e) => Err(e),
            Ok((built, seconds)) => match &built.set {
                None => Err(format!(
                    "cannot build: the build of {} is not an adaptive set",
                    self.entries[sibling].name
                )),
                Some(set) => {
                    QuadTreeSet::from_bytes(&set.to_bytes(), Arc::clone(set.brdf()), set.spec())
                        .map(|copy| {
                            let mixture = mixture || SetOptions::default().mixture;
                            let copy = Arc::new(copy.with_mixture(mixture));
                            let sampler = Arc::new(SharedSet {
                                set: Arc::clone(&copy),
                                bytes: built.sampler.bytes_used(),
                            });
                            let built = BuiltDirection {
                                sampler,
                                set: Some(copy),
                                exact: None,
                            };
                            (built, seconds)
                        })
                        .map_err(|e| format!("cannot build: copying the shared structure: {e}"))
                }
            },
        };
        Some(self.remember(s, b, r))
    }

    /// Builds every `(sampler, BRDF)` of `list` not built yet: each structure once (the
    /// samplers sharing one are derived from it afterwards), the structures on
    /// `rayon::current_num_threads()` workers at once, each build alone in a one-thread pool
    /// ([`Self::build_here`]). Calls `progress(1)` per pair.
    pub(crate) fn build_all(&self, list: &[(usize, usize)], progress: ProgressFn<'_>) {
        let mut own = Vec::new();
        let mut derived = Vec::new();
        for &(s, b) in list {
            let shares = self.share_builds
                && shared_structure(&self.entries[s]).is_some_and(|(v, _)| {
                    own.iter().any(|&(o, ob): &(usize, usize)| {
                        ob == b && shared_structure(&self.entries[o]).map(|x| x.0) == Some(v)
                    })
                });
            if shares {
                derived.push((s, b));
            } else {
                own.push((s, b));
            }
        }
        // Longest first (a long build started last would run alone at the end while the other
        // cores idle): samplers that need a build before those that do not, and among them the
        // BRDFs dearest to evaluate first (a build's cost is mostly BRDF evaluations). The
        // order changes no build, only when each starts.
        let cost: Vec<f64> = {
            let mut bs: Vec<usize> = own.iter().map(|&(_, b)| b).collect();
            bs.sort_unstable();
            bs.dedup();
            let mut c = vec![0.0; self.brdfs.len()];
            for b in bs {
                c[b] = evaluation_cost(self.brdfs[b].raw.as_ref());
            }
            c
        };
        own.sort_by(|&(s1, b1), &(s2, b2)| {
            let n1 = self.entries[s1].capabilities.needs_build;
            let n2 = self.entries[s2].capabilities.needs_build;
            n2.cmp(&n1).then(cost[b2].total_cmp(&cost[b1]))
        });
        let next = std::sync::atomic::AtomicUsize::new(0);
        let workers = rayon::current_num_threads().clamp(1, own.len().max(1));
        std::thread::scope(|scope| {
            for _ in 0..workers {
                scope.spawn(|| {
                    let pool = one_thread_pool();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&(s, b)) = own.get(i) else { break };
                        if self.cached(s, b).is_none() {
                            let _ = match &pool {
                                Some(pool) => pool.install(|| self.build_here(s, b)),
                                None => self.build_here(s, b),
                            };
                        }
                        progress(1);
                    }
                });
            }
        });
        for (s, b) in derived {
            let _ = self.build(s, b);
            progress(1);
        }
    }

    /// How many `(sampler, BRDF)` builds the plan holds (tests: a render reuses them).
    #[cfg(test)]
    pub(crate) fn built_len(&self) -> usize {
        self.built.lock().map_or(0, |v| v.len())
    }

    /// The study's config.
    pub fn config(&self) -> &StudyConfig {
        &self.config
    }

    /// Every cell of the grid, by index.
    pub fn cells(&self) -> Vec<CellSpec> {
        self.cells.iter().map(|c| c.spec.clone()).collect()
    }

    /// The lights, resolved.
    pub fn lights(&self) -> &[Arc<Light>] {
        &self.lights
    }

    /// Progress steps of [`StudyPlan::run`] for `shard`: one per build, per reference, and two
    /// per cell (statistics, timing).
    pub fn steps(&self, shard: Option<Shard>) -> u64 {
        let cells = self.selected(shard);
        (self.builds(&cells).len()
            + self.light_builds(&cells).len()
            + self.references(&cells).len()
            + 2 * cells.len()) as u64
    }

    /// The cells of `shard`: those of the BRDFs `b` (index in the config's order) with
    /// `b mod N = K − 1`, so that a shard builds only its own BRDFs' samplers and computes only
    /// their references (the build is most of a measured BRDF's cost). A shard with no BRDF
    /// (N larger than the number of BRDFs) has no cells.
    fn selected(&self, shard: Option<Shard>) -> Vec<&PlanCell> {
        self.cells
            .iter()
            .filter(|c| shard.is_none_or(|s| s.contains(c.brdf)))
            .collect()
    }

    /// The BRDFs (specs, in config order) whose cells `shard` runs (all for `None`).
    pub fn shard_brdfs(&self, shard: Option<Shard>) -> Vec<&str> {
        self.brdfs
            .iter()
            .enumerate()
            .filter(|(b, _)| shard.is_none_or(|s| s.contains(*b)))
            .map(|(_, b)| b.spec.as_str())
            .collect()
    }

    /// The `(sampler, BRDF spec)` pairs [`StudyPlan::run`] builds for `shard` (all for
    /// `None`), each once: the shards of a study build disjoint sets whose union is the whole
    /// run's.
    pub fn shard_builds(&self, shard: Option<Shard>) -> Vec<(&str, &str)> {
        self.builds(&self.selected(shard))
            .into_iter()
            .map(|(s, b)| (self.entries[s].name, self.brdfs[b].spec.as_str()))
            .collect()
    }

    fn builds(&self, cells: &[&PlanCell]) -> Vec<(usize, usize)> {
        let mut v: Vec<_> = cells
            .iter()
            .filter(|c| c.uses_brdf_sampler())
            .map(|c| (c.sampler, c.brdf))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The `(light, map sampler)` pairs the cells need.
    fn light_builds(&self, cells: &[&PlanCell]) -> Vec<(usize, usize)> {
        let mut v: Vec<_> = cells
            .iter()
            .filter_map(|c| Some((c.light, c.light_sampler()?)))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The map sampler `ls` built for light `l` (a map light).
    fn build_light(&self, l: usize, ls: usize) -> LightBuild {
        let Light::Map { map, .. } = &*self.lights[l] else {
            return Err("not a map light".into());
        };
        self.light_entries[ls]
            .build_envmap(map, &AdaptiveOptions::default())
            .map(Arc::new)
            .map_err(|e| format!("cannot build the map sampler: {e}"))
    }

    fn references(&self, cells: &[&PlanCell]) -> Vec<(usize, usize, usize)> {
        let mut v: Vec<_> = cells.iter().map(|c| (c.brdf, c.theta, c.light)).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Runs the cells of `shard` (all when `None`); see the module docs.
    pub fn run(&self, shard: Option<Shard>, progress: ProgressFn<'_>) -> StudyResults {
        let clock = RunClock::start();
        let mut phases = PhaseClock::start();
        let cells = self.selected(shard);
        // Builds: each structure once, on every core, each timed on its own thread's CPU
        // clock (`build_all`).
        let list = self.builds(&cells);
        self.build_all(&list, progress);
        let built: Vec<((usize, usize), BuildOutcome)> = list
            .into_iter()
            .map(|(s, b)| ((s, b), self.build(s, b)))
            .collect();
        phases.lap("builds");
        let light_built: Vec<((usize, usize), LightBuild)> = self
            .light_builds(&cells)
            .into_par_iter()
            .map(|(l, ls)| {
                let r = self.build_light(l, ls);
                progress(1);
                ((l, ls), r)
            })
            .collect();
        phases.lap("map samplers");
        // References: independent quadratures, on every core.
        let references: Vec<((usize, usize, usize), Reference)> = self
            .references(&cells)
            .into_par_iter()
            .map(|(b, t, l)| {
                let wo = brdf::direction_from_angles(self.config.theta_o_deg[t], 0.0);
                let r = reference(self.brdfs[b].raw.as_ref(), &wo, &self.lights[l]);
                progress(1);
                ((b, t, l), r)
            })
            .collect();
        phases.lap("references");
        let find_build = |c: &PlanCell| {
            built
                .iter()
                .find(|(k, _)| *k == (c.sampler, c.brdf))
                .map(|(_, r)| r)
        };
        let find_light = |c: &PlanCell| -> Option<Result<&EnvMapSampler, String>> {
            let ls = c.light_sampler()?;
            Some(
                light_built
                    .iter()
                    .find(|(k, _)| *k == (c.light, ls))
                    .map_or(Err("not built".to_string()), |(_, r)| {
                        r.as_deref().map_err(Clone::clone)
                    }),
            )
        };
        // A cell's technique and its BRDF sampler's build time, or why it cannot run.
        let technique = |c: &PlanCell| -> Result<(Technique<'_>, f64), String> {
            let brdf = match (c.uses_brdf_sampler(), find_build(c)) {
                (false, _) => None,
                (true, Some(Ok((built, seconds)))) => Some((built.sampler.as_ref(), *seconds)),
                (true, Some(Err(e))) => return Err(e.clone()),
                (true, None) => return Err("not built".into()),
            };
            let light = find_light(c).transpose()?;
            Ok(match (c.kind, brdf, light) {
                (Kind::Brdf, Some((b, t)), _) => (Technique::Brdf(b), t),
                (Kind::Light { .. }, _, Some(l)) => (Technique::Light(l), 0.0),
                (Kind::Mis { heuristic, .. }, Some((b, t)), Some(l)) => (
                    Technique::Mis(MisPair {
                        brdf_sampler: b,
                        light_sampler: l,
                        frame: LocalFrame::identity(),
                        heuristic,
                    }),
                    t,
                ),
                _ => return Err("not built".into()),
            })
        };
        let find_ref = |c: &PlanCell| {
            references
                .iter()
                .find(|(k, _)| *k == (c.brdf, c.theta, c.light))
                .map(|(_, r)| r.clone())
                .unwrap_or(Reference {
                    value: f64::NAN,
                    abs_err: f64::NAN,
                    method: String::new(),
                })
        };
        // Statistics: the MIS cells of one (BRDF sampler, map sampler, BRDF, θo, light) under
        // different heuristics share their draws (`mis_groups`); every other cell runs alone.
        let groups = mis_groups(&cells);
        let mut slots: Vec<Option<CellResult>> = vec![None; cells.len()];
        let done: Vec<Vec<(usize, CellResult)>> = groups
            .par_iter()
            .map(|g| {
                let members: Vec<&PlanCell> = g.iter().map(|&i| cells[i]).collect();
                let out = match technique(members[0]) {
                    Ok((t, _)) => {
                        let refs: Vec<Reference> = members.iter().map(|c| find_ref(c)).collect();
                        self.run_cells(&members, t, refs)
                    }
                    // A BRDF-only member whose MIS group cannot run (its map sampler not
                    // built) runs alone, from its own stream.
                    Err(e) => members
                        .iter()
                        .map(|c| match (c.kind, technique(c)) {
                            (Kind::Brdf, Ok((t, _))) => {
                                self.run_cells(&[c], t, vec![find_ref(c)]).remove(0)
                            }
                            _ => failed(c, find_ref(c), e.clone()),
                        })
                        .collect(),
                };
                progress(g.len() as u64);
                g.iter().copied().zip(out).collect()
            })
            .collect();
        for (i, r) in done.into_iter().flatten() {
            slots[i] = Some(r);
        }
        let mut results: Vec<CellResult> = slots
            .into_iter()
            .map(|r| r.expect("every cell of a group ran"))
            .collect();
        phases.lap("statistics");
        // Timings: every timing thread gets an equal share of the cells (every T-th), and
        // runs its share interleaved — repeat 1 of each of its cells, then repeat 2, … — so
        // that a change of the machine's load during the timing phase shows in every cell's
        // spread. Each time is on its own thread's CPU clock; all threads run at once, so every
        // cell is timed under the same condition (the other cores timing too).
        let timers: Vec<(usize, CellTimer<'_>)> = cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| match (technique(c), results[i].ok()) {
                (Ok((t, seconds)), true) => Some((i, self.cell_timer(c, t, seconds))),
                _ => None,
            })
            .collect();
        let untimed = (cells.len() - timers.len()) as u64;
        let threads = timing_threads().clamp(1, timers.len().max(1));
        let mut shares: Vec<Vec<(usize, CellTimer<'_>)>> =
            (0..threads).map(|_| Vec::new()).collect();
        for (k, t) in timers.into_iter().enumerate() {
            shares[k % threads].push(t);
        }
        let (repeats, samples) = (self.config.timing_repeats, self.config.timing_samples);
        std::thread::scope(|scope| {
            for share in &mut shares {
                scope.spawn(move || {
                    // Rounds of one repeat of each cell still timing, until every cell of
                    // the share has met the stopping rule (`timing_done`).
                    let mut timing: Vec<&mut CellTimer<'_>> =
                        share.iter_mut().map(|(_, t)| t).collect();
                    while !timing.is_empty() {
                        for t in timing.iter_mut() {
                            t.repeat(samples);
                        }
                        let before = timing.len();
                        timing.retain(|t| !timing_done(&t.estimator_ns, repeats));
                        progress((before - timing.len()) as u64);
                    }
                });
            }
        });
        for (i, t) in shares.into_iter().flatten() {
            let r = &mut results[i];
            // Efficiency divides by the MSE at the budget (module `dispersion`); an exact
            // sampler's rounding-level value counts as 0 (no efficiency).
            let mse = if r.zero_variance { 0.0 } else { r.mse.value };
            r.timing = Some(t.finish(mse));
        }
        progress(untimed);
        phases.lap("timings");
        let mut warnings = build_warnings(
            &built,
            |s| self.entries[s].name,
            |b| self.brdfs[b].spec.as_str(),
        );
        warnings.sort();
        warnings.dedup();
        let mut out = StudyResults {
            schema: SCHEMA.to_string(),
            config: self.config.clone(),
            shard,
            total_cells: self.cells.len(),
            notes: self.notes.clone(),
            build_warnings: warnings,
            lights: self
                .config
                .lights
                .iter()
                .zip(&self.lights)
                .map(|(spec, l)| LightInfo {
                    spec: spec.clone(),
                    description: l.describe(),
                })
                .collect(),
            cells: results,
            runs: Vec::new(),
            rankings: Vec::new(),
        };
        if shard.is_none() {
            out.rankings = crate::ranking::rankings(&out);
            phases.lap("rankings");
        }
        out.runs = vec![clock.finish(phases.finish())];
        out
    }

    /// The statistics of `members`, cells of one technique that differ at most in their MIS
    /// heuristic, from one stream of draws (deterministic): the stream of the first member
    /// (`chunk_seed(seed, index)`), each draw's value computed under each member's heuristic.
    /// A lone cell is its own group, so its numbers are those of its own stream.
    fn run_cells(
        &self,
        members: &[&PlanCell],
        technique: Technique<'_>,
        references: Vec<Reference>,
    ) -> Vec<CellResult> {
        let cfg = &self.config;
        let c = members[0];
        let est = self.estimator(c, technique);
        // Each member's value per draw: `Some(h)` its MIS heuristic's, `None` (a BRDF-only
        // member) the estimator's value of the BRDF draw alone.
        let kinds: Vec<Option<MisHeuristic>> = members
            .iter()
            .map(|m| match m.kind {
                Kind::Mis { heuristic, .. } => Some(heuristic),
                _ => None,
            })
            .collect();
        let k = members.len();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(distributions::chunk_seed(
            cfg.seed,
            c.spec.index as u64,
        ));
        // The MIS members' evaluations (the whole pair's), and the BRDF-only member's (its
        // sampler's draws only).
        let mut counter = EvalCounter::default();
        let mut brdf_counter = EvalCounter::default();
        let budget = cfg.n_grid.last().copied().unwrap_or(1);
        let reps = repetitions_at(cfg, c.spec.mode, budget);
        let mut acc: Vec<Accumulator> = references
            .into_iter()
            .map(|reference| Accumulator {
                reference,
                errors: Vec::with_capacity(cfg.n_grid.len()),
                values: Vec::with_capacity(reps),
                all_values: Vec::new(),
            })
            .collect();
        let mut draw = |n: usize, rng: &mut Xoshiro256PlusPlus| {
            if k == 1 {
                vec![est.values(n, rng, &mut counter)]
            } else {
                est.mis_values(&kinds, n, rng, &mut counter, &mut brdf_counter)
            }
        };
        match c.spec.mode {
            Mode::OneSample => {
                // Nested error curves: each repetition draws one stream of `budget` values;
                // its estimate at each N of the grid is the mean of the stream's first N.
                let mut at_n: Vec<Vec<Vec<f64>>> = acc
                    .iter()
                    .map(|_| vec![Vec::with_capacity(reps); cfg.n_grid.len()])
                    .collect();
                for _ in 0..reps {
                    let ys = draw(budget, &mut rng);
                    for ((a, ys), at_n) in acc.iter_mut().zip(ys).zip(at_n.iter_mut()) {
                        let start = a.all_values.len();
                        a.all_values.extend(ys);
                        for (est, sum) in at_n
                            .iter_mut()
                            .zip(prefix_sums(&a.all_values[start..], &cfg.n_grid))
                        {
                            est.push(sum);
                        }
                    }
                }
                for (a, at_n) in acc.iter_mut().zip(at_n) {
                    for (&n, sums) in cfg.n_grid.iter().zip(at_n) {
                        a.values = sums.into_iter().map(|s| s / n as f64).collect();
                        a.error_at(n);
                    }
                }
            }
            Mode::Batch => {
                for &n in &cfg.n_grid {
                    for a in acc.iter_mut() {
                        a.values.clear();
                    }
                    for _ in 0..repetitions_at(cfg, c.spec.mode, n) {
                        let ys = draw(n, &mut rng);
                        for (a, ys) in acc.iter_mut().zip(ys) {
                            a.values.push(ys.into_iter().sum::<f64>() / n as f64);
                        }
                    }
                    for a in acc.iter_mut() {
                        a.error_at(n);
                    }
                }
            }
        }
        if c.spec.mode == Mode::OneSample {
            let ys = draw(cfg.variance_samples, &mut rng);
            for (a, ys) in acc.iter_mut().zip(ys) {
                a.all_values.extend(ys);
            }
        }
        members
            .iter()
            .zip(acc)
            .map(|(m, a)| match (m.kind, technique) {
                (Kind::Brdf, Technique::Mis(pair)) => self.cell_result(
                    m,
                    Technique::Brdf(pair.brdf_sampler),
                    &brdf_counter,
                    reps,
                    a,
                ),
                _ => self.cell_result(m, technique, &counter, reps, a),
            })
            .collect()
    }

    /// A cell's result from its accumulated values.
    fn cell_result(
        &self,
        c: &PlanCell,
        technique: Technique<'_>,
        counter: &EvalCounter,
        reps: usize,
        a: Accumulator,
    ) -> CellResult {
        let budget = self.config.n_grid.last().copied().unwrap_or(1);
        let Accumulator {
            reference,
            errors,
            values,
            all_values,
        } = a;
        let ref_value = reference.value;
        let (variance, mse, tail_share, warnings) = match c.spec.mode {
            Mode::OneSample => {
                let st = dispersion::one_sample_stats(&all_values);
                let mse = dispersion::one_sample_mse(&st, ref_value, reference.abs_err, budget);
                let warnings = dispersion::warnings(
                    st.tail_share,
                    st.n,
                    st.variance,
                    st.variance_ci95,
                    Some((st.mean, st.variance.sqrt())),
                    ref_value,
                    reference.abs_err,
                );
                let variance = WithCi {
                    value: finite(st.variance),
                    ci95: finite(st.variance_ci95),
                };
                (variance, mse, st.tail_share, warnings)
            }
            Mode::Batch => {
                let last = errors.last().map_or(0.0, |e| e.variance_per_sample);
                // Sample variance of R estimates: relative sd ≈ √(2/(R−1)) for near-normal
                // estimates.
                let variance = WithCi {
                    value: last,
                    ci95: finite(Z95 * last * (2.0 / (reps as f64 - 1.0)).sqrt()),
                };
                let (mse, tail_share) =
                    dispersion::batch_mse(&values, ref_value, reference.abs_err, budget);
                let warnings = dispersion::warnings(
                    tail_share,
                    values.len(),
                    variance.value,
                    variance.ci95,
                    None,
                    ref_value,
                    reference.abs_err,
                );
                (variance, mse, tail_share, warnings)
            }
        };
        let mse = BudgetMse {
            value: finite(mse.value),
            ci95: finite(mse.ci95),
            reference_err: finite(mse.reference_err),
            ..mse
        };
        let zero_variance = variance.value <= ZERO_VARIANCE * ref_value * ref_value;
        // The spread of rounding errors says nothing about a sampler.
        let warnings = if zero_variance { Vec::new() } else { warnings };
        CellResult {
            index: c.spec.index,
            sampler: c.spec.sampler.clone(),
            mode: c.spec.mode,
            brdf: c.spec.brdf.clone(),
            theta_o_deg: c.spec.theta_o_deg,
            light: c.spec.light.clone(),
            estimator: c.spec.estimator.clone(),
            light_sampler: c.spec.light_sampler.clone(),
            status: None,
            reference,
            bytes: technique.bytes_used(),
            evaluations_per_sample: counter.per_sample(),
            variance,
            zero_variance,
            mse,
            tail_share,
            warnings,
            errors,
            timing: None,
        }
    }

    /// The estimator of cell `c` with `technique`.
    fn estimator<'a>(&'a self, c: &PlanCell, technique: Technique<'a>) -> Estimator<'a> {
        Estimator {
            brdf: self.brdfs[c.brdf].raw.as_ref(),
            light: &self.lights[c.light],
            technique,
            mode: c.spec.mode,
            wo: brdf::direction_from_angles(c.spec.theta_o_deg, 0.0),
        }
    }

    /// The timer of one cell (its own stream, seeded apart from the statistics').
    fn cell_timer<'a>(
        &'a self,
        c: &PlanCell,
        technique: Technique<'a>,
        build_seconds: f64,
    ) -> CellTimer<'a> {
        let cfg = &self.config;
        CellTimer {
            est: self.estimator(c, technique),
            rng: Xoshiro256PlusPlus::seed_from_u64(distributions::chunk_seed(
                cfg.seed ^ 0x7469_6d65,
                c.spec.index as u64,
            )),
            build_seconds: if c.uses_brdf_sampler()
                && self.entries[c.sampler].capabilities.needs_build
            {
                build_seconds
            } else {
                0.0
            },
            sample_ns: Vec::with_capacity(cfg.timing_repeats),
            estimator_ns: Vec::with_capacity(cfg.timing_repeats),
            estimator_wall_ns: Vec::with_capacity(cfg.timing_repeats),
            sink: 0.0,
        }
    }
}

/// The timing runs of one cell.
struct CellTimer<'a> {
    est: Estimator<'a>,
    rng: Xoshiro256PlusPlus,
    build_seconds: f64,
    sample_ns: Vec<f64>,
    estimator_ns: Vec<f64>,
    estimator_wall_ns: Vec<f64>,
    sink: f64,
}

impl CellTimer<'_> {
    /// One timing run of `n` samples: the sampler alone, then the whole estimator, each on
    /// the thread's CPU clock (where the platform gives it) and on the wall clock.
    fn repeat(&mut self, n: usize) {
        let mut counter = EvalCounter::default();
        let per = 1e9 / n as f64;
        let (cpu, wall) = (thread_cpu_seconds(), Instant::now());
        let drawn = self.est.draw_only(n, &mut self.rng, &mut counter);
        let wall_s = wall.elapsed().as_secs_f64();
        self.sample_ns
            .push(cpu_or_wall(cpu, thread_cpu_seconds(), wall_s) * per);
        self.sink += drawn;
        let (cpu, wall) = (thread_cpu_seconds(), Instant::now());
        let sum: f64 = self.est.values(n, &mut self.rng, &mut counter).iter().sum();
        let wall_s = wall.elapsed().as_secs_f64();
        self.estimator_ns
            .push(cpu_or_wall(cpu, thread_cpu_seconds(), wall_s) * per);
        self.estimator_wall_ns.push(wall_s * per);
        self.sink += sum;
    }

    /// The cell's [`Timing`], efficiency from `mse`.
    fn finish(mut self, mse: f64) -> Timing {
        std::hint::black_box(self.sink);
        let (lo, hi) = self
            .estimator_ns
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        let log_sd = log_sd_of(&self.estimator_ns);
        let wall_log_sd = log_sd_of(&self.estimator_wall_ns);
        let estimator = median(&mut self.estimator_ns);
        Timing {
            clock: if thread_cpu_seconds().is_some() {
                Clock::ThreadCpu
            } else {
                Clock::Wall
            },
            build_seconds: self.build_seconds,
            sample_ns: median(&mut self.sample_ns),
            estimator_ns: estimator,
            estimator_ns_min: finite(lo),
            estimator_ns_max: hi,
            estimator_log_sd: finite(log_sd),
            estimator_wall_ns: median(&mut self.estimator_wall_ns),
            estimator_wall_log_sd: finite(wall_log_sd),
            repeats: self.estimator_ns.len(),
            efficiency: (mse > 0.0 && estimator > 0.0).then(|| 1.0 / (mse * estimator * 1e-9)),
        }
    }
}

/// Elapsed thread CPU time between two readings, or `wall` when the platform has no thread
/// clock.
fn cpu_or_wall(start: Option<f64>, end: Option<f64>, wall: f64) -> f64 {
    match (start, end) {
        (Some(a), Some(b)) => b - a,
        _ => wall,
    }
}

/// One cell's values while its statistics run.
struct Accumulator {
    reference: Reference,
    errors: Vec<ErrorAtN>,
    /// The estimates at the current N.
    values: Vec<f64>,
    /// Every one-sample value drawn (one-sample mode): the variance and the MSE at the budget
    /// are measured on all of them.
    all_values: Vec<f64>,
}

impl Accumulator {
    /// Records the relative errors of the estimates at `n`.
    fn error_at(&mut self, n: usize) {
        let ref_value = self.reference.value;
        let rel: Vec<f64> = self
            .values
            .iter()
            .map(|v| (v - ref_value).abs() / ref_value)
            .collect();
        let (mean_rel, var_rel) = mean_var(&rel);
        let (_, var_est) = mean_var(&self.values);
        self.errors.push(ErrorAtN {
            n,
            mean_rel_err: finite(mean_rel),
            ci95: finite(Z95 * (var_rel / rel.len() as f64).sqrt()),
            rms_rel_err: finite((rel.iter().map(|r| r * r).sum::<f64>() / rel.len() as f64).sqrt()),
            variance_per_sample: finite(n as f64 * var_est),
        });
    }
}

/// The sums of the first `n` values of `stream` for each `n` of `grid` (strictly increasing,
/// none above `stream.len()`), each summed from the start in order — so each equals
/// `stream[..n].iter().sum()` bit for bit, the sum an independent stream of `n` would give.
fn prefix_sums(stream: &[f64], grid: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grid.len());
    let (mut sum, mut k) = (0.0, 0);
    for &n in grid {
        for y in &stream[k..n] {
            sum += *y;
        }
        k = n;
        out.push(sum);
    }
    out
}

/// Independent estimates of a cell at `n`: `repetitions` (32 by default) at every N of the
/// grid, and in batch mode `max(repetitions, batch_repetitions)` (256) at the budget (largest)
/// N, where its variance and MSE rest on those estimates alone. The error curves' intervals at
/// the smaller N are computed from the count they have, as the one-sample mode's are.
fn repetitions_at(cfg: &StudyConfig, mode: Mode, n: usize) -> usize {
    let budget = cfg.n_grid.last().copied().unwrap_or(1);
    match mode {
        Mode::Batch if n == budget => cfg.repetitions.max(cfg.batch_repetitions),
        _ => cfg.repetitions,
    }
}

/// The groups of cells (positions in `cells`) whose statistics run together: the MIS cells of
/// one (BRDF sampler, map sampler, BRDF, θo, light) under each heuristic — the same pair of
/// draws serves every heuristic, only the weights differ, so each cell's values keep their
/// law (one BRDF draw and one map draw per sample) and the study draws once instead of once
/// per heuristic. Each group is led by its first cell (the balance heuristic's in the
/// config's order), whose stream it uses. A one-sample BRDF-only cell joins the group of its
/// BRDF sampler with the first map sampler: its values are the estimator's values of that
/// group's BRDF draws (`g / p` of each), the map draws between them only skip positions of
/// the stream, so its values keep their law (independent draws of its sampler) and it costs
/// no draw or evaluation of its own. Every other cell is a group of its own. The cells of one
/// group are correlated with each other, never with another cell of their own ranking (a
/// ranking compares cells of one estimator, so one heuristic, and the cells of one sampler
/// are in different groups).
fn mis_groups(cells: &[&PlanCell]) -> Vec<Vec<usize>> {
    /// (BRDF sampler, map sampler, BRDF, θo, light).
    type Pair = (usize, usize, usize, usize, usize);
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut lead: Vec<(Pair, usize)> = Vec::new();
    let mut brdf_only = Vec::new();
    for (i, c) in cells.iter().enumerate() {
        let Kind::Mis { ls, .. } = c.kind else {
            if c.kind == Kind::Brdf && c.spec.mode == Mode::OneSample {
                brdf_only.push(i);
            } else {
                groups.push(vec![i]);
            }
            continue;
        };
        let key = (c.sampler, ls, c.brdf, c.theta, c.light);
        match lead.iter().find(|(k, _)| *k == key) {
            Some(&(_, g)) => groups[g].push(i),
            None => {
                lead.push((key, groups.len()));
                groups.push(vec![i]);
            }
        }
    }
    // A one-sample BRDF-only cell joins the MIS group of its BRDF sampler, BRDF, θo and light
    // with the first map sampler (its BRDF draws are that group's), or runs alone.
    for i in brdf_only {
        let c = cells[i];
        let joined = lead
            .iter()
            .filter(|((s, _, b, t, l), _)| {
                (*s, *b, *t, *l) == (c.sampler, c.brdf, c.theta, c.light)
            })
            .min_by_key(|((_, ls, ..), _)| *ls)
            .map(|&(_, g)| g);
        match joined {
            Some(g) => groups[g].push(i),
            None => groups.push(vec![i]),
        }
    }
    groups
}

/// Fewest timing repeats of a cell (or `timing_repeats` when that is smaller).
pub(crate) const TIMING_MIN_REPEATS: usize = 5;

/// Relative standard error of a cell's median time at which its repeats stop early.
pub(crate) const TIMING_PRECISION: f64 = 0.05;

/// The timing repeats' stopping rule, given a cell's times so far (ns, the thread CPU clock):
/// stop after `max` repeats, or after `r ≥ min(TIMING_MIN_REPEATS, max)` repeats once the
/// median's standard error on the log scale, `1.2533 s / √r` (`s` the sample standard
/// deviation of `ln t`, 1.2533 = √(π/2) the median's efficiency factor under normal errors),
/// is at most [`TIMING_PRECISION`]. The rule looks at the cell's own times only, so a cell's
/// count does not depend on the others' or on the thread count. The ranking's time term is
/// `s` itself (the spread of single repeats), which is `√r / 1.2533 ≥ 1.78` times the
/// median's standard error for `r ≥ 5`, as it was 2.39 times at the fixed 9 repeats.
pub(crate) fn timing_done(times: &[f64], max: usize) -> bool {
    let r = times.len();
    if r >= max {
        return true;
    }
    if r < TIMING_MIN_REPEATS.min(max) {
        return false;
    }
    let se = 1.2533 * log_sd_of(times) / (r as f64).sqrt();
    se <= TIMING_PRECISION
}

/// Threads of the timing phase: rayon's (every core, or `RAYON_NUM_THREADS`).
fn timing_threads() -> usize {
    rayon::current_num_threads()
}

/// Sample standard deviation of `ln t` over the positive `t` (0 with fewer than two).
fn log_sd_of(t: &[f64]) -> f64 {
    let logs: Vec<f64> = t.iter().filter(|t| **t > 0.0).map(|t| t.ln()).collect();
    if logs.len() >= 2 {
        mean_var(&logs).1.sqrt()
    } else {
        0.0
    }
}

/// A cell that could not run.
fn failed(c: &PlanCell, reference: Reference, why: String) -> CellResult {
    CellResult {
        index: c.spec.index,
        sampler: c.spec.sampler.clone(),
        mode: c.spec.mode,
        brdf: c.spec.brdf.clone(),
        theta_o_deg: c.spec.theta_o_deg,
        light: c.spec.light.clone(),
        estimator: c.spec.estimator.clone(),
        light_sampler: c.spec.light_sampler.clone(),
        status: Some(why),
        reference,
        bytes: 0,
        evaluations_per_sample: 0.0,
        variance: WithCi {
            value: 0.0,
            ci95: 0.0,
        },
        zero_variance: false,
        mse: BudgetMse {
            n: 0,
            value: 0.0,
            ci95: 0.0,
            reference_err: 0.0,
        },
        tail_share: 0.0,
        warnings: Vec::new(),
        errors: Vec::new(),
        timing: None,
    }
}

/// What one cell's estimator samples (estimators from the `estimators` crate).
#[derive(Clone, Copy)]
enum Technique<'a> {
    /// BRDF sampling alone.
    Brdf(&'a dyn DirectionSampler),
    /// Light sampling alone (the study's shading frame is the world frame).
    Light(&'a EnvMapSampler),
    /// One draw of each, MIS weights.
    Mis(MisPair<'a>),
}

impl Technique<'_> {
    fn bytes_used(&self) -> usize {
        match self {
            Technique::Brdf(s) => s.bytes_used(),
            Technique::Light(l) => l.bytes_used(),
            Technique::Mis(p) => p.brdf_sampler.bytes_used() + p.light_sampler.bytes_used(),
        }
    }
}

/// One cell's estimator.
struct Estimator<'a> {
    brdf: &'a dyn Brdf,
    light: &'a Light,
    technique: Technique<'a>,
    mode: Mode,
    wo: Vec3,
}

impl Estimator<'_> {
    /// `n` BRDF samples in the cell's mode, counting the sampler's BRDF evaluations (BRDF
    /// cells).
    fn draw(
        &self,
        sampler: &dyn DirectionSampler,
        n: usize,
        rng: &mut Xoshiro256PlusPlus,
        counter: &mut EvalCounter,
    ) -> Vec<DirSample> {
        let before = thread_evaluations();
        let s = match self.mode {
            Mode::OneSample => (0..n).map(|_| sampler.sample(&self.wo, rng)).collect(),
            Mode::Batch => sampler.sample_batch(&self.wo, n, rng),
        };
        counter.evaluations += thread_evaluations() - before;
        counter.samples += n as u64;
        s
    }

    /// `n` one-sample values of the cell's estimator (a BRDF cell's in its mode), counting
    /// the samplers' BRDF evaluations (the integrand's own are not counted).
    fn values(
        &self,
        n: usize,
        rng: &mut Xoshiro256PlusPlus,
        counter: &mut EvalCounter,
    ) -> Vec<f64> {
        match self.technique {
            Technique::Brdf(sampler) => {
                let samples = self.draw(sampler, n, rng, counter);
                samples.iter().map(|s| self.value(s)).collect()
            }
            Technique::Light(l) => {
                let frame = LocalFrame::identity();
                counter.samples += n as u64;
                (0..n)
                    .map(|_| estimators::light_value(l, &frame, |wi| self.integrand(wi), rng))
                    .collect()
            }
            Technique::Mis(pair) => {
                let before = thread_evaluations();
                let v = (0..n)
                    .map(|_| pair.value(&self.wo, |wi| self.integrand(wi), rng))
                    .collect();
                counter.evaluations += thread_evaluations() - before;
                counter.samples += n as u64;
                v
            }
        }
    }

    /// `n` one-sample values of an MIS cell under each heuristic of `kinds`, from one pair of
    /// draws per sample (a BRDF draw, then a map draw: [`MisPair::value`]'s order, so the
    /// values under each heuristic are those `MisPair::value` gives from the same stream).
    /// The other technique's pdf is evaluated once per draw and serves every heuristic. A
    /// `None` in `kinds` gets the BRDF-only estimator's value of each BRDF draw
    /// ([`Self::value`]: `g / p`, from the integrand already evaluated for MIS), its sampler's
    /// evaluations counted in `brdf_counter`; `counter` counts the whole pair's.
    fn mis_values(
        &self,
        kinds: &[Option<MisHeuristic>],
        n: usize,
        rng: &mut Xoshiro256PlusPlus,
        counter: &mut EvalCounter,
        brdf_counter: &mut EvalCounter,
    ) -> Vec<Vec<f64>> {
        let Technique::Mis(pair) = self.technique else {
            return vec![self.values(n, rng, counter)];
        };
        let before = thread_evaluations();
        let mut brdf_evaluations = 0;
        let mut out: Vec<Vec<f64>> = kinds.iter().map(|_| Vec::with_capacity(n)).collect();
        for _ in 0..n {
            let drawn = thread_evaluations();
            let s = pair.brdf_sampler.sample(&self.wo, rng);
            brdf_evaluations += thread_evaluations() - drawn;
            let g = self.integrand(&s.wi);
            let other = (g > 0.0 && s.pdf > 0.0)
                .then(|| pair.light_sampler.pdf_world(&pair.frame.to_world(&s.wi)));
            let light = pair.light_sampler.sample_world(rng).map(|(d, pl)| {
                let wi = pair.frame.to_local(&d);
                let g = self.integrand(&wi);
                let other = (g > 0.0 && pl > 0.0).then(|| pair.brdf_sampler.pdf(&self.wo, &wi));
                (g, pl, other)
            });
            for (kind, o) in kinds.iter().zip(out.iter_mut()) {
                let Some(h) = kind else {
                    // `Self::value`: 0 below the horizon (`g` is 0 there) or where p is 0.
                    o.push(if s.pdf > 0.0 { g / s.pdf } else { 0.0 });
                    continue;
                };
                let a = estimators::mis_term(*h, g, s.pdf, 1.0, 1.0, || other.unwrap_or(0.0));
                let v = match light {
                    Some((g, pl, other)) => {
                        a + estimators::mis_term(*h, g, pl, 1.0, 1.0, || other.unwrap_or(0.0))
                    }
                    None => a,
                };
                o.push(v);
            }
        }
        counter.evaluations += thread_evaluations() - before;
        counter.samples += n as u64;
        brdf_counter.evaluations += brdf_evaluations;
        brdf_counter.samples += n as u64;
        out
    }

    /// The sampling alone of `n` values (timing); returns a number to keep.
    fn draw_only(&self, n: usize, rng: &mut Xoshiro256PlusPlus, counter: &mut EvalCounter) -> f64 {
        match self.technique {
            Technique::Brdf(sampler) => self.draw(sampler, n, rng, counter).len() as f64,
            Technique::Light(l) => (0..n).map(|_| l.sample(rng).pdf_sa).sum(),
            Technique::Mis(pair) => (0..n).map(|_| pair.draw(&self.wo, rng).0.z).sum(),
        }
    }

    /// `Y(f_r ⊙ L) cos θ` at a direction (0 below the horizon).
    #[inline]
    fn integrand(&self, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let f = self.brdf.eval_rgb(&self.wo, wi);
        let l = self.light.radiance(wi);
        colour::luminance([f[0] * l[0], f[1] * l[1], f[2] * l[2]]) * wi.z
    }

    /// `Y(f_r ⊙ L) cos θ / p_σ`, 0 below the horizon or where the pdf is 0.
    #[inline]
    fn value(&self, s: &DirSample) -> f64 {
        if !(s.wi.z > 0.0 && s.pdf > 0.0) {
            return 0.0;
        }
        let f = self.brdf.eval_rgb(&self.wo, &s.wi);
        let l = self.light.radiance(&s.wi);
        colour::luminance([f[0] * l[0], f[1] * l[1], f[2] * l[2]]) * s.wi.z / s.pdf
    }
}

/// BRDF evaluations and samples of one cell.
#[derive(Default)]
struct EvalCounter {
    evaluations: u64,
    samples: u64,
}

impl EvalCounter {
    fn per_sample(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            self.evaluations as f64 / self.samples as f64
        }
    }
}

/// Mean and unbiased sample variance (fixed summation order).
fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = x.iter().sum::<f64>() / n;
    if x.len() < 2 {
        return (mean, 0.0);
    }
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

/// The median (sorts `x`); 0 for an empty slice.
fn median(x: &mut [f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    x.sort_by(f64::total_cmp);
    let m = x.len() / 2;
    if x.len() % 2 == 1 {
        x[m]
    } else {
        0.5 * (x[m - 1] + x[m])
    }
}

/// Non-finite values (a zero reference) are stored as `f64::MAX` so JSON stays valid.
fn finite(x: f64) -> f64 {
    if x.is_finite() { x } else { f64::MAX }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampler reporting a wrong pdf (the cosine warp with its pdf scaled by 1.25).
    struct BrokenCosine;

    impl DirectionSampler for BrokenCosine {
        fn sample(&self, wo: &Vec3, u: &mut dyn distributions::UniformSource) -> DirSample {
            let s = baselines_cosine().sample(wo, u);
            DirSample {
                pdf: 1.25 * s.pdf,
                ..s
            }
        }
        fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            1.25 * baselines_cosine().pdf(wo, wi)
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    impl SamplerDiagnostics for BrokenCosine {}

    fn baselines_cosine() -> std::sync::Arc<dyn DirectionSampler> {
        samplers::build_direction(
            "cosine",
            &DirectionRequest::new(
                Arc::from(brdf::parse_spec("lambert").unwrap()),
                &SetOptions::default(),
            ),
        )
        .unwrap()
        .sampler
    }

    /// z-score of the estimator's mean over `n` samples against the reference.
    fn z_score(sampler: &dyn DirectionSampler, n: usize) -> f64 {
        let brdf = brdf::parse_spec("phong:n=10").unwrap();
        let light = Light::parse("area:theta=20,phi=180,radius=15").unwrap();
        let wo = brdf::direction_from_angles(20.0, 0.0);
        let reference = crate::reference(brdf.as_ref(), &wo, &light).value;
        z_of(
            brdf.as_ref(),
            &light,
            Technique::Brdf(sampler),
            reference,
            0.0,
            n,
        )
    }

    /// z-score of a technique's mean over `n` values against `reference`.
    fn z_of(
        brdf: &dyn Brdf,
        light: &Light,
        technique: Technique<'_>,
        reference: f64,
        reference_err: f64,
        n: usize,
    ) -> f64 {
        let est = Estimator {
            brdf,
            light,
            technique,
            mode: Mode::OneSample,
            wo: brdf::direction_from_angles(20.0, 0.0),
        };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let ys = est.values(n, &mut rng, &mut EvalCounter::default());
        let (mean, var) = mean_var(&ys);
        (mean - reference) / (var / n as f64 + reference_err * reference_err).sqrt()
    }

    /// The light and MIS cells' estimators under a small map (a bright patch on a dim
    /// background) agree with the quadrature reference (|z| < 4, fixed seed); MIS whose BRDF
    /// technique reports a wrong pdf (×1.25) is caught (|z| > 6). The reference's own error
    /// bound is in the z-score's denominator.
    #[test]
    fn the_light_and_mis_estimators_are_unbiased_and_a_wrong_pdf_is_caught() {
        let (w, h) = (256, 128);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (16..40).contains(&y) && (112..144).contains(&x) {
                    [30.0, 20.0, 10.0]
                } else {
                    [0.4, 0.5, 0.6]
                }
            })
            .collect();
        let light = Light::Map {
            map: envmap::EnvMap::new(w, h, rgb).unwrap(),
            label: "test".into(),
        };
        let brdf = brdf::parse_spec("phong:n=10").unwrap();
        let wo = brdf::direction_from_angles(20.0, 0.0);
        let reference = crate::reference(brdf.as_ref(), &wo, &light);
        assert!(reference.abs_err < 2e-3 * reference.value, "{reference:?}");
        let Light::Map { map, .. } = &light else {
            unreachable!()
        };
        let cdf = EnvMapSampler::piecewise_constant(map).unwrap();
        let cosine = baselines_cosine();
        let n = 100_000;
        let z = z_of(
            brdf.as_ref(),
            &light,
            Technique::Light(&cdf),
            reference.value,
            reference.abs_err,
            n,
        );
        assert!(z.abs() < 4.0, "light: z = {z}");
        for heuristic in MisHeuristic::ALL {
            let pair = |b| {
                Technique::Mis(MisPair {
                    brdf_sampler: b,
                    light_sampler: &cdf,
                    frame: LocalFrame::identity(),
                    heuristic,
                })
            };
            let z = z_of(
                brdf.as_ref(),
                &light,
                pair(cosine.as_ref()),
                reference.value,
                reference.abs_err,
                n,
            );
            assert!(z.abs() < 4.0, "{heuristic:?}: z = {z}");
            let z = z_of(
                brdf.as_ref(),
                &light,
                pair(&BrokenCosine),
                reference.value,
                reference.abs_err,
                n,
            );
            assert!(z.abs() > 6.0, "{heuristic:?} with a wrong pdf: z = {z}");
        }
    }

    #[test]
    fn the_estimator_is_unbiased_and_a_wrong_pdf_is_caught() {
        let good = z_score(baselines_cosine().as_ref(), 200_000);
        assert!(good.abs() < 4.0, "z = {good}");
        let broken = z_score(&BrokenCosine, 200_000);
        assert!(broken.abs() > 10.0, "z = {broken}");
    }

    #[test]
    fn median_and_variance() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        let (m, v) = mean_var(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m, 2.5);
        assert!((v - 5.0 / 3.0).abs() < 1e-15);
    }
}

#[cfg(test)]
mod build_warning_tests {
    use super::*;
    use brdf::Vec3;
    use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
    use distributions::UniformSource;

    /// A sampler whose report carries one warning line among others.
    struct Warns;

    impl DirectionSampler for Warns {
        fn sample(&self, _wo: &Vec3, _u: &mut dyn UniformSource) -> DirSample {
            DirSample {
                wi: Vec3::new(0.0, 0.0, 1.0),
                pdf: 1.0,
            }
        }
        fn pdf(&self, _wo: &Vec3, _wi: &Vec3) -> f64 {
            1.0
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    impl SamplerDiagnostics for Warns {
        fn build_report(&self) -> Option<String> {
            Some("fit  ok\nwarning: 2 of 2 fits hit the L-BFGS cap\nmemory 0".into())
        }
    }

    #[test]
    fn build_warnings_become_one_line_per_sampler_and_brdf() {
        let ok: BuildOutcome = Ok((
            samplers::BuiltDirection::plain(std::sync::Arc::new(Warns)),
            0.1,
        ));
        let failed: BuildOutcome = Err("cannot build".into());
        let built = vec![((0, 1), ok), ((1, 0), failed)];
        let names = ["srbf", "cosine"];
        let specs = ["lambert", "phong"];
        let w = build_warnings(&built, |s| names[s], |b| specs[b]);
        assert_eq!(
            w,
            vec!["sampler srbf on phong: 2 of 2 fits hit the L-BFGS cap".to_string()]
        );
    }
}

#[cfg(test)]
mod shared_build_tests {
    use super::*;

    /// A small study of the four adaptive sets (two structures, two slice rules each). GGX at
    /// 20 slices: enough trees that a copy's spare vector capacity (hence its memory figure)
    /// differs from the set as built, so the test sees a wrong `bytes` too (≈ 1.5 s).
    fn plan(share_builds: bool) -> StudyPlan {
        let mut c = StudyConfig::new(
            [
                "adaptive",
                "adaptive-mixture",
                "adaptive-paper",
                "adaptive-paper-mixture",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect(),
            vec!["ggx".into()],
            vec![30.0, 50.0],
            vec!["area:theta=20,phi=180,radius=15".into()],
        );
        c.n_grid = vec![4, 16];
        c.repetitions = 8;
        c.batch_repetitions = 8;
        c.variance_samples = 400;
        c.timing_samples = 8;
        c.timing_repeats = 1;
        c.slices = 20;
        c.estimators = Vec::new();
        let mut p = StudyPlan::new(c, Vec::new()).unwrap();
        p.share_builds = share_builds;
        p
    }

    /// Cell results without their timings (the only part that may differ between runs).
    fn statistics(r: &StudyResults) -> Vec<CellResult> {
        r.cells
            .iter()
            .map(|c| CellResult {
                timing: None,
                ..c.clone()
            })
            .collect()
    }

    fn build_seconds(r: &StudyResults, sampler: &str) -> f64 {
        r.cells
            .iter()
            .find(|c| c.sampler == sampler)
            .and_then(|c| c.timing.as_ref())
            .map(|t| t.build_seconds)
            .unwrap()
    }

    #[test]
    fn a_shared_build_gives_the_cells_of_separate_builds() {
        let shared = plan(true).run(None, &|_| {});
        let separate = plan(false).run(None, &|_| {});
        assert!(shared.cells.iter().all(|c| c.ok()), "{:?}", shared.cells);
        assert_eq!(statistics(&shared), statistics(&separate));
        // The shared build is one build: its time is reported for both of its samplers.
        for (a, b) in [
            ("adaptive", "adaptive-mixture"),
            ("adaptive-paper", "adaptive-paper-mixture"),
        ] {
            assert_eq!(build_seconds(&shared, a), build_seconds(&shared, b));
            assert!(build_seconds(&shared, a) > 0.0);
            // The slice rules differ, so the check above compares different samplers.
            let first = |r: &StudyResults, s: &str| {
                r.cells
                    .iter()
                    .find(|c| c.sampler == s)
                    .map(|c| c.variance.value)
                    .unwrap()
            };
            assert_ne!(first(&shared, a), first(&shared, b));
            // One structure, one memory figure.
            let bytes = |s: &str| shared.cells.iter().find(|c| c.sampler == s).unwrap().bytes;
            assert_eq!(bytes(a), bytes(b));
        }
    }
}

#[cfg(test)]
mod shared_draw_tests {
    use super::*;

    /// `cosine` and `lobe-sphere` on `phong:n=20` at θo = 40° under the sky, with small counts
    /// (N ∈ {2, 8}, 4 repetitions, 300 variance samples).
    pub(super) fn two_samplers_on_phong() -> StudyConfig {
        let mut c = StudyConfig::new(
            vec!["cosine".into(), "lobe-sphere".into()],
            vec!["phong:n=20".into()],
            vec![40.0],
            vec!["sky".into()],
        );
        c.n_grid = vec![2, 8];
        c.repetitions = 4;
        c.variance_samples = 300;
        c
    }

    /// MIS of `cosine` and `phong:n=20` under the sky with the given estimators; the map
    /// samplers are the study's two.
    fn run(estimators: &[&str]) -> StudyResults {
        let mut c = two_samplers_on_phong();
        c.timing_samples = 4;
        c.timing_repeats = 1;
        c.estimators = estimators.iter().map(|s| s.to_string()).collect();
        StudyPlan::new(c, Vec::new()).unwrap().run(None, &|_| {})
    }

    /// A cell's statistics, without what names it (index, estimator) or times it.
    fn numbers(c: &CellResult) -> CellResult {
        CellResult {
            index: 0,
            estimator: String::new(),
            timing: None,
            ..c.clone()
        }
    }

    fn of<'a>(r: &'a StudyResults, estimator: &str) -> Vec<&'a CellResult> {
        r.cells
            .iter()
            .filter(|c| c.estimator == estimator)
            .collect()
    }

    /// The balance and power cells of one pair share their draws: each gets exactly the
    /// values it would get alone from the same stream. With both heuristics, the balance
    /// cells equal a balance-only study's and the power cells a power-only study's (whose
    /// power cells sit at the balance cells' indices, so use their streams), every number.
    #[test]
    fn heuristics_sharing_draws_give_each_cell_its_lone_values() {
        let both = run(&["mis-balance", "mis-power"]);
        let balance = run(&["mis-balance"]);
        let power = run(&["mis-power"]);
        for (h, alone) in [("mis-balance", &balance), ("mis-power", &power)] {
            let (a, b) = (of(&both, h), of(alone, h));
            assert_eq!(a.len(), 4, "{h}");
            assert_eq!(a.len(), b.len(), "{h}");
            for (x, y) in a.iter().zip(&b) {
                assert!(x.ok() && x.variance.value > 0.0, "{h}: {x:?}");
                assert_eq!(numbers(x), numbers(y), "{h}");
            }
        }
        // The two heuristics give different numbers from the same draws.
        assert_ne!(
            numbers(of(&both, "mis-balance")[0]).variance,
            numbers(of(&both, "mis-power")[0]).variance
        );
    }

    /// A BRDF-only cell that joins its sampler's MIS group takes that group's BRDF draws (so
    /// other numbers than from its own stream: the estimator is then run without MIS) with
    /// the same law: the same evaluations and memory, and a per-sample variance within the
    /// two runs' intervals (z = 3.29, two-sided 0.1 %, fixed seeds).
    #[test]
    fn a_brdf_only_cell_sharing_mis_draws_keeps_its_law() {
        let both = run(&["mis-balance", "mis-power"]);
        let alone = run(&[]);
        let (a, b) = (of(&both, "brdf"), of(&alone, "brdf"));
        assert_eq!(a.len(), 2);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!((x.index, &x.sampler), (y.index, &y.sampler));
            assert!(x.ok() && y.ok());
            assert_ne!(
                x.variance, y.variance,
                "{}: not from the MIS draws",
                x.sampler
            );
            assert_eq!(x.evaluations_per_sample, y.evaluations_per_sample);
            assert_eq!(x.bytes, y.bytes);
            let (vx, vy) = (x.variance.value, y.variance.value);
            let half = (x.variance.ci95.powi(2) + y.variance.ci95.powi(2)).sqrt();
            assert!(
                (vx - vy).abs() <= 3.29 / Z95 * half,
                "{}: variance {vx} vs {vy} ± {half}",
                x.sampler
            );
        }
    }

    /// The sphere sheet of a subset of a study's BRDFs reuses the samplers the study built:
    /// rendering after the run builds nothing more.
    #[test]
    fn the_sphere_sheet_of_a_subset_reuses_the_study_builds() {
        let mut c = StudyConfig::new(
            vec!["cosine".into(), "adaptive".into()],
            vec!["lambert".into(), "phong:n=20".into()],
            vec![40.0],
            vec!["area:theta=30,phi=180,radius=10".into()],
        );
        c.n_grid = vec![2];
        c.repetitions = 2;
        c.variance_samples = 10;
        c.timing_samples = 2;
        c.timing_repeats = 1;
        c.slices = 8;
        c.estimators = Vec::new();
        let plan = StudyPlan::new(c, Vec::new()).unwrap();
        let _ = plan.run(None, &|_| {});
        assert_eq!(plan.built_len(), 4);
        let cfg = crate::RenderConfig {
            sphere_px: 8,
            spp: 2,
            reference_spp: 4,
            light: 0,
            seed: 1,
            mis: false,
        };
        let r = plan
            .render_subset(&cfg, &["phong:n=20".to_string()], &|_| {})
            .unwrap();
        assert_eq!(r.brdfs, ["phong:n=20"]);
        assert_eq!(plan.built_len(), 4);
    }

    /// `Estimator::mis_values` gives, under each heuristic, `MisPair::value`'s values from
    /// the same stream, and consumes the stream as one `MisPair::value` per sample does.
    #[test]
    fn mis_values_are_mis_pair_values_under_each_heuristic() {
        let light = Light::parse("sky").unwrap();
        let Light::Map { map, .. } = &light else {
            unreachable!()
        };
        let cdf = EnvMapSampler::piecewise_constant(map).unwrap();
        let brdf = brdf::parse_spec("phong:n=20").unwrap();
        let sampler = samplers::build_direction(
            "lobe-sphere",
            &DirectionRequest::new(
                Arc::from(brdf::parse_spec("phong:n=20").unwrap()),
                &SetOptions::default(),
            ),
        )
        .unwrap()
        .sampler;
        let est = |heuristic| Estimator {
            brdf: brdf.as_ref(),
            light: &light,
            technique: Technique::Mis(MisPair {
                brdf_sampler: sampler.as_ref(),
                light_sampler: &cdf,
                frame: LocalFrame::identity(),
                heuristic,
            }),
            mode: Mode::OneSample,
            wo: brdf::direction_from_angles(40.0, 0.0),
        };
        let n = 2000;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let shared = est(MisHeuristic::Balance).mis_values(
            &MisHeuristic::ALL.map(Some),
            n,
            &mut rng,
            &mut EvalCounter::default(),
            &mut EvalCounter::default(),
        );
        // With a BRDF-only member: the same MIS values, and for it the estimator's value of
        // each BRDF draw — the stream replayed: a BRDF draw, its value, then the map draw.
        let mut with_brdf = Xoshiro256PlusPlus::seed_from_u64(11);
        let kinds = [Some(MisHeuristic::Balance), None, Some(MisHeuristic::Power)];
        let mut brdf_counter = EvalCounter::default();
        let joint = est(MisHeuristic::Balance).mis_values(
            &kinds,
            n,
            &mut with_brdf,
            &mut EvalCounter::default(),
            &mut brdf_counter,
        );
        assert_eq!(joint[0], shared[0]);
        assert_eq!(joint[2], shared[1]);
        assert_eq!(with_brdf, rng, "the BRDF-only member draws nothing more");
        let lone = Estimator {
            technique: Technique::Brdf(sampler.as_ref()),
            ..est(MisHeuristic::Balance)
        };
        let mut replay = Xoshiro256PlusPlus::seed_from_u64(11);
        let expected: Vec<f64> = (0..n)
            .map(|_| {
                let s = sampler.sample(&lone.wo, &mut replay);
                let _ = cdf.sample_world(&mut replay);
                lone.value(&s)
            })
            .collect();
        assert_eq!(joint[1], expected);
        assert_eq!(brdf_counter.samples, n as u64);
        assert!(joint[1].iter().filter(|v| **v > 0.0).count() > n / 4);
        for (h, values) in MisHeuristic::ALL.into_iter().zip(&shared) {
            let mut alone = Xoshiro256PlusPlus::seed_from_u64(11);
            let v = est(h).values(n, &mut alone, &mut EvalCounter::default());
            assert_eq!(values, &v, "{h:?}");
            assert_eq!(alone, rng, "{h:?}: the stream is consumed differently");
        }
        assert!(shared[0].iter().any(|v| *v > 0.0));
    }
}

#[cfg(test)]
mod cost_rule_tests {
    use super::*;

    /// Batch-mode cells take `max(repetitions, batch_repetitions)` estimates at the budget N
    /// only (their MSE and variance rest on those), the other N and the one-sample mode
    /// `repetitions`.
    #[test]
    fn batch_cells_take_their_many_repetitions_at_the_budget_only() {
        let mut c = StudyConfig::new(vec![], vec![], vec![], vec![]);
        c.n_grid = vec![1, 25, 2500];
        c.repetitions = 32;
        c.batch_repetitions = 256;
        for n in [1, 25] {
            assert_eq!(repetitions_at(&c, Mode::Batch, n), 32);
            assert_eq!(repetitions_at(&c, Mode::OneSample, n), 32);
        }
        assert_eq!(repetitions_at(&c, Mode::Batch, 2500), 256);
        assert_eq!(repetitions_at(&c, Mode::OneSample, 2500), 32);
        c.repetitions = 300;
        assert_eq!(repetitions_at(&c, Mode::Batch, 2500), 300);
    }

    /// Times with a given spread of `ln t` around 1 µs: `r` values `exp(±sd)` alternating.
    fn times(r: usize, sd: f64) -> Vec<f64> {
        (0..r)
            .map(|i| 1000.0 * if i % 2 == 0 { sd.exp() } else { (-sd).exp() })
            .collect()
    }

    /// The timing rule: never fewer than 5 repeats (or the configured count when smaller),
    /// never more than the configured count, and between them a cell stops once its median's
    /// standard error `1.2533 s / √r` is ≤ 5 %.
    #[test]
    fn timing_repeats_stop_by_the_stated_rule() {
        // Tight times: stop at the fifth repeat, not before.
        for r in 1..5 {
            assert!(!timing_done(&times(r, 0.01), 9), "{r}");
        }
        assert!(timing_done(&times(5, 0.01), 9));
        // At 5 repeats the threshold on s is 0.05 √5 / 1.2533 = 0.0892 (s of the alternating
        // values is a little above `sd`).
        let s = |r, sd| log_sd_of(&times(r, sd));
        assert!(s(5, 0.08) < 0.0892 && timing_done(&times(5, 0.08), 9));
        assert!(s(5, 0.09) > 0.0892 && !timing_done(&times(5, 0.09), 9));
        // Noisy times: every repeat up to the configured count.
        for r in 5..9 {
            assert!(!timing_done(&times(r, 0.5), 9), "{r}");
        }
        assert!(timing_done(&times(9, 0.5), 9));
        // Fewer configured repeats than the minimum: that count.
        assert!(!timing_done(&times(2, 0.5), 3));
        assert!(timing_done(&times(3, 0.5), 3));
        assert!(timing_done(&times(1, 0.0), 1));
    }

    /// A study's cells take the timing repeats the rule gives their own times: between 5 and
    /// `timing_repeats`, and fewer than `timing_repeats` only with a median within 5 %.
    #[test]
    fn a_study_times_each_cell_by_the_rule() {
        let mut c = super::shared_draw_tests::two_samplers_on_phong();
        c.timing_samples = 64;
        c.timing_repeats = 12;
        let r = StudyPlan::new(c, Vec::new()).unwrap().run(None, &|_| {});
        for cell in &r.cells {
            let t = cell.timing.expect("timed");
            assert!((5..=12).contains(&t.repeats), "{}", t.repeats);
            if t.repeats < 12 {
                let se = 1.2533 * t.estimator_log_sd / (t.repeats as f64).sqrt();
                assert!(se <= TIMING_PRECISION, "{se}");
            }
        }
    }
}

#[cfg(test)]
mod nested_curve_tests {
    use super::*;

    /// `cosine` and `lobe-sphere` on `phong:n=20` at θo = 40° under an area light (no map: no
    /// MIS group, each cell alone on its own stream), grid `grid`, `reps` repetitions.
    fn plan(grid: &[usize], reps: usize, variance_samples: usize) -> StudyPlan {
        let mut c = StudyConfig::new(
            vec!["cosine".into(), "lobe-sphere".into()],
            vec!["phong:n=20".into()],
            vec![40.0],
            vec!["area:theta=20,phi=180,radius=15".into()],
        );
        c.n_grid = grid.to_vec();
        c.repetitions = reps;
        c.variance_samples = variance_samples;
        c.timing_samples = 4;
        c.timing_repeats = 1;
        c.estimators = Vec::new();
        StudyPlan::new(c, Vec::new()).unwrap()
    }

    /// The [`ErrorAtN`] of `estimates` at `n` against `reference` (the harness's formulas).
    fn error_of(reference: &Reference, estimates: Vec<f64>, n: usize) -> ErrorAtN {
        let mut a = Accumulator {
            reference: reference.clone(),
            errors: Vec::new(),
            values: estimates,
            all_values: Vec::new(),
        };
        a.error_at(n);
        a.errors.swap_remove(0)
    }

    /// `prefix_sums` sums each prefix in order, as a stream of that length alone would.
    #[test]
    fn prefix_sums_are_the_sums_of_the_prefixes() {
        let stream: Vec<f64> = (0..50).map(|i| (f64::from(i) * 0.37).sin() * 1e3).collect();
        let grid = [1, 2, 7, 25, 50];
        let sums = prefix_sums(&stream, &grid);
        for (&n, s) in grid.iter().zip(sums) {
            assert_eq!(s, stream[..n].iter().sum::<f64>(), "{n}");
        }
    }

    /// Nested error curves, replayed: each repetition of a one-sample cell is one stream of
    /// `budget` values from the cell's seed (repetition after repetition, then the variance
    /// samples); its estimate at each N is the mean of that stream's first N values. Every
    /// number of every N's error (and the variance over all values drawn) equals the replay's.
    #[test]
    fn nested_estimates_are_the_means_of_each_streams_prefixes() {
        let (grid, reps, extra) = ([1, 3, 10, 24], 5, 40);
        let p = plan(&grid, reps, extra);
        let r = p.run(None, &|_| {});
        assert_eq!(r.cells.len(), 2);
        for (c, res) in p.cells.iter().zip(&r.cells) {
            assert!(res.ok(), "{res:?}");
            let (built, _) = p.build(c.sampler, c.brdf).unwrap();
            let est = p.estimator(c, Technique::Brdf(built.sampler.as_ref()));
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(distributions::chunk_seed(
                p.config.seed,
                c.spec.index as u64,
            ));
            let mut counter = EvalCounter::default();
            let streams: Vec<Vec<f64>> = (0..reps)
                .map(|_| est.values(24, &mut rng, &mut counter))
                .collect();
            assert_eq!(res.errors.len(), grid.len());
            for (&n, got) in grid.iter().zip(&res.errors) {
                let estimates = streams
                    .iter()
                    .map(|s| s[..n].iter().sum::<f64>() / n as f64)
                    .collect();
                assert_eq!(*got, error_of(&res.reference, estimates, n), "{n}");
            }
            // Not a comparison of zeros: the estimates at the budget differ.
            assert!(res.errors[grid.len() - 1].variance_per_sample > 0.0);
            let mut all: Vec<f64> = streams.concat();
            all.extend(est.values(extra, &mut rng, &mut counter));
            let st = dispersion::one_sample_stats(&all);
            assert_eq!(st.n, reps * 24 + extra);
            assert_eq!(res.variance.value, st.variance, "{}", res.sampler);
        }
    }

    /// The nested error curve keeps its law at every N: its mean squared relative error at
    /// each N agrees with that of independent estimates drawn afresh at each N (the former
    /// scheme, another stream), 256 repetitions each. Under equal laws the two means of
    /// squared errors differ by a normal variate of variance `v (1/R₁ + 1/R₂)` (`v` the
    /// independent run's sample variance of squared errors); each N is tested at z = 3.29
    /// (two-sided 0.1 %; four N per sampler, two samplers: family-wise ≤ 0.8 %), fixed seeds.
    #[test]
    fn a_nested_error_curve_keeps_its_law_at_every_n() {
        let (grid, reps) = ([1, 4, 16, 64], 256);
        let p = plan(&grid, reps, 2);
        let r = p.run(None, &|_| {});
        for (c, res) in p.cells.iter().zip(&r.cells) {
            assert!(res.ok(), "{res:?}");
            let (built, _) = p.build(c.sampler, c.brdf).unwrap();
            let est = p.estimator(c, Technique::Brdf(built.sampler.as_ref()));
            let reference = res.reference.value;
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x6e65_7374);
            for (&n, got) in grid.iter().zip(&res.errors) {
                let sq: Vec<f64> = (0..reps)
                    .map(|_| {
                        let ys = est.values(n, &mut rng, &mut EvalCounter::default());
                        let rel = (ys.iter().sum::<f64>() / n as f64 - reference) / reference;
                        rel * rel
                    })
                    .collect();
                let (lone, v) = mean_var(&sq);
                let nested = got.rms_rel_err * got.rms_rel_err;
                let half = 3.29 * (v * 2.0 / reps as f64).sqrt();
                assert!(
                    (nested - lone).abs() <= half,
                    "{} at N = {n}: nested {nested} vs independent {lone} ± {half}",
                    res.sampler
                );
                assert!(nested > 0.0 && lone > 0.0);
            }
        }
    }
}
