//! Prints, for every model in `brdf::models()` at its defaults and a synthetic MERL table, the
//! build time of a quadtree set (median of a few runs), its memory, expected and measured
//! trials, BRDF evaluations per accepted sample, bound violations and the sampling rate.
//!
//! Run: `cargo run --release -p brdf-sampling --example model_table [-- OPTIONS]`
//! Columns: median wall-clock build time on the default rayon pool (`build s`), the CPU seconds
//! of one more build (`CPU s`; ≈ 2 × the wall time on 2 idle cores), memory, leaves per tree, expected and measured
//! trials per sample, BRDF evaluations per accepted sample, bound violations, samples per
//! second on one thread at random outgoing directions.
//!
//! Options: `--runs R` (default 3), `--grid N`, `--depth D`, `--tol T`, `--slices K`, `--nmax X`,
//! `--safety S`, `--dilation D`, `--disc-map auto|projected|equal-area`, `--ea-from DEG`,
//! `--variant adaptive|adaptive-paper`, `--only name,name`, `--per-slice S` (default 2000),
//! `--specs 'spec;spec'` (these BRDF specs instead of the model list), `--dense` (the dense
//! image map instead of the refined one), `--refine-tol T` (the refinement's tolerance), `--no-symmetry` (ignore the BRDFs' declared symmetries).

use std::sync::Arc;
use std::time::Instant;

