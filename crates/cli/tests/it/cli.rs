//! End-to-end tests of the `brdf-lab` binary: the CLI contract of the README (columns, pdf
//! conventions, exit codes, one-line errors, atomic outputs).

use std::path::Path;
use std::process::{Command, Output};

fn brdf_lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(args)
        .output()
        .expect("run brdf-lab")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Bad usage or input: exit code 2 and exactly one line on stderr, never a panic.
fn assert_input_error(args: &[&str], needle: &str) {
    let o = brdf_lab(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: not one line: {err}"
    );
    assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

/// A usage error caught by clap: exit code 2 and clap's full message (several lines).
fn assert_usage_error(args: &[&str], needle: &str) {
    let o = brdf_lab(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    assert!(err.contains("--help"), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

fn read_csv(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("csv");
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().expect("number"))
                .collect()
        })
        .collect();
    (header, rows)
}

#[test]
fn bad_inputs_exit_2_with_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let truncated = dir.path().join("truncated.hdr");
    std::fs::write(
        &truncated,
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n\x02\x02",
    )
    .expect("write");
    let garbage = dir.path().join("garbage.pfm");
    std::fs::write(&garbage, b"PF\n3 x\n-1.0\n").expect("write");
    let t = truncated.to_str().expect("path");
    let g = garbage.to_str().expect("path");
    assert_input_error(&["envmap", "-n", "10", "--map", t], "truncated.hdr");
    assert_input_error(&["envmap", "-n", "10", "--map", g], "garbage.pfm");
    assert_input_error(
        &["envmap", "-n", "10", "--map", "/no/such/map.hdr"],
        "map.hdr",
    );
    assert_input_error(&["envmap", "-n", "10", "--map", "map.png"], "map.png");
    assert_usage_error(&["envmap", "-n", "0"], "--samples");
    assert_usage_error(&["envmap", "-n", "10", "--n-max", "0.5"], "--n-max");
    assert_usage_error(&["envmap", "-n", "10", "--n-max", "NaN"], "--n-max");
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "phong:n=-3",
            "--theta-o",
            "30",
            "-n",
            "10",
        ],
        "phong",
    );
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "phong:q=1",
            "--theta-o",
            "30",
            "-n",
            "10",
        ],
        "valid keys",
    );
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "nosuchmodel",
            "--theta-o",
            "30",
            "-n",
            "10",
        ],
        "nosuchmodel",
    );
    assert_usage_error(
        &["sample", "--brdf", "lambert", "--theta-o", "95", "-n", "10"],
        "[0, 90)",
    );
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "lambert",
            "--theta-o",
            "30",
            "-n",
            "10",
            "--sampler",
            "x",
        ],
        "known",
    );
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "merl:/no/such.binary",
            "--theta-o",
            "30",
            "-n",
            "10",
        ],
        "such.binary",
    );
    assert_input_error(&["validate", "--quick", "--sampler", "nope"], "nope");
    // Lobe options out of range: exit 2 with the range.
    let lobe = |flag: &'static str, value: &'static str| {
        [
            "sample",
            "--brdf",
            "phong",
            "--theta-o",
            "30",
            "--sampler",
            "lobe-sphere",
            "-n",
            "5",
            flag,
            value,
        ]
    };
    assert_usage_error(
        &lobe("--lobe-exponent=-1", "--lobe-slices=4"),
        "[0, 1000000]",
    );
    assert_usage_error(&lobe("--lobe-exponent", "NaN"), "--lobe-exponent");
    assert_usage_error(&lobe("--lobe-slices", "0"), "1 ..= 1024");
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "oren-nayar",
            "--theta-o",
            "30",
            "--sampler",
            "analytic",
            "-n",
            "5",
        ],
        "has no analytic sampler",
    );
    // Every not-applicable pair is refused with the registry's one reason (sample, eval,
    // build and product all build through `SamplerEntry::build_direction`).
    assert_input_error(
        &[
            "sample",
            "--brdf",
            "phong",
            "--theta-o",
            "30",
            "--sampler",
            "rgl-native",
            "-n",
            "5",
        ],
        "does not apply to this BRDF: the rgl-native sampler needs an RGL material",
    );
    // Usage errors carry clap's full (multi-line) message; see usage_errors_show_clap_s_….
    assert_usage_error(&["nosuchcommand"], "nosuchcommand");
}

