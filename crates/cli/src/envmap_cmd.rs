//! `brdf-lab envmap`: sample directions ∝ luminance per solid angle of a lat-long map.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler, EnvSample, LaneRng, LeafChoice};
use partition_sampler::{PAR_CHUNK, Sample2, Sampler2D, TreeParams, UniformSource, chunk_seed};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use crate::error::{CliError, CliResult};
use crate::output::{num, write_atomically};
use crate::progress;
use crate::values::{self, counted, display_path};
/// Samples generated per block (each block seeded from (seed, block index): thread-independent).
const BLOCK: usize = 1 << 20;

/// Arguments of `brdf-lab envmap`.
#[derive(Debug, Args)]
pub(crate) struct EnvmapArgs {
    /// Lat-long map (.hdr, .exr or .pfm); without it a built-in procedural sky with a sun is used.
    #[arg(long)]
    map: Option<PathBuf>,
    /// Number of samples to draw.
    #[arg(short = 'n', long = "samples", value_parser = values::at_least(1u64), allow_negative_numbers = true)]
    n: u64,
    /// Seed of the random streams (the samples depend only on it, not on the thread count).
    #[arg(long, default_value_t = 1, value_parser = values::seed, allow_negative_numbers = true)]
    seed: u64,
    /// Write the samples as CSV `u,v,pdf_uv,pdf_sa` (written atomically).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also time and compare every sampler variant and the piecewise-constant CDF baseline.
    #[arg(long)]
    compare: bool,
    /// Environment-map sampler producing the samples (`brdf-lab list` shows them all).
    #[arg(long, default_value = "envmap-adaptive", value_parser = envmap_sampler_names())]
    sampler: String,
    /// Split threshold n_max ≥ 1 of the adaptive samplers (mean trials per sample ≤ n_max).
    #[arg(long, default_value_t = AdaptiveOptions::DEFAULT_N_MAX,
          value_parser = values::real(values::End::Closed(1.0), values::End::None), allow_hyphen_values = true)]
    n_max: f64,
    /// Maximum quadtree depth of the adaptive samplers.
    #[arg(long, default_value_t = TreeParams::DEFAULT_MAX_DEPTH,
          value_parser = values::int(0u32, partition_sampler::MAX_DEPTH_LIMIT), allow_negative_numbers = true)]
    max_depth: u32,
    /// Leaf choice of the adaptive sampler.
    #[arg(long, value_enum, default_value_t = LeafChoiceName::Alias)]
    leaf_choice: LeafChoiceName,
}

/// Leaf-choice names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum LeafChoiceName {
    /// Flattened leaves with an alias table (O(1)).
    Alias,
    /// The papers' per-node CDF descent from the root.
    Descent,
}

/// The registry's environment-map samplers, as clap's possible values of `--sampler`.
fn envmap_sampler_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        samplers::samplers()
            .iter()
            .filter(|e| e.constructor.kind() == "envmap")
            .map(|e| clap::builder::PossibleValue::new(e.name).help(e.summary)),
    )
}

/// The adaptive samplers' options from the command line (the registry entry sets the scheme).
fn adaptive_options(args: &EnvmapArgs, leaf: LeafChoiceName) -> AdaptiveOptions {
    let mut options = AdaptiveOptions::default();
    options.tree.n_max = args.n_max;
    options.tree.max_depth = args.max_depth;
    options.tree.leaf_choice = match leaf {
        LeafChoiceName::Alias => LeafChoice::Alias,
        LeafChoiceName::Descent => LeafChoice::Descent,
    };
    options
}

