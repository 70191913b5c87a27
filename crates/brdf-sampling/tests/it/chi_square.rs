//! Samples against the sampler's own pdf, for several models, both variants and the mixture, at
//! θo ∈ {0°, 30°, 60°, 85°, 89°}: chi-square on 16 × 32 `(cos θ, φ)` bins (α = 1e-4, fixed
//! seeds), pdf consistency (relative 1e-9), samples on the upper unit hemisphere, zero bound
//! violations, ∫ pdf dσ = 1 by quadrature, and the L1 distance to the normalised `f cos`.

use crate::common;

use brdf_sampling::{DirectionSampler, QuadTreeSet, Variant};
use common::*;

const N: usize = 20_000;

fn check_set(spec: &str, set: &QuadTreeSet, seed: u64) {
    let b = set.brdf().clone();
    for (k, &theta) in THETAS.iter().enumerate() {
        let wo = wo_at(theta);
        let samples = draw(set, &wo, N, seed + k as u64);
        for s in &samples {
            assert!(
                s.pdf > 0.0,
                "{spec} {:?} θo={theta}: sample with pdf {}",
                set.variant(),
                s.pdf
            );
            assert!(
                s.wi.z > 0.0 && (s.wi.norm() - 1.0).abs() < 1e-12,
                "{spec}: {:?}",
                s.wi
            );
        }
        let mismatch = worst_pdf_mismatch(set, &wo, &samples);
        assert!(
            mismatch <= 1e-9,
            "{spec} {:?} θo={theta}: pdf mismatch {mismatch:e}",
            set.variant()
        );
        let r = chi_square(&samples, &|w| set.pdf(&wo, w));
        assert!(
            r.p_value >= ALPHA,
            "{spec} {:?} θo={theta}: {}",
            set.variant(),
            r.summary()
        );
        let l1 = l1_to_target(set, b.as_ref(), &wo);
        println!(
            "{spec:<28} {:<16?} θo={theta:>4}°  {}  L1(pdf, f cos) = {l1:.4}",
            set.variant(),
            r.summary()
        );
    }
    let rep = set.report();
    assert_eq!(rep.bound_violations, 0, "{spec} {:?}: {rep}", set.variant());
    assert_eq!(rep.exhausted, 0, "{spec} {:?}", set.variant());
    // ∫ pdf dσ = ∫ f / Î: 1 up to the grid integral's error.
    let wo = wo_at(30.0);
    let total = integral(&|w| set.pdf(&wo, w));
    let tol = 2e-3_f64.max(5.0 * rep.max_integral_rel_err.unwrap_or(0.0));
    assert!(
        (total - 1.0).abs() <= tol,
        "{spec} {:?}: ∫pdf = {total}, tolerance {tol:e}",
        set.variant()
    );
}

fn check_model(spec: &str, seed: u64, mixture: bool) {
    let opts = test_options();
    for variant in [Variant::Adaptive, Variant::Paper] {
        let set = build(spec, variant, &opts);
        check_set(spec, &set, seed);
        if mixture && variant == Variant::Adaptive {
            check_set(spec, &set.with_mixture(true), seed + 100);
        }
    }
}

/// One `#[test]` per `name: spec, seed, mixture;` row, each running
/// `check_model(spec, seed, mixture)`.
macro_rules! model_tests {
    ($($name:ident: $spec:expr, $seed:expr, $mixture:expr;)*) => {
        $(
            #[test]
            fn $name() {
                check_model($spec, $seed, $mixture);
            }
        )*
    };
}

model_tests! {
    lambert: "lambert", 10, false;
    phong_50: "phong:n=50", 20, true;
    phong_1000_sharp: "phong:n=1000", 30, false;
    ggx_alpha_01: "ggx:alpha=0.1", 50, false;
    oren_nayar: "oren-nayar", 60, false;
    minnaert_limb_darkening: "minnaert:k=0.5", 80, false;
}

#[test]
fn ward_anisotropic() {
    let set = build(
        "ward:alpha_x=0.08,alpha_y=0.3",
        Variant::Adaptive,
        &test_options(),
    );
    // A (θ, φ) grid; Ward is half-turn symmetric, so the 8 azimuths of the options are stored
    // as 4 over [0°, 180°).
    assert_eq!(set.layout().phi, 4, "anisotropic BRDFs use a (θ, φ) grid");
    assert!(set.layout().half_turn);
    check_model("ward:alpha_x=0.08,alpha_y=0.3", 40, true);
}

#[test]
fn strauss_unbounded_at_horizon_on_the_equal_area_disc() {
    // f_r ∝ 1/cos θi: every slice is on the equal-area disc (density 2 f_r cos θi).
    let set = build("strauss", Variant::Adaptive, &test_options());
    assert_eq!(set.report().equal_area_trees, set.len());
    check_model("strauss", 70, true);
}
