//! The CI quick tier as the README's test command runs it: every registered sampler passes
//! every test on the analytic BRDFs, every mutant is caught (the report says by which tests) and
//! every mutant's unbroken control passes.
//!
//! One run at `α = 0.005` (Šidák-corrected inside): the five analytic BRDFs of
//! [`validation::QUICK_BRDFS`] at every quick angle with the standalone samplers and the
//! mutants. The RGL fixture ([`validation::QUICK_RGL`]) is the slow part of the quick tier (its
//! references are computed at run time and its evaluation is slow: ≈ 90 CPU-s at one angle),
//! so CI runs it at every quick angle with the binary the tests built (`brdf-lab validate
//! --quick --brdf rgl:… --theta-o 0 --theta-o 45 --theta-o 80` in `.ci/run`): the union of the
//! two is the whole quick tier (docs/validation.md, "What the test command runs and what moved
//! to validate runs").

use std::sync::atomic::{AtomicUsize, Ordering};

use samplers::samplers;
use validation::{ProgressEvent, QUICK_BRDFS, QUICK_RGL, ValidateConfig, mutants, run};

/// Significance level of the run (the level it had when it was one of two runs; CI's RGL run
/// uses the CLI's default).
const ALPHA: f64 = 0.005;

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "heavy: run with `cargo test --release` (CI does)"
)]
fn quick_tier_passes_for_every_sampler_and_catches_every_mutant() {
    let started = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let analytic = ValidateConfig {
        brdfs: QUICK_BRDFS
            .iter()
            .filter(|s| **s != QUICK_RGL)
            .map(|s| (*s).to_owned())
            .collect(),
        mutants: true,
        alpha: ALPHA,
        ..ValidateConfig::quick()
    };
    assert_eq!(analytic.brdfs.len(), QUICK_BRDFS.len() - 1);
    let report = run(&analytic, &|e| match e {
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
    // Format-specific samplers (rgl-native) are checked by CI's RGL run.
    let quick: Vec<std::sync::Arc<dyn brdf::Brdf>> = QUICK_BRDFS
        .iter()
        .filter(|s| **s != QUICK_RGL)
        .map(|s| std::sync::Arc::from(brdf::parse_spec(s).expect("quick spec")))
        .collect();
    for e in samplers()
        .iter()
        .filter(|e| !e.is_direction() || quick.iter().any(|b| e.applicability(b.as_ref()).is_ok()))
    {
        let tests = || report.tests.iter();
        let ran = |t: &validation::TestRecord| t.sampler == e.name && t.test != "skipped";
        assert!(
            tests().any(|t| t.sampler == e.name),
            "sampler {} is missing from the reports",
            e.name
        );
        // Every registered sampler runs real tests.
        assert!(tests().any(ran), "sampler {} ran no test", e.name);
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
