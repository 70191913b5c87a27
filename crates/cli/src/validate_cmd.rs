//! `brdf-lab validate`: the statistical validation suite over samplers, BRDFs and angles;
//! `--shard K/N` runs a part of it and `brdf-lab validate merge` recombines the parts.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use validation::{ProgressEvent, ValidateConfig, ValidationReport};

use crate::error::{CliError, CliResult};
use crate::output::write_atomically;
use crate::progress;
use crate::values::{self, End, count, counted};

/// Arguments of `brdf-lab validate`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct ValidateArgs {
    #[command(subcommand)]
    merge: Option<ValidateSub>,
    /// BRDF spec to test (repeatable); default: the tier's list.
    #[arg(long = "brdf")]
    brdfs: Vec<String>,
    /// Sampler to test (repeatable); default: every sampler of the project.
    #[arg(long = "sampler")]
    samplers: Vec<String>,
    /// Outgoing polar angle in degrees, in [0, 90) (repeatable); default: the tier's list.
    #[arg(long = "theta-o", value_parser = values::theta_o, allow_hyphen_values = true)]
    theta_o: Vec<f64>,
    /// Samples per case (at least 2000); default: the tier's count.
    #[arg(long, value_parser = values::at_least(validation::MIN_SAMPLES), allow_negative_numbers = true)]
    samples: Option<usize>,
    /// Master seed.
    #[arg(long, default_value_t = 1, value_parser = values::seed, allow_negative_numbers = true)]
    seed: u64,
    /// The quick tier (what CI runs) instead of the full tier.
    #[arg(long)]
    quick: bool,
    /// Also run the deliberately broken samplers; every one must be caught.
    #[arg(long)]
    mutants: bool,
    /// Family-wise significance level in (0, 1) (Šidák-corrected over the run's tests).
    #[arg(long, default_value_t = 0.01, value_parser = values::real(End::Open(0.0), End::Open(1.0)), allow_hyphen_values = true)]
    alpha: f64,
    /// Write the report as JSON (schema in docs/validation.md).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write a readable markdown report of every test.
    #[arg(long)]
    report: Option<PathBuf>,
    /// A set saved by `build --out` to validate (repeatable), with the BRDF of its stored spec
    /// at the run's angles; without --sampler, only the sets are validated.
    #[arg(long = "set", value_name = "FILE")]
    sets: Vec<PathBuf>,
    /// Run only the cases i (in the plan's fixed order) with i mod N = K − 1 (K/N, 1 ≤ K ≤ N);
    /// needs --json; `validate merge` judges the parts together (docs/validation.md).
    #[arg(long, value_name = "K/N", requires = "json")]
    shard: Option<String>,
}

/// `brdf-lab validate merge`.
#[derive(Debug, Subcommand)]
enum ValidateSub {
    /// Combine the JSON reports of the shards (`validate --shard K/N --json PART`) into the
    /// single run's report and verdict (exit 1 if a test failed, 3 if no test ran).
    Merge(MergeArgs),
}

/// Arguments of `brdf-lab validate merge`.
#[derive(Debug, Args)]
struct MergeArgs {
    /// The shards' JSON reports, one per shard K = 1..N, in any order.
    #[arg(required = true, value_name = "PART.json")]
    parts: Vec<PathBuf>,
    /// Write the merged report as JSON (the schema of a single run).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the merged readable markdown report.
    #[arg(long)]
    report: Option<PathBuf>,
}

/// Runs `brdf-lab validate`: exit 0 when everything passed, 1 when a test failed (or a mutant
/// escaped), 2 on bad input, 3 when no test ran (every case skipped: no sampler applied).
pub(crate) fn run(args: &ValidateArgs) -> CliResult<()> {
    if let Some(ValidateSub::Merge(m)) = &args.merge {
        return merge(m);
    }
    let shard = values::shard(args.shard.as_deref())?;
    crate::output::check_all([
        ("--json", args.json.as_deref()),
        ("--report", args.report.as_deref()),
    ])?;
    // Warnings for the BRDFs the user named (a spec that does not parse is reported by the
    // suite itself).
    for spec in &args.brdfs {
        if let Ok(b) = brdf::parse_spec(spec) {
            crate::brdf_args::warn_if_implausible(spec, b.as_ref());
        }
    }
    let base = if args.quick {
        ValidateConfig::quick()
    } else {
        ValidateConfig::default()
    };
    let config = ValidateConfig {
        brdfs: if args.brdfs.is_empty() {
            base.brdfs.clone()
        } else {
            args.brdfs.clone()
        },
        samplers: if args.samplers.is_empty() {
            base.samplers.clone()
        } else {
            args.samplers.clone()
        },
        theta_o: if args.theta_o.is_empty() {
            base.theta_o.clone()
        } else {
            args.theta_o.clone()
        },
        samples: args.samples.or(base.samples),
        seed: args.seed,
        quick: args.quick,
        mutants: args.mutants,
        alpha: args.alpha,
        sets: args.sets.clone(),
        ..base
    };
    let pb = progress::bar(0, "validating");
    let on_progress = |e: ProgressEvent| match e {
        ProgressEvent::Started { total } => pb.set_length(total as u64),
        ProgressEvent::Finished { done, .. } => pb.set_position(done as u64),
    };
    let report = validation::run_shard(&config, shard, &on_progress).map_err(CliError::input);
    pb.finish_and_clear();
    let report = report?;
    write_outputs(&report, args.json.as_deref(), args.report.as_deref())?;
    if let Some(info) = &report.shard {
        // A shard's verdict is the merge's: its tests are judged with the others'.
        for w in &report.warnings {
            eprintln!("brdf-lab: warning: {}", w.message);
        }
        println!(
            "shard      {}/{}: {} of the plan's {}, {}; judge them with `brdf-lab validate merge`",
            info.index,
            info.count,
            count(info.cases, "case", "cases"),
            info.total_cases,
            counted(report.tests.len(), "record")
        );
        return Ok(());
    }
    verdict(&report)
}

