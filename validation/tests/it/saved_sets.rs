//! `ValidateConfig::sets`: a set saved by `build --out` is validated with the BRDF of its
//! stored spec; a bad file is a typed error before any work.

use std::sync::Arc;

use brdf_sampling::SetOptions;
use samplers::DirectionRequest;
use validation::{ValidateConfig, ValidationError, run};

#[test]
fn a_saved_set_is_validated_with_its_own_brdf() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phong.set");
    let brdf: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec("phong:n=30").unwrap());
    let options = SetOptions {
        slices: 6,
        ..SetOptions::default()
    };
    let request = DirectionRequest::new(brdf, &options).with_spec("phong:n=30");
    let built = samplers::build_direction("adaptive-paper", &request).unwrap();
    std::fs::write(&path, built.set.unwrap().to_bytes()).unwrap();

    let config = ValidateConfig {
        sets: vec![path],
        theta_o: vec![20.0, 70.0],
        samples: Some(20_000),
        ..ValidateConfig::quick()
    };
    let report = run(&config, &|_| {}).unwrap();
    assert!(!report.tests.is_empty());
    for t in &report.tests {
        assert_eq!(t.sampler, "adaptive-paper (set phong.set)");
        assert_eq!(t.brdf, "phong:n=30");
        assert!(t.passed, "{t:?}");
    }
    let angles: std::collections::BTreeSet<String> = report
        .tests
        .iter()
        .map(|t| format!("{:?}", t.theta_o))
        .collect();
    assert_eq!(angles.len(), 2);
}

#[test]
fn a_bad_set_file_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("garbage.set");
    std::fs::write(&path, b"not a set").unwrap();
    for p in [path, dir.path().join("missing.set")] {
        let config = ValidateConfig {
            sets: vec![p],
            ..ValidateConfig::quick()
        };
        match run(&config, &|_| {}) {
            Err(ValidationError::Set { .. }) => {}
            other => panic!("{:?}", other.map(|r| r.tests.len())),
        }
    }
}
