//! A validation run: resolve the configuration, build the cases, run them in parallel, judge
//! every p-value at the Šidák level, and collect the report.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use brdf::{Brdf, Vec3, direction_from_angles};
use brdf_sampling::DirectionSampler;
use rayon::prelude::*;
use stats::TestOutcome;
#[cfg(test)]
use stats::sidak_level;

use crate::adapters::DirectionAtWo;
use crate::builds::{
    StandaloneCase, build_direction, build_disc, direction_domain, standalone_cases, uses_brdf,
};
use crate::case::{error_outcome, names, run_case, skipped_outcome};
use crate::domain::Domain;
use crate::error::ValidationError;
use crate::mutants::{Mutant, mutants};
use crate::plan::{
    DEFAULT_MEASURED_DIR, FULL_PRESET_MODELS, FULL_THETA_O, MIN_SAMPLES, PRESET_THETA_O, Plan,
    QUICK_BRDFS, QUICK_THETA_O, Shard, Tier, ValidateConfig,
};
use crate::references::{albedo_reference, lit_reference};
use crate::report::{BuildWarning, MutantRecord, ShardInfo, TestRecord, ValidationReport};
use crate::seeding::{case_seed, label_hash};
use crate::subject::AnySubject;
use crate::targets::{BrdfReferences, brdf_direction_subject, brdf_disc_subject};
use samplers::{Registry, SamplerEntry};

/// Progress of a run, reported once at the start and once per finished case.
#[derive(Debug, Clone, PartialEq)]
pub enum ProgressEvent {
    /// The run starts `total` cases (a mutant with its control counts as one).
    Started {
        /// Number of cases.
        total: usize,
    },
    /// A case finished (events may arrive in any order; the report's order is fixed).
    Finished {
        /// Cases finished so far.
        done: usize,
        /// Number of cases.
        total: usize,
        /// `sampler | target | θo` (or `mutant:name`).
        label: String,
        /// Whether all its tests passed at the placeholder level (for mutants: whether caught).
        passed: bool,
    },
}

/// The cases of one run, resolved from a [`ValidateConfig`].
struct Resolved<'r> {
    plan: Plan,
    brdfs: Vec<(String, Arc<dyn Brdf>)>,
    angles: Vec<f64>,
    samplers: Vec<&'r SamplerEntry>,
    sets: Vec<LoadedSet>,
    /// Specs run at [`PRESET_THETA_O`] only (the full tier's default preset fits).
    few_angles: Vec<String>,
}

impl Resolved<'_> {
    /// Whether `spec` runs at `theta` (every angle of the run, except for the full tier's
    /// preset fits, which run at the run's angles that are in [`PRESET_THETA_O`]).
    fn runs(&self, spec: &str, theta: f64) -> bool {
        !self.few_angles.iter().any(|s| s == spec) || PRESET_THETA_O.contains(&theta)
    }
}

/// `rgl:` specs of the `rgl/*.bsdf` files and `cornell:` specs of the `cornell/*.brdf` files
/// under `dir` (none when absent).
fn measured_specs(dir: &Path) -> Vec<String> {
    let mut files: Vec<String> = Vec::new();
    for (sub, ext, model) in [("rgl", "bsdf", "rgl"), ("cornell", "brdf", "cornell")] {
        let Ok(entries) = std::fs::read_dir(dir.join(sub)) else {
            continue;
        };
        let mut found: Vec<String> = entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == ext))
            .map(|p| format!("{model}:{}", p.display()))
            .collect();
        found.sort();
        files.extend(found);
    }
    files
}

fn merl_specs(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<String> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "binary"))
        .map(|p| format!("merl:{}", p.display()))
        .collect();
    files.sort();
    files
}

