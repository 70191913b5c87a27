//! End-to-end tests of `brdf-lab validate --shard K/N` and `validate merge`: three shards run
//! as separate processes merge to the single run's report and verdict; bad merges are refused.

use std::path::Path;
use std::process::{Command, Output};

fn brdf_lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(args)
        .output()
        .expect("run brdf-lab")
}

/// A small validation: one BRDF sampler on one BRDF at three angles (3 cases) and the planar
/// grid sampler (1 case), 5000 samples per case: about 1.5 CPU-s.
const SMALL: &[&str] = &[
    "validate",
    "--quick",
    "--sampler",
    "cosine",
    "--sampler",
    "grid-cdf",
    "--brdf",
    "lambert",
    "--theta-o",
    "0",
    "--theta-o",
    "30",
    "--theta-o",
    "60",
    "--samples",
    "5000",
];

fn run(base: &[&str], extra: &[&str]) -> Output {
    let mut args = base.to_vec();
    args.extend_from_slice(extra);
    brdf_lab(&args)
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("read json")).expect("parse json")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `base` whole and as `n` shards, and merges the shards; returns the exit codes of the
/// whole run and of the merge with their JSON reports.
fn whole_and_merged(
    dir: &Path,
    base: &[&str],
    n: usize,
) -> ((i32, serde_json::Value), (i32, serde_json::Value)) {
    let whole = dir.join("whole.json");
    let o = run(base, &["--json", path(&whole)]);
    let whole_code = o.status.code().expect("exit code");
    let mut parts = Vec::new();
    for k in 1..=n {
        let part = dir.join(format!("part{k}.json"));
        let shard = format!("{k}/{n}");
        let o = run(base, &["--shard", &shard, "--json", path(&part)]);
        // A shard's verdict is the merge's: it exits 0 once its part is written.
        assert_eq!(o.status.code(), Some(0), "shard {shard}: {}", stderr(&o));
        let v = json(&part);
        assert_eq!(v["shard"]["index"], k);
        assert_eq!(v["shard"]["count"], n);
        parts.push(part);
    }
    let merged = dir.join("merged.json");
    let report = dir.join("merged.md");
    let mut args = vec!["validate", "merge"];
    // Any order.
    args.extend(parts.iter().rev().map(|p| path(p)));
    args.extend(["--json", path(&merged), "--report", path(&report)]);
    let o = brdf_lab(&args);
    let merge_code = o.status.code().expect("exit code");
    assert!(
        std::fs::read_to_string(&report)
            .expect("merged markdown")
            .contains("# brdf-lab validate"),
        "{}",
        stderr(&o)
    );
    ((whole_code, json(&whole)), (merge_code, json(&merged)))
}

fn sorted_tests(v: &serde_json::Value) -> Vec<String> {
    let mut t: Vec<String> = v["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .map(ToString::to_string)
        .collect();
    t.sort();
    t
}

#[test]
fn three_shards_in_separate_processes_merge_to_the_single_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ((whole_code, whole), (merge_code, merged)) = whole_and_merged(dir.path(), SMALL, 3);
    assert_eq!(whole_code, merge_code);
    assert_eq!(whole_code, 0, "the small run passes: {whole}");
    // Every record (statistic, p-value, verdict), and the run's verdict, m and Šidák level.
    assert_eq!(sorted_tests(&whole), sorted_tests(&merged));
    assert_eq!(whole["tests"].as_array().map(Vec::len), Some(40));
    for key in ["passed", "m", "per_test_level", "alpha", "seed", "samples"] {
        assert_eq!(whole[key], merged[key], "{key}");
    }
    // In fact the whole document, in the same order.
    assert_eq!(whole, merged);
    assert!(merged.get("shard").is_none());
}

#[test]
fn a_failing_run_merges_to_the_same_failures_and_exit_1() {
    // At α = 0.99 the Šidák level over the run's 24 p-valued tests is ≈ 0.17 and some tests
    // fail; each shard alone judges its ≈ 8 tests at ≈ 0.44 and fails more of them, so the
    // merge must re-judge the union to find the single run's failures.
    let mut base = SMALL.to_vec();
    base.extend(["--alpha", "0.99"]);
    let dir = tempfile::tempdir().expect("tempdir");
    let ((whole_code, whole), (merge_code, merged)) = whole_and_merged(dir.path(), &base, 3);
    assert_eq!((whole_code, merge_code), (1, 1));
    assert_eq!(whole, merged);
    let failed = |v: &serde_json::Value| {
        v["tests"]
            .as_array()
            .expect("tests")
            .iter()
            .filter(|t| t["passed"] == false)
            .count()
    };
    let provisional: usize = (1..=3)
        .map(|k| failed(&json(&dir.path().join(format!("part{k}.json")))))
        .sum();
    assert!(failed(&merged) > 0 && provisional > failed(&merged));
}

#[test]
fn a_run_that_tested_nothing_merges_to_exit_3() {
    // rgl-native applies to RGL files only: every case is skipped.
    let base = &[
        "validate",
        "--quick",
        "--sampler",
        "rgl-native",
        "--brdf",
        "lambert",
        "--theta-o",
        "0",
        "--theta-o",
        "45",
        "--samples",
        "5000",
    ];
    let dir = tempfile::tempdir().expect("tempdir");
    let ((whole_code, whole), (merge_code, merged)) = whole_and_merged(dir.path(), base, 2);
    assert_eq!((whole_code, merge_code), (3, 3));
    assert_eq!(whole, merged);
}

#[test]
fn merging_refuses_missing_duplicate_and_foreign_shards() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = |name: &str| dir.path().join(name);
    // Cheap parts: the grid sampler alone (one case) in 2 shards; shard 2 is empty.
    let base = &[
        "validate",
        "--quick",
        "--sampler",
        "grid-cdf",
        "--samples",
        "2000",
    ];
    for (k, file) in [(1, "a1.json"), (2, "a2.json")] {
        let o = run(
            base,
            &["--shard", &format!("{k}/2"), "--json", path(&p(file))],
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let o = run(
        base,
        &[
            "--seed",
            "2",
            "--shard",
            "2/2",
            "--json",
            path(&p("b2.json")),
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let whole = p("whole.json");
    assert!(run(base, &["--json", path(&whole)]).status.success());

    let merge = |parts: &[&str]| {
        let mut args = vec!["validate", "merge"];
        let parts: Vec<String> = parts.iter().map(|f| path(&p(f)).to_owned()).collect();
        args.extend(parts.iter().map(String::as_str));
        let out = p("out.json");
        args.extend(["--json", path(&out)]);
        let o = brdf_lab(&args);
        (o.status.code(), stderr(&o), out.exists())
    };
    let (code, err, written) = merge(&["a1.json"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("missing shard(s): 2/2"), "{err}");
    assert!(!written, "a refused merge writes nothing");
    let (code, err, _) = merge(&["a1.json", "a1.json"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("given twice"), "{err}");
    let (code, err, _) = merge(&["a1.json", "b2.json"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("another configuration"), "{err}");
    let (code, err, _) = merge(&["whole.json"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("not a shard"), "{err}");
    let (code, err, written) = merge(&["a2.json", "a1.json"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(written);
    assert_eq!(json(&p("out.json")), json(&whole));

    // A shard needs --json, and K/N with 1 ≤ K ≤ N.
    let o = run(base, &["--shard", "1/2"]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(base, &["--shard", "3/2", "--json", path(&p("x.json"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--shard 3/2"), "{}", stderr(&o));
}
