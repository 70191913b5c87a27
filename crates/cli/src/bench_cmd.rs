//! `brdf-lab bench`: the cost of one sample, as an estimator pays it, for several samplers of
//! one BRDF in one run — "which sampler is fastest for my material".
//!
//! One sample is `sample(ωo, u) -> (ωi, pdf)` **plus the one evaluation `f_r(ωo, ωi)`** the
//! estimator `f cos / pdf` needs, drawn together through the fused
//! [`DirectionSampler::sample_eval`] (a rejection sampler returns the `f` of its accepted
//! trial; the others evaluate once). Queries are either one fixed `ωo` (`--theta-o/--phi-o`) or a
//! fresh `ωo` per query (`--queries random`: uniform in solid angle over θo ∈ [0°, 89°], as
//! when ωo changes from pixel to pixel). Samples are split into fixed chunks, each with its own
//! generator seeded from `(seed, chunk)`, so the samples do not depend on the thread count.
//!
//! Wall time is measured `--repeat` times per sampler, interleaved across samplers (so a change
//! of machine load spreads over all of them), and the median is reported with the spread.
//! BRDF evaluations per sample (including the estimator's one) are counted in a separate,
//! untimed pass through the study's counting wrapper (`study::CountingBrdf`, which keeps the
//! model's prepared fast path); they do not depend on the load. The timed runs go through the
//! same wrapper (one thread-local increment per evaluation, a few ns at most).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, EvalSample};
use clap::{Args, ValueEnum};
use partition_sampler::{chunk_seed, thread_trials};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use study::{CountingBrdf, thread_evaluations};

use crate::brdf_args::{self, Given, SamplerArgs};
use crate::error::{CliError, CliResult};
use crate::output::write_atomically;
use crate::progress;
use crate::values;

/// Samples per independently seeded chunk.
const CHUNK: usize = 4096;

/// Largest θo of a random query, degrees (grazing, but not at the horizon).
const RANDOM_THETA_MAX_DEG: f64 = 89.0;

/// Samples of the untimed counting pass (at most).
const COUNT_SAMPLES: usize = 200_000;

/// How the outgoing directions of the queries are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Queries {
    /// One ωo for every query (`--theta-o`, `--phi-o`).
    Fixed,
    /// A fresh ωo per query, uniform in solid angle over θo ∈ [0°, 89°].
    Random,
}

/// Arguments of `brdf-lab bench`.
#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
    /// BRDF: `name` or `name:key=value,...` (e.g. `ggx:alpha=0.2`), `merl:PATH`, `rgl:PATH`, ….
    /// Optional with --set (then the sets' stored spec; when given it must match theirs).
    #[arg(long = "brdf", required_unless_present = "set_files")]
    spec: Option<String>,
    /// Samplers to compare (registry names, see `brdf-lab list`); several in one run.
    #[arg(long = "sampler", num_args = 1.., required_unless_present = "set_files")]
    samplers: Vec<String>,
    /// Also compare a set written by `build --out` (repeatable): loaded, not built (its own
    /// options apply; its build time is reported as 0). Every set must be for the same BRDF.
    #[arg(long = "set", value_name = "FILE")]
    set_files: Vec<PathBuf>,
    /// Outgoing directions: `fixed` (one ωo) or `random` (a fresh ωo per query).
    #[arg(long, value_enum, default_value_t = Queries::Random)]
    queries: Queries,
    /// Outgoing polar angle θo in degrees, in [0, 90) (with `--queries fixed`).
    #[arg(long = "theta-o", default_value_t = 30.0, value_parser = values::theta_o, allow_hyphen_values = true)]
    theta_o: f64,
    /// Outgoing azimuth φo in degrees, in [−360, 360] (with `--queries fixed`).
    #[arg(long = "phi-o", default_value_t = 0.0, value_parser = values::azimuth, allow_hyphen_values = true)]
    phi_o: f64,
    /// Samples per timed run.
    #[arg(short = 'n', long = "samples", default_value_t = 1_000_000,
          value_parser = values::int(1u64, 1_000_000_000), allow_negative_numbers = true)]
    n: u64,
    /// Timed runs per sampler (interleaved across samplers); the median is reported.
    #[arg(long, default_value_t = 5, value_parser = values::int(1u32, 1000), allow_negative_numbers = true)]
    repeat: u32,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = values::int(1u32, 1024), allow_negative_numbers = true)]
    threads: Option<u32>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1, value_parser = values::seed)]
    seed: u64,
    /// Draw each chunk's queries (4096) in one batch call (`sample_eval_batch`: samplers that
    /// have a batch path group the queries, e.g. `adaptive-exact` by interval) instead of one
    /// query at a time.
    #[arg(long)]
    batch: bool,
    /// Also write the results as JSON (a list, one object per sampler) here, atomically.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    #[command(flatten)]
    set: SamplerArgs,
}

