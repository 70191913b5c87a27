//! The factored baseline (Lawrence 2004) against its own pdf, the BRDF and deliberately broken
//! variants.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

use baselines::{FactoredOptions, FactoredSampler, NmfCost, Reparam};
use brdf::{Brdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::DirectionSampler;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use stats::{QuadratureOptions, SphereBinning, chi_square_test, mean_z_test};

fn brdf(spec: &str) -> Arc<dyn Brdf> {
    Arc::from(parse_spec(spec).expect("spec"))
}

/// Midpoint rule over the sphere in `(cos θ, φ)` (equal solid-angle cells).
fn sphere_integral(n: usize, f: impl Fn(&Vec3) -> f64) -> f64 {
    let (nz, nphi) = (2 * n, 2 * n);
    let cell = (2.0 / nz as f64) * (TAU / nphi as f64);
    let mut total = 0.0;
    for i in 0..nz {
        let z = -1.0 + (i as f64 + 0.5) * 2.0 / nz as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) * TAU / nphi as f64;
            total += f(&Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    total * cell
}

/// `∫ f_r cos θi dωi` by the midpoint rule in `(θ, φ)` on a fine grid.
fn albedo(b: &dyn Brdf, wo: &Vec3) -> f64 {
    let (nt, np) = (1000, 1000);
    let (dt, dp) = (FRAC_PI_2 / nt as f64, TAU / np as f64);
    let mut total = 0.0;
    for i in 0..nt {
        let t = (i as f64 + 0.5) * dt;
        let (s, c) = t.sin_cos();
        for j in 0..np {
            let p = (j as f64 + 0.5) * dp;
            let wi = Vec3::new(s * p.cos(), s * p.sin(), c);
            total += b.eval(wo, &wi) * c * s;
        }
    }
    total * dt * dp
}

fn estimates(
    s: &dyn DirectionSampler,
    b: &dyn Brdf,
    wo: &Vec3,
    n: usize,
    seed: u64,
    pdf: &dyn Fn(&Vec3) -> f64,
) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let d = s.sample(wo, &mut rng);
            if d.wi.z > 0.0 {
                b.eval(wo, &d.wi) * d.wi.z / pdf(&d.wi)
            } else {
                0.0
            }
        })
        .collect()
}

fn small() -> FactoredOptions {
    FactoredOptions {
        max_iterations: 500,
        ..FactoredOptions::default()
    }
}

#[test]
fn pdf_integrates_to_one_over_the_sphere() {
    for (spec, reparam, alpha) in [
        ("phong:n=50", Reparam::HalfAngle, 0.05),
        ("phong:n=50", Reparam::HalfAngle, 0.0),
        ("ward", Reparam::Spherical, 0.0),
        ("ggx:alpha=0.2", Reparam::HalfAngle, 0.2),
    ] {
        let b = brdf(spec);
        let options = FactoredOptions {
            reparam,
            defensive_alpha: alpha,
            ..small()
        };
        let s = FactoredSampler::build(b.as_ref(), &options).unwrap();
        // (At θo = 0 the half-angle density of a peaked lobe sits in a 5° cap around the
        // pole, which this midpoint rule resolves only to ~1 %; the validation suite's
        // adaptive quadrature covers that angle.)
        for theta in [10.0, 40.0, 80.0] {
            let wo = direction_from_angles(theta, 20.0);
            let total = sphere_integral(800, |wi| s.pdf(&wo, wi));
            assert!(
                (total - 1.0).abs() < 5e-3,
                "{spec} {reparam:?} θo {theta}: {total}"
            );
        }
    }
}

