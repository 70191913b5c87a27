//! L1 distance between each model's `adaptive` pdf and the ideal density `f·cos / ∫f·cos`
//! (both w.r.t. solid angle), at several outgoing angles: how close nearest-slice sampling is to
//! perfect importance sampling (0 = exact; 2 = disjoint).
//!
//! `cargo run --release -p brdf-sampling --example l1_table [-- --skip name,name]`
//! Quadrature: midpoint rule on a 256 × 512 grid in (cosθ, φ) (unit Jacobian).

use std::sync::Arc;

use brdf::{Brdf, Vec3, models, parse_spec};
use brdf_sampling::{DirectionSampler, SetOptions};

mod support;
use support::integrate;

const ANGLES: [f64; 5] = [0.0, 30.0, 60.0, 85.0, 89.0];
const N_COS: usize = 256;
const N_PHI: usize = 512;

/// `∫ |p − f·cos/A| dω` with `A = ∫ f·cos dω`.
fn l1(set: &dyn DirectionSampler, brdf: &dyn Brdf, wo: &Vec3) -> f64 {
    let albedo = integrate(&|wi| brdf.eval(wo, wi) * wi.z, N_COS, N_PHI);
    integrate(
        &|wi| (set.pdf(wo, wi) - brdf.eval(wo, wi) * wi.z / albedo).abs(),
        N_COS,
        N_PHI,
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let skip: Vec<String> = args
        .iter()
        .position(|a| a == "--skip")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    println!(
        "| model | {} |",
        ANGLES.map(|a| format!("{a}°")).join(" | ")
    );
    println!("|---|{}", "---|".repeat(ANGLES.len()));
    for m in models()
        .iter()
        .filter(|m| !m.needs_argument() && !skip.iter().any(|s| s == m.name))
    {
        let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(m.name)?);
        let set = brdf_sampling::QuadTreeSet::build(
            brdf.clone(),
            brdf_sampling::Variant::Adaptive,
            &SetOptions::default(),
        )?;
        let cells: Vec<String> = ANGLES
            .iter()
            .map(|&a| {
                format!(
                    "{:.3}",
                    l1(&set, brdf.as_ref(), &brdf::direction_from_angles(a, 0.0))
                )
            })
            .collect();
        println!("| {} | {} |", m.name, cells.join(" | "));
    }
    Ok(())
}
