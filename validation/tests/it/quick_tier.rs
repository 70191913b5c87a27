//! The CI quick tier as the README's test command runs it: every registered sampler passes
//! every test, every mutant is caught (the report says by which tests) and every mutant's
//! unbroken control passes.
//!
//! Two runs at `α = 0.005` each (Bonferroni: 0.01 for the test as a whole, each run Šidák-
//! corrected inside): the five analytic BRDFs of [`validation::QUICK_BRDFS`] at every quick
//! angle with the standalone samplers and the mutants, and the RGL fixture
//! ([`validation::QUICK_RGL`]) at [`RGL_THETA_O`] only, for the BRDF samplers. The fixture at
//! the tier's other angles costs ≈ 2.5 times the rest of the tier (its references are computed
//! at run time and its evaluation is slow); CI runs it there with the binary the tests built
//! (`brdf-lab validate --quick --brdf rgl:… --theta-o 0 --theta-o 80` in `.ci/run`), so the
//! union of the two is the whole quick tier (docs/validation.md, "What the test command runs
//! and what moved to validate runs").

use std::sync::atomic::{AtomicUsize, Ordering};

use samplers::samplers;
use validation::{ProgressEvent, QUICK_BRDFS, QUICK_RGL, ValidateConfig, mutants, run, uses_brdf};

/// The one angle of the quick tier at which this test runs the RGL fixture.
const RGL_THETA_O: f64 = 45.0;

/// Significance level of each of the two runs.
const ALPHA_PER_RUN: f64 = 0.005;

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
        alpha: ALPHA_PER_RUN,
        ..ValidateConfig::quick()
    };
    assert_eq!(analytic.brdfs.len(), QUICK_BRDFS.len() - 1);
    let rgl = ValidateConfig {
        brdfs: vec![QUICK_RGL.to_owned()],
        samplers: samplers()
            .iter()
            .filter(|e| uses_brdf(e))
            .map(|e| e.name.to_owned())
            .collect(),
        theta_o: vec![RGL_THETA_O],
        alpha: ALPHA_PER_RUN,
        ..ValidateConfig::quick()
    };
    let mut reports = Vec::new();
    for config in [&analytic, &rgl] {
        started.store(0, Ordering::SeqCst);
        finished.store(0, Ordering::SeqCst);
        let report = run(config, &|e| match e {
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
        reports.push(report);
    }
    let [report, rgl_report] = <[_; 2]>::try_from(reports).expect("two runs");
    assert!(rgl_report.mutants.is_empty());

    for t in report.failures().chain(rgl_report.failures()) {
        eprintln!(
            "FAILED {} / {} / {:?}: {} = {} (p = {:?}): {}",
            t.sampler, t.brdf, t.theta_o, t.test, t.statistic, t.p_value, t.detail
        );
    }
    // Format-specific samplers (rgl-native) run when a quick-tier BRDF is of their format.
    let quick: Vec<std::sync::Arc<dyn brdf::Brdf>> = QUICK_BRDFS
        .iter()
        .map(|s| std::sync::Arc::from(brdf::parse_spec(s).expect("quick spec")))
        .collect();
    for e in samplers()
        .iter()
        .filter(|e| !e.is_direction() || quick.iter().any(|b| e.applicability(b.as_ref()).is_ok()))
    {
        let tests = || report.tests.iter().chain(&rgl_report.tests);
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
    assert!(
        rgl_report.passed(),
        "a sampler failed on the RGL fixture (see above)"
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