#[test]
fn envmap_csv_follows_the_contract_and_output_is_atomic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s.csv");
    let o = brdf_lab(&[
        "envmap",
        "-n",
        "5000",
        "--seed",
        "3",
        "--out",
        out.to_str().expect("path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(header, "u,v,pdf_uv,pdf_sa");
    assert_eq!(rows.len(), 5000);
    for r in &rows {
        let (u, v, pdf_uv, pdf_sa) = (r[0], r[1], r[2], r[3]);
        assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
        let expected =
            pdf_uv / (2.0 * std::f64::consts::PI.powi(2) * (std::f64::consts::PI * v).sin());
        assert!((pdf_sa - expected).abs() <= 1e-9 * expected, "{r:?}");
    }
    // Same seed, same samples; no temporary files left behind.
    let again = dir.path().join("t.csv");
    let o = brdf_lab(&[
        "envmap",
        "-n",
        "5000",
        "--seed",
        "3",
        "--out",
        again.to_str().expect("path"),
    ]);
    assert!(o.status.success());
    assert_eq!(
        std::fs::read(&out).expect("a"),
        std::fs::read(&again).expect("b")
    );
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 2);
    // A failing run does not replace an existing output.
    let o = brdf_lab(&[
        "envmap",
        "-n",
        "10",
        "--map",
        "/no/such.hdr",
        "--out",
        out.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(read_csv(&out).1.len(), 5000);
}

#[test]
fn eval_reports_the_pdf_that_sample_reported() {
    let dir = tempfile::tempdir().expect("tempdir");
    let samples = dir.path().join("s.csv");
    let evals = dir.path().join("e.csv");
    let common = [
        "--brdf",
        "phong:n=50,ks=0.7,kd=0.3",
        "--theta-o",
        "37",
        "--phi-o",
        "20",
        "--slices",
        "9",
    ];
    let mut args = vec![
        "sample",
        "-n",
        "3000",
        "--sampler",
        "adaptive",
        "--out",
        samples.to_str().expect("p"),
    ];
    args.extend(common);
    let o = brdf_lab(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut args = vec![
        "eval",
        "--sampler",
        "adaptive",
        "--dirs",
        samples.to_str().expect("p"),
    ];
    args.extend(["--out", evals.to_str().expect("p")]);
    args.extend(common);
    let o = brdf_lab(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (h1, s) = read_csv(&samples);
    let (h2, e) = read_csv(&evals);
    assert_eq!(h1, "x,y,z,pdf");
    assert_eq!(h2, "x,y,z,f,pdf");
    assert_eq!(s.len(), e.len());
    for (a, b) in s.iter().zip(&e) {
        assert_eq!(&a[..3], &b[..3]);
        assert!(
            (a[3] - b[4]).abs() <= 1e-12 * a[3].max(1e-300),
            "{a:?} vs {b:?}"
        );
        assert!(b[3] >= 0.0 && a[2] > 0.0);
    }
}

#[test]
fn validate_quick_case_passes_and_writes_the_json_schema() {
    let dir = tempfile::tempdir().expect("tempdir");
    let json = dir.path().join("v.json");
    let md = dir.path().join("v.md");
    let o = brdf_lab(&[
        "validate",
        "--quick",
        "--sampler",
        "cosine",
        "--brdf",
        "lambert",
        "--theta-o",
        "30",
        "--json",
        json.to_str().expect("p"),
        "--report",
        md.to_str().expect("p"),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse");
    assert_eq!(v["passed"], true);
    assert!(v["alpha"].is_number());
    let t = &v["tests"][0];
    for key in [
        "brdf",
        "sampler",
        "theta_o",
        "test",
        "statistic",
        "p_value",
        "passed",
    ] {
        assert!(t.get(key).is_some(), "missing {key}");
    }
    assert!(
        std::fs::read_to_string(&md)
            .expect("md")
            .contains("| sampler |")
    );
}

#[test]
fn eval_normalises_directions_once_for_f_and_every_pdf() {
    // One direction given three ways: unit, shorter (norm 0.707) and longer (norm 1.414).
    let dir = tempfile::tempdir().expect("tempdir");
    let dirs = dir.path().join("d.csv");
    let n = (0.5f64).sqrt();
    std::fs::write(
        &dirs,
        format!(
            "x,y,z\n{},{},{}\n0.3,0.4,0.5\n0.6,0.8,1.0\n",
            0.3 / n,
            0.4 / n,
            0.5 / n
        ),
    )
    .expect("write");
    for sampler in ["adaptive", "adaptive-paper", "cosine", "uniform"] {
        let out = dir.path().join(format!("{sampler}.csv"));
        let mut args = vec![
            "eval",
            "--brdf",
            "phong:n=50",
            "--theta-o",
            "45",
            "--sampler",
            sampler,
            "--dirs",
            dirs.to_str().expect("p"),
            "--out",
            out.to_str().expect("p"),
        ];
        // `--slices` configures the adaptive sets only (refused with the others).
        if sampler.starts_with("adaptive") {
            args.extend(["--slices", "9"]);
        }
        let o = brdf_lab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let (header, rows) = read_csv(&out);
        assert_eq!(header, "x,y,z,f,pdf");
        assert_eq!(rows.len(), 3);
        for r in &rows {
            // The written direction is the unit vector that f and the pdf saw.
            let norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            assert!((norm - 1.0).abs() < 1e-12, "{sampler}: {r:?}");
            for k in 0..5 {
                assert!(
                    (r[k] - rows[0][k]).abs() <= 1e-12 * rows[0][k].abs().max(1e-300),
                    "{sampler}: column {k}: {r:?} vs {:?}",
                    rows[0]
                );
            }
            assert!(r[4] > 0.0, "{sampler}: {r:?}");
        }
    }
}

/// The `albedo` summary line of `sample`: (estimate, σ, reference, reference error, agree).
fn albedo_line(text: &str) -> (f64, f64, f64, f64, bool) {
    let line = text
        .lines()
        .find(|l| l.starts_with("albedo"))
        .unwrap_or_else(|| panic!("no albedo line in {text}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let after = |w: &str| -> f64 {
        let i = words.iter().position(|x| *x == w).expect(w);
        words[i + 1]
            .trim_end_matches([';', ','])
            .parse()
            .expect(line)
    };
    let pm: Vec<f64> = words
        .iter()
        .enumerate()
        .filter(|(_, w)| **w == "±")
        .map(|(i, _)| {
            words[i + 1]
                .trim_end_matches([';', ','])
                .parse()
                .expect(line)
        })
        .collect();
    (
        after("estimate"),
        pm[0],
        after("reference"),
        pm[1],
        line.contains("agree"),
    )
}

#[test]
fn sample_compares_with_an_adaptive_reference_albedo() {
    // Fixed 64 × 256 grids gave 0.8536 (true 0.920846) and 0.9639 (true 0.999847) here.
    for (spec, theta, truth) in [
        ("ggx:alpha=0.1", "89.5", 0.920_846_217),
        ("ggx:alpha=0.01", "45", 0.999_846_808),
    ] {
        let o = brdf_lab(&[
            "sample",
            "--brdf",
            spec,
            "--theta-o",
            theta,
            "--slices",
            "9",
            "-n",
            "20000",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
        let (estimate, sigma, reference, err, agree) = albedo_line(&text);
        assert!((reference - truth).abs() < 1e-5, "{spec}: {text}");
        assert!(err < 1e-4, "{spec}: {text}");
        assert!(sigma > 0.0 && estimate > 0.0, "{text}");
        assert!(agree, "{spec}: {text}");
    }
}

#[test]
fn usage_errors_show_clap_s_full_message() {
    // Missing required arguments are named.
    let o = brdf_lab(&["sample", "--brdf", "lambert"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("required arguments were not provided"),
        "{err}"
    );
    assert!(
        err.contains("--theta-o") && err.contains("--samples"),
        "{err}"
    );
    assert!(err.contains("Usage:"), "{err}");
    // Possible values and "similar argument" tips are kept.
    let o = brdf_lab(&["envmap", "-n", "10", "--sampler", "adaptiv"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("possible values") && err.contains("envmap-cdf"),
        "{err}"
    );
    let o = brdf_lab(&["envmap", "-n", "10", "--compar"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--compare"), "{err}");
    // No subcommand: the help on stderr, exit 2.
    let o = brdf_lab(&[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(o.stdout.is_empty());
    assert!(
        err.contains("Usage:") && err.contains("sample") && err.contains("validate"),
        "{err}"
    );
    // --help and --version still go to stdout with exit 0.
    let o = brdf_lab(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("Usage:"));
}

#[test]
fn output_paths_are_checked_before_any_work() {
    // A prefix without `.tmp`: the internal temporary names must not leak into messages.
    let dir = tempfile::Builder::new()
        .prefix("brdf-lab-test")
        .tempdir()
        .expect("tempdir");
    let missing = dir.path().join("no/such/dir/out.csv");
    let missing = missing.to_str().expect("p");
    let sample = [
        "sample",
        "--brdf",
        "phong",
        "--theta-o",
        "30",
        "-n",
        "100",
        "--slices",
        "9",
    ];
    let one_line_before_work = |args: &[&str], needle: &str| {
        let o = brdf_lab(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
        assert!(!err.contains(".tmp"), "{args:?}: a temporary path: {err}");
        assert!(
            o.stdout.is_empty(),
            "{args:?}: work was done: {}",
            String::from_utf8_lossy(&o.stdout)
        );
    };
    let with = |extra: &[&str]| -> Vec<String> {
        sample.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let run = |v: Vec<String>, needle: &str| {
        let args: Vec<&str> = v.iter().map(String::as_str).collect();
        one_line_before_work(&args, needle);
    };
    run(with(&["--out", missing]), "does not exist");
    run(with(&["--out", "."]), "is a directory");
    run(
        with(&["--out", dir.path().to_str().expect("p")]),
        "is a directory",
    );
    // eval: the output is checked before the directions are read.
    one_line_before_work(
        &[
            "eval",
            "--brdf",
            "phong",
            "--theta-o",
            "30",
            "--dirs",
            "/no/such/dirs.csv",
            "--out",
            missing,
        ],
        "does not exist",
    );
    one_line_before_work(
        &[
            "build", "--brdf", "phong", "--slices", "9", "--out", missing,
        ],
        "does not exist",
    );
    one_line_before_work(
        &["envmap", "-n", "1000", "--out", missing],
        "does not exist",
    );
    // validate: neither output is written when the other cannot be.
    let json = dir.path().join("v.json");
    one_line_before_work(
        &[
            "validate",
            "--quick",
            "--sampler",
            "cosine",
            "--brdf",
            "lambert",
            "--theta-o",
            "30",
            "--json",
            json.to_str().expect("p"),
            "--report",
            missing,
        ],
        "does not exist",
    );
    assert!(!json.exists());
    let started = std::time::Instant::now();
    one_line_before_work(&["validate", "--json", missing], "does not exist");
    assert!(started.elapsed().as_secs_f64() < 10.0);
}

#[cfg(unix)]
#[test]
fn output_files_get_the_mode_of_a_normal_new_file() {
    use std::os::unix::fs::PermissionsExt;
    // The process umask, as the kernel reports it (Linux); 022 elsewhere.
    let umask = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Umask:"))
                .and_then(|v| u32::from_str_radix(v.trim(), 8).ok())
        })
        .unwrap_or(0o022);
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("s.csv");
    let o = brdf_lab(&["envmap", "-n", "100", "--out", out.to_str().expect("p")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mode = std::fs::metadata(&out).expect("meta").permissions().mode() & 0o777;
    assert_eq!(mode, 0o666 & !umask, "{mode:o}");
}

#[test]
fn sample_writes_csv_to_stdout_and_the_summary_to_stderr() {
    let args = [
        "sample",
        "--brdf",
        "phong",
        "--theta-o",
        "30",
        "-n",
        "500",
        "--slices",
        "9",
    ];
    let o = brdf_lab(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("x,y,z,pdf"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect(l)).collect())
        .collect();
    assert_eq!(rows.len(), 500);
    assert!(rows.iter().all(|r| r.len() == 4 && r[3] > 0.0));
    let err = stderr(&o);
    assert!(err.contains("albedo") && err.contains("sampler"), "{err}");
    // With --out: the same rows in the file, nothing on stdout, the summary on stderr.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("s.csv");
    let mut with_out = args.to_vec();
    with_out.extend(["--out", path.to_str().expect("p")]);
    let o = brdf_lab(&with_out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(stderr(&o).contains("albedo") && stderr(&o).contains("wrote"));
    assert_eq!(read_csv(&path).1, rows);
}

#[test]
fn max_depth_says_which_grid_it_needs() {
    let base = ["build", "--brdf", "lambert", "--slices", "1"];
    let with = |extra: &[&str]| -> Vec<String> {
        base.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let run = |v: Vec<String>| {
        let args: Vec<&str> = v.iter().map(String::as_str).collect();
        brdf_lab(&args)
    };
    let o = run(with(&["--max-depth", "8"]));
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--grid 512"), "{err}");
    let o = run(with(&["--max-depth", "8", "--grid", "512"]));
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(with(&["--grid", "100"]));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--grid"), "{}", stderr(&o));
    let o = brdf_lab(&["build", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(
        help.contains("--grid") && help.contains("2^(max_depth+1)"),
        "{help}"
    );
}

#[test]
fn implausible_brdfs_are_warned_about_not_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let dirs = dir.path().join("d.csv");
    std::fs::write(&dirs, "0,0,1\n").expect("write");
    let d = dirs.to_str().expect("p");
    let cases: [&[&str]; 4] = [
        &["sample", "--theta-o", "30", "-n", "100", "--slices", "3"],
        &["eval", "--theta-o", "30", "--dirs", d],
        &["build", "--slices", "3"],
        &[
            "validate",
            "--quick",
            "--sampler",
            "cosine",
            "--theta-o",
            "30",
            "--samples",
            "20000",
        ],
    ];
    for case in cases {
        for (spec, warned) in [
            ("phong:ks=0.9,kd=0.9", true),
            ("phong:ks=0.7,kd=0.3", false),
        ] {
            let mut args = case.to_vec();
            args.extend(["--brdf", spec]);
            let o = brdf_lab(&args);
            let err = stderr(&o);
            assert!(o.status.code() != Some(2), "{args:?}: {err}");
            let lines: Vec<&str> = err
                .lines()
                .filter(|l| l.starts_with("brdf-lab: warning:"))
                .collect();
            if warned {
                assert_eq!(lines.len(), 1, "{args:?}: {err}");
                assert!(
                    lines[0].contains(spec) && lines[0].contains("1.800"),
                    "{err}"
                );
            } else {
                assert!(lines.is_empty(), "{args:?}: {err}");
            }
        }
    }
}

#[test]
fn long_runs_print_progress_lines_when_stderr_is_not_a_terminal() {
    // The interval is 10 s by default; 0.05 s here so that a short build shows lines.
    let o = Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .args(["build", "--brdf", "ggx:alpha=0.05"])
        .env("BRDF_LAB_PROGRESS_SECS", "0.05")
        .output()
        .expect("run");
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("building: "))
        .collect();
    assert!(!lines.is_empty(), "{err}");
    // Before the build reports its slice count (on a loaded machine a line can come first),
    // a line says `building: 0 done, 0 s elapsed`; then `building: 12/90 (13 %), 1 s elapsed`.
    for l in &lines {
        assert!(
            l.ends_with("s elapsed")
                && (l.contains('/') && l.contains(" %)") || l.contains(" done, ")),
            "{l}"
        );
    }
    assert!(lines.iter().any(|l| l.contains(" %)")), "{err}");
    // Stdout keeps only the report.
    assert!(!String::from_utf8_lossy(&o.stdout).contains("building:"));
}

#[test]
fn sets_written_by_build_are_used_by_sample_and_eval() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = |name: &str| dir.path().join(name).to_str().expect("p").to_string();
    let (set, samples, evals) = (p("phong.set"), p("s.csv"), p("e.csv"));
    let o = brdf_lab(&[
        "build",
        "--brdf",
        "phong:n=50",
        "--slices",
        "9",
        "--out",
        &set,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let at = ["--theta-o", "37", "--phi-o", "20"];
    let run = |args: &[&str]| {
        let mut v = args.to_vec();
        v.extend(at);
        brdf_lab(&v)
    };
    let o = run(&["sample", "--set", &set, "-n", "2000", "--out", &samples]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("9 slices"), "{}", stderr(&o));
    let o = run(&["eval", "--set", &set, "--dirs", &samples, "--out", &evals]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, s) = read_csv(Path::new(&samples));
    let (h, e) = read_csv(Path::new(&evals));
    assert_eq!(h, "x,y,z,f,pdf");
    assert_eq!(s.len(), 2000);
    for (a, b) in s.iter().zip(&e) {
        assert!((a[3] - b[4]).abs() <= 1e-12 * a[3], "{a:?} vs {b:?}");
    }
    // --brdf may be given and must match; --sampler must be the set's; set options conflict.
    let o = run(&["sample", "--set", &set, "--brdf", "phong:n=50", "-n", "10"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let usage = |args: &[&str], needle: &str| {
        let o = run(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    };
    usage(
        &["sample", "--set", &set, "--brdf", "phong:n=60", "-n", "10"],
        "phong:n=50",
    );
    usage(
        &["eval", "--set", &set, "--brdf", "ward", "--dirs", &samples],
        "phong:n=50",
    );
    usage(
        &["sample", "--set", &set, "--sampler", "cosine", "-n", "10"],
        "adaptive",
    );
    usage(
        &[
            "eval",
            "--set",
            &set,
            "--sampler",
            "adaptive-paper",
            "--dirs",
            &samples,
        ],
        "adaptive",
    );
    usage(
        &["sample", "--set", &set, "--slices", "3", "-n", "10"],
        "--slices",
    );
    usage(&["sample", "-n", "10"], "--brdf");
    usage(&["sample", "--set", "/no/such.set", "-n", "10"], "such.set");
    usage(&["sample", "--set", &samples, "-n", "10"], "s.csv");
}

/// `build --sampler adaptive-exact --out FILE` saves the sampler (issue 29 item 5); `sample`,
/// `eval` and `validate` load it with `--set`, and the loaded sampler draws the same samples
/// as a fresh build with the same seed. A truncated file is refused with its reason (exit 2).
#[test]
fn adaptive_exact_is_saved_by_build_and_loaded_by_set() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = |name: &str| dir.path().join(name).to_str().expect("p").to_string();
    let (set, loaded, fresh, evals) = (p("phong.exact"), p("l.csv"), p("f.csv"), p("e.csv"));
    let o = brdf_lab(&[
        "build",
        "--brdf",
        "phong:n=50",
        "--sampler",
        "adaptive-exact",
        "--out",
        &set,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("wrote"));
    let at = [
        "--theta-o",
        "37",
        "--phi-o",
        "20",
        "-n",
        "500",
        "--seed",
        "7",
    ];
    let run = |args: &[&str]| {
        let mut v = args.to_vec();
        v.extend(at);
        brdf_lab(&v)
    };
    let o = run(&["sample", "--set", &set, "--out", &loaded]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&[
        "sample",
        "--brdf",
        "phong:n=50",
        "--sampler",
        "adaptive-exact",
        "--out",
        &fresh,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (read_csv(Path::new(&loaded)), read_csv(Path::new(&fresh)));
    assert_eq!(a.1.len(), 500);
    assert_eq!(a, b, "loaded and freshly built samples differ");
    let o = brdf_lab(&[
        "eval",
        "--set",
        &set,
        "--dirs",
        &loaded,
        "--out",
        &evals,
        "--theta-o",
        "37",
        "--phi-o",
        "20",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (s, e) in a.1.iter().zip(&read_csv(Path::new(&evals)).1) {
        assert!((s[3] - e[4]).abs() <= 1e-12 * s[3], "{s:?} vs {e:?}");
    }
    let o = brdf_lab(&[
        "validate",
        "--quick",
        "--set",
        &set,
        "--theta-o",
        "40",
        "--samples",
        "20000",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let bytes = std::fs::read(&set).expect("set");
    let cut = p("cut.exact");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
    assert_input_error(
        &["sample", "--set", &cut, "-n", "10", "--theta-o", "37"],
        "truncated",
    );
}

#[test]
fn validate_checks_a_set_written_by_build() {
    let dir = tempfile::tempdir().expect("tempdir");
    let set = dir.path().join("ggx.set");
    let set = set.to_str().expect("path");
    let o = brdf_lab(&[
        "build",
        "--brdf",
        "ggx:alpha=0.3",
        "--slices",
        "9",
        "--out",
        set,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = dir.path().join("v.json");
    let o = brdf_lab(&[
        "validate",
        "--quick",
        "--set",
        set,
        "--theta-o",
        "40",
        "--samples",
        "20000",
        "--json",
        json.to_str().expect("path"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse");
    let tests = v["tests"].as_array().expect("tests");
    assert!(!tests.is_empty());
    assert!(
        tests
            .iter()
            .all(|t| t["sampler"] == "adaptive (set ggx.set)" && t["brdf"] == "ggx:alpha=0.3")
    );
    let o = brdf_lab(&["validate", "--quick", "--set", "/no/such.set"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("such.set"), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn outputs_follow_links_and_never_replace_special_files() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().expect("tempdir");
    // A symbolic link stays a link; its target receives the data (also when it is new).
    let link = dir.path().join("link.csv");
    let real = dir.path().join("real.csv");
    std::os::unix::fs::symlink("real.csv", &link).expect("symlink");
    let o = brdf_lab(&["envmap", "-n", "10", "--out", link.to_str().expect("p")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::symlink_metadata(&link)
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert_eq!(read_csv(&real).1.len(), 10);
    // A FIFO (as `--out >(gzip > s.gz)` gives) is written in place, not replaced by a file.
    let fifo = dir.path().join("fifo");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        return; // no mkfifo here
    }
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = fifo.clone();
    std::thread::spawn(move || {
        let _ = tx.send(std::fs::read_to_string(&reader));
    });
    let o = brdf_lab(&["envmap", "-n", "10", "--out", fifo.to_str().expect("p")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the FIFO received nothing")
        .expect("read");
    assert_eq!(text.lines().count(), 11, "{text}");
    let kind = std::fs::symlink_metadata(&fifo).expect("fifo").file_type();
    assert!(kind.is_fifo());
}

#[test]
fn list_into_a_closed_pipe_ends_quietly() {
    // `brdf-lab list | head -1`: the reader has gone before the listing is written (the pipe
    // is closed right after the spawn, long before the process has started up); the listing
    // must stop without a panic and exit 0.
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .arg("list")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn brdf-lab");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "exit {:?}: {err}", out.status);
    assert!(!err.contains("panicked"), "{err}");
}

/// A numeric value out of its range: clap's usage error naming the option, the value and the
/// range (exit 2), never a clamp, a run or "unexpected argument".
fn assert_out_of_range(args: &[&str], flag: &str, range: &str) {
    let o = brdf_lab(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains("invalid value") && err.contains(flag) && err.contains(range),
        "{args:?}: `{flag}`, `{range}` not in {err}"
    );
    assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    assert!(
        o.stdout.is_empty(),
        "{args:?} ran: {}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn numeric_options_are_range_checked_by_name() {
    let sample = |extra: &[&'static str]| {
        let mut a = vec!["sample", "--brdf", "lambert", "--theta-o", "30", "-n", "5"];
        a.extend_from_slice(extra);
        a
    };
    assert_out_of_range(
        &["sample", "--brdf", "lambert", "--theta-o", "30", "-n", "-5"],
        "--samples",
        "must be an integer in 1 ..= 1000000000",
    );
    assert_out_of_range(
        &["envmap", "-n", "-5"],
        "--samples",
        "must be an integer ≥ 1",
    );
    for phi in ["1e308", "NaN", "inf", "-inf", "400"] {
        assert_out_of_range(&sample(&["--phi-o", phi]), "--phi-o", "[-360, 360]");
    }
    for theta in ["90", "-1", "NaN", "inf"] {
        assert_out_of_range(
            &["sample", "--brdf", "lambert", "--theta-o", theta, "-n", "5"],
            "--theta-o",
            "[0, 90)",
        );
    }
    assert_out_of_range(
        &sample(&["--seed", "-1"]),
        "--seed",
        "0 ..= 18446744073709551615",
    );
    assert_out_of_range(&sample(&["--n-max", "NaN"]), "--n-max", "≥ 1");
    assert_out_of_range(
        &sample(&["--equal-area-from", "inf"]),
        "--equal-area-from",
        "[0, 90]",
    );
    assert_out_of_range(&sample(&["--slices", "0"]), "--slices", "1 ..= 4096");
    assert_out_of_range(&sample(&["--max-depth", "-1"]), "--max-depth", "0 ..= ");
    assert_out_of_range(
        &sample(&["--sampler", "cascade-cdf", "--epsilon", "NaN"]),
        "--epsilon",
        "(0, 1)",
    );
    assert_out_of_range(
        &sample(&["--sampler", "factored", "--factored-alpha", "2"]),
        "--factored-alpha",
        "[0, 1]",
    );
    assert_out_of_range(
        &sample(&["--sampler", "factored", "--factored-j", "-3"]),
        "--factored-j",
        "1 ..= 16",
    );
    assert_out_of_range(
        &["validate", "--quick", "--alpha", "0"],
        "--alpha",
        "(0, 1)",
    );
    assert_out_of_range(
        &["validate", "--quick", "--theta-o", "NaN"],
        "--theta-o",
        "[0, 90)",
    );
    assert_out_of_range(
        &["validate", "--quick", "--samples", "10"],
        "--samples",
        "≥ 2000",
    );
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("o");
    let out_s = out.to_str().expect("path");
    // `study --spp 0` ran at 1 spp and exited 0; now refused before any work.
    assert_out_of_range(
        &["study", "--spp", "0", "--out", out_s],
        "--spp",
        "1 ..= 65536",
    );
    assert_out_of_range(
        &["study", "merge", "x", "--spp", "-4", "--out", out_s],
        "--spp",
        "1 ..= 65536",
    );
    assert_out_of_range(
        &["study", "--repetitions", "1", "--out", out_s],
        "--repetitions",
        "≥ 2",
    );
    assert_out_of_range(
        &["study", "--n-grid", "-1,4", "--out", out_s],
        "--n-grid",
        "≥ 1",
    );
    assert!(!out.exists());
    // The srbf options keep the library's one-line reason (`product` relies on it).
    assert_input_error(
        &sample(&["--sampler", "srbf", "--srbf-max-iter", "0"]),
        "--srbf-max-iter 0",
    );
}

#[test]
fn sampler_options_are_refused_where_they_do_nothing() {
    let base = ["sample", "--brdf", "phong", "--theta-o", "30", "-n", "5"];
    let with = |extra: &[&'static str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        a
    };
    assert_input_error(
        &with(&["--epsilon", "0.01"]),
        "--epsilon applies to sampler cascade-cdf, not adaptive",
    );
    assert_input_error(
        &with(&["--sampler", "tabulated-cdf", "--epsilon", "0.01"]),
        "--epsilon applies to sampler cascade-cdf, not tabulated-cdf",
    );
    assert_input_error(
        &with(&["--sampler", "cosine", "--factored-j", "2"]),
        "--factored-j applies to sampler factored, not cosine",
    );
    assert_input_error(
        &with(&["--sampler", "cosine", "--n-max", "2"]),
        "--n-max applies to samplers adaptive, adaptive-paper",
    );
    assert_input_error(
        &with(&["--sampler", "lobe-sphere", "--cdf-slices", "4"]),
        "--cdf-slices applies to samplers tabulated-cdf, cascade-cdf, not lobe-sphere",
    );
    assert_input_error(
        &[
            "build",
            "--brdf",
            "phong",
            "--sampler",
            "srbf",
            "--lobe-slices",
            "4",
        ],
        "--lobe-slices applies to samplers lobe-sphere, lobe-hemisphere, not srbf",
    );
    let dir = tempfile::tempdir().expect("tempdir");
    let dirs = dir.path().join("d.csv");
    std::fs::write(&dirs, "0,0,1\n").expect("write");
    assert_input_error(
        &[
            "eval",
            "--brdf",
            "phong",
            "--theta-o",
            "30",
            "--dirs",
            dirs.to_str().expect("path"),
            "--srbf-lobes",
            "3",
        ],
        "--srbf-lobes applies to sampler srbf, not none (no --sampler given)",
    );
    // The product-only options are not options of sample, eval or build.
    assert_usage_error(&with(&["--srbf-keep", "3"]), "--srbf-keep");
    for cmd in ["sample", "eval", "build"] {
        let help = String::from_utf8_lossy(&brdf_lab(&[cmd, "--help"]).stdout).to_string();
        for product_only in [
            "--srbf-keep",
            "--srbf-map-lobes",
            "--srbf-defensive ",
            "--srbf-map-fit-width",
        ] {
            assert!(
                !help.contains(product_only),
                "{cmd} --help lists {product_only}"
            );
        }
        assert!(
            help.contains("--srbf-lobes") && help.contains("--epsilon"),
            "{help}"
        );
    }
    let help = String::from_utf8_lossy(&brdf_lab(&["product", "--help"]).stdout).to_string();
    assert!(
        help.contains("--srbf-keep") && help.contains("--srbf-map-lobes"),
        "{help}"
    );
    // An option given with the sampler it configures is accepted.
    let o = brdf_lab(&with(&[
        "--sampler",
        "cascade-cdf",
        "--epsilon",
        "0.01",
        "--cdf-slices",
        "2",
        "--cdf-grid",
        "16x32",
    ]));
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn every_built_sampler_reports_time_memory_and_its_fit() {
    for (sampler, extra, fit) in [
        (
            "tabulated-cdf",
            vec!["--cdf-slices", "2", "--cdf-grid", "16x32"],
            "CDF points stored",
        ),
        ("lobe-sphere", vec!["--lobe-slices", "4"], "exponent n in ["),
        (
            "factored",
            vec!["--factored-grid", "4,4,8,4", "--factored-iterations", "50"],
            "relative error",
        ),
        (
            "srbf",
            vec!["--srbf-slices", "2", "--srbf-fit-rows", "8"],
            "fit rel. L2 mean",
        ),
    ] {
        let mut args = vec!["build", "--brdf", "phong:n=20", "--sampler", sampler];
        args.extend(extra);
        let o = brdf_lab(&args);
        assert!(o.status.success(), "{sampler}: {}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        let line = out
            .lines()
            .find(|l| l.starts_with("sampler "))
            .unwrap_or_else(|| panic!("{sampler}: no sampler line in {out}"));
        assert!(
            line.contains(&format!("{sampler} built in")) && line.contains(" bytes"),
            "{sampler}: {line}"
        );
        assert!(out.contains(fit), "{sampler}: `{fit}` not in {out}");
    }
}

#[test]
fn srbf_fits_at_the_iteration_cap_are_warned_about_everywhere() {
    let dir = tempfile::tempdir().expect("tempdir");
    let dirs = dir.path().join("d.csv");
    std::fs::write(&dirs, "0,0,1\n").expect("write");
    let capped = [
        "--sampler",
        "srbf",
        "--srbf-slices",
        "2",
        "--srbf-max-iter",
        "1",
    ];
    let warning = "brdf-lab: warning: --sampler srbf: 2 of 2 BRDF slice fits hit the iteration cap";
    let runs: [Vec<&str>; 3] = [
        vec!["build", "--brdf", "phong:n=200"],
        vec![
            "sample",
            "--brdf",
            "phong:n=200",
            "--theta-o",
            "30",
            "-n",
            "10",
            "--out",
            "/dev/null",
        ],
        vec![
            "eval",
            "--brdf",
            "phong:n=200",
            "--theta-o",
            "30",
            "--dirs",
            dirs.to_str().expect("path"),
            "--out",
            "/dev/null",
        ],
    ];
    for mut args in runs {
        args.extend(capped);
        let o = brdf_lab(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(warning), "{args:?}: {}", stderr(&o));
    }
    // Converged fits (a cap high enough for lambert's two slices): no warning.
    let o = brdf_lab(&[
        "build",
        "--brdf",
        "lambert",
        "--sampler",
        "srbf",
        "--srbf-slices",
        "2",
        "--srbf-max-iter",
        "1000",
    ]);
    assert!(
        o.status.success() && !stderr(&o).contains("warning"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn validate_that_runs_no_test_does_not_pass() {
    // Every case skipped: no PASSED, exit 3 with the reason.
    let o = brdf_lab(&[
        "validate",
        "--quick",
        "--sampler",
        "analytic",
        "--brdf",
        "oren-nayar",
        "--theta-o",
        "30",
    ]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{out}{err}");
    assert!(!out.contains("PASSED"), "{out}");
    assert!(
        out.contains("0 tests (1 case skipped)") && out.contains("NO TEST RAN"),
        "{out}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("no test ran: 1 case skipped (analytic | oren-nayar: BRDF model `oren-nayar` has no analytic sampler"),
        "{err}"
    );
    // Partly skipped: the run passes and says how many cases were skipped.
    let o = brdf_lab(&[
        "validate",
        "--quick",
        "--sampler",
        "analytic",
        "--brdf",
        "oren-nayar",
        "--brdf",
        "lambert",
        "--theta-o",
        "30",
        "--samples",
        "2000",
    ]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert_eq!(o.status.code(), Some(0), "{out}{}", stderr(&o));
    assert!(
        out.contains("(1 case skipped)") && out.contains("result     PASSED"),
        "{out}"
    );
}

#[test]
fn help_texts_point_inside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for cmd in [
        "list", "sample", "eval", "build", "validate", "envmap", "study", "product",
    ] {
        let help = String::from_utf8_lossy(&brdf_lab(&[cmd, "--help"]).stdout).to_string();
        assert!(!help.is_empty(), "{cmd}");
        assert!(
            !help.contains("design.md") && !help.contains("../shared/docs"),
            "{cmd}: {help}"
        );
        for doc in help.split_whitespace().filter(|w| w.contains("docs/")) {
            let doc = doc.trim_matches(|c: char| !(c.is_alphanumeric() || "/._-".contains(c)));
            assert!(
                root.join(doc).is_file(),
                "{cmd} --help points to {doc}, not in the repository"
            );
        }
    }
    let help = String::from_utf8_lossy(&brdf_lab(&["validate", "--help"]).stdout).to_string();
    assert!(help.contains("docs/validation.md"), "{help}");
}

#[test]
fn paths_counts_and_nouns_are_printed_as_a_reader_expects() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir(dir.path().join("sub")).expect("mkdir");
    let o = Command::new(env!("CARGO_BIN_EXE_brdf-lab"))
        .current_dir(dir.path())
        .env("RAYON_NUM_THREADS", "1")
        .args([
            "sample",
            "--brdf",
            "lambert",
            "--theta-o",
            "30",
            "-n",
            "1",
            "--sampler",
            "cosine",
            "--out",
            "sub/.././sub/../s.csv",
        ])
        .output()
        .expect("run brdf-lab");
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("on 1 thread)"), "{err}");
    assert!(err.contains("wrote      s.csv (1 row: x,y,z,pdf)"), "{err}");
    assert!(dir.path().join("s.csv").is_file());
    // A path outside the working directory: absolute and canonical, without `..`.
    let o = brdf_lab(&[
        "sample",
        "--brdf",
        "lambert",
        "--theta-o",
        "30",
        "-n",
        "2",
        "--sampler",
        "cosine",
        "--out",
        dir.path().join("sub/../t.csv").to_str().expect("path"),
    ]);
    let err = stderr(&o);
    let canonical = std::fs::canonicalize(dir.path())
        .expect("canonical")
        .join("t.csv");
    assert!(
        err.contains(&format!("wrote      {} (2 rows", canonical.display())),
        "{err}"
    );
    assert!(!err.contains(".."), "{err}");
}
