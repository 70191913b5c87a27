//! `brdf-lab build`: build (and optionally save) a BRDF's set of adaptive quadtrees.

use std::path::PathBuf;

use clap::Args;

use crate::brdf_args::{self, Given, SamplerArgs};
use crate::error::{CliError, CliResult};
use crate::values::display_path;

/// Arguments of `brdf-lab build`.
#[derive(Debug, Args)]
pub(crate) struct BuildArgs {
    /// BRDF: `name` or `name:key=value,...` or `merl:PATH`.
    #[arg(long = "brdf")]
    spec: String,
    /// `adaptive` (default), `adaptive-paper`, …, `adaptive-exact` or another built direction
    /// sampler (reported, not saved).
    #[arg(long, default_value = "adaptive")]
    sampler: String,
    /// Save the set (or the `adaptive-exact` sampler) here (postcard with a format-version
    /// header; written atomically); `--set FILE` loads it in the other commands.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    set: SamplerArgs,
}

/// Runs `brdf-lab build`.
pub(crate) fn run(args: &BuildArgs, given: &Given) -> CliResult<()> {
    crate::output::check_all([("--out", args.out.as_deref())])?;
    args.set.check()?;
    let entry = samplers::find(&args.sampler).map_err(CliError::input)?;
    let is_set = matches!(entry.constructor, samplers::Constructor::AdaptiveSet { .. });
    let buildable = is_set || entry.is_direction() && entry.capabilities.needs_build;
    let saveable = is_set || entry.name == "adaptive-exact" || args.out.is_none();
    if !(buildable && saveable) {
        let sets: Vec<&str> = samplers::samplers()
            .iter()
            .filter(|e| matches!(e.constructor, samplers::Constructor::AdaptiveSet { .. }))
            .map(|e| e.name)
            .collect();
        return Err(CliError::input(format!(
            "--sampler {}: `build` makes (and `--out` saves) adaptive quadtree sets ({}) and adaptive-exact; other built direction samplers are built and reported without --out",
            args.sampler,
            sets.join(", ")
        )));
    }
    brdf_args::check_options_apply(given, Some(entry.name))?;
    let brdf = brdf_args::parse_brdf(&args.spec)?;
    let (built, elapsed) = brdf_args::build(&args.sampler, &args.spec, brdf, &args.set)?;
    println!("brdf       {}", args.spec);
    // Every sampler: the build's wall time and memory; then its own report (fit quality, …).
    println!(
        "sampler    {} built in {:.3} s, {} bytes ({:.1} KiB)",
        entry.name,
        elapsed.as_secs_f64(),
        built.sampler().bytes_used(),
        built.sampler().bytes_used() as f64 / 1024.0
    );
    brdf_args::print_set_report(&built);
    for line in brdf_args::report_lines(built.sampler()) {
        println!("{line}");
    }
    if let (Some(path), Some(bytes)) = (&args.out, built.to_bytes(&args.spec)) {
        crate::output::write_atomically(path, |w| w.write_all(&bytes))?;
        println!("wrote      {} ({} bytes)", display_path(path), bytes.len());
    }
    Ok(())
}
