//! End-to-end tests of `brdf-lab product`: bad input exits 2 with the reason before any work;
//! a small run writes the JSON and CSV of design.md §5.

use std::process::{Command, Output};

fn brdf_lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(args)
        .output()
        .expect("run brdf-lab")
}

/// Exit code 2, one line on stderr containing `needle`, no panic.
fn assert_input_error(args: &[&str], needle: &str) {
    let o = brdf_lab(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

const BASE: [&str; 6] = ["product", "--brdf", "lambert", "--theta-o", "30", "-n=1000"];

/// Small SRBF fits (2 slices of 8 rows, 2 lobes; a 4-lobe map fit 16 wide) for fast runs,
/// with the cosine BRDF sampler and the map's CDF light sampler.
const SMALL_SRBF: [&str; 14] = [
    "--srbf-slices",
    "2",
    "--srbf-fit-rows",
    "8",
    "--srbf-lobes",
    "2",
    "--srbf-map-lobes",
    "4",
    "--srbf-map-fit-width",
    "16",
    "--brdf-sampler",
    "cosine",
    "--light-sampler",
    "envmap-cdf",
];

fn with(extra: &[&str]) -> Vec<String> {
    BASE.iter().chain(extra).map(|s| s.to_string()).collect()
}

fn run_input_error(extra: &[&str], needle: &str) {
    let args = with(extra);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    assert_input_error(&refs, needle);
}

#[test]
fn bad_input_is_exit_2_with_the_reason() {
    run_input_error(&["--normal", "0,0,0"], "normal");
    run_input_error(&["--srbf-lobes", "0"], "lobe count must be at least 1");
    run_input_error(&["--srbf-map-lobes", "0"], "map lobe count");
    run_input_error(&["--srbf-lambda", "0,100"], "bandwidth bounds");
    run_input_error(&["--srbf-map-lambda", "-1,100"], "bandwidth bounds");
    run_input_error(&["--srbf-defensive", "1"], "defensive share");
    let dir = tempfile::tempdir().unwrap();
    let black = dir.path().join("black.pfm");
    let mut bytes = b"PF\n2 1\n-1.0\n".to_vec();
    bytes.extend(std::iter::repeat_n(0u8, 2 * 3 * 4));
    std::fs::write(&black, bytes).unwrap();
    run_input_error(&["--map", black.to_str().unwrap()], "black");
}

/// [`SMALL_SRBF`] with a small reference: a run of seconds.
fn small_fits() -> Vec<&'static str> {
    [&SMALL_SRBF[..], &["--reference-samples", "20000"]].concat()
}

#[test]
fn small_run_writes_json_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("p.json");
    let csv = dir.path().join("p.csv");
    let mut extra = vec!["--normal", "0.2,-0.1,1"];
    extra.extend(small_fits());
    extra.extend([
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let args = with(&extra);
    let doc = run_for_json(&args.iter().map(String::as_str).collect::<Vec<_>>(), &json);
    assert!(doc["reference"]["estimate"].as_f64().unwrap() > 0.0);
    assert!(doc["reference"]["std_err"].as_f64().unwrap() > 0.0);
    let estimators = doc["estimators"].as_array().unwrap();
    estimator_names(
        &doc,
        &[
            "srbf-product",
            "brdf:cosine",
            "light:envmap-cdf",
            "mis-balance:cosine+envmap-cdf",
            "mis-power:cosine+envmap-cdf",
        ],
    );
    for e in estimators {
        for key in [
            "estimate",
            "std_err",
            "seconds",
            "reference",
            "reference_std_err",
            "variance_time",
        ] {
            assert!(e[key].as_f64().is_some_and(f64::is_finite), "{key} in {e}");
        }
    }
    let table = std::fs::read_to_string(&csv).unwrap();
    assert!(table.starts_with("estimator,estimate,std_err,"));
    assert_eq!(table.lines().count(), 1 + estimators.len());
}

/// A `w × h` PFM of radiance `base` with one pixel `(x, y)` (row 0 at the top) of `hot`.
fn hot_pixel_pfm(path: &std::path::Path, w: usize, h: usize, (x, y): (usize, usize), hot: f32) {
    let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for row in (0..h).rev() {
        for col in 0..w {
            let v: f32 = if (col, row) == (x, y) { hot } else { 0.1 };
            for _ in 0..3 {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn heavy_tailed_estimators_get_a_warning_instead_of_a_bare_z() {
    // One pixel 1000 times brighter than the rest, holding a third of the map's power: cosine
    // sampling hits it about 6 times in 4000 draws, each hit holding a large share of the
    // variance (flagged); light sampling under Lambert has weights f·cos·Φ spread over
    // thousands of values (not flagged).
    let dir = tempfile::tempdir().unwrap();
    let map = dir.path().join("hot.pfm");
    hot_pixel_pfm(&map, 64, 32, (10, 8), 100.0);
    let json = dir.path().join("h.json");
    let args = [
        "product",
        "--brdf",
        "lambert",
        "--theta-o",
        "30",
        "-n",
        "4000",
        "--map",
        map.to_str().unwrap(),
    ];
    let rest = [
        "--reference-samples",
        "200000",
        "--json",
        json.to_str().unwrap(),
    ];
    let o = brdf_lab(&[&args[..], &SMALL_SRBF, &rest].concat());
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let row = |name: &str| {
        doc["estimators"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["estimator"] == name)
            .unwrap_or_else(|| panic!("{name} missing"))
            .clone()
    };
    let cosine = row("brdf:cosine");
    assert_eq!(cosine["heavy_tailed"], true, "{cosine}");
    assert!(cosine["tail_share"].as_f64().unwrap() > 0.05, "{cosine}");
    assert!(
        cosine["warning"]
            .as_str()
            .unwrap()
            .starts_with("heavy tail")
    );
    let line = out.lines().find(|l| l.starts_with("brdf:cosine ")).unwrap();
    assert!(line.contains(" heavy "), "{line}");
    assert!(
        err.contains("brdf-lab: warning: brdf:cosine: heavy tail"),
        "{err}"
    );
    let light = row("light:envmap-cdf");
    assert_eq!(light["heavy_tailed"], false, "{light}");
    assert!(light["warning"].is_null());
}

#[test]
fn product_set_adds_a_saved_set_as_a_brdf_sampler() {
    let dir = tempfile::tempdir().unwrap();
    let set = crate::bench::saved_set(dir.path(), "l.set", "lambert", &["--slices", "1"]);
    let json = dir.path().join("p.json");
    // No --brdf: the set's stored spec.
    let mut args = vec![
        "product",
        "--theta-o",
        "30",
        "-n=1000",
        "--set",
        set.to_str().unwrap(),
    ];
    args.extend(small_fits());
    args.extend(["--json", json.to_str().unwrap()]);
    let doc = run_for_json(&args, &json);
    assert_eq!(doc["brdf"], "lambert");
    let rows = doc["estimators"].as_array().unwrap();
    let names = estimator_names(
        &doc,
        &[
            "brdf:cosine",
            "brdf:adaptive@l.set",
            "mis-balance:adaptive@l.set+envmap-cdf",
        ],
    );
    // MIS of the loaded set with the map sampler agrees with the reference (BRDF sampling alone
    // misses the sky's sun at 1000 samples, as `brdf:cosine` does).
    let row = &rows[names
        .iter()
        .position(|n| *n == "mis-balance:adaptive@l.set+envmap-cdf")
        .unwrap()];
    assert!(row["z"].as_f64().unwrap().abs() < 4.0, "{row}");
    // A set built for another BRDF than --brdf is refused before any work.
    assert_input_error(
        &[
            "product",
            "--brdf",
            "phong",
            "--theta-o",
            "30",
            "-n=1000",
            "--set",
            set.to_str().unwrap(),
        ],
        "built for --brdf lambert",
    );
}

/// Runs `args` (exit 0 required) and reads the JSON document it wrote to `json`.
fn run_for_json(args: &[&str], json: &std::path::Path) -> serde_json::Value {
    let o = brdf_lab(args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// The estimator names of a `product --json` document, in its order; each of `expected` must be
/// among them.
fn estimator_names<'a>(doc: &'a serde_json::Value, expected: &[&str]) -> Vec<&'a str> {
    let names: Vec<&str> = doc["estimators"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["estimator"].as_str().unwrap())
        .collect();
    for expected in expected {
        assert!(names.contains(expected), "{names:?}");
    }
    names
}