fn resolve<'r>(
    registry: &'r Registry,
    config: &ValidateConfig,
    given: &[(String, Arc<dyn Brdf>)],
) -> Result<Resolved<'r>, ValidationError> {
    if !(config.alpha > 0.0 && config.alpha < 1.0) {
        return Err(ValidationError::BadAlpha(config.alpha));
    }
    let tier = config.tier();
    let samples = config.samples.unwrap_or(Plan::default_samples(tier));
    if samples < MIN_SAMPLES {
        return Err(ValidationError::TooFewSamples {
            got: samples,
            min: MIN_SAMPLES,
        });
    }
    let angles: Vec<f64> = if config.theta_o.is_empty() {
        match tier {
            Tier::Quick => QUICK_THETA_O.to_vec(),
            Tier::Full => FULL_THETA_O.to_vec(),
        }
    } else {
        config.theta_o.clone()
    };
    if let Some(&bad) = angles
        .iter()
        .find(|a| !(a.is_finite() && **a >= 0.0 && **a < 90.0))
    {
        return Err(ValidationError::BadAngle(bad));
    }
    let sets = load_sets(&config.sets)?;
    let mut entries: Vec<&SamplerEntry> = Vec::new();
    if config.samplers.is_empty() && sets.is_empty() {
        entries.extend(registry.entries().iter());
    } else {
        for name in &config.samplers {
            let e = registry.find(name)?;
            if !entries.iter().any(|x| x.name == e.name) {
                entries.push(e);
            }
        }
    }
    let mut few_angles: Vec<String> = Vec::new();
    let specs: Vec<String> = if config.brdfs.is_empty() && !given.is_empty() {
        Vec::new()
    } else if config.brdfs.is_empty() {
        match tier {
            Tier::Quick => QUICK_BRDFS.iter().map(|s| (*s).to_owned()).collect(),
            Tier::Full => {
                let mut v: Vec<String> = brdf::models()
                    .iter()
                    .filter(|m| !m.needs_argument())
                    .map(|m| m.name.to_owned())
                    .collect();
                if let Some(dir) = &config.merl_dir {
                    v.extend(merl_specs(dir));
                    v.extend(measured_specs(Path::new(DEFAULT_MEASURED_DIR)));
                }
                for model in FULL_PRESET_MODELS {
                    let presets = brdf::preset_names(model).unwrap_or_default();
                    let specs: Vec<String> = presets
                        .iter()
                        .map(|n| format!("{model}:material={n}"))
                        .collect();
                    few_angles.extend(specs.iter().cloned());
                    v.extend(specs);
                }
                v
            }
        }
    } else {
        config.brdfs.clone()
    };
    let mut brdfs = Vec::with_capacity(specs.len());
    for spec in specs {
        match brdf::parse_spec(&spec) {
            Ok(b) => brdfs.push((spec, Arc::from(b))),
            Err(source) => return Err(ValidationError::Brdf { spec, source }),
        }
    }
    brdfs.extend(given.iter().map(|(l, b)| (l.clone(), Arc::clone(b))));
    if entries.is_empty() && sets.is_empty() {
        return Err(ValidationError::Empty("no sampler selected".into()));
    }
    if !sets.is_empty() && angles.is_empty() {
        return Err(ValidationError::Empty(
            "saved sets need at least one angle".into(),
        ));
    }
    if entries.iter().any(|e| uses_brdf(e)) && (brdfs.is_empty() || angles.is_empty()) {
        return Err(ValidationError::Empty(
            "BRDF samplers need at least one BRDF and one angle".into(),
        ));
    }
    Ok(Resolved {
        plan: Plan::new(tier, samples),
        brdfs,
        angles,
        samplers: entries,
        sets,
        few_angles,
    })
}

/// The outcomes of one case.
struct CaseResult {
    /// Index in the run's full plan.
    index: usize,
    sampler: String,
    target: String,
    theta_o: Option<f64>,
    domain: String,
    outcomes: Vec<TestOutcome>,
}

impl CaseResult {
    fn label(&self) -> String {
        match self.theta_o {
            Some(t) => format!("{} | {} | {t}°", self.sampler, self.target),
            None => format!("{} | {}", self.sampler, self.target),
        }
    }
}

/// A unit of parallel work: one sampler with one BRDF (all angles, sharing one build), or one
/// standalone case.
enum Job<'a> {
    Brdf {
        entry: &'a SamplerEntry,
        brdf: usize,
    },
    Standalone {
        entry: &'a SamplerEntry,
        case: &'a StandaloneCase,
    },
    /// A saved set (index into the run's sets), with its own BRDF.
    Set(usize),
}

fn references_for(brdf: &dyn Brdf, wo: &Vec3) -> Result<BrdfReferences, String> {
    Ok(BrdfReferences {
        albedo: albedo_reference(brdf, wo).map_err(|e| e.to_string())?,
        lit: lit_reference(brdf, wo).map_err(|e| e.to_string())?,
    })
}

fn case_label(sampler: &str, target: &str, theta: Option<f64>) -> String {
    format!("{sampler}|{target}|{theta:?}")
}

