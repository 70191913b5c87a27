//! The `sgd` and `abc` presets: every one of the 100 MERL fits builds from its spec, declared
//! symmetries hold numerically, values are finite and non-negative, unknown names suggest close
//! matches.

use crate::common::pairs_below_85;
use brdf::models::{Abc, Sgd};
use brdf::{Brdf, SpecError, Vec3, direction_from_angles, parse_spec, preset_names, rotate_z};

/// Every preset of `sgd` and `abc`: its model, its name and the BRDF its spec builds.
fn every_preset() -> impl Iterator<Item = (&'static str, &'static str, Box<dyn Brdf>)> {
    ["sgd", "abc"].into_iter().flat_map(|model| {
        preset_names(model)
            .expect("presets")
            .into_iter()
            .map(move |n| {
                let b = parse_spec(&format!("{model}:material={n}")).expect("builds");
                (model, n, b)
            })
    })
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn one_hundred_presets_each() {
    for model in ["sgd", "abc"] {
        let names = preset_names(model).expect("a preset model");
        assert_eq!(names.len(), 100, "{model}");
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 100, "{model}: duplicate names");
        for n in &names {
            let b = parse_spec(&format!("{model}:material={n}"))
                .unwrap_or_else(|e| panic!("{model}:{n}: {e}"));
            assert_eq!(b.name(), model);
        }
    }
    assert_eq!(preset_names("phong"), None);
    assert_eq!(
        Sgd::preset("metallic-gold").map(|s| s.material().to_string()),
        Some("gold-metallic-paint".into()),
        "the SGD table's other names are accepted"
    );
}

/// Declared symmetries (isotropy, mirror, half-turn, reciprocity) on every preset, and values
/// finite and ≥ 0.
#[test]
fn declared_symmetries_hold_for_every_preset() {
    let ps = pairs_below_85(21, 60);
    for (model, n, b) in every_preset() {
        assert!(b.is_isotropic() && b.is_mirror_symmetric() && b.is_reciprocal());
        for (k, (wo, wi)) in ps.iter().enumerate() {
            let f = b.eval_rgb(wo, wi);
            assert!(f.iter().all(|v| v.is_finite() && *v >= 0.0), "{n}: {f:?}");
            let y = b.eval(wo, wi);
            let m = |v: &Vec3| Vec3::new(v.x, -v.y, v.z);
            let a = 0.3 + k as f64;
            for (what, other) in [
                ("reciprocity", b.eval(wi, wo)),
                ("mirror", b.eval(&m(wo), &m(wi))),
                ("rotation", b.eval(&rotate_z(wo, a), &rotate_z(wi, a))),
            ] {
                assert!(rel(y, other) < 1e-9, "{model}:{n} {what}: {y} vs {other}");
            }
        }
    }
}

/// Fits of real materials reflect a plausible amount of light: the luminance albedo at 30° of
/// every preset is in (0, 1.3) (fits are not constrained to conserve energy, hence the margin),
/// and the value is never below the diffuse term `kd/π`.
#[test]
fn albedos_are_plausible() {
    let wo = direction_from_angles(30.0, 0.0);
    for (model, n, b) in every_preset() {
        let a = brdf::directional_albedo(b.as_ref(), &wo, 48, 96);
        assert!(a > 0.0 && a < 1.3, "{model}:{n}: albedo {a}");
    }
    let abc = Abc::preset("white-diffuse-bball").expect("preset");
    let far = direction_from_angles(60.0, 180.0);
    let f = abc.eval_rgb(&direction_from_angles(60.0, 0.0), &far);
    let kd = abc.params().kd;
    for ch in 0..3 {
        assert!(f[ch] >= kd[ch] / std::f64::consts::PI, "{f:?}");
    }
}

#[test]
fn unknown_materials_list_close_matches() {
    match parse_spec("sgd:material=gold-metalic-paint") {
        Err(SpecError::UnknownMaterial {
            model, suggestions, ..
        }) => {
            assert_eq!(model, "sgd");
            assert_eq!(
                suggestions.first().map(String::as_str),
                Some("gold-metallic-paint")
            );
        }
        other => panic!("{:?}", other.map(|b| b.name().to_string())),
    }
    let msg = parse_spec("abc:material=chrom")
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        msg.contains("close matches") && msg.contains("chrome"),
        "{msg}"
    );
    assert!(matches!(
        parse_spec("abc"),
        Err(SpecError::MissingMaterial { model: "abc" })
    ));
    assert!(matches!(
        parse_spec("sgd:name=x"),
        Err(SpecError::UnknownKey { .. })
    ));
    assert!(matches!(
        parse_spec("sgd:gold"),
        Err(SpecError::Malformed { .. })
    ));
}

/// ABC declares a bounded horizon: its value at θi → 90° stays finite and close to the value
/// just before.
#[test]
fn horizon_behaviour_matches_the_declarations() {
    let wo = direction_from_angles(40.0, 0.0);
    for n in preset_names("abc").expect("presets") {
        let b = Abc::preset(n).expect("preset");
        assert!(b.bounded_at_horizon());
        let near = b.eval(&wo, &direction_from_angles(89.9, 90.0));
        let nearer = b.eval(&wo, &direction_from_angles(89.9999, 90.0));
        assert!(nearer <= 2.0 * near + 1e-9, "{n}: {near} → {nearer}");
    }
    // SGD keeps the safe declaration (`false`): `1/cos θi` is cancelled only where a fit's
    // shadowing term reaches 0 before the horizon.
    assert!(
        !Sgd::preset("aluminium")
            .expect("preset")
            .bounded_at_horizon()
    );
}