/// Runs `brdf-lab envmap`.
pub(crate) fn run(args: &EnvmapArgs) -> CliResult<()> {
    crate::output::check_all([("--out", args.out.as_deref())])?;
    if !(args.n_max >= 1.0 && args.n_max.is_finite()) {
        return Err(CliError::input(format!(
            "--n-max must be a finite number ≥ 1, got {}",
            args.n_max
        )));
    }
    let (map, map_name) = match &args.map {
        Some(path) => {
            let map = EnvMap::load(path)
                .map_err(|e| CliError::input(format!("{}: {e}", display_path(path))))?;
            (map, display_path(path))
        }
        None => {
            let (map, _) = estimators::load_map(None).map_err(CliError::input)?;
            (map, "built-in procedural sky with a sun".to_string())
        }
    };
    println!(
        "map        {map_name} ({} x {} pixels)",
        map.width(),
        map.height()
    );

    let entry = samplers::find(&args.sampler).map_err(CliError::input)?;
    let sampler = entry
        .build_envmap(&map, &adaptive_options(args, args.leaf_choice))
        .map_err(CliError::input)?;
    print_sampler_summary(entry.name, &sampler);

    let n = usize::try_from(args.n).map_err(CliError::input)?;
    let exact = exact_luminance_integral(&map);
    let started = Instant::now();
    let mut estimate = KahanMean::default();
    let pb = progress::bar(n.div_ceil(BLOCK) as u64, "sampling");
    let mut blocks: Vec<Vec<Sample2>> = Vec::new();
    for (b, start) in (0..n).step_by(BLOCK).enumerate() {
        let len = BLOCK.min(n - start);
        let block = sampler.sample_uv_par(len, chunk_seed(args.seed, b as u64));
        for s in block.iter().map(|s| EnvSample::from_uv(*s)) {
            let y = envmap::luminance(map.radiance_uv(s.u, s.v));
            estimate.add(if s.pdf_sa > 0.0 { y / s.pdf_sa } else { 0.0 });
        }
        if args.out.is_some() {
            blocks.push(block);
        }
        pb.inc(1);
    }
    pb.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    println!(
        "samples    {n} in {:.3} s ({:.2} M samples/s on {}, incl. the estimator)",
        elapsed,
        n as f64 / elapsed / 1e6,
        counted(rayon::current_num_threads(), "thread")
    );
    if let Some(stats) = sampler.stats() {
        let measured = stats
            .measured_mean_trials
            .map_or("n/a".to_string(), |t| format!("{t:.4}"));
        println!(
            "trials     measured {measured} per sample; bound violations {}",
            stats.bound_violations
        );
    }
    let mean = estimate.mean();
    println!(
        "check      ∫ Y dω: estimate {mean:.6e} vs exact {exact:.6e} (relative error {:.2e})",
        ((mean - exact) / exact).abs()
    );

    if let Some(path) = &args.out {
        write_samples(path, &blocks)?;
        println!(
            "wrote      {} ({}: u,v,pdf_uv,pdf_sa)",
            display_path(path),
            counted(n, "row")
        );
    }
    if args.compare {
        compare(&map, args)?;
    }
    Ok(())
}

fn print_sampler_summary(name: &str, sampler: &EnvMapSampler) {
    println!(
        "sampler    {name} built in {:.3} ms, {} bytes",
        sampler.build_time().as_secs_f64() * 1e3,
        sampler.bytes_used()
    );
    if let Some(s) = sampler.stats() {
        println!(
            "tree       {} nodes, {} leaves, depth {}, expected mean trials {:.4}, integral {:.6e} ({:?}{})",
            s.nodes,
            s.leaves,
            s.depth,
            s.expected_mean_trials,
            s.integral,
            s.integral_source,
            s.integral_rel_err
                .map_or(String::new(), |e| format!(", rel. err. {e:.1e}"))
        );
    }
}

