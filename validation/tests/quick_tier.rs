//! The CI quick tier: every registered sampler passes every test, every mutant is caught (the
//! report says by which tests) and every mutant's unbroken control passes.

use std::sync::atomic::{AtomicUsize, Ordering};

use samplers::samplers;
use validation::{ProgressEvent, ValidateConfig, mutants, run};

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "heavy: run with `cargo test --release` (CI does)"
)]
fn quick_tier_passes_for_every_sampler_and_catches_every_mutant() {
    let started = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let config = ValidateConfig {
        mutants: true,
        ..ValidateConfig::quick()
    };
    let report = run(&config, &|e| match e {
        ProgressEvent::Started { total } => started.store(total, Ordering::SeqCst),
        ProgressEvent::Finished { .. } => {
            finished.fetch_add(1, Ordering::SeqCst);
        }
    })
    .expect("the quick tier's configuration is valid");
    assert!(started.load(Ordering::SeqCst) > 0);
    assert_eq!(
        started.load(Ordering::SeqCst),
        finished.load(Ordering::SeqCst)
    );

    for t in report.failures() {
        eprintln!(
            "FAILED {} / {} / {:?}: {} = {} (p = {:?}): {}",
            t.sampler, t.brdf, t.theta_o, t.test, t.statistic, t.p_value, t.detail
        );
    }
    // Format-specific samplers (rgl-native) run when a quick-tier BRDF is of their format.
    let quick: Vec<std::sync::Arc<dyn brdf::Brdf>> = validation::QUICK_BRDFS
        .iter()
        .map(|s| std::sync::Arc::from(brdf::parse_spec(s).expect("quick spec")))
        .collect();
    for e in samplers()
        .iter()
        .filter(|e| !e.is_direction() || quick.iter().any(|b| e.applicability(b.as_ref()).is_ok()))
    {
        let ran = |t: &&validation::TestRecord| t.sampler == e.name && t.test != "skipped";
        assert!(
            report.tests.iter().any(|t| t.sampler == e.name),
            "sampler {} is missing from the report",
            e.name
        );
        // Every registered sampler runs real tests.
        assert!(
            report.tests.iter().any(|t| ran(&t)),
            "sampler {} ran no test",
            e.name
        );
    }
    assert!(
        report.tests.iter().all(|t| t.passed),
        "a correct sampler failed the quick tier (see above)"
    );

    assert!(mutants().len() >= 6);
    assert_eq!(report.mutants.len(), mutants().len());
    for m in &report.mutants {
        eprintln!(
            "mutant {:<26} caught by {:?} (min p {:?}); control passes: {}",
            m.name, m.caught_by, m.min_p_value, m.control_passed
        );
        assert!(m.detected, "mutant {} was not caught", m.name);
        for name in &m.caught_by {
            assert!(m.tests.iter().any(|t| &t.test == name && !t.passed));
        }
        assert!(m.control_passed, "the control of mutant {} failed", m.name);
    }
    assert!(report.passed());
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).expect("valid JSON");
    assert_eq!(json["passed"], true);
    assert_eq!(
        json["mutants"].as_array().map(Vec::len),
        Some(mutants().len())
    );
}
