//! `brdf-lab sample`: draw incident directions for one BRDF and outgoing direction.
//!
//! The samples (CSV `x,y,z,pdf`) go to `--out` or to standard output; the summary always goes
//! to standard error.

use std::path::PathBuf;
use std::time::Instant;

use brdf_sampling::DirSample;
use clap::Args;
use partition_sampler::chunk_seed;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;

use crate::brdf_args::{self, BrdfArgs, Given, SamplerArgs};
use crate::error::{CliError, CliResult};
use crate::output::{num, write_atomically};
use crate::progress;
use crate::values::{self, counted, display_path};

/// Samples per independently seeded chunk (output depends on the seed only, not on threads).
const CHUNK: usize = 4096;

/// Arguments of `brdf-lab sample`.
#[derive(Debug, Args)]
pub(crate) struct SampleArgs {
    #[command(flatten)]
    brdf: BrdfArgs,
    /// Sampler name (see `brdf-lab list`; default adaptive). With --set: the set's.
    #[arg(long)]
    sampler: Option<String>,
    /// Sample a set written by `build --out` (it stores the BRDF spec and the sampler):
    /// --brdf is then optional and must match, and the set's own options apply.
    #[arg(long = "set", value_name = "FILE", conflicts_with_all = brdf_args::SET_OPTION_IDS)]
    set_file: Option<PathBuf>,
    /// Number of samples.
    #[arg(short = 'n', long = "samples", value_parser = values::int(1u64, 1_000_000_000), allow_negative_numbers = true)]
    n: u64,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1, value_parser = values::seed, allow_negative_numbers = true)]
    seed: u64,
    /// Write the samples as CSV `x,y,z,pdf` (pdf w.r.t. solid angle) here, atomically, instead
    /// of to standard output. The summary always goes to standard error.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    set: SamplerArgs,
}

/// Runs `brdf-lab sample`.
pub(crate) fn run(args: &SampleArgs, given: &Given) -> CliResult<()> {
    crate::output::check_all([("--out", args.out.as_deref())])?;
    args.set.check()?;
    let wo = brdf_args::outgoing(&args.brdf)?;
    let (spec, brdf, built, name) = match &args.set_file {
        Some(path) => {
            let loaded =
                brdf_args::load_set(path, args.brdf.spec.as_deref(), args.sampler.as_deref())?;
            brdf_args::check_options_apply(given, Some(loaded.3))?;
            loaded
        }
        None => {
            let name = args.sampler.as_deref().unwrap_or("adaptive");
            brdf_args::check_options_apply(given, Some(name))?;
            let spec = brdf_args::required_spec(&args.brdf)?;
            let brdf = brdf_args::parse_brdf(spec)?;
            let (built, _) = brdf_args::build(name, spec, brdf.clone(), &args.set)?;
            (spec.to_string(), brdf, built, name)
        }
    };
    let sampler = built.sampler();
    eprintln!(
        "brdf       {spec} at θo = {}°, φo = {}°",
        args.brdf.theta_o, args.brdf.phi_o
    );
    if let Some(path) = &args.set_file {
        eprintln!("set file   {}", display_path(path));
    }
    eprintln!(
        "sampler    {} ({} bytes)",
        name.trim(),
        sampler.bytes_used()
    );

    let n = usize::try_from(args.n).map_err(CliError::input)?;
    let chunks = n.div_ceil(CHUNK);
    let pb = progress::bar(chunks as u64, "sampling");
    let started = Instant::now();
    let samples: Vec<Vec<DirSample>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let len = CHUNK.min(n - c * CHUNK);
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(args.seed, c as u64));
            let out = (0..len).map(|_| sampler.sample(&wo, &mut rng)).collect();
            pb.inc(1);
            out
        })
        .collect();
    pb.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    eprintln!(
        "samples    {n} in {elapsed:.3} s ({:.2} M samples/s on {})",
        n as f64 / elapsed / 1e6,
        counted(rayon::current_num_threads(), "thread")
    );

    // The directional albedo ∫ f cos dω, estimated by (1/N) Σ f cos / p and by the adaptive
    // reference quadrature (brdf_sampling::reference_albedo).
    let (mut sum, mut sum2) = (0.0, 0.0);
    for s in samples.iter().flatten() {
        let v = if s.pdf > 0.0 && s.wi.z > 0.0 {
            brdf.eval(&wo, &s.wi) * s.wi.z / s.pdf
        } else {
            0.0
        };
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    let std_err = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
    // A sampler whose pdf is normalised by a quadrature declares that quadrature's relative
    // error at ωo: a systematic error of the estimate that no number of samples averages
    // away. The error at this ωo, not the largest over the set's slices (issue 27: a grazing
    // slice's 7.9e-2 made the check unable to fail at θo = 40°).
    let normalisation = sampler.normaliser_rel_err(&wo).map(|e| e * mean.abs());
    eprintln!(
        "albedo     {}",
        albedo_summary(brdf.as_ref(), &wo, mean, std_err, normalisation)
    );
    for line in brdf_args::set_report_lines(&built) {
        eprintln!("{line}");
    }
    if !matches!(built, brdf_args::Built::Set(_)) {
        for line in brdf_args::report_lines(built.sampler()) {
            eprintln!("{line}");
        }
    }

    let write = |w: &mut dyn std::io::Write| -> std::io::Result<()> {
        writeln!(w, "x,y,z,pdf")?;
        for s in samples.iter().flatten() {
            writeln!(
                w,
                "{},{},{},{}",
                num(s.wi.x),
                num(s.wi.y),
                num(s.wi.z),
                num(s.pdf)
            )?;
        }
        Ok(())
    };
    match &args.out {
        Some(path) => {
            write_atomically(path, write)?;
            eprintln!(
                "wrote      {} ({}: x,y,z,pdf)",
                display_path(path),
                counted(n, "row")
            );
        }
        None => crate::output::write_stdout(write)?,
    }
    Ok(())
}

/// `estimate X ± σ (1σ); reference Y ± e; agree …` for the estimate `mean ± std_err` of the
/// directional albedo at `wo`. Agreement: within 3 combined σ, `√(σ² + e² + s²)` with `s` the
/// sampler's estimated normalisation error (`normalisation`, absolute), when it has one.
fn albedo_summary(
    brdf: &dyn brdf::Brdf,
    wo: &brdf::Vec3,
    mean: f64,
    std_err: f64,
    normalisation: Option<f64>,
) -> String {
    let estimate = format!("estimate {mean:.6} ± {std_err:.2e} (1σ)");
    match brdf_sampling::reference_albedo(brdf, wo) {
        Ok(r) => {
            let s = normalisation.unwrap_or(0.0);
            // Rounding floor: a zero-variance estimate of an exact reference.
            let sigma = std_err.hypot(r.abs_err).hypot(s).max(1e-12 * mean.abs());
            let z = (mean - r.value).abs() / sigma;
            let incl = if normalisation.is_some() {
                format!(", σ includes the set's normalisation error {s:.1e}")
            } else {
                String::new()
            };
            let verdict = if z <= 3.0 {
                format!("agree within 3 combined σ ({z:.2}σ apart{incl})")
            } else {
                format!("DISAGREE: {z:.1} combined σ apart (> 3σ{incl})")
            };
            format!(
                "{estimate}; reference {:.6} ± {:.1e} (adaptive quadrature); {verdict}",
                r.value, r.abs_err
            )
        }
        Err(e) => format!("{estimate}; no reference ({e})"),
    }
}
