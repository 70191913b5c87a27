//! The study's sphere images alone (no variance cells): equal-samples and equal-time images of
//! the `--quick` study's BRDFs (or those given) under one light, every registered preferred
//! sampler, BRDF sampling alone and with MIS (each sampler with the light's own sampler), with
//! the cost table (coherent vs random ωo, MIS), and the adaptive product images with the
//! ranking of every estimator at equal time. docs/benchmarks.md §21, §23.8, §26.6, §26.7 (the reference).
//!
//! ```text
//! cargo run --release -p study --example sphere_costs -- LIGHT [PX] [SPP] [BRDF ...]
//! ```
//! e.g. `LIGHT = envmap:PATH/grace_probe_latlong.hdr`, `PX = 80`, `SPP = 64`.

use study::{RenderConfig, StudyConfig, StudyPlan};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(light) = args.first().cloned() else {
        eprintln!("sphere_costs: usage: sphere_costs LIGHT [PX] [SPP] [BRDF ...]");
        std::process::exit(2);
    };
    let number = |k: usize, default: usize| -> usize {
        args.get(k)
            .map_or(Ok(default), |s| s.parse())
            .unwrap_or_else(|e| {
                eprintln!("sphere_costs: argument {k}: {e}");
                std::process::exit(2);
            })
    };
    let (px, spp) = (number(1, 80), number(2, 64));
    let brdfs: Vec<String> = if args.len() > 3 {
        args[3..].to_vec()
    } else {
        study::QUICK_BRDFS.iter().map(|s| s.to_string()).collect()
    };
    let samplers = StudyConfig::quick(None).0.samplers;
    let config = StudyConfig::new(samplers, brdfs, vec![30.0], vec![light]);
    let plan = StudyPlan::new(config, Vec::new()).unwrap_or_else(|e| {
        eprintln!("sphere_costs: {e}");
        std::process::exit(1);
    });
    let cfg = RenderConfig {
        sphere_px: px,
        spp,
        reference_spp: 512,
        light: 0,
        seed: 1,
        mis: true,
    };
    let render = plan.render(&cfg, &|_| {}).unwrap_or_else(|e| {
        eprintln!("sphere_costs: {e}");
        std::process::exit(1);
    });
    println!("{}", render.markdown(&[]));
    // The reference's own error (estimated from its halves), weights and pilot variances.
    let re = &render.reference_error;
    println!(
        "reference: {:.1} s, own relative error {:.3} % (whole row); process CPU s (MIS part, pilots, product part): {:?}",
        render.reference.seconds,
        100.0 * re.whole,
        re.cpu_seconds
    );
    for (j, spec) in render.brdfs.iter().enumerate() {
        println!(
            "  reference on `{spec}`: own error {:.3} %, MIS weight {:.4}, pilot relative variance per sample MIS {:.4} / product {:.4}",
            100.0 * re.per_sphere[j],
            re.mis_weight[j],
            re.pilot_rel_var[j].0,
            re.pilot_rel_var[j].1
        );
    }
    // Per sphere: each sampler's relative error at equal time, best first, BRDF sampling alone
    // and with MIS.
    for kind in ["equal time", "MIS equal time"] {
        for (spec, rows) in render.sphere_ranking(kind) {
            if rows.is_empty() {
                continue;
            }
            println!(
                "sphere `{spec}`, {kind} (sampler, spp, rel. error ± 95 %, above the best ± Šidák 95 %, tied with the best): adaptive {}",
                study::AdaptiveVerdict::of(&rows).word()
            );
            print_rows(&rows, 24);
        }
    }
    // Every estimator together at equal time: BRDF only, MIS (`sampler+MIS`), adaptive product.
    if let Some(pc) = &render.product_cost {
        println!(
            "adaptive product cost: setup {:.0} ns per pixel + {:.0} ns per sample ({:.0} ns per pixel sample at 8 spp, {:.1} BRDF evaluations per pixel at 8 spp)",
            pc.setup_ns, pc.per_sample_ns, pc.at8_ns, pc.evals_per_pixel8
        );
        for (spec, rows) in render.sphere_ranking_all() {
            println!(
                "sphere `{spec}`, every estimator at equal time: adaptive {}",
                study::AdaptiveVerdict::of(&rows).word()
            );
            print_rows(&rows[..rows.len().min(8)], 28);
        }
    }
    if let Some(v) = render.equal_time_verdict() {
        println!("{v}");
    }
}

/// One line per sampler: relative error ± its 95 % half-width, the distance above the best ±
/// its Šidák 95 % half-width, tied or worse; the sampler's name padded to `width`.
fn print_rows(rows: &[study::SphereError], width: usize) {
    for r in rows {
        println!(
            "  {:<width$} {:>5} {:>8.3} ± {:.3} %  {:>+7.3} ± {:.3}  {}",
            r.sampler,
            r.spp,
            100.0 * r.error,
            100.0 * r.ci95,
            100.0 * r.above_best,
            100.0 * r.above_best_hw,
            if r.tied_with_best { "tied" } else { "worse" }
        );
    }
}
