//! Where one validation case spends its time: CPU seconds and pdf evaluations of each
//! quadrature stage of the suite (references, expected bin masses, normalisation, the two KS
//! projection CDFs) for one direction sampler, BRDF and outgoing angle, on the full tier's
//! binning; plus the (cos θ, φ) cells of an 8 × 8 grid that take the most pdf evaluations.
//!
//! ```sh
//! cargo run --release -p validation --example case_cost -- SAMPLER BRDF THETA_O [SAMPLES]
//! # e.g. analytic blinn 89 200000
//! ```
//!
//! A stage that takes far more evaluations than the others, concentrated in one cell, points
//! at a feature of the pdf (a peak, a jump, round-off) that the adaptive quadrature refines
//! to its depth limit.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use stats::{Axis, expected_masses_with, normalisation, projection_cdf_with_singularities};
use support::Probe;
use validation::references::{albedo_reference, lit_reference};

mod support;

/// Side of the grid of (cos θ, φ) cells the evaluations are counted in.
const GRID: usize = 8;

fn main() -> Result<(), String> {
    let probe = Probe::from_args("case_cost", 200_000)?;
    // The sampler's declared singular directions, as the suite grades towards them (PLAIN=1:
    // none).
    let singular = probe.singular();
    let Probe {
        sampler,
        brdf,
        wo,
        plan,
        binning,
    } = probe;
    let samples = plan.samples as u64;
    let opts = &plan.quadrature;

    let started = Instant::now();
    let albedo = albedo_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?;
    let lit = lit_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?;
    println!(
        "{:>14} {:8.2} s   albedo {:.8} (± {:.1e}), lit {:.8} (± {:.1e})",
        "references",
        started.elapsed().as_secs_f64(),
        albedo.value,
        albedo.abs_error,
        lit.value,
        lit.abs_error
    );

    let cells: Vec<AtomicU64> = (0..GRID * GRID).map(|_| AtomicU64::new(0)).collect();
    let pdf = |w: [f64; 3]| {
        let u = ((w[2] + 1.0) * 0.5 * GRID as f64) as usize;
        let phi = w[1].atan2(w[0]).rem_euclid(std::f64::consts::TAU);
        let v = (phi / std::f64::consts::TAU * GRID as f64) as usize;
        cells[u.min(GRID - 1) * GRID + v.min(GRID - 1)].fetch_add(1, Ordering::Relaxed);
        sampler.pdf(&wo, &brdf::Vec3::new(w[0], w[1], w[2]))
    };
    let stage = |name: &str, run: &dyn Fn() -> Result<String, String>| -> Result<(), String> {
        cells.iter().for_each(|c| c.store(0, Ordering::Relaxed));
        let t = Instant::now();
        let detail = run()?;
        let counts: Vec<u64> = cells.iter().map(|c| c.load(Ordering::Relaxed)).collect();
        let total: u64 = counts.iter().sum();
        let (worst, most) = counts
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| **c)
            .map_or((0, 0), |(i, c)| (i, *c));
        println!(
            "{name:>14} {:8.2} s {total:>12} pdf evaluations, {:.0} % in cos θ ∈ [{:.3}, {:.3}], φ ∈ [{:.0}°, {:.0}°]; {detail}",
            t.elapsed().as_secs_f64(),
            100.0 * most as f64 / total.max(1) as f64,
            -1.0 + 2.0 * (worst / GRID) as f64 / GRID as f64,
            -1.0 + 2.0 * (worst / GRID + 1) as f64 / GRID as f64,
            360.0 * (worst % GRID) as f64 / GRID as f64,
            360.0 * (worst % GRID + 1) as f64 / GRID as f64,
        );
        Ok(())
    };
    stage("bin masses", &|| {
        let t = expected_masses_with(&pdf, &binning, samples, opts).map_err(|e| e.to_string())?;
        Ok(format!("{} unconverged bins", t.unconverged_bins))
    })?;
    stage("normalisation", &|| {
        normalisation(&binning, &pdf, 1.0, plan.normalisation_tolerance, opts)
            .map(|o| o.detail)
            .map_err(|e| e.to_string())
    })?;
    for (axis, name) in [(Axis::U, "KS cos θ"), (Axis::V, "KS φ")] {
        stage(name, &|| {
            let cdf =
                projection_cdf_with_singularities(&binning, &pdf, axis, samples, opts, &singular)
                    .map_err(|e| e.to_string())?;
            Ok(format!("{} knots", cdf.knots().len()))
        })?;
    }
    Ok(())
}
