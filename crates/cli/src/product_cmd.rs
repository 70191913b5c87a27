//! `brdf-lab product`: reflected radiance `L_r(ωo) = ∫ L(ωi) f_r(ωo, ωi) cos θi dωi` under an
//! environment map, estimated side by side by SRBF product sampling (Tsai 2008), BRDF sampling,
//! light sampling and MIS, against a converged reference (design.md §5).
//!
//! The shading frame is explicit: `--normal` (world space, the map's frame) and `--rotation`
//! about it; `--theta-o/--phi-o` are in that local frame. Samplers come from the registry.

use std::path::PathBuf;

use clap::Args;
use estimators::{LocalFrame, ProductExperiment, load_map};
use serde::Serialize;

use crate::bench_cmd::{load_attached, spec_with_sets};
use crate::brdf_args::{SetArgs, parse_brdf};
use crate::error::{CliError, CliResult};
use crate::output::{check_all, num, write_atomically};
use crate::values;

/// Arguments of `brdf-lab product`.
#[derive(Debug, Args)]
pub(crate) struct ProductArgs {
    /// BRDF: `name` or `name:key=value,...` or `merl:PATH`. Optional with --set (then the
    /// sets' stored spec; when given it must match theirs).
    #[arg(long = "brdf", required_unless_present = "set_files")]
    spec: Option<String>,
    /// Lat-long map (.hdr, .exr or .pfm) in world space; without it the built-in procedural sky.
    #[arg(long)]
    map: Option<PathBuf>,
    /// World-space surface normal `X,Y,Z` (normalised here; the zero vector is refused).
    #[arg(long, default_value = "0,0,1", value_parser = parse_vec3, allow_hyphen_values = true)]
    normal: [f64; 3],
    /// Rotation of the tangent frame about the normal, in degrees, in [−360, 360].
    #[arg(long, default_value_t = 0.0, value_parser = values::azimuth, allow_hyphen_values = true)]
    rotation: f64,
    /// Outgoing polar angle θo in the local frame, degrees in [0, 90).
    #[arg(long = "theta-o", value_parser = values::theta_o, allow_hyphen_values = true)]
    theta_o: f64,
    /// Outgoing azimuth φo in the local frame, degrees in [−360, 360].
    #[arg(long = "phi-o", default_value_t = 0.0, value_parser = values::azimuth, allow_hyphen_values = true)]
    phi_o: f64,
    /// Samples per estimator.
    #[arg(short = 'n', long = "samples", value_parser = values::int(16u64, 1_000_000_000), allow_negative_numbers = true)]
    n: u64,
    /// Seed (each estimator gets its own stream derived from it).
    #[arg(long, default_value_t = 1, value_parser = values::seed)]
    seed: u64,
    /// BRDF direction samplers for the `brdf` and `mis` estimators (repeatable; registry names).
    #[arg(long = "brdf-sampler", default_values_t = ["srbf".to_string(), "cosine".to_string()])]
    brdf_samplers: Vec<String>,
    /// A set written by `build --out` (repeatable), loaded instead of built: one more BRDF
    /// sampler of the `brdf` and `mis` estimators, named `SAMPLER@FILE`, after the
    /// --brdf-sampler ones. Every set must be for the same BRDF.
    #[arg(long = "set", value_name = "FILE")]
    set_files: Vec<PathBuf>,
    /// Environment-map samplers for the `light` and `mis` estimators (repeatable).
    #[arg(long = "light-sampler", default_values_t = ["envmap-adaptive".to_string(), "envmap-cdf".to_string()])]
    light_samplers: Vec<String>,
    /// Samples of the reference (MIS, balance heuristic, of the first BRDF and light samplers).
    #[arg(long = "reference-samples", default_value_t = 4_000_000, value_parser = values::int(16u64, 1_000_000_000), allow_negative_numbers = true)]
    reference_samples: u64,
    /// Write the results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the results as CSV (`estimator,estimate,std_err,samples,seconds,seconds_per_sample,variance_time,z,reference,reference_std_err,heavy_tailed,tail_share,variance_rel_ci95`).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Options of the samplers (the srbf fits: --srbf-*).
    #[command(flatten)]
    set: SetArgs,
}

fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("`{s}`: expected X,Y,Z"));
    }
    let mut v = [0.0; 3];
    for (x, p) in v.iter_mut().zip(parts) {
        *x = p.trim().parse().map_err(|e| format!("`{p}`: {e}"))?;
    }
    Ok(v)
}

