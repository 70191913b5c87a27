//! Cornell `.brdf` reader: synthetic files with a known answer, the shared real files when
//! `../shared` is present, malformed files (typed errors, never a panic).

use crate::common::pairs_below_85;
use brdf::measured::cornell::{self, CornellBrdf, CornellError, MIN_SAMPLES};
use brdf::{Brdf, SpecError, Vec3, direction_from_angles, parse_spec, rotate_z};
use proptest::prelude::*;
use std::fmt::Write;
use std::path::PathBuf;

const WAVELENGTHS: usize = 31;

/// A synthetic file: a regular grid of (θi, θo, Δφ) samples whose spectrum is flat with value
/// `value(θi, θo, Δφ)`, with comments and the wavelength list over two lines.
fn synthetic(value: impl Fn(f64, f64, f64) -> f64) -> String {
    let mut s = String::from("# num wls\n31\n\n# wls\n");
    for k in 0..WAVELENGTHS {
        let _ = write!(s, "{} ", 400 + 10 * k);
        if k == 18 {
            s.push('\n');
        }
    }
    s.push_str("\n# theta i, phi i, theta s, phi_s, values\n");
    for i in 0..10 {
        for o in 0..10 {
            for p in 0..9 {
                let (ti, to) = (i as f64 * 0.17, o as f64 * 0.17);
                let dp = p as f64 * std::f64::consts::PI / 8.0;
                let v = value(ti, to, dp);
                let _ = write!(s, "{ti} 0.3 {to} {}", 0.3 - dp);
                for _ in 0..WAVELENGTHS {
                    let _ = write!(s, " {v}");
                }
                s.push('\n');
            }
        }
    }
    s
}

/// A constant spectrum gives a constant grey BRDF everywhere (the Gaussian weights average
/// equal values), with its value as luminance.
#[test]
fn constant_data_give_a_constant_brdf() {
    let b = CornellBrdf::parse(&synthetic(|_, _, _| 0.2)).expect("valid");
    assert_eq!(b.samples(), 900);
    assert_eq!(b.wavelengths().len(), WAVELENGTHS);
    for (wo, wi) in pairs_below_85(1, 200) {
        let f = b.eval(&wo, &wi);
        assert!((f - 0.2).abs() < 2e-3, "{f}");
    }
}

/// At a sample's own directions the interpolant is close to the sample (the nearest weight
/// dominates), and it varies with the data: a lobe in the data is a lobe in f.
#[test]
fn interpolation_follows_the_data() {
    let lobe = |ti: f64, to: f64, dp: f64| {
        // Peak in the mirror configuration (θi = θo, Δφ = π).
        0.05 + 2.0 * (-(ti - to).powi(2) / 0.2 - (dp - std::f64::consts::PI).powi(2) / 1.0).exp()
    };
    let b = CornellBrdf::parse(&synthetic(lobe)).expect("valid");
    let wo = direction_from_angles(0.51f64.to_degrees(), 0.0);
    let peak = b.eval(&wo, &brdf::mirror(&wo));
    let side = b.eval(&wo, &direction_from_angles(0.51f64.to_degrees(), 90.0));
    assert!(peak > 3.0 * side, "peak {peak}, side {side}");
    let exact = lobe(0.51, 0.51, std::f64::consts::PI);
    assert!((peak - exact).abs() < 0.25 * exact, "{peak} vs {exact}");
}

/// Declared symmetries hold exactly by construction of the remapped space.
#[test]
fn declared_symmetries_hold() {
    let b = CornellBrdf::parse(&synthetic(|ti, to, dp| {
        0.1 + ti * to + 0.3 * dp.cos().abs()
    }))
    .expect("valid");
    assert!(b.is_isotropic() && b.is_mirror_symmetric() && b.is_reciprocal());
    let m = |v: &Vec3| Vec3::new(v.x, -v.y, v.z);
    for (k, (wo, wi)) in pairs_below_85(2, 300).iter().enumerate() {
        let f = b.eval(wo, wi);
        assert!(f.is_finite() && f >= 0.0);
        let a = 0.7 * k as f64;
        for other in [
            b.eval(wi, wo),
            b.eval(&m(wo), &m(wi)),
            b.eval(&rotate_z(wo, a), &rotate_z(wi, a)),
        ] {
            assert!((f - other).abs() <= 1e-9 * f.max(1e-12), "{f} vs {other}");
        }
    }
    let (p, q) = (
        cornell::remap(0.3, 0.1, 0.7, 2.0),
        cornell::remap(0.7, 2.0, 0.3, 0.1),
    );
    for k in 0..3 {
        approx::assert_abs_diff_eq!(p[k], q[k], epsilon = 1e-15);
    }
}