/// Writes the JSON and markdown reports asked for (each atomically).
fn write_outputs(
    report: &ValidationReport,
    json: Option<&Path>,
    md: Option<&Path>,
) -> CliResult<()> {
    if let Some(path) = json {
        let json = report.to_json();
        write_atomically(path, |w| w.write_all(json.as_bytes()))?;
    }
    if let Some(path) = md {
        let md = report.to_markdown();
        write_atomically(path, |w| w.write_all(md.as_bytes()))?;
    }
    Ok(())
}

/// `brdf-lab validate merge`: reads the parts, merges them (refusing missing, duplicate or
/// mismatched shards), writes the outputs and exits as the single run would.
fn merge(args: &MergeArgs) -> CliResult<()> {
    crate::output::check_all([
        ("--json", args.json.as_deref()),
        ("--report", args.report.as_deref()),
    ])?;
    let parts = args
        .parts
        .iter()
        .map(|path| {
            let name = crate::values::display_path(path);
            let text = std::fs::read_to_string(path)
                .map_err(|e| CliError::input(format!("cannot read {name}: {e}")))?;
            let report: ValidationReport = serde_json::from_str(&text).map_err(|e| {
                CliError::input(format!("{name} is not a validate JSON report: {e}"))
            })?;
            Ok((name, report))
        })
        .collect::<CliResult<Vec<_>>>()?;
    let n = parts.len();
    let report = validation::merge(parts).map_err(CliError::input)?;
    write_outputs(&report, args.json.as_deref(), args.report.as_deref())?;
    println!("merged     {}", count(n, "shard", "shards"));
    verdict(&report)
}

/// Prints the summary of a whole (or merged) run and returns its exit status: 0 passed,
/// 1 a test failed (or a mutant escaped), 3 no test ran.
fn verdict(report: &ValidationReport) -> CliResult<()> {
    for w in &report.warnings {
        eprintln!("brdf-lab: warning: {}", w.message);
    }
    let failed: Vec<_> = report.tests.iter().filter(|t| !t.passed).collect();
    let skipped: Vec<_> = report.skipped().collect();
    let run = report.tests_run();
    let skipped_note = match skipped.len() {
        0 => String::new(),
        k => format!(" ({} skipped)", count(k, "case", "cases")),
    };
    println!(
        "validate   {}{skipped_note}, {} failed, α = {} (Šidák-corrected per test)",
        counted(run, "test"),
        failed.len(),
        report.alpha
    );
    if let Some(first) = skipped.first() {
        println!(
            "skipped    {} where the sampler does not apply, e.g. {} | {}: {}",
            count(skipped.len(), "case", "cases"),
            first.sampler,
            first.brdf,
            why(first)
        );
    }
    for t in failed.iter().take(20) {
        println!(
            "  FAILED   {} | {} | θo {} | {}: statistic {:.4e}, p = {}",
            t.sampler,
            t.brdf,
            t.theta_o.map_or("-".to_string(), |a| format!("{a}°")),
            t.test,
            t.statistic,
            t.p_value.map_or("-".to_string(), |p| format!("{p:.3e}"))
        );
    }
    if !report.mutants.is_empty() {
        let caught = report.mutants.iter().filter(|m| m.detected).count();
        println!("mutants    {caught}/{} caught", report.mutants.len());
        for m in &report.mutants {
            let by = if m.caught_by.is_empty() {
                "-".to_string()
            } else {
                m.caught_by.join(", ")
            };
            println!(
                "  {:<8} {:<32} caught by: {by}",
                if m.detected { "caught" } else { "ESCAPED" },
                m.name
            );
        }
    }
    if run == 0 {
        println!("result     NO TEST RAN");
        let reason = skipped.first().map_or_else(
            || "no case matched the selection".to_string(),
            |t| format!("{} | {}: {}", t.sampler, t.brdf, why(t)),
        );
        Err(CliError::NothingTested(format!(
            "no test ran: {} skipped ({reason})",
            count(skipped.len(), "case", "cases")
        )))
    } else if report.passed() {
        println!("result     PASSED");
        Ok(())
    } else {
        Err(CliError::TestFailed(
            "validation failed (see the lines above)".to_string(),
        ))
    }
}

/// The reason of a skipped case (its detail without the `skipped: ` prefix).
fn why(t: &validation::TestRecord) -> &str {
    t.detail.strip_prefix("skipped: ").unwrap_or(&t.detail)
}