/// One estimator's row of the output.
#[derive(Debug, Serialize)]
struct Row {
    estimator: String,
    estimate: f64,
    std_err: f64,
    samples: usize,
    seconds: f64,
    seconds_per_sample: f64,
    variance_time: f64,
    /// `(estimate − reference) / √(σ² + σ_ref²)`; no yardstick when `heavy_tailed`.
    z: f64,
    reference: f64,
    reference_std_err: f64,
    /// Largest share of the variance estimate held by one sample.
    tail_share: f64,
    /// Relative half-width of the variance estimate's 95 % interval.
    variance_rel_ci95: f64,
    /// The standard error (and so `z`) is no yardstick (`Estimate::heavy_tailed`).
    heavy_tailed: bool,
    /// Why, when `heavy_tailed`.
    warning: Option<String>,
}

/// The fits' quality and cost.
#[derive(Debug, Serialize)]
struct FitSummary {
    brdf_slices: usize,
    brdf_lobes: usize,
    brdf_mean_rel_l2: f64,
    brdf_max_rel_l2: f64,
    brdf_mean_rel_l1: f64,
    brdf_not_converged: usize,
    brdf_seconds: f64,
    brdf_bytes: usize,
    map_lobes: usize,
    map_rel_l2: f64,
    map_rel_l1: f64,
    map_converged: bool,
    map_seconds: f64,
    map_bytes: usize,
    product_lobes: usize,
    kept_lobes: usize,
    kept_mass_fraction: f64,
    /// Samples of the product estimator drawn from its cosine component.
    cosine_samples: usize,
}

/// The JSON document.
#[derive(Debug, Serialize)]
struct Report {
    brdf: String,
    map: String,
    normal: [f64; 3],
    rotation_deg: f64,
    theta_o: f64,
    phi_o: f64,
    reference: Estimate2,
    fits: FitSummary,
    estimators: Vec<Row>,
}

/// The reference estimate.
#[derive(Debug, Serialize)]
struct Estimate2 {
    estimator: String,
    estimate: f64,
    std_err: f64,
    samples: usize,
    seconds: f64,
    heavy_tailed: bool,
    warning: Option<String>,
}