#[test]
fn malformed_files_are_typed_errors() {
    let good = synthetic(|_, _, _| 0.1);
    let lines: Vec<&str> = good.lines().collect();
    let with_line = |i: usize, replacement: &str| {
        let mut l = lines.clone();
        l[i] = replacement;
        l.join("\n")
    };
    let last = lines.len() - 1;
    // A sample line with a value missing.
    let short: String = lines[last]
        .rsplit_once(' ')
        .map(|(a, _)| a.to_string())
        .unwrap_or_default();
    let e = CornellBrdf::parse(&with_line(last, &short)).expect_err("wrong column count");
    assert!(
        matches!(
            e,
            CornellError::ColumnCount {
                found: 34,
                expected: 35,
                ..
            }
        ),
        "{e}"
    );
    let nan = lines[last].replacen("0.1", "NaN", 1);
    assert!(matches!(
        CornellBrdf::parse(&with_line(last, &nan)),
        Err(CornellError::NonFinite { .. })
    ));
    let rest = lines[last].split_once(' ').map_or("", |(_, r)| r);
    let negative_angle = format!("-0.2 {rest}");
    assert!(matches!(
        CornellBrdf::parse(&with_line(last, &negative_angle)),
        Err(CornellError::Angle { .. })
    ));
    assert!(matches!(
        CornellBrdf::parse(&with_line(last, "1 2 x")),
        Err(CornellError::NotANumber { .. })
    ));
    assert!(matches!(
        CornellBrdf::parse(""),
        Err(CornellError::BadCount { .. })
    ));
    assert!(matches!(
        CornellBrdf::parse("abc\n"),
        Err(CornellError::BadCount { .. })
    ));
    assert!(matches!(
        CornellBrdf::parse("31\n400 410\n"),
        Err(CornellError::MissingWavelengths { .. })
    ));
    let few: String = lines[..lines.len() - 900 + MIN_SAMPLES - 1].join("\n");
    assert!(matches!(
        CornellBrdf::parse(&few),
        Err(CornellError::TooFewSamples { found }) if found == MIN_SAMPLES - 1
    ));
    // Negative spectral values are clamped and reported.
    let neg = lines[last].replacen(" 0.1", " -0.05", 2);
    let b = CornellBrdf::parse(&with_line(last, &neg)).expect("negatives are clamped");
    let c = b.clamped().expect("reported");
    assert_eq!(c.count, 2);
    assert!(matches!(
        parse_spec("cornell"),
        Err(SpecError::MissingFile { model: "cornell" })
    ));
}

/// The interpolant is continuous: along a fine path of `ωi` the value never jumps by more
/// than a smooth function's step allows, even though the neighbour set changes many times
/// along it (data: a rough pseudo-random value per sample). The plain Gaussian-weighted mean of
/// the 8 nearest (the reader's former rule) fails this check on the same path.
#[test]
fn the_interpolant_is_continuous_where_the_neighbour_set_changes() {
    let b = CornellBrdf::parse(&synthetic(|ti, to, dp| {
        0.05 + ((7.3 * ti + 11.1 * to + 5.7 * dp).sin() * 1e3)
            .fract()
            .abs()
    }))
    .expect("valid");
    let wo = direction_from_angles(37.0, 0.0);
    let steps = 20_000;
    // From θi = 1° (at θi = 0 the remap's Δφ is undefined: a pole, not a neighbour change).
    let path = |k: usize| direction_from_angles(1.0 + 79.0 * k as f64 / steps as f64, 123.0);
    let (mut max_jump, mut changes) = (0.0f64, 0usize);
    let mut prev = b.eval(&wo, &path(0));
    for k in 1..=steps {
        let v = b.eval(&wo, &path(k));
        let jump = (v - prev).abs();
        if jump > 0.0 {
            changes += 1;
        }
        max_jump = max_jump.max(jump);
        prev = v;
    }
    assert!(changes > steps / 2);
    // Values span ~[0.05, 1.05]; a step of 0.004° moves the remapped point by ~1e-4, the
    // kernel's scale is 0.05: a continuous interpolant moves by well under 1e-2 per step.
    assert!(max_jump < 1e-2, "largest step change {max_jump}");
}

