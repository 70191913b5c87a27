//! Shared helpers of the integration tests: small sets, sampling, chi-square against the
//! sampler's own pdf on `(cos θ, φ)` bins, normalisation and L1 distances by quadrature.
#![allow(dead_code, unreachable_pub, missing_docs)]

use std::sync::Arc;

use brdf::{Brdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::{DirSample, DirectionSampler, QuadTreeSet, SetOptions, Variant};
use partition_sampler::UniformSource;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use stats::{QuadratureOptions, SphereBinning};

/// Significance level of each statistical test in this crate.
pub const ALPHA: f64 = 1e-4;

/// Outgoing polar angles every model is tested at (degrees).
pub const THETAS: [f64; 5] = [0.0, 30.0, 60.0, 85.0, 89.0];

/// Options of the test sets: 9 θ slices (centres 5°, 15°, …, 85°), 6 × 8 anisotropic.
pub fn test_options() -> SetOptions {
    SetOptions {
        slices: 9,
        anisotropic_slices: [6, 8],
        ..SetOptions::default()
    }
}

pub fn brdf(spec: &str) -> Arc<dyn Brdf> {
    Arc::from(parse_spec(spec).unwrap_or_else(|e| panic!("{spec}: {e}")))
}

pub fn build(spec: &str, variant: Variant, opts: &SetOptions) -> QuadTreeSet {
    QuadTreeSet::build(brdf(spec), variant, opts)
        .unwrap_or_else(|e| panic!("{spec}: {e}"))
        .with_spec(spec)
}

/// The outgoing direction used for θo (φo = 37° so the rotation is exercised).
pub fn wo_at(theta_deg: f64) -> Vec3 {
    direction_from_angles(theta_deg, 37.0)
}

pub fn draw(s: &dyn DirectionSampler, wo: &Vec3, n: usize, seed: u64) -> Vec<DirSample> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let u: &mut dyn UniformSource = &mut rng;
    (0..n).map(|_| s.sample(wo, u)).collect()
}

pub fn bins() -> SphereBinning {
    SphereBinning::hemisphere(16, 32).expect("binning")
}

pub fn quad() -> QuadratureOptions {
    QuadratureOptions {
        min_depth: 2,
        ..QuadratureOptions::default()
    }
}

/// Chi-square p-value of `samples` against `pdf` (solid angle) on 16 × 32 `(cos θ, φ)` bins.
pub fn chi_square(
    samples: &[DirSample],
    pdf: &(dyn Fn(&Vec3) -> f64 + Sync),
) -> stats::ChiSquareResult {
    chi_square_with(samples, pdf, &quad())
}

/// [`chi_square`] with explicit quadrature options.
pub fn chi_square_with(
    samples: &[DirSample],
    pdf: &(dyn Fn(&Vec3) -> f64 + Sync),
    opts: &QuadratureOptions,
) -> stats::ChiSquareResult {
    let pts: Vec<[f64; 3]> = samples.iter().map(|s| [s.wi.x, s.wi.y, s.wi.z]).collect();
    let f = |d: [f64; 3]| pdf(&Vec3::new(d[0], d[1], d[2]));
    stats::chi_square_test(&bins(), &f, &pts, opts).expect("chi-square")
}

/// `∫ pdf dσ` over the hemisphere.
pub fn integral(pdf: &(dyn Fn(&Vec3) -> f64 + Sync)) -> f64 {
    let f = |d: [f64; 3]| pdf(&Vec3::new(d[0], d[1], d[2]));
    stats::integrate(&f, &bins(), 1e-6, &quad())
        .expect("quadrature")
        .value
}

/// L1 distance `∫ |p − f cos / ∫ f cos| dσ` between a sampler's pdf and the normalised target,
/// computed on the disc (`dσ = dA / cos θ`, so the integrand is `|p/cos − f/∫f dA|`) by the
/// midpoint rule on a 512² grid.
pub fn l1_to_target(s: &dyn DirectionSampler, brdf: &dyn Brdf, wo: &Vec3) -> f64 {
    const M: usize = 512;
    let h = 2.0 / M as f64;
    let mut p = Vec::new();
    let mut t = Vec::new();
    for j in 0..M {
        for i in 0..M {
            let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
            let z2 = 1.0 - x * x - y * y;
            if z2 > 0.0 {
                let w = Vec3::new(x, y, z2.sqrt());
                p.push(s.pdf(wo, &w) / w.z);
                t.push(brdf.eval(wo, &w));
            }
        }
    }
    let norm: f64 = t.iter().sum::<f64>() * h * h;
    p.iter()
        .zip(&t)
        .map(|(a, b)| (a - b / norm).abs())
        .sum::<f64>()
        * h
        * h
}

/// Largest relative difference between the pdf returned by `sample` and `pdf(wo, wi)`.
pub fn worst_pdf_mismatch(s: &dyn DirectionSampler, wo: &Vec3, samples: &[DirSample]) -> f64 {
    samples
        .iter()
        .map(|d| {
            let p = s.pdf(wo, &d.wi);
            if p == d.pdf {
                0.0
            } else {
                (p - d.pdf).abs() / p.abs().max(d.pdf.abs())
            }
        })
        .fold(0.0, f64::max)
}
