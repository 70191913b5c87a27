//! Calibration of the suite's statistical tests (docs/validation.md): runs correct samplers
//! over many seeds and prints, per test, the observed false-rejection rate next to the nominal
//! level (raw p-values, no Šidák correction), with the two-sided binomial p-value of the
//! observed count. Too many rejections mean the quadrature is too coarse; too few mean the
//! test is weaker than it claims.
//!
//! ```sh
//! cargo run --release -p validation --example calibrate -- [--seeds 200] [--samples 200000] [--only adaptive]
//! ```

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use brdf::direction_from_angles;
use rayon::prelude::*;
use stats::{calibrate, sidak_level};
use validation::adapters::DirectionAtWo;
use validation::references::{albedo_reference, lit_reference};
use validation::targets::{BrdfReferences, brdf_direction_subject};
use validation::{
    AnySubject, Plan, QUICK_SAMPLES, Tier, build_direction, direction_domain, run_case, seeding,
    standalone_cases,
};

fn adaptive_phong() -> Result<(String, AnySubject), String> {
    let entry = samplers::find("adaptive").map_err(|e| e.to_string())?;
    let domain = direction_domain(entry).ok_or("adaptive is not a direction sampler")?;
    let brdf: Arc<dyn brdf::Brdf> =
        Arc::from(brdf::parse_spec("phong:n=50").map_err(|e| e.to_string())?);
    let wo = direction_from_angles(45.0, 0.0);
    let refs = BrdfReferences {
        albedo: albedo_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?,
        lit: lit_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?,
    };
    let built = build_direction(entry, &brdf).map_err(|e| e.to_string())?;
    Ok((
        "adaptive, phong:n=50, 45°".into(),
        AnySubject::Direction(brdf_direction_subject(
            Arc::new(DirectionAtWo::new(built, wo)),
            domain,
            brdf,
            wo,
            &refs,
        )),
    ))
}

fn standalone(name: &str, target: &str) -> Result<(String, AnySubject), String> {
    let entry = samplers::find(name).map_err(|e| e.to_string())?;
    let cases = standalone_cases(entry).ok_or_else(|| format!("{name} is not standalone"))?;
    let case = cases
        .map_err(|e| e.to_string())?
        .into_iter()
        .find(|c| c.target == target)
        .ok_or_else(|| format!("{name} has no target {target}"))?;
    Ok((
        format!("{name}, {target}"),
        AnySubject::Planar(case.subject),
    ))
}

fn main() {
    let (mut seeds, mut samples, mut only) = (200u64, QUICK_SAMPLES, None::<String>);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let v = args.next().unwrap_or_default();
        match (a.as_str(), v.parse::<u64>().ok()) {
            ("--seeds", Some(v)) => seeds = v,
            ("--samples", Some(v)) => samples = v as usize,
            ("--only", _) => only = Some(v),
            _ => {
                eprintln!("usage: calibrate [--seeds N] [--samples N] [--only SAMPLER]");
                std::process::exit(2);
            }
        }
    }
    let subjects = [
        adaptive_phong(),
        standalone("envmap-adaptive", "map:procedural-sky-128x64"),
        standalone("grid-cdf", "grid:synthetic-16x8"),
    ];
    let plan = Plan::new(Tier::Quick, samples);
    println!(
        "Calibration: {seeds} seeds per subject, {samples} one-sample draws + {} batches of {} per run (quick-tier binning and quadrature).\n",
        plan.batches, plan.batch_size
    );
    println!(
        "| subject | test | runs | rate at α = 0.05 | binomial p | rate at α = 0.01 | binomial p |"
    );
    println!("|---|---|---|---|---|---|---|");
    for s in subjects {
        let (label, subject) = match s {
            Ok(x)
                if only
                    .as_ref()
                    .is_some_and(|o| !x.0.starts_with(&format!("{o},"))) =>
            {
                continue;
            }
            Ok(x) => x,
            Err(e) => {
                eprintln!("cannot build subject: {e}");
                std::process::exit(1);
            }
        };
        let start = Instant::now();
        let seed_list: Vec<u64> = (0..seeds).collect();
        // p-values per test name, in seed order.
        let runs: Vec<Vec<(String, Option<f64>)>> = seed_list
            .par_iter()
            .map(|&seed| {
                run_case(&subject, &plan, seeding::case_seed(seed, "calibration"))
                    .into_iter()
                    .map(|o| (o.name, o.p_value))
                    .collect()
            })
            .collect();
        let mut by_test: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut order: Vec<String> = Vec::new();
        for run in &runs {
            for (name, p) in run {
                if let Some(p) = p {
                    if !order.contains(name) {
                        order.push(name.clone());
                    }
                    by_test.entry(name.clone()).or_default().push(*p);
                }
            }
        }
        for name in &order {
            let ps = &by_test[name];
            let idx: Vec<u64> = (0..ps.len() as u64).collect();
            let c05 = calibrate(&idx, 0.05, |i| Ok(ps[i as usize]));
            let c01 = calibrate(&idx, 0.01, |i| Ok(ps[i as usize]));
            if let (Ok(a), Ok(b)) = (c05, c01) {
                println!(
                    "| {label} | {name} | {} | {:.3} ({}) | {:.2} | {:.3} ({}) | {:.2} |",
                    a.runs,
                    a.rate,
                    a.rejections,
                    a.binomial_p_value,
                    b.rate,
                    b.rejections,
                    b.binomial_p_value
                );
            }
        }
        // The whole case judged as the suite does (Šidák over its p-valued tests, α = 0.01).
        let m = order.len();
        let level = sidak_level(0.01, m);
        let family = runs
            .iter()
            .filter(|run| run.iter().any(|(_, p)| p.is_some_and(|p| p < level)))
            .count();
        println!(
            "| {label} | any of the {m} tests at the Šidák level {level:.2e} (family α = 0.01) | {} | | | {:.3} ({family}) | |",
            runs.len(),
            family as f64 / runs.len().max(1) as f64
        );
        eprintln!("{label}: {:.1} s", start.elapsed().as_secs_f64());
    }
}