#[allow(clippy::too_many_arguments)]
fn run_brdf_job(
    entry: &SamplerEntry,
    r: &Resolved,
    bi: usize,
    refs: &[Result<BrdfReferences, String>],
    seed: u64,
    cases: Cases<'_>,
    on_done: &(dyn Fn(&CaseResult) + Sync),
    warnings: &Mutex<Vec<BuildWarning>>,
) -> Vec<CaseResult> {
    let (spec, brdf) = &r.brdfs[bi];
    // Nothing of this job in the shard: not built.
    if !(0..cases_at(r, spec)).any(|k| (cases.keep)(cases.base + k)) {
        return Vec::new();
    }
    // A sampler that does not apply to this BRDF (the registry says why) is skipped and
    // reported, never built.
    if let Err(na) = entry.applicability(brdf.as_ref()) {
        return skipped_angles(entry.name, spec, r, &na.reason, cases, on_done);
    }
    // Direction samplers are built once per BRDF; disc samplers per angle.
    let built = direction_domain(entry).map(|domain| {
        build_direction(entry, brdf)
            .map(|s| (s, domain))
            .map_err(|e| e.to_string())
    });
    if let Some(Ok((sampler, _))) = &built
        && let Ok(mut all) = warnings.lock()
    {
        all.extend(build_warnings(
            entry.name,
            spec,
            cases.base,
            sampler.build_report(),
        ));
    }
    let subject_at = |wo: Vec3, refs: &BrdfReferences| match &built {
        Some(b) => {
            let (sampler, domain) = b.as_ref().map_err(Clone::clone)?;
            Ok(direction_subject(sampler, *domain, brdf, wo, refs))
        }
        None => Ok(AnySubject::Planar(brdf_disc_subject(
            build_disc(entry, brdf, &wo).map_err(|e| e.to_string())?,
            Arc::clone(brdf),
            wo,
            refs,
        ))),
    };
    run_angles(entry.name, spec, r, refs, seed, cases, on_done, &subject_at)
}

/// The `warning: …` lines of a build report, as the report's build warnings of the job whose
/// first case is `case`.
fn build_warnings(
    sampler: &str,
    spec: &str,
    case: usize,
    report: Option<String>,
) -> Vec<BuildWarning> {
    report
        .iter()
        .flat_map(|r| r.lines())
        .filter_map(|l| l.strip_prefix("warning: "))
        .map(|w| BuildWarning {
            case,
            message: format!("sampler {sampler} on {spec}: {w}"),
        })
        .collect()
}

/// The first case index of a job and the shard's selection of case indices.
#[derive(Clone, Copy)]
struct Cases<'a> {
    base: usize,
    keep: &'a (dyn Fn(usize) -> bool + Sync),
}

/// The number of cases of `spec` in the run: the angles it runs at.
fn cases_at(r: &Resolved, spec: &str) -> usize {
    r.angles.iter().filter(|&&t| r.runs(spec, t)).count()
}

/// The cases of a sampler that does not apply to a BRDF: one skipped outcome per angle the
/// BRDF runs at.
fn skipped_angles(
    sampler: &str,
    spec: &str,
    r: &Resolved,
    reason: &str,
    cases: Cases<'_>,
    on_done: &(dyn Fn(&CaseResult) + Sync),
) -> Vec<CaseResult> {
    r.angles
        .iter()
        .filter(|&&theta| r.runs(spec, theta))
        .enumerate()
        .filter(|(k, _)| (cases.keep)(cases.base + k))
        .map(|(k, &theta)| {
            let c = CaseResult {
                index: cases.base + k,
                sampler: sampler.to_owned(),
                target: spec.to_owned(),
                theta_o: Some(theta),
                domain: "—".to_owned(),
                outcomes: vec![skipped_outcome(reason)],
            };
            on_done(&c);
            c
        })
        .collect()
}

/// A direction sampler at `wo` as a subject on `domain`.
fn direction_subject(
    sampler: &Arc<dyn DirectionSampler>,
    domain: Domain,
    brdf: &Arc<dyn Brdf>,
    wo: Vec3,
    refs: &BrdfReferences,
) -> AnySubject {
    AnySubject::Direction(brdf_direction_subject(
        Arc::new(DirectionAtWo::new(Arc::clone(sampler), wo)),
        domain,
        Arc::clone(brdf),
        wo,
        refs,
    ))
}