/// ∫ Y dω over the sphere for a piecewise-constant lat-long map: Σ Y_ij (2π/W)(cos θ_i − cos θ_{i+1}).
fn exact_luminance_integral(map: &EnvMap) -> f64 {
    let (w, h) = (map.width(), map.height());
    let lum = map.luminance();
    let mut total = 0.0;
    for row in 0..h {
        let band =
            envmap::latlong::sin_integral(row as f64 / h as f64, (row + 1) as f64 / h as f64);
        let row_sum: f64 = lum[row * w..(row + 1) * w].iter().sum();
        // ∫ over the band of sinθ dθ dφ with θ = πv, φ = 2πu: (2π/W)·π·∫ sin(πv) dv per pixel.
        total += row_sum * (2.0 * std::f64::consts::PI / w as f64) * std::f64::consts::PI * band;
    }
    total
}

/// A compensated running mean (order-fixed, so results do not depend on threads).
#[derive(Default)]
struct KahanMean {
    sum: f64,
    comp: f64,
    n: u64,
}

impl KahanMean {
    fn add(&mut self, x: f64) {
        let y = x - self.comp;
        let t = self.sum + y;
        self.comp = (t - self.sum) - y;
        self.sum = t;
        self.n += 1;
    }
    fn mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.sum / self.n as f64
        }
    }
}

fn write_samples(path: &std::path::Path, blocks: &[Vec<Sample2>]) -> CliResult<()> {
    let total: usize = blocks.iter().map(Vec::len).sum();
    let pb = progress::bar(total as u64, "writing");
    let result = write_atomically(path, |w| {
        writeln!(w, "u,v,pdf_uv,pdf_sa")?;
        for block in blocks {
            for s in block.iter().map(|s| EnvSample::from_uv(*s)) {
                writeln!(
                    w,
                    "{},{},{},{}",
                    num(s.u),
                    num(s.v),
                    num(s.pdf_uv),
                    num(s.pdf_sa)
                )?;
            }
            pb.inc(block.len() as u64);
        }
        Ok(())
    });
    pb.finish_and_clear();
    result
}

/// Samples per buffer when a consumer draws with [`Sampler2D::sample_into`] (a renderer's
/// batch of directions); the buffer is reused, never stored.
const CONSUMER_BATCH: usize = 256;

/// Draws `len` samples from `rng` and consumes them (sums their pdfs): one `sample_uv` call per
/// sample, or (`block`) [`Sampler2D::sample_into`] on a reused buffer of [`CONSUMER_BATCH`].
/// Both give the same samples.
fn consume<U: UniformSource>(sampler: &EnvMapSampler, len: usize, rng: &mut U, block: bool) -> f64 {
    if !block {
        return (0..len).map(|_| sampler.sample_uv(rng).pdf).sum();
    }
    let mut buf = [Sample2 {
        point: [0.0; 2],
        pdf: 0.0,
    }; CONSUMER_BATCH];
    let mut sum = 0.0;
    let mut left = len;
    while left > 0 {
        let k = left.min(CONSUMER_BATCH);
        sampler.sample_into(rng, &mut buf[..k]);
        sum += buf[..k].iter().map(|s| s.pdf).sum::<f64>();
        left -= k;
    }
    sum
}

/// Draws `n` samples on all threads and consumes them (sums their pdfs) without storing them,
/// as a renderer would: fixed chunks of [`PAR_CHUNK`] with generators seeded from (seed, chunk),
/// so the samples are a function of the seed only. `lanes`: the chunks' generators are
/// [`LaneRng`]s (the batch path's lane-parallel generator; `block` is then implied).
fn consume_par(sampler: &EnvMapSampler, n: usize, seed: u64, block: bool, lanes: bool) -> f64 {
    use rayon::prelude::*;
    let chunks = n.div_ceil(PAR_CHUNK);
    let sums: Vec<f64> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let len = PAR_CHUNK.min(n - c * PAR_CHUNK);
            if lanes {
                return consume(sampler, len, &mut LaneRng::for_chunk(seed, c as u64), true);
            }
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, c as u64));
            consume(sampler, len, &mut rng, block)
        })
        .collect();
    sums.iter().sum()
}