/// One sampler's figures.
#[derive(Debug, Clone, Serialize)]
struct BenchRecord {
    /// The sampler's registry name.
    sampler: String,
    /// Median wall time per sample (incl. the estimator's `f`), ns, on `threads` threads.
    ns_per_sample: f64,
    /// Fastest and slowest of the timed runs, ns per sample.
    ns_per_sample_min: f64,
    ns_per_sample_max: f64,
    /// Every timed run, ns per sample, in the order run.
    ns_per_sample_runs: Vec<f64>,
    /// BRDF evaluations per sample, the estimator's one included (counted, not timed).
    evals_per_sample: f64,
    /// Rejection trials (proposals, accepted or not) per sample, counted in the same untimed
    /// pass; `null` for a sampler that records none (one proposal per sample).
    trials_per_sample: Option<f64>,
    /// Samples per timed run.
    samples: usize,
    /// Threads of the timed runs.
    threads: usize,
    /// `fixed` or `random`.
    queries: Queries,
    /// Whether the queries went through the batch path (`--batch`).
    batch: bool,
    /// Build time, seconds (wall).
    build_seconds: f64,
    /// Bytes of the sampler's precomputed structures.
    bytes_used: usize,
    /// Mean of `f cos / pdf` over the timed run's samples: the directional albedo (fixed ωo) or
    /// its average over the queries' ωo; a checksum that the work was done.
    mean_weight: f64,
}

/// The outgoing direction of query `i` of a chunk.
fn query(queries: Queries, fixed: &Vec3, rng: &mut Xoshiro256PlusPlus) -> Vec3 {
    match queries {
        Queries::Fixed => *fixed,
        Queries::Random => {
            // Uniform in solid angle over the cap θ ≤ θmax: cos θ uniform on [cos θmax, 1].
            let cos_max = RANDOM_THETA_MAX_DEG.to_radians().cos();
            let c = 1.0 - rng.random::<f64>() * (1.0 - cos_max);
            let s = (1.0 - c * c).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * rng.random::<f64>();
            Vec3::new(s * phi.cos(), s * phi.sin(), c)
        }
    }
}

/// Draws `n` samples (and their `f`) in seeded chunks — one query at a time, or with `batch`
/// a chunk's queries in one [`DirectionSampler::sample_eval_batch`] call; returns
/// Σ f cos / pdf and the evaluations and rejection trials counted on the worker threads.
fn run_samples(
    sampler: &dyn DirectionSampler,
    brdf: &dyn Brdf,
    queries: Queries,
    fixed: &Vec3,
    n: usize,
    seed: u64,
    batch: bool,
) -> (f64, u64, u64) {
    let chunks = n.div_ceil(CHUNK);
    (0..chunks)
        .into_par_iter()
        .map(|c| {
            let len = CHUNK.min(n - c * CHUNK);
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, c as u64));
            let before = thread_evaluations();
            let trials_before = thread_trials();
            let mut sum = 0.0;
            if batch {
                // The chunk's queries first, then one batch call (the sampler may group them).
                let wos: Vec<Vec3> = (0..len).map(|_| query(queries, fixed, &mut rng)).collect();
                let mut out = Vec::with_capacity(len);
                sampler.sample_eval_batch(brdf, &wos, &mut rng, &mut out);
                sum = out.iter().map(EvalSample::weight).sum();
            } else {
                for _ in 0..len {
                    let wo = query(queries, fixed, &mut rng);
                    sum += sampler.sample_eval(brdf, &wo, &mut rng).weight();
                }
            }
            (
                sum,
                thread_evaluations() - before,
                thread_trials() - trials_before,
            )
        })
        .reduce(|| (0.0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2))
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

/// A built sampler of the benchmark and its build figures.
struct Subject {
    name: String,
    sampler: Arc<dyn DirectionSampler>,
    build_seconds: f64,
}

fn build(name: &str, spec: &str, args: &BenchArgs, brdf: Arc<dyn Brdf>) -> CliResult<Subject> {
    let (built, elapsed) = brdf_args::build(name, spec, brdf, &args.set)?;
    let build_seconds = elapsed.as_secs_f64();
    let sampler: Arc<dyn DirectionSampler> = built.shared();
    Ok(Subject {
        name: name.to_string(),
        sampler,
        build_seconds,
    })
}

