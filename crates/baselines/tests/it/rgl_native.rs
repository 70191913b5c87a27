//! The RGL format's own sampler on the real fixture: the reported pdf is the density of the
//! samples (sample/pdf agreement, the pdf's integral equals the fraction of samples above the
//! horizon, and a deliberately broken Jacobian fails the same check), and the estimator of the
//! albedo agrees with quadrature.

use baselines::RglNative;
use brdf::{RglBrdf, Vec3, direction_from_angles, directional_albedo, parse_spec};
use brdf_sampling::{DirectionSampler, sampled_albedo, upper_hemisphere_integral};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use std::path::PathBuf;

fn fixture() -> RglBrdf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/measured/rgl/paper_white_rgb.bsdf");
    RglBrdf::load(&p).expect("fixture")
}

#[test]
fn sample_and_pdf_agree() {
    let s = RglNative::new(fixture());
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    for th in [0.0, 30.0, 60.0, 80.0] {
        let wo = direction_from_angles(th, 25.0);
        for _ in 0..2000 {
            let d = s.sample(&wo, &mut rng);
            approx::assert_abs_diff_eq!(d.wi.norm(), 1.0, epsilon = 1e-12);
            if d.pdf > 0.0 {
                let p = s.pdf(&wo, &d.wi);
                approx::assert_relative_eq!(p, d.pdf, max_relative = 1e-6);
            }
        }
    }
}

/// `∫_Ω p dσ` by a midpoint rule in `(cos θ, φ)` on 600 × 600 cells, with `pdf` as given.
fn upper_integral(pdf: &(dyn Fn(&Vec3) -> f64 + Sync)) -> f64 {
    upper_hemisphere_integral(pdf, 600, 600)
}

fn fraction_above(s: &RglNative, wo: &Vec3, n: usize) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
    (0..n).filter(|_| s.sample(wo, &mut rng).wi.z > 0.0).count() as f64 / n as f64
}

#[test]
fn the_pdf_integrates_to_the_mass_of_the_samples() {
    let s = RglNative::new(fixture());
    for th in [0.0, 45.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        let integral = upper_integral(&|wi| s.pdf(&wo, wi));
        let above = fraction_above(&s, &wo, 200_000);
        assert!(
            (integral - above).abs() < 0.01,
            "θo {th}: ∫p = {integral}, fraction above = {above}"
        );
        // A broken Jacobian (the 4|ωo·m| of the reflection left out) fails the same check.
        let broken = upper_integral(&|wi| {
            let m = (wo + wi).normalize();
            s.pdf(&wo, wi) * 4.0 * wo.dot(&m).abs()
        });
        assert!(
            (broken - above).abs() > 0.05,
            "θo {th}: broken ∫p = {broken}"
        );
    }
}

#[test]
fn the_estimator_finds_the_albedo() {
    let b = fixture();
    let s = RglNative::new(b.clone());
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    for th in [0.0, 60.0] {
        let wo = direction_from_angles(th, 0.0);
        let e = sampled_albedo(&s, &b, &wo, 100_000, &mut rng);
        let (mean, se) = (e.mean, e.std_error());
        let reference = directional_albedo(&b, &wo, 96, 192);
        assert!(
            (mean - reference).abs() < 4.0 * se + 2e-3 * reference,
            "θo {th}: estimate {mean} ± {se}, quadrature {reference}"
        );
    }
}

#[test]
fn other_brdfs_are_refused() {
    let lambert = parse_spec("lambert").expect("builds");
    let err = RglNative::for_brdf(lambert.as_ref()).expect_err("not an RGL file");
    assert!(err.to_string().contains("rgl:PATH"));
    assert!(!RglNative::accepts(lambert.as_ref()));
    assert!(RglNative::accepts(&fixture()));
}
