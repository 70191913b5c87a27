//! A synthetic MERL file (an analytic model tabulated with `brdf::write_merl` into a temporary
//! directory): sets build from the measured-data lookup, samples follow the sampler's own pdf
//! (chi-square, α = 1e-4), pdfs are consistent, no bound is violated, and a saved set reloads.

mod common;

use std::sync::Arc;

use brdf::{Brdf, MerlBrdf};
use brdf_sampling::{DirectionSampler, QuadTreeSet, Variant};
use common::*;

fn synthetic_merl(dir: &std::path::Path) -> (Arc<dyn Brdf>, String) {
    let analytic = brdf("phong:n=50");
    let path = dir.join("phong50.binary");
    brdf::write_merl(&path, &|th, td, pd| {
        let (wo, wi) = brdf::merl::half_diff_to_directions(th, td, pd);
        if wo.z > 0.0 && wi.z > 0.0 {
            analytic.eval_rgb(&wo, &wi)
        } else {
            [-1.0; 3]
        }
    })
    .unwrap();
    (
        Arc::new(MerlBrdf::load(&path).unwrap()),
        format!("merl:{}", path.display()),
    )
}

fn check(variant: Variant) {
    let dir = tempfile::tempdir().unwrap();
    let (merl, spec) = synthetic_merl(dir.path());
    let coarse = stats::QuadratureOptions {
        accuracy: 0.05,
        max_depth: 6,
        ..quad()
    };
    {
        let set = QuadTreeSet::build(merl.clone(), variant, &test_options())
            .unwrap()
            .with_spec(&spec);
        for (k, theta) in THETAS.into_iter().enumerate() {
            let wo = wo_at(theta);
            let samples = draw(&set, &wo, 20_000, 70 + k as u64);
            assert!(samples.iter().all(|s| s.pdf > 0.0 && s.wi.z > 0.0));
            let mismatch = worst_pdf_mismatch(&set, &wo, &samples);
            assert!(mismatch <= 1e-9, "θo={theta}: {mismatch:e}");
            // The pdf is piecewise constant (nearest-bin lookup): a coarser quadrature target
            // (expected-count error 5% of √E) keeps the adaptive refinement cheap.
            let r = chi_square_with(&samples, &|w| set.pdf(&wo, w), &coarse);
            println!("merl {:?} θo={theta}: {}", set.variant(), r.summary());
            assert!(
                r.p_value >= ALPHA,
                "{:?} θo={theta}: {}",
                set.variant(),
                r.summary()
            );
        }
        let rep = set.report();
        assert_eq!(rep.bound_violations, 0, "{rep}");
        let back = QuadTreeSet::from_bytes(&set.to_bytes(), merl.clone(), &spec).unwrap();
        let wo = wo_at(45.0);
        assert_eq!(draw(&set, &wo, 100, 1), draw(&back, &wo, 100, 1));
    }
}

#[test]
fn merl_adaptive() {
    check(Variant::Adaptive);
}

#[test]
fn merl_adaptive_paper() {
    check(Variant::Paper);
}