/// Runs one sampler (as `subject_at` builds it per `ωo`) for one BRDF at every angle of the run.
#[allow(clippy::too_many_arguments)]
fn run_angles(
    sampler: &str,
    spec: &str,
    r: &Resolved,
    refs: &[Result<BrdfReferences, String>],
    seed: u64,
    cases: Cases<'_>,
    on_done: &(dyn Fn(&CaseResult) + Sync),
    subject_at: &(dyn Fn(Vec3, &BrdfReferences) -> Result<AnySubject, String> + Sync),
) -> Vec<CaseResult> {
    let mut out = Vec::with_capacity(r.angles.len());
    let mut k = 0;
    for (ai, &theta) in r.angles.iter().enumerate() {
        if !r.runs(spec, theta) {
            continue;
        }
        let index = cases.base + k;
        k += 1;
        if !(cases.keep)(index) {
            continue;
        }
        let wo = direction_from_angles(theta, 0.0);
        let subject: Result<AnySubject, String> = refs
            .get(ai)
            .cloned()
            .unwrap_or_else(|| Err("missing reference".into()))
            .and_then(|refs| subject_at(wo, &refs));
        let (domain, outcomes) = match &subject {
            Ok(s) => (
                s.domain().name().to_owned(),
                run_case(
                    s,
                    &r.plan,
                    case_seed(seed, &case_label(sampler, spec, Some(theta))),
                ),
            ),
            Err(e) => ("—".to_owned(), vec![error_outcome(names::BUILD, e)]),
        };
        let c = CaseResult {
            index,
            sampler: sampler.to_owned(),
            target: spec.to_owned(),
            theta_o: Some(theta),
            domain,
            outcomes,
        };
        on_done(&c);
        out.push(c);
    }
    out
}

/// A saved set of the run, re-attached to the BRDF of its stored spec.
struct LoadedSet {
    /// `NAME (set FILE)`.
    label: String,
    spec: String,
    brdf: Arc<dyn Brdf>,
    sampler: Arc<dyn DirectionSampler>,
}

fn load_sets(paths: &[PathBuf]) -> Result<Vec<LoadedSet>, ValidationError> {
    paths
        .iter()
        .map(|path| {
            let fail = |reason: String| ValidationError::Set {
                path: path.clone(),
                reason,
            };
            let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
            let (entry, built) =
                samplers::load_set(&bytes, None).map_err(|e| fail(e.to_string()))?;
            // A quadtree set knows its spec; an `adaptive-exact` file records it.
            let (spec, brdf) = match (&built.set, &built.exact) {
                (Some(set), _) => (set.spec().to_owned(), Arc::clone(set.brdf())),
                (None, Some(exact)) => (
                    brdf_sampling::ExactSet::stored_spec(&bytes)
                        .map_err(|e| fail(e.to_string()))?,
                    Arc::clone(exact.brdf()),
                ),
                (None, None) => return Err(fail("not an adaptive set".into())),
            };
            let file = path.file_name().map_or_else(
                || path.display().to_string(),
                |f| f.to_string_lossy().into_owned(),
            );
            Ok(LoadedSet {
                label: format!("{} (set {file})", entry.name),
                spec,
                brdf,
                sampler: built.sampler,
            })
        })
        .collect()
}

/// Runs a validation: every selected sampler × BRDF × angle (and the standalone samplers'
/// targets), then the mutants when asked.
///
/// `progress` is called from worker threads (hence `Sync`) with a [`ProgressEvent::Started`]
/// and one [`ProgressEvent::Finished`] per case. The report depends only on the configuration
/// (seed included), never on the number of threads: cases are seeded from the master seed and
/// their own labels, samples are drawn in fixed chunks with one generator each, and results
/// are collected in a fixed order.
///
/// # Errors
/// [`ValidationError`] for bad input (unknown sampler, bad BRDF spec, bad angle, too few
/// samples, bad `alpha`, empty selection). Failing samplers are reported, not errors.
pub fn run(
    config: &ValidateConfig,
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    run_with(&Registry::builtin(), config, progress)
}

/// [`run`] with the samplers of `registry` (names in `config.samplers` are looked up there;
/// an empty selection runs all of its entries): a sampler added with
/// [`samplers::Registry::with`] — from a crate outside the workspace, or from Python — runs
/// the same suite as the built-in ones. Mutants and saved sets are the built-in ones.
///
/// # Errors
/// As [`run`].
pub fn run_with(
    registry: &Registry,
    config: &ValidateConfig,
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    run_shard_with(registry, config, None, progress)
}

/// Runs the cases of one shard of a validation (all of them with `None`, as [`run`] does).
///
/// The run's cases are numbered in a fixed order (the standalone samplers whose targets could
/// not be built, then every sampler × BRDF × angle, the standalone samplers' targets and the
/// saved sets' angles in job order, then the mutants); `shard` keeps the cases `i` with
/// `i mod N = K − 1` ([`Shard::contains`]). Each case is seeded from the master seed and its
/// own label, so its records equal the single run's; a sampler is built only when the shard
/// holds one of its cases. The shard's report carries a [`ShardInfo`] (its `passed` judges its
/// own tests only); [`crate::merge`] recombines the parts into the single run's report.
///
/// # Errors
/// As [`run`].
pub fn run_shard(
    config: &ValidateConfig,
    shard: Option<Shard>,
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    run_shard_with(&Registry::builtin(), config, shard, progress)
}

