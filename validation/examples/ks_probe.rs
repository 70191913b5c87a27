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

use std::sync::Arc;

use brdf::{Vec3, direction_from_angles};
use brdf_sampling::DirectionSampler;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use stats::{Axis, Binning, projection_cdf, projection_cdf_with_singularities};
use validation::{Plan, Tier, build_direction, direction_domain};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [sampler, spec, theta, rest @ ..] = args.as_slice() else {
        return Err("usage: ks_probe SAMPLER BRDF THETA_O [SAMPLES]".into());
    };
    let theta: f64 = theta.parse().map_err(|e| format!("THETA_O: {e}"))?;
    let n: usize = match rest.first() {
        Some(s) => s.parse().map_err(|e| format!("SAMPLES: {e}"))?,
        None => 1_000_000,
    };
    let entry = samplers::find(sampler).map_err(|e| e.to_string())?;
    let domain = direction_domain(entry).ok_or("not a direction sampler")?;
    let brdf: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec(spec).map_err(|e| e.to_string())?);
    let wo = direction_from_angles(theta, 0.0);
    let plan = Plan::new(Tier::Full, n);
    let binning = plan
        .resolution
        .sphere_binning(domain)
        .map_err(|e| e.to_string())?
        .ok_or("no direction binning")?;
    let s: Arc<dyn DirectionSampler> = build_direction(entry, &brdf).map_err(|e| e.to_string())?;
    let pdf = |w: [f64; 3]| s.pdf(&wo, &Vec3::new(w[0], w[1], w[2]));
    // As the suite does: graded towards the sampler's declared singular directions, unless
    // PLAIN=1 (the quadrature before that declaration existed).
    let singular: Vec<[f64; 2]> = if std::env::var_os("PLAIN").is_some() {
        Vec::new()
    } else {
        s.singular_directions(&wo)
            .iter()
            .filter_map(|d| binning.param_of(&[d.x, d.y, d.z]))
            .flat_map(|[u, v]| {
                [
                    [u, v],
                    [u, v - std::f64::consts::TAU],
                    [u, v + std::f64::consts::TAU],
                ]
            })
            .collect()
    };
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
    let rows = plan.resolution.directions[0] * if domain.name() == "sphere" { 2 } else { 1 };
    let u0 = if domain.name() == "sphere" { -1.0 } else { 0.0 };
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
