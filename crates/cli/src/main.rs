//! `brdf-lab`: the command line of the brdf-lab research framework (design.md §5).
//!
//! Exit codes: 0 success (all tests passed), 1 a statistical test failed, 2 bad usage or input.

mod brdf_args;
mod build_cmd;
mod envmap_cmd;
mod error;
mod eval_cmd;
mod list_cmd;
mod output;
mod progress;
mod sample_cmd;
mod validate_cmd;

use clap::{Parser, Subcommand};
use error::CliError;

/// Importance sampling of reflectance functions: samplers, validation and studies.
#[derive(Debug, Parser)]
#[command(name = "brdf-lab", version, about, long_about = None)]
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
    /// Run the statistical validation suite (exit 1 if a test fails).
    Validate(validate_cmd::ValidateArgs),
    /// Sample an environment map (directions ∝ luminance per solid angle) and print a summary.
    Envmap(envmap_cmd::EnvmapArgs),
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                    let _ = e.print();
                    std::process::exit(0);
                }
                _ => {
                    // One line: clap's own message without the usage block.
                    let text = e.to_string();
                    let line = text
                        .lines()
                        .next()
                        .unwrap_or("bad usage")
                        .trim_start_matches("error: ");
                    eprintln!("brdf-lab: error: {line} (see `brdf-lab --help`)");
                    std::process::exit(2);
                }
            }
        }
    };
    let result = match cli.command {
        Command::List => list_cmd::run(),
        Command::Sample(args) => sample_cmd::run(&args),
        Command::Eval(args) => eval_cmd::run(&args),
        Command::Build(args) => build_cmd::run(&args),
        Command::Validate(args) => validate_cmd::run(&args),
        Command::Envmap(args) => envmap_cmd::run(&args),
    };
    if let Err(e) = result {
        report_and_exit(&e);
    }
}

fn report_and_exit(e: &CliError) -> ! {
    eprintln!("brdf-lab: error: {e}");
    std::process::exit(e.exit_code());
}
