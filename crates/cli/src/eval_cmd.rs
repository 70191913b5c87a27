//! `brdf-lab eval`: BRDF values (and a sampler's pdf) at given incident directions.

use std::path::{Path, PathBuf};

use brdf::Vec3;
use clap::Args;

use crate::brdf_args::{self, BrdfArgs, Given, SamplerArgs};
use crate::error::{CliError, CliResult};
use crate::output::{num, write_atomically};
use crate::values::{counted, display_path};

/// Arguments of `brdf-lab eval`.
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    #[command(flatten)]
    brdf: BrdfArgs,
    /// Also report this sampler's pdf (w.r.t. solid angle), the same value `sample` reports.
    #[arg(long)]
    sampler: Option<String>,
    /// Report the pdf of a set written by `build --out` (it stores the BRDF spec and the
    /// sampler): --brdf is then optional and must match, and the set's own options apply.
    #[arg(long = "set", value_name = "FILE", conflicts_with_all = brdf_args::SET_OPTION_IDS)]
    set_file: Option<PathBuf>,
    /// CSV of incident directions `x,y,z` (one per row; a header row is allowed; more columns
    /// are ignored, so `sample --out` files work as they are). Each direction is normalised
    /// once when read; the output's x,y,z columns are that unit vector, the one both f and the
    /// pdf are evaluated at. A zero or non-finite direction is refused.
    #[arg(long)]
    dirs: PathBuf,
    /// Write `x,y,z,f[,pdf]` here (atomically) instead of standard output.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    set: SamplerArgs,
}

/// Reads the directions of a CSV file, each normalised to a unit vector (exit 2 naming the bad
/// line). The one rule for every sampler: f and every pdf see the same unit vector.
fn read_directions(path: &Path) -> CliResult<Vec<Vec3>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::input(format!("{}: {e}", display_path(path))))?;
    let mut dirs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Option<Vec<f64>> = fields
            .iter()
            .take(3)
            .map(|f| f.parse::<f64>().ok())
            .collect();
        match parsed {
            Some(v) if v.len() == 3 => {
                let d = Vec3::new(v[0], v[1], v[2]);
                // Rows already unit to rounding (e.g. `sample --out`) are kept bit for bit.
                let unit = if (d.norm_squared() - 1.0).abs() <= 4.0 * f64::EPSILON {
                    d
                } else {
                    d / d.norm()
                };
                if !(d.iter().all(|c| c.is_finite())
                    && d.norm() > 0.0
                    && (unit.norm() - 1.0).abs() < 1e-12)
                {
                    return Err(CliError::input(format!(
                        "{}:{}: direction must be finite, non-zero and normalisable",
                        display_path(path),
                        i + 1
                    )));
                }
                dirs.push(unit);
            }
            // A header row (first non-empty line that is not numeric) is skipped.
            _ if dirs.is_empty()
                && fields.first().is_some_and(|f| f.parse::<f64>().is_err())
                && i < 1 => {}
            _ => {
                return Err(CliError::input(format!(
                    "{}:{}: expected three numbers `x,y,z`, got `{line}`",
                    display_path(path),
                    i + 1
                )));
            }
        }
    }
    if dirs.is_empty() {
        return Err(CliError::input(format!(
            "{}: no directions",
            display_path(path)
        )));
    }
    Ok(dirs)
}

/// Runs `brdf-lab eval`.
pub(crate) fn run(args: &EvalArgs, given: &Given) -> CliResult<()> {
    crate::output::check_all([("--out", args.out.as_deref())])?;
    args.set.check()?;
    let wo = brdf_args::outgoing(&args.brdf)?;
    let dirs = read_directions(&args.dirs)?;
    let (brdf, built) = match &args.set_file {
        Some(path) => {
            let (_, brdf, set, name) =
                brdf_args::load_set(path, args.brdf.spec.as_deref(), args.sampler.as_deref())?;
            brdf_args::check_options_apply(given, Some(name))?;
            (brdf, Some(set))
        }
        None => {
            brdf_args::check_options_apply(given, args.sampler.as_deref())?;
            let spec = brdf_args::required_spec(&args.brdf)?;
            let brdf = brdf_args::parse_brdf(spec)?;
            let built = match &args.sampler {
                Some(name) => Some(brdf_args::build(name, spec, brdf.clone(), &args.set)?.0),
                None => None,
            };
            (brdf, built)
        }
    };
    let rows: Vec<(Vec3, f64, Option<f64>)> = dirs
        .iter()
        .map(|wi| {
            // `wi` is unit (normalised when read): f and the pdf see the same vector.
            let f = brdf.eval(&wo, wi);
            let pdf = built.as_ref().map(|b| b.sampler().pdf(&wo, wi));
            (*wi, f, pdf)
        })
        .collect();
    let write = |w: &mut dyn std::io::Write| -> std::io::Result<()> {
        writeln!(
            w,
            "{}",
            if built.is_some() {
                "x,y,z,f,pdf"
            } else {
                "x,y,z,f"
            }
        )?;
        for (d, f, pdf) in &rows {
            write!(w, "{},{},{},{}", num(d.x), num(d.y), num(d.z), num(*f))?;
            if let Some(p) = pdf {
                write!(w, ",{}", num(*p))?;
            }
            writeln!(w)?;
        }
        Ok(())
    };
    match &args.out {
        Some(path) => {
            write_atomically(path, write)?;
            eprintln!(
                "wrote {} ({})",
                display_path(path),
                counted(rows.len(), "row")
            );
        }
        None => crate::output::write_stdout(write)?,
    }
    Ok(())
}