/// `--brdf` (`spec`), or else the stored spec of the first of the `--set` files; every set is
/// checked to be for it (`brdf_args::load_set`'s errors). `product` shares it.
pub(crate) fn spec_with_sets(spec: Option<&str>, sets: &[PathBuf]) -> CliResult<String> {
    let mut spec = spec.map(str::to_owned);
    for path in sets {
        let (stored, ..) = brdf_args::load_set(path, spec.as_deref(), None)?;
        spec.get_or_insert(stored);
    }
    spec.ok_or_else(|| CliError::input("--brdf SPEC is required without --set"))
}

/// The set saved in `path` (written by `build --out`, for `spec`: see [`spec_with_sets`])
/// attached to `brdf`, named `SAMPLER@FILE` (its registry name and file name).
pub(crate) fn load_attached(
    path: &std::path::Path,
    spec: &str,
    brdf: Arc<dyn Brdf>,
) -> CliResult<(String, Arc<dyn DirectionSampler>)> {
    let fail = |why: String| CliError::input(format!("--set {}: {why}", path.display()));
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let (entry, built) =
        samplers::load_set(&bytes, Some((brdf, spec))).map_err(|e| fail(e.to_string()))?;
    let file = path
        .file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy();
    Ok((format!("{}@{file}", entry.name), built.sampler))
}

/// Runs `brdf-lab bench`.
pub(crate) fn run(args: &BenchArgs, given: &Given) -> CliResult<()> {
    crate::output::check_all([("--json", args.json.as_deref())])?;
    args.set.check()?;
    // Each sampler option given must configure at least one of the samplers compared (the
    // built ones: a saved set keeps its own options).
    let options = if args.samplers.is_empty() {
        &[][..]
    } else {
        &given.0[..]
    };
    for option in options {
        let one = Given(vec![option.clone()]);
        let checks: Vec<CliResult<()>> = args
            .samplers
            .iter()
            .map(|s| brdf_args::check_options_apply(&one, Some(s)))
            .collect();
        if checks.iter().all(Result::is_err) {
            return checks.into_iter().next().unwrap_or(Ok(()));
        }
    }
    // θo and φo are range-checked by their parsers (`values::theta_o`, `values::azimuth`).
    let n = usize::try_from(args.n).map_err(CliError::input)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.map_or(0, |t| t as usize))
        .build()
        .map_err(CliError::input)?;
    let threads = pool.current_num_threads();
    let fixed = brdf::direction_from_angles(args.theta_o, args.phi_o);
    let spec = spec_with_sets(args.spec.as_deref(), &args.set_files)?;
    let plain = brdf_args::parse_brdf(&spec)?;
    let counted: Arc<dyn Brdf> = Arc::new(CountingBrdf(plain.clone()));

    // Built over the counting wrapper: one build serves both passes (a build can take seconds).
    let mut subjects = Vec::with_capacity(args.samplers.len() + args.set_files.len());
    for name in &args.samplers {
        subjects.push(build(name, &spec, args, counted.clone())?);
    }
    // Saved sets, attached to the counting wrapper; loaded, not built.
    for path in &args.set_files {
        let (name, sampler) = load_attached(path, &spec, counted.clone())?;
        subjects.push(Subject {
            name,
            sampler,
            build_seconds: 0.0,
        });
    }

    // Evaluations and trials per sample: an untimed pass on the worker threads.
    let count_n = n.min(COUNT_SAMPLES);
    let counts: Vec<(f64, Option<f64>)> = pool.install(|| {
        subjects
            .iter()
            .map(|s| {
                let (_, e, t) = run_samples(
                    s.sampler.as_ref(),
                    counted.as_ref(),
                    args.queries,
                    &fixed,
                    count_n,
                    args.seed,
                    args.batch,
                );
                let per = |c: u64| c as f64 / count_n as f64;
                (per(e), (t > 0).then(|| per(t)))
            })
            .collect()
    });

    // Timed runs, interleaved: run r of every sampler before run r + 1 of any.
    let pb = progress::bar(u64::from(args.repeat) * subjects.len() as u64, "timing");
    let mut runs = vec![Vec::with_capacity(args.repeat as usize); subjects.len()];
    let mut means = vec![0.0; subjects.len()];
    pool.install(|| {
        for _ in 0..args.repeat {
            for (k, s) in subjects.iter().enumerate() {
                let started = Instant::now();
                let (sum, _, _) = run_samples(
                    s.sampler.as_ref(),
                    counted.as_ref(),
                    args.queries,
                    &fixed,
                    n,
                    args.seed,
                    args.batch,
                );
                let ns = started.elapsed().as_secs_f64() * 1e9 / n as f64;
                runs[k].push(ns);
                means[k] = sum / n as f64;
                pb.inc(1);
            }
        }
    });
    pb.finish_and_clear();

    let records: Vec<BenchRecord> = subjects
        .iter()
        .enumerate()
        .map(|(k, s)| BenchRecord {
            sampler: s.name.clone(),
            ns_per_sample: median(&runs[k]),
            ns_per_sample_min: runs[k].iter().copied().fold(f64::INFINITY, f64::min),
            ns_per_sample_max: runs[k].iter().copied().fold(0.0, f64::max),
            ns_per_sample_runs: runs[k].clone(),
            evals_per_sample: counts[k].0,
            trials_per_sample: counts[k].1,
            samples: n,
            threads,
            queries: args.queries,
            batch: args.batch,
            build_seconds: s.build_seconds,
            bytes_used: s.sampler.bytes_used(),
            mean_weight: means[k],
        })
        .collect();
    print_table(args, &spec, &records, threads);
    if let Some(path) = &args.json {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &records).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
        eprintln!("wrote      {}", path.display());
    }
    Ok(())
}