/// [`run_shard`] with the samplers of `registry` (see [`run_with`]).
///
/// # Errors
/// As [`run`].
pub fn run_shard_with(
    registry: &Registry,
    config: &ValidateConfig,
    shard: Option<Shard>,
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    run_brdfs_shard(registry, config, &[], shard, progress)
}

/// [`run_with`] on BRDF objects too: `brdfs` (label, BRDF) are validated after the specs of
/// `config.brdfs` (alone when that is empty), each labelled in the report by its label. For
/// BRDFs that no spec names (e.g. a Python callable).
///
/// # Errors
/// As [`run`].
pub fn run_with_brdfs(
    registry: &Registry,
    config: &ValidateConfig,
    brdfs: &[(String, Arc<dyn Brdf>)],
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    run_brdfs_shard(registry, config, brdfs, None, progress)
}

fn run_brdfs_shard(
    registry: &Registry,
    config: &ValidateConfig,
    given: &[(String, Arc<dyn Brdf>)],
    shard: Option<Shard>,
    progress: &(dyn Fn(ProgressEvent) + Sync),
) -> Result<ValidationReport, ValidationError> {
    let r = resolve(registry, config, given)?;
    let seed = config.seed;

    // Standalone samplers' cases are built up front (cheap), so the total is known.
    let standalone: Vec<(&SamplerEntry, Result<Vec<StandaloneCase>, String>)> = r
        .samplers
        .iter()
        .filter_map(|e| standalone_cases(e).map(|cases| (*e, cases.map_err(|err| err.to_string()))))
        .collect();
    let brdf_entries: Vec<&SamplerEntry> = r
        .samplers
        .iter()
        .copied()
        .filter(|e| uses_brdf(e))
        .collect();
    let mut jobs: Vec<Job<'_>> = Vec::new();
    for &entry in &brdf_entries {
        // Pairs where the sampler does not apply are jobs too: reported as skipped cases.
        for bi in 0..r.brdfs.len() {
            jobs.push(Job::Brdf { entry, brdf: bi });
        }
    }
    // The plan's case labels in the fixed order (their index is the case's number).
    let mut labels: Vec<String> = Vec::new();
    let mut failed_builds: Vec<(&SamplerEntry, &String)> = Vec::new();
    for (entry, cases) in &standalone {
        match cases {
            Ok(cases) => jobs.extend(cases.iter().map(|case| Job::Standalone { entry, case })),
            Err(e) => {
                labels.push(case_label(entry.name, "—", None));
                failed_builds.push((entry, e));
            }
        }
    }
    jobs.extend((0..r.sets.len()).map(Job::Set));
    let mut bases: Vec<usize> = Vec::with_capacity(jobs.len());
    for job in &jobs {
        bases.push(labels.len());
        match job {
            Job::Brdf { entry, brdf } => {
                let spec = &r.brdfs[*brdf].0;
                labels.extend(
                    r.angles
                        .iter()
                        .filter(|&&t| r.runs(spec, t))
                        .map(|&t| case_label(entry.name, spec, Some(t))),
                );
            }
            Job::Standalone { entry, case } => {
                labels.push(case_label(entry.name, &case.target, None));
            }
            Job::Set(i) => {
                let set = &r.sets[*i];
                labels.extend(
                    r.angles
                        .iter()
                        .filter(|&&t| r.runs(&set.spec, t))
                        .map(|&t| case_label(&set.label, &set.spec, Some(t))),
                );
            }
        }
    }
    let mutant_list = if config.mutants { mutants() } else { &[] };
    let mutant_base = labels.len();
    labels.extend(mutant_list.iter().map(|m| format!("mutant:{}", m.name)));
    let total_cases = labels.len();
    let keep = |i: usize| shard.is_none_or(|s| s.contains(i));
    let total = (0..total_cases).filter(|&i| keep(i)).count();
    progress(ProgressEvent::Started { total });
    let done = AtomicUsize::new(0);
    let notify = |label: String, passed: bool| {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress(ProgressEvent::Finished {
            done: d,
            total,
            label,
            passed,
        });
    };
    let on_done = |c: &CaseResult| notify(c.label(), c.outcomes.iter().all(|o| o.passed));

    // References of every (BRDF, angle) that a case of the shard needs, shared by the
    // samplers.
    let mut needed = vec![vec![false; r.angles.len()]; r.brdfs.len()];
    for (job, &base) in jobs.iter().zip(&bases) {
        if let Job::Brdf { brdf, .. } = job {
            let spec = &r.brdfs[*brdf].0;
            let running = r
                .angles
                .iter()
                .enumerate()
                .filter(|(_, t)| r.runs(spec, **t));
            for (k, (ai, _)) in running.enumerate() {
                needed[*brdf][ai] |= keep(base + k);
            }
        }
    }
    let refs: Vec<Vec<Result<BrdfReferences, String>>> = r
        .brdfs
        .par_iter()
        .zip(&needed)
        .map(|((_, b), need)| {
            r.angles
                .par_iter()
                .zip(need)
                .map(|(&t, &need)| {
                    if need {
                        references_for(b.as_ref(), &direction_from_angles(t, 0.0))
                    } else {
                        Err("not run at this angle in this shard".to_owned())
                    }
                })
                .collect()
        })
        .collect();

    let failed_builds: Vec<CaseResult> = failed_builds
        .into_iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(index, (entry, e))| CaseResult {
            index,
            sampler: entry.name.to_owned(),
            target: "—".into(),
            theta_o: None,
            domain: "—".into(),
            outcomes: vec![error_outcome(names::BUILD, e)],
        })
        .collect();
    let warnings: Mutex<Vec<BuildWarning>> = Mutex::new(Vec::new());
    let results: Vec<Vec<CaseResult>> = jobs
        .par_iter()
        .zip(&bases)
        .map(|(job, &base)| {
            let cases = Cases { base, keep: &keep };
            match job {
                Job::Brdf { entry, brdf } => run_brdf_job(
                    entry,
                    &r,
                    *brdf,
                    &refs[*brdf],
                    seed,
                    cases,
                    &on_done,
                    &warnings,
                ),
                Job::Standalone { .. } if !keep(base) => Vec::new(),
                Job::Standalone { entry, case } => {
                    let c = CaseResult {
                        index: base,
                        sampler: entry.name.to_owned(),
                        target: case.target.clone(),
                        theta_o: None,
                        domain: case.subject.domain.name().to_owned(),
                        outcomes: run_case(
                            &AnySubject::Planar(case.subject.clone()),
                            &r.plan,
                            case_seed(seed, &case_label(entry.name, &case.target, None)),
                        ),
                    };
                    on_done(&c);
                    vec![c]
                }
                Job::Set(i) => {
                    let set = &r.sets[*i];
                    let running = || r.angles.iter().filter(|&&t| r.runs(&set.spec, t));
                    if !(0..running().count()).any(|k| keep(base + k)) {
                        return Vec::new();
                    }
                    let refs: Vec<Result<BrdfReferences, String>> = r
                        .angles
                        .iter()
                        .map(|&t| references_for(set.brdf.as_ref(), &direction_from_angles(t, 0.0)))
                        .collect();
                    let subject_at = |wo: Vec3, refs: &BrdfReferences| {
                        Ok(direction_subject(
                            &set.sampler,
                            Domain::Hemisphere,
                            &set.brdf,
                            wo,
                            refs,
                        ))
                    };
                    run_angles(
                        &set.label,
                        &set.spec,
                        &r,
                        &refs,
                        seed,
                        cases,
                        &on_done,
                        &subject_at,
                    )
                }
            }
        })
        .collect();
    let mutant_results: Vec<MutantCase> = mutant_list
        .par_iter()
        .enumerate()
        .filter(|(j, _)| keep(mutant_base + j))
        .map(|(j, m)| {
            let index = mutant_base + j;
            let label = |kind: &str| format!("{kind}:{}", m.name);
            let wo = direction_from_angles(m.theta_o, 0.0);
            let built = brdf::parse_spec(m.brdf)
                .map_err(|e| e.to_string())
                .and_then(|b| {
                    let b: Arc<dyn Brdf> = Arc::from(b);
                    let refs = references_for(b.as_ref(), &wo)?;
                    m.build(&b, &wo, &refs)
                });
            let run_one = |s: Result<&AnySubject, &String>, kind: &str| {
                let (domain, outcomes) = match s {
                    Ok(s) => (
                        s.domain().name().to_owned(),
                        run_case(s, &r.plan, case_seed(seed, &label(kind))),
                    ),
                    Err(e) => ("—".to_owned(), vec![error_outcome(names::BUILD, e)]),
                };
                CaseResult {
                    index,
                    sampler: label(kind),
                    target: m.brdf.to_owned(),
                    theta_o: Some(m.theta_o),
                    domain,
                    outcomes,
                }
            };
            let (mc, cc) = match &built {
                Ok(case) => (
                    run_one(Ok(&case.mutant), "mutant"),
                    run_one(Ok(&case.control), "control"),
                ),
                Err(e) => (run_one(Err(e), "mutant"), run_one(Err(e), "control")),
            };
            notify(label("mutant"), mc.outcomes.iter().any(|o| !o.passed));
            (m, mc, cc)
        })
        .collect();

    let shard_info = shard.map(|s| ShardInfo {
        index: s.index,
        count: s.count,
        total_cases,
        cases: total,
        fingerprint: fingerprint(config, &labels),
    });
    Ok(assemble(
        config,
        &r.plan,
        failed_builds
            .into_iter()
            .chain(results.into_iter().flatten())
            .collect(),
        mutant_results,
        warnings.into_inner().unwrap_or_default(),
        shard_info,
    ))
}

