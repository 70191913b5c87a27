//! Benchmark of the CDF baselines (baselines.md §B) beside uniform sampling and the adaptive
//! set: build time, memory and time per sample on a MERL-layout BRDF and an analytic model,
//! then the Douglas–Peucker tolerance sweep with compression ratio and variance cost.
//!
//! `cargo run --release -p baselines --example cdf_benchmark [-- --samples N]`
//!
//! The MERL-layout file is a tabulated Cook–Torrance written to the temporary directory and
//! read back (MERL data are not redistributable), so the measured path includes the MERL
//! lookup. Builds are parallel over slices and report wall-clock and process CPU seconds;
//! sampling runs on one thread and reports that thread's CPU time per sample (Linux
//! `/proc/thread-self/schedstat`, wall-clock elsewhere), so that a busy machine does not
//! inflate it.

use std::sync::Arc;
use std::time::Instant;

use baselines::cdf::{CascadeSlice, CdfSampler, SliceCdf, TabulatedSlice};
use baselines::{CascadeCdf, CdfOptions, CdfReport, TabulatedCdf, UniformHemisphere};
use brdf::{Brdf, MerlBrdf, Vec3, direction_from_angles};
use brdf_sampling::{DirectionSampler, QuadTreeSet, SetOptions, Variant, sampled_albedo};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Outgoing angles of the per-sample timing and of the variance measurement.
const THETA_O: [f64; 4] = [0.0, 30.0, 60.0, 85.0];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut samples = 1_000_000usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--samples" => samples = args.next().ok_or("--samples needs N")?.parse()?,
            _ => return Err(format!("unexpected argument `{a}` (usage: [--samples N])").into()),
        }
    }
    let path = std::env::temp_dir().join(format!("cdf-benchmark-{}.binary", std::process::id()));
    let analytic = brdf::parse_spec("cook-torrance:m=0.15")?;
    MerlBrdf::tabulate(analytic.as_ref()).write(&path)?;
    let merl: Arc<dyn Brdf> = Arc::new(MerlBrdf::load(&path)?);
    std::fs::remove_file(&path)?;
    let phong: Arc<dyn Brdf> = Arc::from(brdf::parse_spec("phong:n=50")?);

    println!(
        "threads: {} (rayon); {samples} samples per sampler, θo cycling over {THETA_O:?}",
        rayon::current_num_threads()
    );
    for (label, brdf) in [
        ("MERL-layout (tabulated cook-torrance:m=0.15)", &merl),
        ("phong:n=50", &phong),
    ] {
        println!("\n## {label}\n");
        println!(
            "| sampler | build s (wall / CPU) | memory MiB | CDF points stored / fine | CPU ns per sample | variance of f·cos/p (mean over θo) |"
        );
        println!("|---|---:|---:|---:|---:|---:|");
        compare(brdf, samples)?;
        println!("\n### ε sweep (cascade-cdf, default grid)\n");
        println!(
            "| ε | build s (wall / CPU) | memory MiB | compression ratio | CPU ns per sample | variance | tabulated-cdf of the same memory: grid, variance |"
        );
        println!("|---:|---:|---:|---:|---:|---:|---|");
        sweep(brdf, samples / 4)?;
    }
    Ok(())
}

/// CPU nanoseconds of the calling thread (Linux), if available.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// CPU seconds (user + system) of the whole process (Linux, 100 ticks per second), if available.
fn process_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    Some(ticks as f64 / 100.0)
}

/// Runs `build`, returning its result and `"wall / CPU"` seconds.
fn timed<T>(build: impl FnOnce() -> T) -> (T, String) {
    let cpu0 = process_cpu_s();
    let start = Instant::now();
    let out = build();
    let wall = start.elapsed().as_secs_f64();
    let cpu = match (cpu0, process_cpu_s()) {
        (Some(a), Some(b)) => format!("{:.2}", b - a),
        _ => "n/a".into(),
    };
    (out, format!("{wall:.2} / {cpu}"))
}

/// Mean time per sample (one thread's CPU time), cycling over [`THETA_O`].
fn time_per_sample(s: &dyn DirectionSampler, n: usize) -> f64 {
    let wos: Vec<Vec3> = THETA_O
        .iter()
        .map(|&t| direction_from_angles(t, 20.0))
        .collect();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let mut guard = 0.0;
    let cpu0 = thread_cpu_ns();
    let start = Instant::now();
    for i in 0..n {
        guard += s.sample(&wos[i % wos.len()], &mut rng).pdf;
    }
    let wall = start.elapsed().as_secs_f64() * 1e9;
    assert!(guard.is_finite());
    let t = match (cpu0, thread_cpu_ns()) {
        (Some(a), Some(b)) => (b - a) as f64,
        _ => wall,
    };
    t / n as f64
}

