//! Trials and BRDF evaluations per sample of `adaptive-exact` against its `max_trials` cap
//! (issue 29): builds the exact sampler of one BRDF spec at each cap given, then draws N
//! samples through `sample_eval` at random outgoing directions (uniform in solid angle,
//! θo ≤ 89°, as `brdf-lab bench --queries random`) on one thread, and prints per cap: the
//! intervals, the build's BRDF evaluations (kept intervals), the memory, the trials and
//! evaluations per sample and the mean weight `f cos / pdf` (the albedo averaged over ωo: the
//! same figure at every cap, to its standard error).
//!
//! `cargo run --release -p brdf-sampling --example exact_cost -- SPEC N CAP[/N_MAX] ...`
//! (e.g. `phong:n=120 200000 2 1.5 1.5/1.3`; `CAP/N_MAX` also sets the trees' own split
//! threshold `n_max`). Counts are deterministic (fixed seeds), so this is
//! the figure to use on a loaded machine; put it under `valgrind --tool=cachegrind` for
//! instructions.

use std::sync::Arc;

use brdf::parse_spec;
use brdf_sampling::{
    DirectionSampler, ExactOptions, ExactSet, SamplerDiagnostics, thread_evaluations,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: exact_cost SPEC N CAP [CAP ...]";
    let spec = args.first().ok_or(usage)?;
    let n: usize = args.get(1).ok_or(usage)?.parse()?;
    // `CAP` or `CAP/N_MAX`: the interval cap and the trees' own split threshold.
    let caps: Vec<(f64, Option<f64>)> = args[2..]
        .iter()
        .map(|s| -> Result<_, std::num::ParseFloatError> {
            Ok(match s.split_once('/') {
                Some((c, m)) => (c.parse()?, Some(m.parse()?)),
                None => (s.parse()?, None),
            })
        })
        .collect::<Result<_, _>>()?;
    if caps.is_empty() {
        return Err(usage.into());
    }
    let brdf: Arc<dyn brdf::Brdf> = Arc::from(parse_spec(spec)?);
    println!(
        "{:>6} {:>6} {:>9} {:>11} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "cap",
        "n_max",
        "intervals",
        "build evals",
        "KiB",
        "trials",
        "evals",
        "mean w",
        "violations"
    );
    for (cap, n_max) in caps {
        let mut opts = ExactOptions {
            max_trials: cap,
            ..ExactOptions::default()
        };
        if let Some(m) = n_max {
            opts.set.tree.n_max = m;
        }
        let set = ExactSet::build(Arc::clone(&brdf), &opts, None)?;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let e0 = thread_evaluations();
        let mut sum = 0.0;
        for _ in 0..n {
            let c = 1.0 - rng.random::<f64>() * (1.0 - 89f64.to_radians().cos());
            let s = (1.0 - c * c).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * rng.random::<f64>();
            let wo = brdf::Vec3::new(s * phi.cos(), s * phi.sin(), c);
            sum += set.sample_eval(brdf.as_ref(), &wo, &mut rng).weight();
        }
        let evals = (thread_evaluations() - e0) as f64 / n as f64;
        let report = set.report();
        println!(
            "{cap:>6} {:>6} {:>9} {:>11} {:>10.1} {:>10.3} {evals:>10.3} {:>10.5} {:>10}",
            opts.set.tree.n_max,
            set.len(),
            report.build_evaluations,
            set.bytes_used() as f64 / 1024.0,
            report.trials as f64 / report.samples.max(1) as f64,
            sum / n as f64,
            set.bound_violations().unwrap_or(0),
        );
    }
    Ok(())
}
