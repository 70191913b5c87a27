//! A bare sampling loop of one quadtree set for profilers (`perf record`, `valgrind
//! --tool=callgrind`): builds the `adaptive` set of one BRDF spec, then draws N directions on
//! one thread at random outgoing directions (θo uniform in [0°, 89.9°), φo uniform; 1024 of
//! them, cycled, as `model_table` does). Prints the thread's CPU time per sample (from
//! `/proc/thread-self/stat`, Linux; the figure to quote on a loaded machine), the wall time,
//! and the BRDF evaluations per sample.
//!
//! `cargo run --release -p brdf-sampling --example set_loop -- [SPEC|all] [N] [adaptive|exact]`
//! (defaults `phong`, 2 000 000, `adaptive`; `exact` builds the `adaptive-exact` set instead). `all` runs every model of `brdf::models()` at its defaults and a
//! synthetic MERL table (`merl(phong:n=50)`, as `model_table` does) and prints the mean
//! samples/s; `merl(SPEC)` tabulates SPEC in the MERL layout.

use std::sync::Arc;
use std::time::Instant;

use brdf::parse_spec;
use brdf_sampling::{
    DirectionSampler, ExactOptions, ExactSet, QuadTreeSet, SetOptions, Variant, thread_evaluations,
};
use distributions::thread_cpu_seconds;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

mod support;

/// One line per spec: CPU and wall time per sample, evaluations per sample; returns M samples/s
/// from the thread's CPU time (wall time where CPU time is unavailable).
fn run(spec: &str, n: usize, exact: bool) -> Result<f64, Box<dyn std::error::Error>> {
    let brdf: Arc<dyn brdf::Brdf> =
        if let Some(inner) = spec.strip_prefix("merl(").and_then(|s| s.strip_suffix(')')) {
            Arc::new(brdf::MerlBrdf::tabulate(&*parse_spec(inner)?))
        } else {
            Arc::from(parse_spec(spec)?)
        };
    if exact {
        let set = ExactSet::build(brdf, &ExactOptions::default(), None)?;
        time_loop(spec, &set, n)
    } else {
        let set = QuadTreeSet::build(brdf, Variant::Adaptive, &SetOptions::default())?;
        time_loop(spec, &set, n)
    }
}

/// Times `n` samples of `set` (see the module docs) and prints one line.
fn time_loop<S: DirectionSampler>(
    spec: &str,
    set: &S,
    n: usize,
) -> Result<f64, Box<dyn std::error::Error>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let wos: Vec<_> = (0..1024)
        .map(|_| {
            brdf::direction_from_angles(rng.random::<f64>() * 89.9, rng.random::<f64>() * 360.0)
        })
        .collect();
    let e0 = thread_evaluations();
    let c0 = thread_cpu_seconds();
    let t = Instant::now();
    let mut acc = 0.0;
    for k in 0..n {
        acc += set.sample(&wos[k % wos.len()], &mut rng).pdf;
    }
    std::hint::black_box(acc);
    let wall = t.elapsed().as_secs_f64();
    let cpu = thread_cpu_seconds().zip(c0).map(|(a, b)| a - b);
    let evals = (thread_evaluations() - e0) as f64 / n as f64;
    println!(
        "{spec:<24} wall {:>7.1} ns/sample  CPU {:>7} ns/sample  {evals:.3} evaluations/sample",
        wall / n as f64 * 1e9,
        cpu.map_or("n/a".to_string(), |c| format!("{:.1}", c / n as f64 * 1e9)),
    );
    Ok(n as f64 / cpu.unwrap_or(wall) / 1e6)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = args.first().map_or("phong", String::as_str);
    let n: usize = args
        .get(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(2_000_000);
    let exact = match args.get(2).map(String::as_str) {
        None | Some("adaptive") => false,
        Some("exact") => true,
        Some(other) => return Err(format!("unknown sampler {other} (adaptive|exact)").into()),
    };
    if spec != "all" {
        run(spec, n, exact)?;
        return Ok(());
    }
    let specs = support::all_specs();
    let mut rates = Vec::new();
    for s in &specs {
        rates.push(run(s, n, exact)?);
    }
    println!(
        "mean over {} models: {:.2} M samples/s (CPU time)",
        rates.len(),
        rates.iter().sum::<f64>() / rates.len() as f64
    );
    Ok(())
}
