//! Runs a validation suite from the command line (the same library call as
//! `brdf-lab validate`), printing progress and the markdown report.
//!
//! ```sh
//! cargo run --release -p validation --example suite -- --quick --mutants [--sampler NAME]... \
//!     [--brdf SPEC]... [--theta-o DEG]... [--samples N] [--seed S] [--json FILE] [--report FILE]
//! ```

use std::time::Instant;

use validation::{ProgressEvent, ValidateConfig, run};

fn main() {
    let mut config = ValidateConfig::full();
    let (mut json, mut report) = (None, None);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_default();
        match a.as_str() {
            "--quick" => config.quick = true,
            "--mutants" => config.mutants = true,
            "--sampler" => config.samplers.push(value()),
            "--brdf" => config.brdfs.push(value()),
            "--theta-o" => config.theta_o.push(value().parse().unwrap_or(f64::NAN)),
            "--samples" => config.samples = value().parse().ok(),
            "--seed" => config.seed = value().parse().unwrap_or(1),
            "--json" => json = Some(value()),
            "--report" => report = Some(value()),
            other => {
                eprintln!("unknown argument {other}");
                std::process::exit(2);
            }
        }
    }
    let start = Instant::now();
    let progress = |e: ProgressEvent| {
        if let ProgressEvent::Finished {
            done,
            total,
            label,
            passed,
        } = e
        {
            eprintln!(
                "[{done:>3}/{total}] {:>7.1}s {} {label}",
                start.elapsed().as_secs_f64(),
                if passed { "ok  " } else { "FAIL" }
            );
        }
    };
    let r = match run(&config, &progress) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    eprintln!("elapsed {:.1} s", start.elapsed().as_secs_f64());
    if let Some(path) = json {
        std::fs::write(path, r.to_json()).unwrap_or_else(|e| eprintln!("cannot write json: {e}"));
    }
    let md = r.to_markdown();
    match report {
        Some(path) => {
            std::fs::write(path, md).unwrap_or_else(|e| eprintln!("cannot write report: {e}"))
        }
        None => println!("{md}"),
    }
    std::process::exit(if r.passed() { 0 } else { 1 });
}
