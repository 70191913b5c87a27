//! End-to-end tests of `brdf-lab study` and `study merge`: outputs, shards, bad input.

use std::path::Path;
use std::process::{Command, Output};

fn brdf_lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(args)
        .output()
        .expect("run brdf-lab")
}

/// A tiny study: 2 samplers, 1 BRDF, 2 angles, small N grid.
fn tiny(out: &Path, extra: &[&str]) -> Output {
    let out = out.to_str().expect("utf-8 path");
    let mut args = vec![
        "study",
        "--sampler",
        "cosine",
        "--sampler",
        "adaptive",
        "--brdf",
        "phong:n=20",
        "--theta-o",
        "30",
        "--theta-o",
        "60",
        "--light",
        "area",
        "--n-grid",
        "1,16,64",
        "--repetitions",
        "4",
        "--spp",
        "4",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    brdf_lab(&args)
}

/// `results.json` without the `timing` objects and what depends on them or on the run
/// (`rankings`, `runs`).
fn numbers(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("results.json")).expect("results.json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    for c in v["cells"].as_array_mut().expect("cells") {
        c["timing"] = serde_json::Value::Null;
    }
    assert_eq!(
        v["rankings"].as_array().map(Vec::len),
        Some(2),
        "one ranking per θo"
    );
    v["rankings"] = serde_json::Value::Null;
    v["runs"] = serde_json::Value::Null;
    v
}

#[test]
fn a_study_writes_its_outputs_and_shards_merge_to_the_same_numbers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let whole = dir.path().join("whole");
    let o = tiny(&whole, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "report.md",
        "results.csv",
        "results.json",
        "images/reference.png",
        "images/reference.pfm",
        "images/spheres-equal-samples.png",
        "plots/l0-b0-t30-error-vs-samples.png",
        "plots/l0-b0-t30-error-vs-samples.svg",
        "plots/l0-b0-t60-efficiency.png",
    ] {
        assert!(whole.join(f).is_file(), "{f} missing");
    }
    let report = std::fs::read_to_string(whole.join("report.md")).expect("report");
    for needle in [
        "## Outcome",
        "†",
        "plots/l0-b0-t30-error-vs-time.png",
        "## Sphere images",
    ] {
        assert!(report.contains(needle), "report lacks {needle}");
    }
    let shards: Vec<_> = (1..=3).map(|k| dir.path().join(format!("s{k}"))).collect();
    for (k, s) in shards.iter().enumerate() {
        let o = tiny(s, &["--shard", &format!("{}/3", k + 1)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let merged = dir.path().join("merged");
    // An existing output directory: its other files are kept, no temporary directory is left.
    std::fs::create_dir(&merged).expect("mkdir");
    std::fs::write(merged.join("keep.txt"), "mine").expect("write");
    let mut args = vec!["study", "merge"];
    let names: Vec<String> = shards.iter().map(|s| s.display().to_string()).collect();
    args.extend(names.iter().map(String::as_str));
    let merged_str = merged.display().to_string();
    args.extend(["--out", &merged_str, "--spp", "4"]);
    let o = brdf_lab(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(numbers(&merged), numbers(&whole));
    assert!(merged.join("images/reference.png").is_file());
    assert!(merged.join("keep.txt").is_file());
    for d in [dir.path(), merged.as_path(), whole.as_path()] {
        let stray: Vec<_> = std::fs::read_dir(d)
            .expect("dir")
            .flatten()
            .filter(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".brdf-lab-study-")
            })
            .collect();
        assert!(stray.is_empty(), "{stray:?}");
    }
    // A missing shard is refused, and leaves no output directory.
    let partial = dir.path().join("partial").display().to_string();
    let o = brdf_lab(&["study", "merge", &names[0], &names[1], "--out", &partial]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing shards: 3/3"));
    assert!(
        !Path::new(&partial).exists(),
        "a failed merge left {partial}"
    );
}

#[test]
fn a_failed_merge_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x");
    let o = brdf_lab(&[
        "study",
        "merge",
        dir.path().join("nonexist").to_str().expect("path"),
        "--out",
        out.to_str().expect("path"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("nonexist/results.json"), "{err}");
    assert!(!out.exists(), "a failed merge created {}", out.display());
    // Nor a temporary directory beside it.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .flatten()
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn bad_input_exits_2_with_one_line_before_any_work() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("o");
    let file = dir.path().join("file");
    std::fs::write(&file, "x").expect("write");
    let out_s = out.display().to_string();
    for (args, needle) in [
        (vec!["--sampler", "nope"], "unknown sampler `nope`"),
        (vec!["--sampler", "envmap-cdf"], "not a direction sampler"),
        (vec!["--brdf", "nope"], "unknown BRDF model"),
        (vec!["--light", "moon"], "unknown light `moon`"),
        (
            vec!["--light", "envmap:/nonexistent.hdr"],
            "--light envmap:/nonexistent.hdr",
        ),
        (vec!["--n-grid", "4,2"], "strictly increasing"),
        (vec!["--theta-o", "95"], "not in [0°, 90°)"),
        (vec!["--shard", "4/3"], "--shard 4/3"),
    ] {
        let mut a = vec!["study"];
        a.extend(args.iter().copied());
        a.extend(["--out", &out_s]);
        let o = brdf_lab(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{a:?}: {err}");
        assert!(err.contains(needle), "{a:?}: {err}");
        assert!(!out.exists(), "{a:?} created the output directory");
    }
    // An output path that is a file: refused before any work.
    let o = brdf_lab(&["study", "--out", &file.display().to_string()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("not a directory"), "{err}");
}