/// Per-sample variance of the albedo estimator `f cos / p`, averaged over [`THETA_O`].
fn variance(brdf: &dyn Brdf, s: &dyn DirectionSampler, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
    let per = n / THETA_O.len();
    THETA_O
        .iter()
        .map(|&t| {
            let wo = direction_from_angles(t, 20.0);
            sampled_albedo(s, brdf, &wo, per, &mut rng).variance
        })
        .sum::<f64>()
        / THETA_O.len() as f64
}

fn row(
    name: &str,
    build: &str,
    bytes: usize,
    points: &str,
    brdf: &dyn Brdf,
    s: &dyn DirectionSampler,
    n: usize,
) {
    println!(
        "| {name} | {build} | {:.2} | {points} | {:.0} | {:.4} |",
        bytes as f64 / (1 << 20) as f64,
        time_per_sample(s, n),
        variance(brdf, s, n / 4)
    );
}

/// Builds the CDF sampler of slice kind `S` under `o` and prints its [`row`], its points column
/// written by `points` from the build report.
fn cdf_row<S: SliceCdf>(
    name: &str,
    brdf: &Arc<dyn Brdf>,
    o: &CdfOptions,
    n: usize,
    points: impl Fn(&CdfReport) -> String,
) -> Result<(), Box<dyn std::error::Error>> {
    let (s, build) = timed(|| CdfSampler::<S>::build(brdf.as_ref(), o));
    let s = s?;
    let r = s.report();
    row(name, &build, r.bytes, &points(r), brdf.as_ref(), &s, n);
    Ok(())
}

fn compare(brdf: &Arc<dyn Brdf>, n: usize) -> Result<(), Box<dyn std::error::Error>> {
    row("uniform", "—", 0, "—", brdf.as_ref(), &UniformHemisphere, n);
    let o = CdfOptions::default();
    cdf_row::<TabulatedSlice>("tabulated-cdf", brdf, &o, n, |r| {
        format!("{} / {}", r.stored_points, r.fine_points)
    })?;
    cdf_row::<CascadeSlice>("cascade-cdf (ε = 1e-3)", brdf, &o, n, |r| {
        format!(
            "{} / {} ({:.4})",
            r.stored_points,
            r.fine_points,
            r.compression_ratio()
        )
    })?;
    for (name, variant) in [
        ("adaptive", Variant::Adaptive),
        ("adaptive-paper", Variant::Paper),
    ] {
        let (set, build) =
            timed(|| QuadTreeSet::build(Arc::clone(brdf), variant, &SetOptions::default()));
        let set = set?;
        row(name, &build, set.bytes_used(), "—", brdf.as_ref(), &set, n);
    }
    Ok(())
}

fn sweep(brdf: &Arc<dyn Brdf>, n: usize) -> Result<(), Box<dyn std::error::Error>> {
    for epsilon in [1e-2, 3e-3, 1e-3, 3e-4, 1e-4] {
        let o = CdfOptions {
            epsilon,
            ..CdfOptions::default()
        };
        let (c, build) = timed(|| CascadeCdf::build(brdf.as_ref(), &o));
        let c = c?;
        let r = c.report().clone();
        // The fair baseline: an uncompressed table with (about) the same bytes, n_φ = 2 n_z.
        let cells_per_slice = r.bytes as f64 / 8.0 / r.layout.len() as f64;
        let n_z = ((cells_per_slice / 2.0).sqrt().round() as usize).max(1);
        let same = CdfOptions {
            n_z,
            n_phi: 2 * n_z,
            ..CdfOptions::default()
        };
        let t = TabulatedCdf::build(brdf.as_ref(), &same)?;
        println!(
            "| {epsilon:e} | {build} | {:.2} | {:.4} | {:.0} | {:.4} | {}×{} ({:.2} MiB), {:.4} |",
            r.bytes as f64 / (1 << 20) as f64,
            r.compression_ratio(),
            time_per_sample(&c, n),
            variance(brdf.as_ref(), &c, n),
            n_z,
            2 * n_z,
            t.bytes_used() as f64 / (1 << 20) as f64,
            variance(brdf.as_ref(), &t, n),
        );
    }
    Ok(())
}