#[test]
fn samples_follow_the_pdf_and_a_missing_jacobian_is_rejected() {
    let b = brdf("phong:n=50");
    let options = FactoredOptions {
        defensive_alpha: 0.0,
        ..small()
    };
    let s = FactoredSampler::build(b.as_ref(), &options).unwrap();
    let wo = direction_from_angles(45.0, 0.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let samples: Vec<_> = (0..100_000).map(|_| s.sample(&wo, &mut rng)).collect();
    for d in &samples {
        let p = s.pdf(&wo, &d.wi);
        assert!((p - d.pdf).abs() <= 1e-12 * p && p > 0.0);
    }
    let points: Vec<[f64; 3]> = samples.iter().map(|d| [d.wi.x, d.wi.y, d.wi.z]).collect();
    let bins = SphereBinning::sphere(40, 40).unwrap();
    let opts = QuadratureOptions::default();
    let pdf = |x: [f64; 3]| s.pdf(&wo, &Vec3::new(x[0], x[1], x[2]));
    let good = chi_square_test(&bins, &pdf, &points, &opts).unwrap();
    assert!(good.p_value > 1e-3, "{good:?}");

    // Broken: the half-angle density without the 1/(4 ωi·ωh) Jacobian, renormalised.
    let no_jac = |wi: &Vec3| {
        let h = (wi + wo).normalize();
        s.pdf(&wo, wi) * 4.0 * wi.dot(&h).abs()
    };
    let mass = sphere_integral(300, no_jac);
    let broken = |x: [f64; 3]| no_jac(&Vec3::new(x[0], x[1], x[2])) / mass;
    let bad = chi_square_test(&bins, &broken, &points, &opts).unwrap();
    assert!(bad.p_value < 1e-6, "{bad:?}");
}

#[test]
fn estimator_is_unbiased_and_broken_pdfs_are_caught() {
    for (spec, theta) in [("phong:n=50", 30.0), ("ward", 60.0), ("lambert", 85.0)] {
        let b = brdf(spec);
        let s = FactoredSampler::build(b.as_ref(), &small()).unwrap();
        let wo = direction_from_angles(theta, 10.0);
        let reference = albedo(b.as_ref(), &wo);
        let good = estimates(&s, b.as_ref(), &wo, 200_000, 3, &|wi| s.pdf(&wo, wi));
        let z = mean_z_test(&good, reference, 1e-3).unwrap();
        assert!(z.passed, "{spec}: {z:?}");
        // Missing Jacobian (the reported pdf of the factored part without 1/(4 ωi·ωh)).
        let no_jac = |wi: &Vec3| {
            let h = (wi + wo).normalize();
            0.95 * s.factored_pdf(&wo, wi) * 4.0 * wi.dot(&h).abs() + 0.05 * wi.z.max(0.0) / PI
        };
        let bad = estimates(&s, b.as_ref(), &wo, 200_000, 3, &no_jac);
        let z = mean_z_test(&bad, reference, 1e-3).unwrap();
        assert!(!z.passed, "{spec}: missing Jacobian not caught {z:?}");
    }
}

#[test]
fn chosen_term_only_pdf_is_caught() {
    // The pdf of one term instead of the mixture: evaluate every sample with the term of
    // largest weight only. The estimator drifts away from the albedo.
    let b = brdf("phong:n=20");
    let options = FactoredOptions {
        outer_terms: 3,
        inner_terms: 2,
        defensive_alpha: 0.0,
        ..small()
    };
    let s = FactoredSampler::build(b.as_ref(), &options).unwrap();
    let wo = direction_from_angles(50.0, 0.0);
    let w = s.term_weights(&wo).to_vec();
    assert!(w.iter().filter(|&&x| x > 1e-3).count() >= 2, "{w:?}");
    let reference = albedo(b.as_ref(), &wo);
    let good = estimates(&s, b.as_ref(), &wo, 200_000, 5, &|wi| s.pdf(&wo, wi));
    assert!(mean_z_test(&good, reference, 1e-3).unwrap().passed);
    let single = |wi: &Vec3| s.term_pdf(&wo, wi, 0);
    let bad = estimates(&s, b.as_ref(), &wo, 200_000, 5, &single);
    assert!(!mean_z_test(&bad, reference, 1e-3).unwrap().passed);
}

#[test]
fn support_is_covered_with_the_defensive_mixture() {
    for spec in ["phong:n=200", "ward", "oren-nayar"] {
        let b = brdf(spec);
        let s = FactoredSampler::build(b.as_ref(), &small()).unwrap();
        for theta in [0.0, 60.0, 89.0] {
            let wo = direction_from_angles(theta, 0.0);
            let holes = sphere_integral(200, |wi| {
                if wi.z > 0.0
                    && b.eval(&wo, wi) > 0.0
                    && s.pdf(&wo, wi).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                {
                    1.0
                } else {
                    0.0
                }
            });
            assert_eq!(holes, 0.0, "{spec} θo {theta}");
        }
    }
}

#[test]
fn builds_are_reproducible_and_report_their_fit() {
    let b = brdf("ashikhmin-shirley");
    let options = FactoredOptions {
        cost: NmfCost::KullbackLeibler,
        ..small()
    };
    let a = FactoredSampler::build(b.as_ref(), &options).unwrap();
    let c = FactoredSampler::build(b.as_ref(), &options).unwrap();
    let wo = direction_from_angles(35.0, 70.0);
    let wi = direction_from_angles(40.0, 250.0);
    assert_eq!(a.pdf(&wo, &wi), c.pdf(&wo, &wi));
    let r = a.report();
    assert_eq!(r.outer.relative_error, c.report().outer.relative_error);
    assert!(r.outer.relative_error > 0.0 && r.outer.relative_error < 1.0);
    assert!(r.total_relative_error > 0.0 && r.total_relative_error < 1.0);
    assert_eq!(r.inner.len(), 3);
    assert!(r.bytes > 0 && r.bytes == a.bytes_used());
    assert!(r.to_string().contains("relative error"));
}

#[test]
fn bad_options_and_bad_brdfs_are_errors() {
    let b = brdf("lambert");
    let zero_j = FactoredOptions {
        outer_terms: 0,
        ..FactoredOptions::default()
    };
    let e = FactoredSampler::build(b.as_ref(), &zero_j).unwrap_err();
    assert!(e.to_string().contains("1..=16"), "{e}");
    let zero_grid = FactoredOptions {
        theta_o_cells: 0,
        ..FactoredOptions::default()
    };
    assert!(FactoredSampler::build(b.as_ref(), &zero_grid).is_err());
    let zero = brdf("lambert:rho=0");
    assert!(FactoredSampler::build(zero.as_ref(), &small()).is_err());
}

#[test]
fn iteration_cap_keeps_the_result_and_reports_it() {
    let b = brdf("phong:n=50");
    let options = FactoredOptions {
        max_iterations: 2,
        ..FactoredOptions::default()
    };
    let s = FactoredSampler::build(b.as_ref(), &options).unwrap();
    assert!(!s.report().converged());
    assert!(s.report().to_string().contains("NOT converged"));
    let wo = direction_from_angles(30.0, 0.0);
    let total = sphere_integral(300, |wi| s.pdf(&wo, wi));
    assert!((total - 1.0).abs() < 5e-3, "{total}");
}

#[test]
fn anisotropic_and_full_row_tables_are_unbiased() {
    // θo × φo rows: an anisotropic BRDF, and an isotropic one with the θo-only variant off.
    for (spec, isotropic_rows) in [
        ("ward:alpha_x=0.1,alpha_y=0.3", true),
        ("phong:n=30", false),
    ] {
        let b = brdf(spec);
        let options = FactoredOptions {
            isotropic_rows,
            ..small()
        };
        let s = FactoredSampler::build(b.as_ref(), &options).unwrap();
        assert!(!s.report().rows_theta_only);
        assert_eq!(s.report().rows, 16 * 32);
        for (theta, phi) in [(25.0, 40.0), (70.0, 200.0)] {
            let wo = direction_from_angles(theta, phi);
            let total = sphere_integral(600, |wi| s.pdf(&wo, wi));
            assert!((total - 1.0).abs() < 5e-3, "{spec} {theta} {phi}: {total}");
            let reference = albedo(b.as_ref(), &wo);
            let values = estimates(&s, b.as_ref(), &wo, 100_000, 8, &|wi| s.pdf(&wo, wi));
            let z = mean_z_test(&values, reference, 1e-3).unwrap();
            assert!(z.passed, "{spec} {theta} {phi}: {z:?}");
        }
    }
}

#[test]
fn every_analytic_model_at_the_full_tier_angles_is_unbiased() {
    // E[g/p] against the albedo for every analytic model at θo ∈ {0, 30, 60, 85, 89}° with the
    // default options (Šidák-corrected over the cases), plus p > 0 at every sample.
    let cases: Vec<(&str, f64)> = brdf::models()
        .iter()
        .filter(|m| !m.needs_argument())
        .flat_map(|m| [0.0, 30.0, 60.0, 85.0, 89.0].map(|t| (m.name, t)))
        .collect();
    let alpha = 1.0 - (1.0 - 1e-3f64).powf(1.0 / cases.len() as f64);
    let options = FactoredOptions {
        max_iterations: 300,
        ..FactoredOptions::default()
    };
    let mut built = std::collections::HashMap::new();
    for (name, theta) in cases {
        let b = brdf(name);
        let s = built
            .entry(name)
            .or_insert_with(|| FactoredSampler::build(b.as_ref(), &options).unwrap());
        let wo = direction_from_angles(theta, 0.0);
        let reference = albedo(b.as_ref(), &wo);
        let values = estimates(s, b.as_ref(), &wo, 40_000, 21, &|wi| s.pdf(&wo, wi));
        let z = mean_z_test(&values, reference, alpha).unwrap();
        assert!(z.passed, "{name} θo {theta}: {z:?}");
    }
}
