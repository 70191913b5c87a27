//! End-to-end test of `brdf-lab bench`: several samplers in one run, the JSON contract
//! (`sampler`, `ns_per_sample`, `evals_per_sample`, `samples`, `threads`, `queries`), counts
//! that do not depend on the thread count, and bad input as exit 2 with the reason.

use std::process::{Command, Output};

fn brdf_lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(args)
        .output()
        .expect("run brdf-lab")
}

fn bench_json(threads: &str, queries: &str) -> Vec<serde_json::Value> {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let o = brdf_lab(&[
        "bench",
        "--brdf",
        "phong:n=40",
        "--sampler",
        "cosine",
        "analytic",
        "-n",
        "20000",
        "--repeat",
        "2",
        "--threads",
        threads,
        "--queries",
        queries,
        "--json",
        json.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("cosine") && out.contains("analytic"), "{out}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    v.as_array().expect("a list").clone()
}

#[test]
fn bench_writes_one_record_per_sampler_and_counts_do_not_depend_on_threads() {
    let one = bench_json("1", "random");
    let two = bench_json("2", "random");
    assert_eq!(one.len(), 2);
    for (a, b) in one.iter().zip(&two) {
        for key in [
            "sampler",
            "ns_per_sample",
            "evals_per_sample",
            "samples",
            "threads",
            "queries",
        ] {
            assert!(a.get(key).is_some(), "{key} missing in {a}");
        }
        assert_eq!(a["sampler"], b["sampler"]);
        assert_eq!(a["samples"], 20000);
        assert_eq!(a["queries"], "random");
        assert!(a["ns_per_sample"].as_f64().unwrap() > 0.0);
        // Evaluations are counted, not timed: the same on 1 and 2 threads.
        assert_eq!(a["evals_per_sample"], b["evals_per_sample"]);
        // The same samples whatever the thread count (sums up to rounding).
        let (ma, mb) = (
            a["mean_weight"].as_f64().unwrap(),
            b["mean_weight"].as_f64().unwrap(),
        );
        assert!((ma - mb).abs() <= 1e-12 * ma.abs(), "{ma} vs {mb}");
    }
    assert_eq!(one[0]["threads"], 1);
    assert_eq!(two[0]["threads"], 2);
    // Cosine sampling needs exactly the estimator's evaluation above the horizon.
    let cos_evals = one[0]["evals_per_sample"].as_f64().unwrap();
    assert!(cos_evals > 0.9 && cos_evals <= 1.0, "{cos_evals}");
    let fixed = bench_json("1", "fixed");
    assert_eq!(fixed[0]["queries"], "fixed");
}

#[test]
fn bench_bad_input_is_exit_2_with_the_reason() {
    for (args, needle) in [
        (
            vec!["bench", "--brdf", "phong", "--sampler", "nope"],
            "nope",
        ),
        (
            vec!["bench", "--brdf", "nope", "--sampler", "cosine"],
            "nope",
        ),
        (
            vec![
                "bench",
                "--brdf",
                "phong",
                "--sampler",
                "cosine",
                "--queries",
                "fixed",
                "--theta-o",
                "95",
            ],
            "theta-o",
        ),
    ] {
        let o = brdf_lab(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
