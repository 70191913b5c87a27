//! Build time, memory and per-sample time of the factored baseline (Lawrence 2004) on
//! analytic models and on a MERL-layout BRDF, and a sweep of J, K ∈ {1..4}.
//!
//! `cargo run --release -p baselines --example factored_bench [-- --quick]`
//!
//! The MERL-layout BRDF is an analytic model tabulated into MERL's 90 × 90 × 180 half/difference
//! table (`MerlBrdf::tabulate`), so it is looked up exactly as a measured file would be.
//! `--quick` skips the sweep.

use std::hint::black_box;
use std::time::Instant;

use baselines::{FactoredOptions, FactoredSampler};
use brdf::{Brdf, MerlBrdf, direction_from_angles, parse_spec};
use brdf_sampling::DirectionSampler;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// Nanoseconds per `sample` and per `pdf` call at θo = 45°, over `n` draws.
fn per_call(s: &FactoredSampler, n: usize) -> (f64, f64) {
    let wo = direction_from_angles(45.0, 30.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let t = Instant::now();
    let mut dirs = Vec::with_capacity(n);
    for _ in 0..n {
        dirs.push(s.sample(&wo, &mut rng).wi);
    }
    let sample_ns = t.elapsed().as_secs_f64() * 1e9 / n as f64;
    let t = Instant::now();
    let mut acc = 0.0;
    for wi in &dirs {
        acc += s.pdf(&wo, wi);
    }
    black_box(acc);
    (sample_ns, t.elapsed().as_secs_f64() * 1e9 / n as f64)
}

fn row(
    name: &str,
    brdf: &dyn Brdf,
    options: &FactoredOptions,
) -> Result<(), Box<dyn std::error::Error>> {
    let s = FactoredSampler::build(brdf, options)?;
    let r = s.report();
    let (sample_ns, pdf_ns) = per_call(&s, 1_000_000);
    println!(
        "{name:<28} J={} K={} build {:>7.3} s  iters {:>4}{}  rel.err outer {:.3e} total {:.3e}  {:>8} B  sample {:>6.1} ns  pdf {:>6.1} ns",
        r.outer_terms,
        r.inner_terms,
        r.build_seconds,
        r.outer.iterations,
        if r.converged() { " " } else { "*" },
        r.outer.relative_error,
        r.total_relative_error,
        r.bytes,
        sample_ns,
        pdf_ns
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let quick = std::env::args().any(|a| a == "--quick");
    println!("threads: {}", rayon::current_num_threads());
    println!("(* = an iteration cap was hit; the residual is reported)");
    let defaults = FactoredOptions::default();
    let merl = MerlBrdf::tabulate(parse_spec("blinn:n=100")?.as_ref());
    for spec in [
        "lambert",
        "phong:n=50",
        "ward",
        "ggx:alpha=0.2",
        "ashikhmin-shirley",
    ] {
        row(spec, parse_spec(spec)?.as_ref(), &defaults)?;
    }
    row("merl-layout blinn:n=100", &merl, &defaults)?;
    let full_rows = FactoredOptions {
        isotropic_rows: false,
        ..FactoredOptions::default()
    };
    row("merl-layout, θo×φo rows", &merl, &full_rows)?;
    if !quick {
        println!("J, K sweep on the MERL-layout BRDF");
        for j in 1..=4 {
            for k in 1..=4 {
                let o = FactoredOptions {
                    outer_terms: j,
                    inner_terms: k,
                    ..FactoredOptions::default()
                };
                row("merl-layout blinn:n=100", &merl, &o)?;
            }
        }
    }
    Ok(())
}
