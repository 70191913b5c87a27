//! The report: JSON schema of design.md §5, markdown, determinism across thread counts.

use serde_json::Value;
use validation::{ValidateConfig, run};

fn small(mutants: bool) -> ValidateConfig {
    ValidateConfig {
        samplers: vec![
            "adaptive".into(),
            "quadtree-disc".into(),
            "envmap-cdf".into(),
        ],
        brdfs: vec!["phong:n=50".into()],
        theta_o: vec![45.0],
        samples: Some(5_000),
        mutants,
        ..ValidateConfig::quick()
    }
}

#[test]
fn json_has_the_design_schema() {
    let report = run(&small(true), &|_| {}).expect("valid config");
    let v: Value = serde_json::from_str(&report.to_json()).expect("valid JSON");
    assert_eq!(v["alpha"].as_f64(), Some(0.01));
    assert!(v["passed"].is_boolean());
    let tests = v["tests"].as_array().expect("tests array");
    assert!(!tests.is_empty());
    for t in tests {
        for key in ["brdf", "sampler", "test"] {
            assert!(t[key].is_string(), "{key} in {t}");
        }
        assert!(t["passed"].is_boolean());
        assert!(t["theta_o"].is_number() || t["theta_o"].is_null());
        assert!(t["statistic"].is_number() || t["statistic"].is_null());
        assert!(t["p_value"].is_number() || t["p_value"].is_null());
    }
    // BRDF cases carry their angle; standalone samplers (environment maps) have none.
    assert!(
        tests
            .iter()
            .any(|t| t["sampler"] == "adaptive" && t["theta_o"] == 45.0)
    );
    assert!(
        tests
            .iter()
            .any(|t| t["sampler"] == "envmap-cdf" && t["theta_o"].is_null())
    );
    assert!(
        tests
            .iter()
            .any(|t| t["test"] == "chi-square" && t["p_value"].is_number())
    );
    assert!(
        tests
            .iter()
            .any(|t| t["test"] == "normalisation" && t["p_value"].is_null())
    );
    let mutants = v["mutants"].as_array().expect("mutants array");
    assert_eq!(mutants.len(), validation::mutants().len());
    for m in mutants {
        assert!(m["name"].is_string() && m["detected"].is_boolean());
        assert!(m["caught_by"].is_array());
    }
    let none = run(&small(false), &|_| {}).expect("valid config");
    let v: Value = serde_json::from_str(&none.to_json()).expect("valid JSON");
    assert_eq!(v["mutants"].as_array().map(Vec::len), Some(0));
}

#[test]
fn markdown_lists_every_test_with_statistic_and_p_value() {
    let report = run(&small(false), &|_| {}).expect("valid config");
    let md = report.to_markdown();
    assert!(md.contains("| sampler | target | θo | test | statistic | p-value | result |"));
    let rows = md.lines().filter(|l| l.starts_with("| adaptive |")).count();
    assert_eq!(
        rows,
        report
            .tests
            .iter()
            .filter(|t| t.sampler == "adaptive")
            .count()
    );
    assert!(md.contains(if report.passed() { "PASSED" } else { "FAILED" }));
}

#[test]
fn same_seed_same_report_on_one_and_two_threads() {
    let config = small(false);
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| run(&config, &|_| {}).expect("valid config").to_json())
    };
    let one = on(1);
    assert_eq!(one, on(2));
    let other = run(
        &ValidateConfig {
            seed: 2,
            ..config.clone()
        },
        &|_| {},
    )
    .expect("valid config")
    .to_json();
    assert_ne!(one, other, "the seed must matter");
}