/// `--compare`: build time, memory, mean trials and samples/s (1 thread and all threads) of
/// every variant, measured in this run.
fn compare(map: &EnvMap, args: &EnvmapArgs) -> CliResult<()> {
    // Every registered environment-map sampler; the adaptive ones with both leaf choices.
    let mut variants = Vec::new();
    for entry in samplers::samplers()
        .iter()
        .filter(|e| e.constructor.kind() == "envmap")
    {
        variants.push((entry, LeafChoiceName::Alias));
        if entry.capabilities.batch_mode {
            variants.push((entry, LeafChoiceName::Descent));
        }
    }
    let n = usize::try_from(args.n)
        .map_err(CliError::input)?
        .clamp(100_000, 4_000_000);
    let threads = rayon::current_num_threads();
    println!();
    println!(
        "compare    {n} samples per variant (--samples clamped to [10^5, 4·10^6] for the timings), median of 5 builds; M/s on 1 thread and on {}, 'one' = one sample_uv call per sample, 'blk' = sample_into on buffers of {CONSUMER_BATCH} (same samples; consumed, not stored), 'lane' = 'blk' drawn from the lane-parallel generator LaneRng (other samples, same law)",
        counted(threads, "thread")
    );
    println!(
        "{:<24} {:<8} {:>10} {:>12} {:>10} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
        "sampler",
        "leaves",
        "build ms",
        "memory KiB",
        "trials",
        "M/s 1 one",
        "M/s 1 blk",
        format!("M/s {threads} one"),
        format!("M/s {threads} blk"),
        "M/s 1 lane",
        format!("M/s {threads} lane"),
    );
    let pb = progress::bar(variants.len() as u64, "comparing");
    let mut rows = Vec::new();
    for (entry, leaf) in variants {
        let options = adaptive_options(args, leaf);
        let mut builds = Vec::new();
        let mut sampler = None;
        for _ in 0..5 {
            let s = entry.build_envmap(map, &options).map_err(CliError::input)?;
            builds.push(s.build_time().as_secs_f64() * 1e3);
            sampler = Some(s);
        }
        let Some(sampler) = sampler else { continue };
        builds.sort_by(f64::total_cmp);
        let mut rates = [0.0; 6];
        let mut sinks = [0.0; 6];
        for (k, (parallel, block, lanes)) in [
            (false, false, false),
            (false, true, false),
            (true, false, false),
            (true, true, false),
            (false, true, true),
            (true, true, true),
        ]
        .into_iter()
        .enumerate()
        {
            let t = Instant::now();
            sinks[k] = match (parallel, lanes) {
                (true, _) => consume_par(&sampler, n, args.seed, block, lanes),
                (false, true) => consume(&sampler, n, &mut LaneRng::seed_from_u64(args.seed), true),
                (false, false) => {
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(args.seed);
                    consume(&sampler, n, &mut rng, block)
                }
            };
            rates[k] = n as f64 / t.elapsed().as_secs_f64() / 1e6;
        }
        std::hint::black_box(sinks);
        let trials = sampler
            .stats()
            .and_then(|s| s.measured_mean_trials)
            .map_or("1 (exact)".to_string(), |t| format!("{t:.4}"));
        let leaf_name = match (sampler.as_adaptive().is_some(), leaf) {
            (false, _) => "-",
            (true, LeafChoiceName::Alias) => "alias",
            (true, LeafChoiceName::Descent) => "descent",
        };
        rows.push(format!(
            "{:<24} {:<8} {:>10.3} {:>12.1} {:>10} {:>11.2} {:>11.2} {:>11.2} {:>11.2} {:>11.2} {:>11.2}",
            entry.name,
            leaf_name,
            builds[builds.len() / 2],
            sampler.bytes_used() as f64 / 1024.0,
            trials,
            rates[0],
            rates[1],
            rates[2],
            rates[3],
            rates[4],
            rates[5],
        ));
        pb.inc(1);
    }
    pb.finish_and_clear();
    for row in rows {
        println!("{row}");
    }
    Ok(())
}