use brdf::{Brdf, MerlBrdf, parse_spec};
use brdf_sampling::{DirectionSampler, QuadTreeSet, SetOptions, Variant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

mod support;
use support::{arg, cpu_seconds, table_specs};

struct Row {
    name: String,
    trees: usize,
    build_s: f64,
    single_s: f64,
    kib: f64,
    leaves: f64,
    expected: f64,
    measured: f64,
    evals: f64,
    violations: u64,
    msps: f64,
}

fn measure(
    name: &str,
    brdf: Arc<dyn Brdf>,
    variant: Variant,
    opts: &SetOptions,
    runs: usize,
    per_slice: usize,
) -> Row {
    let mut times = Vec::new();
    let mut set = None;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let s = QuadTreeSet::build(Arc::clone(&brdf), variant, opts).expect("build");
        times.push(t.elapsed().as_secs_f64());
        set = Some(s);
        if times[0] > 20.0 {
            break;
        }
    }
    times.sort_by(f64::total_cmp);
    // CPU seconds of one more build (process user + system time, robust to other load).
    let c0 = cpu_seconds();
    let _ = QuadTreeSet::build(Arc::clone(&brdf), variant, opts).expect("build");
    let single_s = cpu_seconds() - c0;
    let set = set.expect("at least one run");
    let rep = set.report_with_cost(per_slice, 7);
    // Sampling rate on one thread at random outgoing directions.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let n = 200_000;
    let wos: Vec<_> = (0..1024)
        .map(|_| {
            brdf::direction_from_angles(rng.random::<f64>() * 89.9, rng.random::<f64>() * 360.0)
        })
        .collect();
    let t = Instant::now();
    let mut acc = 0.0;
    for k in 0..n {
        acc += set.sample(&wos[k % wos.len()], &mut rng).pdf;
    }
    std::hint::black_box(acc);
    let msps = n as f64 / t.elapsed().as_secs_f64() / 1e6;
    let rep2 = set.report();
    Row {
        name: name.to_string(),
        trees: rep.trees,
        build_s: times[times.len() / 2],
        single_s,
        kib: rep.memory_bytes as f64 / 1024.0,
        leaves: rep.leaves as f64 / rep.trees as f64,
        expected: rep.expected_mean_trials,
        measured: rep.measured_mean_trials.unwrap_or(f64::NAN),
        evals: rep.evaluations_per_sample.unwrap_or(f64::NAN),
        violations: rep2.bound_violations,
        msps,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut opts = SetOptions::default();
    if let Some(d) = arg::<u32>(&args, "--depth") {
        opts = opts.with_depth(d);
    }
    if let Some(g) = arg(&args, "--grid") {
        opts.grid = g;
    }
    if let Some(t) = arg(&args, "--tol") {
        opts.tree.volume_tolerance = t;
    }
    if let Some(k) = arg(&args, "--slices") {
        opts.slices = k;
    }
    if let Some(n) = arg(&args, "--nmax") {
        opts.tree.n_max = n;
    }
    if let Some(s) = arg(&args, "--safety") {
        opts.safety_factor = s;
    }
    if let Some(a) = arg(&args, "--ea-from") {
        opts.equal_area_from_deg = a;
    }
    if let Some(d) = arg(&args, "--dilation") {
        opts.bound_dilation = d;
    }
    if let Some(m) = arg::<String>(&args, "--disc-map") {
        match brdf_sampling::DiscMapPolicy::parse(&m) {
            Some(p) => opts.disc_map = p,
            None => {
                eprintln!("--disc-map must be auto, projected or equal-area");
                std::process::exit(2);
            }
        }
    }
    if let Some(t) = arg::<f64>(&args, "--refine-tol") {
        opts.grid_refinement = Some(partition_sampler::Refinement {
            tolerance: t,
            ..Default::default()
        });
    }
    if args.iter().any(|a| a == "--dense") {
        opts.grid_refinement = None;
    }
    if args.iter().any(|a| a == "--no-symmetry") {
        opts.symmetries = false;
    }
    let variant = match arg::<String>(&args, "--variant").as_deref() {
        Some("adaptive-paper") => Variant::Paper,
        _ => Variant::Adaptive,
    };
    let runs = arg(&args, "--runs").unwrap_or(3);
    let per_slice = arg(&args, "--per-slice").unwrap_or(2000);
    let only: Option<Vec<String>> =
        arg::<String>(&args, "--only").map(|s| s.split(',').map(str::to_string).collect());
    let wanted = |n: &str| only.as_ref().is_none_or(|o| o.iter().any(|x| x == n));

    println!(
        "options: slices {} (anisotropic {:?}), n_max {}, max_depth {}, grid {}, safety {}, dilation {}, volume_tolerance {}, disc map {:?}, variant {:?}, {} rayon threads",
        opts.slices,
        opts.anisotropic_slices,
        opts.tree.n_max,
        opts.tree.max_depth,
        opts.grid,
        opts.safety_factor,
        opts.bound_dilation,
        opts.tree.volume_tolerance,
        opts.disc_map,
        variant,
        rayon::current_num_threads()
    );
    println!(
        "| {:<22} | {:>5} | {:>8} | {:>8} | {:>9} | {:>7} | {:>8} | {:>8} | {:>10} | {:>6} | {:>9} |",
        "model",
        "trees",
        "build s",
        "CPU s",
        "KiB",
        "leaves",
        "E[trials]",
        "trials",
        "evals/smp",
        "viol.",
        "Msample/s"
    );
    println!(
        "|{:-<24}|{:->7}|{:->10}|{:->10}|{:->11}|{:->9}|{:->10}|{:->10}|{:->12}|{:->8}|{:->11}|",
        "", "", "", "", "", "", "", "", "", "", ""
    );
    let mut rows = Vec::new();
    let specs = table_specs(&args);
    for spec in specs.iter().filter(|s| wanted(s)) {
        let brdf: Arc<dyn Brdf> =
            if let Some(inner) = spec.strip_prefix("merl(").and_then(|s| s.strip_suffix(')')) {
                Arc::new(MerlBrdf::tabulate(&*parse_spec(inner).expect("spec")))
            } else {
                Arc::from(parse_spec(spec).expect("spec"))
            };
        let r = measure(spec, brdf, variant, &opts, runs, per_slice);
        println!(
            "| {:<22} | {:>5} | {:>8.3} | {:>8.3} | {:>9.1} | {:>7.1} | {:>8.3} | {:>8.3} | {:>10.3} | {:>6} | {:>9.2} |",
            r.name,
            r.trees,
            r.build_s,
            r.single_s,
            r.kib,
            r.leaves,
            r.expected,
            r.measured,
            r.evals,
            r.violations,
            r.msps
        );
        rows.push(r);
    }
    let iso: Vec<&Row> = rows.iter().filter(|r| r.trees == opts.slices).collect();
    let mean = |f: &dyn Fn(&Row) -> f64, rs: &[&Row]| {
        rs.iter().map(|r| f(r)).sum::<f64>() / rs.len().max(1) as f64
    };
    let all: Vec<&Row> = rows.iter().collect();
    println!(
        "mean over {} models: memory {:.1} KiB ({:.1} KiB over the {} isotropic-layout sets), E[trials] {:.3}, trials {:.3}, evals/sample {:.3}; max build {:.3} s",
        all.len(),
        mean(&|r| r.kib, &all),
        mean(&|r| r.kib, &iso),
        iso.len(),
        mean(&|r| r.expected, &all),
        mean(&|r| r.measured, &all),
        mean(&|r| r.evals, &all),
        rows.iter().map(|r| r.build_s).fold(0.0, f64::max)
    );
}
