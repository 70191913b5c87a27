//! Checks the KS projection test's tabulated `cos θ` CDF of one direction sampler against its
//! own samples, row by row of the full tier's binning: a row whose tabulated mass differs from
//! the sampled fraction by many standard errors, while the chi-square of the same case passes,
//! is a quadrature error of the projection CDF (a feature of the pdf its line integrals miss),
//! not a sampler defect.
//!
//! Set `PLAIN=1` to tabulate without the sampler's declared singular directions.
//!
//! ```sh
//! cargo run --release -p validation --example ks_probe -- SAMPLER BRDF THETA_O [SAMPLES]
//! # e.g. analytic ward-original 89 1000000
//! ```

use brdf::Vec3;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use stats::{Axis, projection_cdf, projection_cdf_with_singularities};
use support::Probe;

mod support;

fn main() -> Result<(), String> {
    let probe = Probe::from_args("ks_probe", 1_000_000)?;
    // As the suite does: graded towards the sampler's declared singular directions, unless
    // PLAIN=1 (the quadrature before that declaration existed).
    let singular = probe.singular();
    let Probe {
        sampler: s,
        wo,
        plan,
        binning,
        ..
    } = probe;
    let n = plan.samples;
    let pdf = |w: [f64; 3]| s.pdf(&wo, &Vec3::new(w[0], w[1], w[2]));
    let cdf = if singular.is_empty() {
        projection_cdf(&binning, &pdf, Axis::U, n as u64, &plan.quadrature)
    } else {
        projection_cdf_with_singularities(
            &binning,
            &pdf,
            Axis::U,
            n as u64,
            &plan.quadrature,
            &singular,
        )
    }
    .map_err(|e| e.to_string())?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let mut us: Vec<f64> = (0..n)
        .map(|_| {
            let d = s.sample(&wo, &mut rng);
            d.wi.z / d.wi.norm()
        })
        .collect();
    us.sort_by(f64::total_cmp);
    let below = |u: f64| us.partition_point(|&x| x <= u) as f64 / n as f64;
    let sphere = !binning.is_hemisphere();
    let rows = plan.resolution.directions[0] * if sphere { 2 } else { 1 };
    let u0 = if sphere { -1.0 } else { 0.0 };
    let width = (1.0 - u0) / rows as f64;
    println!("cos θ row            tabulated   sampled     (σ)   z");
    for r in 0..rows {
        let (lo, hi) = (u0 + r as f64 * width, u0 + (r + 1) as f64 * width);
        let tab = cdf.eval(hi) - cdf.eval(lo);
        let emp = below(hi) - below(lo);
        let sigma = (emp.max(1.0 / n as f64) / n as f64).sqrt();
        let z = (emp - tab) / sigma;
        let flag = if z.abs() > 5.0 { "  <--" } else { "" };
        println!("[{lo:+.4}, {hi:+.4}]  {tab:.6}  {emp:.6}  ({sigma:.1e})  {z:+.1}{flag}");
    }
    Ok(())
}