/// Runs `brdf-lab product`.
pub(crate) fn run(args: &ProductArgs) -> CliResult<()> {
    check_all([
        ("--json", args.json.as_deref()),
        ("--csv", args.csv.as_deref()),
    ])?;
    if !(args.theta_o >= 0.0 && args.theta_o < 90.0) {
        return Err(CliError::input(format!(
            "--theta-o must be in [0, 90) degrees, got {}",
            args.theta_o
        )));
    }
    if !(args.phi_o.is_finite() && args.rotation.is_finite()) {
        return Err(CliError::input("--phi-o and --rotation must be finite"));
    }
    let frame = LocalFrame::new(args.normal, args.rotation.to_radians())
        .map_err(|e| CliError::input(format!("--normal: {e}")))?;
    let baselines = args.set.baselines.options()?;
    let spec = spec_with_sets(args.spec.as_deref(), &args.set_files)?;
    let brdf = parse_brdf(&spec)?;
    let saved = args
        .set_files
        .iter()
        .map(|path| load_attached(path, &spec, brdf.clone()))
        .collect::<CliResult<Vec<_>>>()?;
    let (map, map_name) =
        load_map(args.map.as_deref()).map_err(|e| CliError::input(format!("--map {e}")))?;
    let outcome = ProductExperiment {
        brdf,
        spec: &spec,
        map: &map,
        frame,
        wo: brdf::direction_from_angles(args.theta_o, args.phi_o),
        n: args.n as usize,
        reference_samples: args.reference_samples as usize,
        seed: args.seed,
        brdf_samplers: &args.brdf_samplers,
        saved_brdf_samplers: &saved,
        light_samplers: &args.light_samplers,
        set_options: args.set.options(),
        baselines,
    }
    .run()
    .map_err(CliError::input)?;
    let (reference, estimates, br, map_fit, stats) = (
        &outcome.reference,
        &outcome.estimates,
        &outcome.brdf_fit,
        &outcome.map_fit,
        &outcome.stats,
    );
    if let Some(w) = br.lbfgs_cap_warning() {
        eprintln!("brdf-lab: warning: {w}");
    }
    if !map_fit.report.converged {
        eprintln!(
            "brdf-lab: warning: the map fit hit the L-BFGS cap (--srbf-max-iter); residual (rel. L2) {:.3e}",
            map_fit.report.rel_l2
        );
    }

    let rows: Vec<Row> = estimates
        .iter()
        .map(|e| Row {
            estimator: e.estimator.clone(),
            estimate: e.estimate,
            std_err: e.std_err,
            samples: e.samples,
            seconds: e.seconds,
            seconds_per_sample: e.seconds_per_sample(),
            variance_time: e.variance_time(),
            z: (e.estimate - reference.estimate)
                / (e.std_err.powi(2) + reference.std_err.powi(2)).sqrt(),
            reference: reference.estimate,
            reference_std_err: reference.std_err,
            tail_share: e.tail_share,
            variance_rel_ci95: e.variance_rel_ci95,
            heavy_tailed: e.heavy_tailed,
            warning: e.warning(),
        })
        .collect();

    println!("brdf       {spec}");
    println!(
        "map        {map_name} ({} x {} pixels)",
        map.width(),
        map.height()
    );
    println!(
        "frame      normal ({}, {}, {}), rotation {}°, θo {}°, φo {}°",
        args.normal[0], args.normal[1], args.normal[2], args.rotation, args.theta_o, args.phi_o
    );
    println!(
        "srbf fit   BRDF: {} slices, {} lobes, rel. L2 mean {:.3} max {:.3}, rel. L1 mean {:.3}, {:.2} s, {} bytes",
        br.slices, br.lobes, br.mean_rel_l2, br.max_rel_l2, br.mean_rel_l1, br.seconds, br.bytes
    );
    println!(
        "           map: {} lobes, rel. L2 {:.3}, rel. L1 {:.3}, {:.2} s, {} bytes; product: {} lobes, kept {} ({:.1} % of the mass), {} cosine samples",
        map_fit.lobes.len(),
        map_fit.report.rel_l2,
        map_fit.report.rel_l1,
        map_fit.report.seconds,
        map_fit.bytes_used(),
        stats.product_lobes,
        stats.kept,
        100.0 * stats.kept_mass_fraction,
        stats.cosine_samples
    );
    println!(
        "reference  {:.6e} ± {:.2e} ({}, {} samples, {:.2} s)",
        reference.estimate,
        reference.std_err,
        reference.estimator,
        reference.samples,
        reference.seconds
    );
    println!(
        "{:<44} {:>13} {:>10} {:>8} {:>10} {:>10}",
        "estimator", "estimate", "std err", "z", "ns/sample", "var×time"
    );
    for r in &rows {
        // A heavy-tailed estimate's standard error is no yardstick: no bare z for it.
        let z = if r.heavy_tailed {
            "heavy".to_string()
        } else {
            format!("{:.2}", r.z)
        };
        println!(
            "{:<44} {:>13.6e} {:>10.3e} {:>8} {:>10.1} {:>10.3e}",
            r.estimator,
            r.estimate,
            r.std_err,
            z,
            1e9 * r.seconds_per_sample,
            r.variance_time
        );
    }
    if let Some(w) = reference.warning() {
        eprintln!(
            "brdf-lab: warning: the reference ({}): {w}; every z above rests on its standard error",
            reference.estimator
        );
    }
    for r in rows.iter().filter(|r| r.heavy_tailed) {
        eprintln!(
            "brdf-lab: warning: {}: {}; its standard error is no yardstick (z would be {:.2})",
            r.estimator,
            r.warning.as_deref().unwrap_or("heavy tail"),
            r.z
        );
    }

    if let Some(path) = &args.csv {
        write_atomically(path, |w| {
            writeln!(
                w,
                "estimator,estimate,std_err,samples,seconds,seconds_per_sample,variance_time,z,reference,reference_std_err,heavy_tailed,tail_share,variance_rel_ci95"
            )?;
            for r in &rows {
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    r.estimator,
                    num(r.estimate),
                    num(r.std_err),
                    r.samples,
                    num(r.seconds),
                    num(r.seconds_per_sample),
                    num(r.variance_time),
                    num(r.z),
                    num(r.reference),
                    num(r.reference_std_err),
                    r.heavy_tailed,
                    num(r.tail_share),
                    num(r.variance_rel_ci95)
                )?;
            }
            Ok(())
        })?;
    }
    if let Some(path) = &args.json {
        let report = Report {
            brdf: spec.clone(),
            map: map_name,
            normal: args.normal,
            rotation_deg: args.rotation,
            theta_o: args.theta_o,
            phi_o: args.phi_o,
            reference: Estimate2 {
                estimator: reference.estimator.clone(),
                estimate: reference.estimate,
                std_err: reference.std_err,
                samples: reference.samples,
                seconds: reference.seconds,
                heavy_tailed: reference.heavy_tailed,
                warning: reference.warning(),
            },
            fits: FitSummary {
                brdf_slices: br.slices,
                brdf_lobes: br.lobes,
                brdf_mean_rel_l2: br.mean_rel_l2,
                brdf_max_rel_l2: br.max_rel_l2,
                brdf_mean_rel_l1: br.mean_rel_l1,
                brdf_not_converged: br.not_converged,
                brdf_seconds: br.seconds,
                brdf_bytes: br.bytes,
                map_lobes: map_fit.lobes.len(),
                map_rel_l2: map_fit.report.rel_l2,
                map_rel_l1: map_fit.report.rel_l1,
                map_converged: map_fit.report.converged,
                map_seconds: map_fit.report.seconds,
                map_bytes: map_fit.bytes_used(),
                product_lobes: stats.product_lobes,
                kept_lobes: stats.kept,
                kept_mass_fraction: stats.kept_mass_fraction,
                cosine_samples: stats.cosine_samples,
            },
            estimators: rows,
        };
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    Ok(())
}