fn print_table(args: &BenchArgs, spec: &str, records: &[BenchRecord], threads: usize) {
    let queries = match args.queries {
        Queries::Fixed => format!("fixed ωo (θo = {}°, φo = {}°)", args.theta_o, args.phi_o),
        Queries::Random => {
            format!("a random ωo per query (uniform in solid angle, θo ≤ {RANDOM_THETA_MAX_DEG}°)")
        }
    };
    println!("brdf       {spec}");
    println!("queries    {queries}");
    if args.batch {
        println!("batches    {CHUNK} queries per sample_eval_batch call");
    }
    println!(
        "timing     {} samples per run, median of {} interleaved run{}, {threads} thread{}; \
         a sample = sample_eval(ωo, u) -> (ωi, pdf, f(ωo, ωi)), the estimator's f included",
        args.n,
        args.repeat,
        if args.repeat == 1 { "" } else { "s" },
        if threads == 1 { "" } else { "s" },
    );
    let fastest = records
        .iter()
        .map(|r| r.ns_per_sample)
        .fold(f64::INFINITY, f64::min);
    println!(
        "{:<24} {:>10} {:>17} {:>9} {:>10} {:>10} {:>10} {:>12} {:>11}",
        "sampler",
        "ns/sample",
        "min–max",
        "× fastest",
        "evals/smp",
        "trials/smp",
        "build s",
        "memory KiB",
        "mean f·c/p"
    );
    for r in records {
        println!(
            "{:<24} {:>10.1} {:>17} {:>9.2} {:>10.3} {:>10} {:>10.3} {:>12.1} {:>11.5}",
            r.sampler,
            r.ns_per_sample,
            format!("{:.1}–{:.1}", r.ns_per_sample_min, r.ns_per_sample_max),
            r.ns_per_sample / fastest,
            r.evals_per_sample,
            r.trials_per_sample
                .map_or_else(|| "–".to_string(), |t| format!("{t:.3}")),
            r.build_seconds,
            r.bytes_used as f64 / 1024.0,
            r.mean_weight,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_queries_lie_in_the_cap_and_are_seeded() {
        let mut a = Xoshiro256PlusPlus::seed_from_u64(7);
        let mut b = Xoshiro256PlusPlus::seed_from_u64(7);
        let cos_max = RANDOM_THETA_MAX_DEG.to_radians().cos();
        let z = Vec3::new(0.0, 0.0, 1.0);
        for _ in 0..10_000 {
            let w = query(Queries::Random, &z, &mut a);
            assert!((w.norm() - 1.0).abs() < 1e-12);
            assert!(w.z >= cos_max - 1e-12 && w.z <= 1.0);
            assert_eq!(w, query(Queries::Random, &z, &mut b));
        }
        assert_eq!(query(Queries::Fixed, &z, &mut a), z);
    }

    #[test]
    fn samples_and_counts_do_not_depend_on_the_thread_count() {
        let brdf: Arc<dyn Brdf> = Arc::new(CountingBrdf(Arc::from(
            brdf::parse_spec("phong:n=20").unwrap(),
        )));
        let sampler = baselines::CosineHemisphere;
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let on = |t: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| {
                    run_samples(
                        &sampler,
                        brdf.as_ref(),
                        Queries::Random,
                        &wo,
                        20_000,
                        3,
                        false,
                    )
                })
        };
        let (s1, e1, t1) = on(1);
        let (s2, e2, t2) = on(2);
        // Chunk sums are added in a fixed tree order by rayon's reduce only up to
        // associativity: compare to rounding.
        approx::assert_relative_eq!(s1, s2, max_relative = 1e-12);
        assert_eq!(e1, e2);
        // Cosine sampling evaluates f once per sample above the horizon: the estimator's.
        assert!(e1 <= 20_000 && e1 > 19_000, "{e1}");
        // Cosine sampling makes no rejection trial.
        assert_eq!((t1, t2), (0, 0));
    }
}
