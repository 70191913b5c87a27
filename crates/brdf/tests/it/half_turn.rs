//! Each model's `is_half_turn_symmetric` declaration against a numerical check. With the
//! half-turn about the normal `R_π(x, y, z) = (−x, −y, z)`, a declaring model must satisfy, on
//! 2000 seeded random direction pairs (θ up to 89.9°, a quarter of them grazing),
//! `|f(R_π ωo, R_π ωi) − f(ωo, ωi)| ≤ 10⁻¹² max(1, |f|)`, for default parameters and for
//! anisotropic settings (which must really be anisotropic: a quarter-turn changes them).
//! An anisotropic BRDF with a term odd in `x` is the negative control: the same checker must
//! flag it.

use crate::common;

use brdf::{Brdf, MerlBrdf, Vec3, models, parse_spec, rotate_z};
use common::{close, direction_pairs};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2};

/// The half-turn about the normal, `(x, y, z) ↦ (−x, −y, z)`.
fn half_turn(v: &Vec3) -> Vec3 {
    Vec3::new(-v.x, -v.y, v.z)
}

/// The first pair that breaks half-turn symmetry, as `(ωo, ωi, a, b)` with `a = f(ωo, ωi)` and
/// `b = f(R_π ωo, R_π ωi)`. `None` when every pair passes.
fn find_half_turn_asymmetry(
    b: &dyn Brdf,
    pairs: &[(Vec3, Vec3)],
) -> Option<(Vec3, Vec3, f64, f64)> {
    pairs.iter().find_map(|(wo, wi)| {
        let a = b.eval(wo, wi);
        let t = b.eval(&half_turn(wo), &half_turn(wi));
        (!close(a, t)).then_some((*wo, *wi, a, t))
    })
}

/// Panics with the offending pair when a declaring model fails the check, and when it is
/// identically zero on the pairs (which would make the check vacuous).
fn assert_half_turn_symmetric(label: &str, b: &dyn Brdf, pairs: &[(Vec3, Vec3)]) {
    assert!(b.is_half_turn_symmetric(), "{label}: not declared");
    if let Some((wo, wi, a, t)) = find_half_turn_asymmetry(b, pairs) {
        panic!("{label}: f = {a:e} but turned {t:e} at ωo = {wo:?}, ωi = {wi:?}");
    }
    let peak = pairs
        .iter()
        .map(|(wo, wi)| b.eval(wo, wi))
        .fold(0.0, f64::max);
    assert!(peak > 0.0, "{label}: identically zero on the pairs");
}

/// Registry models that declare the symmetry with their default parameters, after checking
/// each declaration. Every analytic model declares it (isotropic ones trivially, the
/// anisotropic ones because their anisotropy is elliptical or, for Poulin–Fournier, because the
/// cylinder surface is even in x and in y).
#[test]
fn declarations_match_the_check() {
    let pairs = direction_pairs(0x7a1f_0001);
    let mut declared = Vec::new();
    for info in models() {
        if info.needs_argument() {
            continue; // needs a table; see `merl_tables_are_half_turn_symmetric`
        }
        let b = parse_spec(info.name).unwrap();
        if b.is_half_turn_symmetric() {
            declared.push(info.name);
            assert_half_turn_symmetric(info.name, b.as_ref(), &pairs);
        }
    }
    // Every analytic model of the registry, in registry order.
    let expected: Vec<&str> = models()
        .iter()
        .filter(|m| !m.needs_argument())
        .map(|m| m.name)
        .collect();
    assert_eq!(expected.len(), 20);
    println!("half-turn symmetric: {}", declared.join(", "));
    assert_eq!(declared, expected);
}

/// Anisotropic settings keep the declaration and pass the check; a quarter-turn about the
/// normal does change each of them somewhere on the pairs, so the check is not vacuous.
#[test]
fn anisotropic_settings_pass_the_check() {
    let pairs = direction_pairs(0x7a1f_0002);
    for spec in [
        "ward:alpha_x=0.05,alpha_y=0.3",
        "ward-original:alpha_x=0.05,alpha_y=0.3",
        "ashikhmin-shirley:nu=10,nv=1000",
        "ashikhmin-shirley:nu=500,nv=5,rs=0.3,rd=0.7",
        "ggx:alpha=0.1,alpha_y=0.4",
        "ggx:alpha=0.8,alpha_y=0.02,f0=0.9",
        "beckmann:alpha=0.1,alpha_y=0.4",
        "beckmann:alpha=0.6,alpha_y=0.05",
        "lafortune:cx=-1,cy=-0.5",
        "lafortune:cx=0.8,cy=-1.1,cz=0.6,n=30",
        "schlick-specular:p=0.2",
        "schlick-diffuse:p=0.05,r=0.1",
        "poulin-fournier",
        "poulin-fournier:d=3.5,n=200,ks=0.5,kd=0.3",
        "poulin-fournier:d=2.5,n=4,ks=0.8,kd=0.1",
    ] {
        let b = parse_spec(spec).unwrap();
        assert!(!b.is_isotropic(), "{spec}");
        assert_half_turn_symmetric(spec, b.as_ref(), &pairs);
        let quarter_turn_changes = pairs.iter().any(|(wo, wi)| {
            let a = b.eval(wo, wi);
            let q = b.eval(&rotate_z(wo, FRAC_PI_2), &rotate_z(wi, FRAC_PI_2));
            (a - q).abs() > 1e-6 * a.abs().max(1.0)
        });
        assert!(quarter_turn_changes, "{spec}: isotropic on the pairs");
    }
}

/// A MERL table with values depending on all of `(θh, θd, φd)` (and not even in `φd`) is
/// half-turn symmetric: the lookup ignores `φh`.
#[test]
fn merl_tables_are_half_turn_symmetric() {
    let pairs = direction_pairs(0x7a1f_0003);
    let table = MerlBrdf::from_fn(|th, td, pd| {
        let v = 0.2 + th + 0.5 * td + 0.3 * (1.0 + (3.0 * pd).sin());
        [v, 0.5 * v, 2.0 * v]
    });
    assert_half_turn_symmetric("merl", &table, &pairs);
}

/// Anisotropic and odd in `x`: `f = (1 + ½ ωi.x ωo.z)/π` (non-negative since
/// `|ωi.x ωo.z| ≤ 1`); the half-turn flips the sign of `ωi.x`.
struct OddInX;

impl Brdf for OddInX {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if wo.z > 0.0 && wi.z > 0.0 {
            FRAC_1_PI * (1.0 + 0.5 * wi.x * wo.z)
        } else {
            0.0
        }
    }
}

#[test]
fn the_check_sees_a_term_odd_in_x() {
    let pairs = direction_pairs(0x7a1f_0001);
    assert!(
        pairs.iter().all(|(wo, wi)| OddInX.eval(wo, wi) >= 0.0),
        "the control must be a valid (non-negative) BRDF"
    );
    assert!(
        !OddInX.is_half_turn_symmetric(),
        "the default must be false"
    );
    assert!(!OddInX.is_isotropic(), "the default must be false");
    let Some((wo, wi, a, t)) = find_half_turn_asymmetry(&OddInX, &pairs) else {
        panic!("a BRDF odd in x passed the half-turn check");
    };
    // The two values differ by ωi.x ωo.z/π, far above the tolerance.
    assert!((a - t).abs() > 1e-6, "{wo:?} {wi:?} {a} {t}");
    assert!(((a - t) - FRAC_1_PI * wi.x * wo.z).abs() < 1e-12, "{a} {t}");
}
