//! A sampler that does not apply to a BRDF (`samplers::SamplerEntry::applicability`: `analytic`
//! for a model without an analytic sampler, `rgl-native` for a non-RGL BRDF) is skipped and
//! reported, not failed; a real build failure still fails.

use validation::{TestRecord, ValidateConfig, ValidationReport, names, run};

/// The quick tier of `sampler` on `brdfs` at `theta_o` with `samples` samples.
fn run_quick(brdfs: &[&str], sampler: &str, theta_o: &[f64], samples: usize) -> ValidationReport {
    let config = ValidateConfig {
        brdfs: brdfs.iter().map(|b| b.to_string()).collect(),
        samplers: vec![sampler.into()],
        theta_o: theta_o.to_vec(),
        samples: Some(samples),
        ..ValidateConfig::quick()
    };
    run(&config, &|_| {}).expect("valid configuration")
}

/// The report's skipped cases.
fn skipped(report: &ValidationReport) -> Vec<&TestRecord> {
    report
        .tests
        .iter()
        .filter(|t| t.test == names::SKIPPED)
        .collect()
}

/// Whether `brdf` was really tested (it has a χ² result).
fn really_tested(report: &ValidationReport, brdf: &str) -> bool {
    report
        .tests
        .iter()
        .any(|t| t.brdf == brdf && t.test == names::CHI_SQUARE)
}

#[test]
fn analytic_on_a_model_without_one_is_skipped_and_reported() {
    let report = run_quick(
        &["oren-nayar", "lambert"],
        "analytic",
        &[30.0, 60.0],
        validation::MIN_SAMPLES,
    );
    let skipped = skipped(&report);
    assert_eq!(skipped.len(), 2, "one per angle of oren-nayar");
    assert!(skipped.iter().all(|t| t.brdf == "oren-nayar" && t.passed));
    assert!(skipped[0].detail.contains("has no analytic sampler"));
    // lambert has one: it is really tested.
    assert!(really_tested(&report, "lambert"));
    assert!(report.passed());
}

#[test]
fn rgl_native_on_an_analytic_model_is_skipped_and_reported() {
    let report = run_quick(&["lambert"], "rgl-native", &[30.0], validation::MIN_SAMPLES);
    let tests: Vec<_> = report
        .tests
        .iter()
        .filter(|t| t.sampler == "rgl-native")
        .collect();
    assert_eq!(tests.len(), 1, "one skipped case, nothing run");
    assert_eq!(tests[0].test, names::SKIPPED);
    assert!(tests[0].detail.contains("needs an RGL material"));
    // Every case skipped: nothing was tested, which is not a pass (the CLI exits 3).
    assert_eq!(report.tests_run(), 0);
    assert!(!report.passed());
}

#[test]
fn a_bad_option_is_a_failed_build_not_a_skip() {
    let lambert: std::sync::Arc<dyn brdf::Brdf> =
        std::sync::Arc::from(brdf::parse_spec("lambert").unwrap());
    let options = brdf_sampling::SetOptions::default();
    let bad = samplers::DirectionRequest::new(lambert, &options).with_baselines(
        baselines::BaselineOptions {
            lobe: baselines::LobeOptions {
                slices: 0,
                ..baselines::LobeOptions::default()
            },
            ..baselines::BaselineOptions::default()
        },
    );
    let err = samplers::build_direction("lobe-sphere", &bad).unwrap_err();
    assert!(
        !matches!(err, samplers::RegistryError::NotApplicable(_)),
        "{err}"
    );
}

#[test]
fn quadtree_disc_skips_brdfs_unbounded_at_the_horizon() {
    let report = run_quick(
        &["ward-original", "lambert"],
        "quadtree-disc",
        &[45.0],
        20_000,
    );
    let skipped = skipped(&report);
    assert_eq!(skipped.len(), 1, "ward-original at 45°");
    assert!(skipped[0].brdf == "ward-original" && skipped[0].passed);
    assert!(
        skipped[0].detail.contains("grows without bound"),
        "{}",
        skipped[0].detail
    );
    // lambert is bounded: it is really tested.
    assert!(really_tested(&report, "lambert"));
    for t in report.failures() {
        eprintln!(
            "FAILED {} {} {:?} {} {}",
            t.sampler, t.brdf, t.theta_o, t.test, t.detail
        );
    }
    assert!(report.passed());
}
