//! A sampler that does not apply to a BRDF (`analytic` for a model without an analytic
//! sampler) is skipped and reported, not failed; a real build failure still fails.

use validation::{ValidateConfig, names, not_applicable, run};

#[test]
fn analytic_on_a_model_without_one_is_skipped_and_reported() {
    let config = ValidateConfig {
        brdfs: vec!["oren-nayar".into(), "lambert".into()],
        samplers: vec!["analytic".into()],
        theta_o: vec![30.0, 60.0],
        samples: Some(validation::MIN_SAMPLES),
        ..ValidateConfig::quick()
    };
    let report = run(&config, &|_| {}).expect("valid configuration");
    let skipped: Vec<_> = report
        .tests
        .iter()
        .filter(|t| t.test == names::SKIPPED)
        .collect();
    assert_eq!(skipped.len(), 2, "one per angle of oren-nayar");
    assert!(skipped.iter().all(|t| t.brdf == "oren-nayar" && t.passed));
    assert!(skipped[0].detail.contains("has no analytic sampler"));
    // lambert has one: it is really tested.
    assert!(
        report
            .tests
            .iter()
            .any(|t| t.brdf == "lambert" && t.test == names::CHI_SQUARE)
    );
    assert!(report.passed());
}

#[test]
fn only_the_missing_analytic_sampler_counts_as_not_applicable() {
    let oren: std::sync::Arc<dyn brdf::Brdf> =
        std::sync::Arc::from(brdf::parse_spec("oren-nayar").unwrap());
    let options = brdf_sampling::SetOptions::default();
    let request = samplers::DirectionRequest::new(oren, &options);
    let err = samplers::build_direction("analytic", &request).unwrap_err();
    assert!(not_applicable(&err), "{err}");
    let bad = request.with_baselines(baselines::BaselineOptions {
        lobe: baselines::LobeOptions {
            slices: 0,
            ..baselines::LobeOptions::default()
        },
        ..baselines::BaselineOptions::default()
    });
    let err = samplers::build_direction("lobe-sphere", &bad).unwrap_err();
    assert!(!not_applicable(&err), "{err}");
}

#[test]
fn quadtree_disc_skips_brdfs_unbounded_at_the_horizon() {
    let config = ValidateConfig {
        brdfs: vec!["ward-original".into(), "lambert".into()],
        samplers: vec!["quadtree-disc".into()],
        theta_o: vec![45.0],
        samples: Some(20_000),
        ..ValidateConfig::quick()
    };
    let report = run(&config, &|_| {}).expect("valid configuration");
    let skipped: Vec<_> = report
        .tests
        .iter()
        .filter(|t| t.test == names::SKIPPED)
        .collect();
    assert_eq!(skipped.len(), 1, "ward-original at 45°");
    assert!(skipped[0].brdf == "ward-original" && skipped[0].passed);
    assert!(
        skipped[0].detail.contains("grows without bound"),
        "{}",
        skipped[0].detail
    );
    // lambert is bounded: it is really tested.
    assert!(
        report
            .tests
            .iter()
            .any(|t| t.brdf == "lambert" && t.test == names::CHI_SQUARE)
    );
    for t in report.failures() {
        eprintln!(
            "FAILED {} {} {:?} {} {}",
            t.sampler, t.brdf, t.theta_o, t.test, t.detail
        );
    }
    assert!(report.passed());
}