/// A mutant with its case and its control's.
type MutantCase = (&'static Mutant, CaseResult, CaseResult);

/// FNV-1a (hex) of the configuration (as JSON) and of the plan's case labels in order.
fn fingerprint(config: &ValidateConfig, labels: &[String]) -> String {
    let mut text = serde_json::to_string(config).unwrap_or_default();
    for l in labels {
        text.push('\n');
        text.push_str(l);
    }
    format!("{:016x}", label_hash(&text))
}

fn records(c: &CaseResult) -> Vec<TestRecord> {
    c.outcomes
        .iter()
        .map(|o| TestRecord {
            case: c.index,
            ..TestRecord::new(&c.target, &c.sampler, c.theta_o, &c.domain, o)
        })
        .collect()
}

fn assemble(
    config: &ValidateConfig,
    plan: &Plan,
    cases: Vec<CaseResult>,
    mutant_results: Vec<MutantCase>,
    warnings: Vec<BuildWarning>,
    shard: Option<ShardInfo>,
) -> ValidationReport {
    let mutants: Vec<MutantRecord> = mutant_results
        .iter()
        .map(|(m, mc, cc)| MutantRecord {
            case: mc.index,
            name: m.name.to_owned(),
            // Derived from the tests by `judged`.
            detected: false,
            caught_by: Vec::new(),
            min_p_value: None,
            control_passed: false,
            description: m.description.to_owned(),
            brdf: m.brdf.to_owned(),
            theta_o: m.theta_o,
            tests: records(mc),
            control_tests: records(cc),
        })
        .collect();
    ValidationReport {
        alpha: config.alpha,
        passed: false,
        tests: cases.iter().flat_map(records).collect(),
        mutants,
        tier: plan.tier.name().to_owned(),
        seed: config.seed,
        samples: plan.samples,
        batches: [plan.batches, plan.batch_size],
        m: 0,
        per_test_level: 0.0,
        warnings,
        shard,
    }
    .judged()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(sampler: &str, outcomes: Vec<TestOutcome>) -> CaseResult {
        CaseResult {
            index: 0,
            sampler: sampler.into(),
            target: "lambert".into(),
            theta_o: Some(0.0),
            domain: "hemisphere".into(),
            outcomes,
        }
    }

    fn p(name: &str, p: f64) -> TestOutcome {
        TestOutcome::with_p_value(name, 1.0, p, 0.01, String::new())
    }

    fn det(name: &str, ok: bool) -> TestOutcome {
        TestOutcome::deterministic(name, 0.0, ok, String::new())
    }

    fn assembled(cases: Vec<CaseResult>, pairs: Vec<(CaseResult, CaseResult)>) -> ValidationReport {
        let config = ValidateConfig::quick();
        let pairs = pairs
            .into_iter()
            .zip(mutants())
            .map(|((mc, cc), m)| (m, mc, cc))
            .collect();
        assemble(
            &config,
            &Plan::new(Tier::Quick, 1000),
            cases,
            pairs,
            Vec::new(),
            None,
        )
    }

    #[test]
    fn p_values_are_judged_at_the_sidak_level() {
        // m = 4 p-valued tests at α = 0.01: the per-test level is ≈ 0.0025.
        let cases = vec![
            case("a", vec![p("x", 0.004), p("y", 0.5), det("z", true)]),
            case("b", vec![p("x", 0.3), p("y", 0.9)]),
        ];
        let r = assembled(cases, Vec::new());
        assert_eq!(r.m, 4);
        assert!((r.per_test_level - sidak_level(0.01, 4)).abs() < 1e-15);
        assert!(
            r.tests.iter().all(|t| t.passed),
            "0.004 passes at the Šidák level"
        );
        assert!(r.passed());
        let r = assembled(
            vec![case("a", vec![p("x", 0.001), p("y", 0.5)])],
            Vec::new(),
        );
        assert!(!r.passed() && !r.tests[0].passed && r.tests[1].passed);
        let r = assembled(vec![case("a", vec![det("x", false)])], Vec::new());
        assert!(!r.passed());
    }

    #[test]
    fn a_missed_mutant_or_a_failed_control_fails_the_run() {
        let good = || case("control:m", vec![p("x", 0.5)]);
        let caught = || case("mutant:m", vec![p("x", 1e-30), p("y", 0.4)]);
        let missed = || case("mutant:m", vec![p("x", 0.2)]);
        let r = assembled(vec![case("a", vec![p("x", 0.5)])], vec![(caught(), good())]);
        assert!(r.passed());
        assert_eq!(r.mutants[0].caught_by, vec!["x".to_owned()]);
        assert_eq!(r.mutants[0].min_p_value, Some(1e-30));
        let r = assembled(vec![case("a", vec![p("x", 0.5)])], vec![(missed(), good())]);
        assert!(!r.passed() && !r.mutants[0].detected);
        let bad_control = case("control:m", vec![p("x", 1e-9)]);
        let r = assembled(
            vec![case("a", vec![p("x", 0.5)])],
            vec![(caught(), bad_control)],
        );
        assert!(!r.passed() && !r.mutants[0].control_passed);
    }

    #[test]
    fn a_run_whose_every_case_was_skipped_did_not_pass() {
        let skipped = || case("analytic", vec![skipped_outcome("no analytic sampler")]);
        let r = assembled(vec![skipped()], Vec::new());
        assert!(!r.passed() && r.tests.iter().all(|t| t.passed));
        assert_eq!((r.tests_run(), r.skipped_cases()), (0, 1));
        assert!(
            r.to_markdown().contains("**Result: NO TEST RAN**"),
            "{}",
            r.to_markdown()
        );
        let json: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
        assert_eq!(json["passed"], false);
        let r = assembled(vec![skipped(), case("b", vec![p("x", 0.5)])], Vec::new());
        assert!(r.passed());
        assert_eq!((r.tests_run(), r.skipped_cases()), (1, 1));
        assert!(
            r.to_markdown().contains("1 test run, 1 case skipped"),
            "{}",
            r.to_markdown()
        );
        assert!(!assembled(Vec::new(), Vec::new()).passed());
    }

    #[test]
    fn uniform_on_lambert_at_the_minimum_count_gets_a_chi_square() {
        // `validate --sampler uniform --brdf lambert --samples 2000` (the full tier): the
        // 24 × 48 bins expected 1.7 samples each, all pooled into one cell — no statistic.
        let config = ValidateConfig {
            samplers: vec!["uniform".into()],
            brdfs: vec!["lambert".into()],
            theta_o: vec![30.0],
            samples: Some(crate::MIN_SAMPLES),
            ..ValidateConfig::full()
        };
        let report = run(&config, &|_| {}).expect("valid config");
        let chi: Vec<_> = report
            .tests
            .iter()
            .filter(|t| t.test == names::CHI_SQUARE)
            .collect();
        assert_eq!(chi.len(), 1);
        assert!(
            chi[0].statistic.is_finite() && chi[0].p_value.is_some_and(|p| p > 0.0),
            "{:?}",
            chi[0]
        );
        assert!(report.passed(), "{}", report.to_markdown());
    }

    #[test]
    fn build_warnings_reach_the_report_and_its_markdown() {
        let report = Some(
            "srbf       2 slices\nwarning: 2 of 2 BRDF slice fits hit the iteration cap\nmore"
                .into(),
        );
        let w = build_warnings("srbf", "phong", 3, report);
        assert_eq!(
            w,
            [BuildWarning {
                case: 3,
                message: "sampler srbf on phong: 2 of 2 BRDF slice fits hit the iteration cap"
                    .into()
            }]
        );
        assert!(build_warnings("srbf", "phong", 3, None).is_empty());
        let config = ValidateConfig::quick();
        let r = assemble(
            &config,
            &Plan::new(Tier::Quick, 1000),
            vec![case("a", vec![p("x", 0.5)])],
            Vec::new(),
            [w.clone(), w.clone()].concat(),
            None,
        );
        // One warning per build, in the markdown and the JSON.
        assert_eq!(r.warnings, w);
        assert!(
            r.to_markdown()
                .contains("## Build warnings\n\n- sampler srbf on phong: 2 of 2")
        );
        let back: ValidationReport = serde_json::from_str(&r.to_json()).unwrap();
        assert_eq!(back.warnings, w);
    }
}
