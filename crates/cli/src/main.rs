//! `brdf-lab`: the command line of the brdf-lab research framework (README.md).
//!
//! Exit codes: 0 success (all tests passed), 1 a statistical test failed, 2 bad usage or input,
//! 3 `validate` ran no test (every case skipped).

mod allocator;
mod baseline_args;
mod bench_cmd;
mod brdf_args;
mod build_cmd;
mod envmap_cmd;
mod error;
mod eval_cmd;
mod list_cmd;
mod output;
mod product_cmd;
mod progress;
mod sample_cmd;
mod study_cmd;
mod validate_cmd;
mod values;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use error::CliError;

/// Importance sampling of reflectance functions: samplers, validation and studies.
#[derive(Debug, Parser)]
#[command(name = "brdf-lab", version, about, long_about = None, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the BRDF models with their parameters, and the samplers.
    List,
    /// Draw incident directions for a BRDF and outgoing direction (CSV x,y,z,pdf).
    Sample(sample_cmd::SampleArgs),
    /// Evaluate the BRDF (and a sampler's pdf) at directions read from a CSV file.
    Eval(eval_cmd::EvalArgs),
    /// Build (and save) a BRDF's set of adaptive quadtrees, with its report.
    Build(build_cmd::BuildArgs),
    /// Run the statistical validation suite (exit 1 if a test fails, 3 if no test ran).
    Validate(validate_cmd::ValidateArgs),
    /// Sample an environment map (directions ∝ luminance per solid angle) and print a summary.
    Envmap(envmap_cmd::EnvmapArgs),
    /// Variance-versus-cost study of the direction samplers (report, CSV, JSON, plots); `study merge` combines shards.
    Study(study_cmd::StudyArgs),
    /// Reflected radiance under an environment map: SRBF product, BRDF, light and MIS estimators.
    Product(product_cmd::ProductArgs),
    /// Time per sample (with the estimator's f) and BRDF evaluations per sample of several samplers.
    Bench(bench_cmd::BenchArgs),
}

fn main() {
    // Freed blocks of a build stay in the heaps for reuse instead of being handed back to the
    // kernel and faulted in again (glibc; docs/benchmarks.md §28.4).
    allocator::raise_thresholds();
    // Usage errors: clap's full message (missing arguments by name, possible values, "similar
    // argument" tips, the usage line) on stderr, exit 2. No subcommand: the help on stderr,
    // exit 2 (`arg_required_else_help`). `--help` / `--version`: stdout, exit 0.
    let matches = Cli::command()
        .try_get_matches()
        .unwrap_or_else(|e| e.exit());
    let cli =
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut Cli::command()).exit());
    // The options given on the command line (not defaulted): a sampler option given for a
    // sampler it does not configure is refused.
    let given = matches
        .subcommand()
        .map(|(_, m)| brdf_args::Given::of(m))
        .unwrap_or_default();
    let result = match cli.command {
        Command::List => list_cmd::run(),
        Command::Sample(args) => sample_cmd::run(&args, &given),
        Command::Eval(args) => eval_cmd::run(&args, &given),
        Command::Build(args) => build_cmd::run(&args, &given),
        Command::Validate(args) => validate_cmd::run(&args),
        Command::Envmap(args) => envmap_cmd::run(&args),
        Command::Study(args) => study_cmd::run(&args),
        Command::Product(args) => product_cmd::run(&args),
        Command::Bench(args) => bench_cmd::run(&args, &given),
    };
    if let Err(e) = result {
        report_and_exit(&e);
    }
}

fn report_and_exit(e: &CliError) -> ! {
    eprintln!("brdf-lab: error: {e}");
    std::process::exit(e.exit_code());
}
