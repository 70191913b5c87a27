//! Spec grammar and its typed errors.

use brdf::{Brdf, ParamDefault, SpecError, find_model, models, parse_spec};
use proptest::prelude::*;

fn err(spec: &str) -> SpecError {
    match parse_spec(spec) {
        Err(e) => e,
        Ok(b) => panic!("{spec} unexpectedly parsed as {}", b.name()),
    }
}

#[test]
fn accepted_forms() {
    let p = parse_spec("phong:n=50,ks=0.7,kd=0.3").unwrap();
    assert_eq!(p.name(), "phong");
    assert!(parse_spec("  Phong : n = 50 , ks=0.7 ").is_ok());
    assert!(parse_spec("phong:").is_ok());
    assert!(parse_spec("phong:n=1e2").is_ok());
    assert_eq!(parse_spec("torrance").unwrap().name(), "cook-torrance");
    assert_eq!(parse_spec("he").unwrap().name(), "htsg");
    assert_eq!(parse_spec("schlick-d").unwrap().name(), "schlick-diffuse");
    // `alpha_y` defaults to `alpha`; giving it makes the model anisotropic.
    assert!(parse_spec("ggx:alpha=0.3").unwrap().is_isotropic());
    assert!(
        !parse_spec("ggx:alpha=0.3,alpha_y=0.1")
            .unwrap()
            .is_isotropic()
    );
    assert!(parse_spec("ward:alpha_y=0.15").unwrap().is_isotropic());
    assert!(parse_spec("ward:alpha_x=0.2").unwrap().is_isotropic());
}

#[test]
fn typed_errors() {
    assert!(matches!(err(""), SpecError::Empty));
    assert!(matches!(err("   "), SpecError::Empty));
    match err("phongg") {
        SpecError::UnknownModel { name, known } => {
            assert_eq!(name, "phongg");
            assert!(known.contains("phong") && known.contains("ggx") && known.contains("merl"));
        }
        e => panic!("{e}"),
    }
    match err("phong:q=1") {
        e @ SpecError::UnknownKey { .. } => {
            let msg = e.to_string();
            assert!(
                msg.contains("`q`") && msg.contains("valid keys: n, ks, kd"),
                "{msg}"
            );
        }
        e => panic!("{e}"),
    }
    for bad in [
        "phong:n=abc",
        "phong:n=",
        "phong:n=nan",
        "phong:n=inf",
        "phong:n=1,2",
    ] {
        let e = err(bad);
        assert!(
            matches!(e, SpecError::BadNumber { .. } | SpecError::Malformed { .. }),
            "{bad}: {e}"
        );
    }
    assert!(matches!(err("phong:n=abc"), SpecError::BadNumber { ref key, .. } if key == "n"));
    assert!(matches!(err("phong:n"), SpecError::Malformed { .. }));
    assert!(matches!(
        err("phong:n=1,,ks=0.2"),
        SpecError::Malformed { .. }
    ));
    assert!(matches!(err("phong:=3"), SpecError::Malformed { .. }));
    match err("phong:ks=1.5") {
        e @ SpecError::OutOfRange { .. } => {
            let msg = e.to_string();
            assert!(msg.contains("[0, 1]") && msg.contains("ks"), "{msg}");
        }
        e => panic!("{e}"),
    }
    assert!(matches!(err("ggx:alpha=0"), SpecError::OutOfRange { .. }));
    assert!(matches!(err("phong:n=3,n=4"), SpecError::DuplicateKey { ref key, .. } if key == "n"));
    assert!(matches!(err("merl"), SpecError::MissingPath));
    assert!(matches!(err("merl:  "), SpecError::MissingPath));
    assert!(matches!(
        err("merl:/nonexistent/dir/file.binary"),
        SpecError::Merl(brdf::MerlError::Io { .. })
    ));
}

#[test]
fn registry_lists_required_keys() {
    let keys = |name: &str| -> Vec<&str> {
        find_model(name)
            .unwrap()
            .params
            .iter()
            .map(|p| p.key)
            .collect()
    };
    assert_eq!(keys("phong"), ["n", "ks", "kd"]);
    assert_eq!(keys("blinn"), ["n", "ks", "kd"]);
    assert_eq!(keys("ward"), ["alpha_x", "alpha_y", "rho_s", "rho_d"]);
    assert!(keys("ggx").starts_with(&["alpha", "alpha_y"]));
    assert!(keys("beckmann").starts_with(&["alpha", "alpha_y"]));
    assert_eq!(keys("cook-torrance")[0], "m");
    assert_eq!(keys("oren-nayar")[1], "sigma");
    assert_eq!(keys("lambert"), ["rho"]);
    assert!(find_model("lafortune").is_some());
    // The seed papers' sixteen models are all present.
    for name in brdf::SEED_003_MODELS {
        assert!(find_model(name).is_some(), "{name}");
    }
    assert!(models().len() >= 21);
}

/// Any in-range assignment of every key parses and builds.
fn any_valid_spec() -> impl Strategy<Value = String> {
    let infos: Vec<_> = models().iter().filter(|m| !m.needs_argument()).collect();
    (0..infos.len(), proptest::collection::vec(0.0..1.0f64, 8)).prop_map(move |(i, us)| {
        let m = infos[i];
        let items: Vec<String> = m
            .params
            .iter()
            .zip(&us)
            .filter(|(p, _)| matches!(p.default, ParamDefault::Value(_)))
            .map(|(p, u)| {
                let (lo, hi) = (p.range.min, p.range.max);
                // Stay strictly inside open ends.
                let v = lo + (hi - lo) * (0.001 + 0.998 * u);
                format!("{}={v}", p.key)
            })
            .collect();
        format!("{}:{}", m.name, items.join(","))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]
    #[test]
    fn valid_specs_parse(spec in any_valid_spec()) {
        // In-range values may still violate a documented cross-parameter constraint (Lafortune
        // overflow guard, Beard–Maxwell R(0) > 0); anything else must build.
        let b = match parse_spec(&spec) {
            Ok(b) => b,
            Err(SpecError::Invalid(brdf::ParamError::Constraint { .. })) => return Ok(()),
            Err(e) => return Err(TestCaseError::fail(format!("{spec}: {e}"))),
        };
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let wi = brdf::direction_from_angles(40.0, 170.0);
        for (a, c) in [(&wo, &wi), (&wi, &wo), (&wo, &brdf::mirror(&wo))] {
            let f = b.eval(a, c);
            prop_assert!(f.is_finite() && f >= 0.0, "{}: {}", spec, f);
        }
    }
}