/// The shared Cornell files (when `../shared` is present): 1439 samples each, read quickly,
/// finite non-negative values on the whole hemisphere.
#[test]
fn shared_files_read() {
    let dir =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/measured/cornell");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        println!(
            "notice: {} absent, shared Cornell files skipped",
            dir.display()
        );
        return;
    };
    let mut n = 0;
    for e in entries.filter_map(Result::ok) {
        let spec = format!("cornell:{}", e.path().display());
        let b = parse_spec(&spec).unwrap_or_else(|err| panic!("{spec}: {err}"));
        for (wo, wi) in pairs_below_85(3, 500) {
            let f = b.eval_rgb(&wo, &wi);
            assert!(
                f.iter().all(|v| v.is_finite() && *v >= 0.0),
                "{spec}: {f:?}"
            );
        }
        n += 1;
    }
    assert_eq!(n, 3);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    /// Random edits of a valid file never panic.
    #[test]
    fn fuzzed_files_never_panic(edits in proptest::collection::vec((0usize..4000, 0u8..128), 1..10),
                                cut in 0usize..200_000) {
        let mut bytes = synthetic(|ti, _, _| 0.1 + ti).into_bytes();
        for (i, v) in edits {
            if i < bytes.len() {
                bytes[i] = v;
            }
        }
        bytes.truncate(cut);
        let _ = CornellBrdf::parse(&String::from_utf8_lossy(&bytes));
    }
}

/// A count line claiming 2^40 wavelengths (or samples) gets a typed error at once: the count is
/// bounded by 10,000 and the samples are only those the text holds.
#[test]
fn huge_claims_are_refused_before_allocating() {
    let t = std::time::Instant::now();
    let r = CornellBrdf::parse("1099511627776\n400 500\n0 0 0 0 1 1\n");
    assert!(
        matches!(r, Err(CornellError::BadCount { line: 1, .. })),
        "{r:?}"
    );
    let r = CornellBrdf::parse("10000\n400 500\n");
    assert!(
        matches!(
            r,
            Err(CornellError::MissingWavelengths {
                found: 2,
                expected: 10_000
            })
        ),
        "{r:?}"
    );
    assert!(t.elapsed().as_secs_f64() < 0.5);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    /// Tokens of a valid file replaced by huge, negative, non-finite or non-numeric ones, lines
    /// dropped or duplicated: a typed error or a material whose values are finite and
    /// non-negative.
    #[test]
    fn token_edits_give_a_typed_error_or_a_valid_material(
        edits in proptest::collection::vec((any::<proptest::sample::Index>(), 0usize..10), 1..6),
        dup in proptest::option::of(any::<proptest::sample::Index>()),
    ) {
        let tokens = ["1e38", "-1e38", "nan", "inf", "-5", "0", "1099511627776", "x", "", "3.2"];
        let text = synthetic(|ti, _, _| 0.1 + ti);
        let mut lines: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(' ').map(str::to_string).collect())
            .collect();
        for (at, k) in edits {
            let line = at.index(lines.len());
            let n = lines[line].len();
            let tok = at.index(n.max(1)).min(n.saturating_sub(1));
            if n > 0 {
                lines[line][tok] = tokens[k].to_string();
            }
        }
        if let Some(d) = dup {
            let i = d.index(lines.len());
            let copy = lines[i].clone();
            lines.insert(i, copy);
        }
        let edited: Vec<String> = lines.iter().map(|l| l.join(" ")).collect();
        if let Ok(b) = CornellBrdf::parse(&edited.join("\n")) {
            for (wo, wi) in pairs_below_85(4, 10) {
                let v = b.eval(&wo, &wi);
                prop_assert!(v.is_finite() && v >= 0.0, "{}", v);
            }
        }
    }
}
