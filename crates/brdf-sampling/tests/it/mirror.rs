//! Declared symmetries: a set evaluates half of each isotropic slice (mirror) or stores half
//! the azimuths of an anisotropic BRDF (half-turn), gives the same pdf as without them, and a
//! false mirror declaration is caught by the build's probe.

use std::sync::Arc;

use brdf::Vec3;
use brdf_sampling::{DirectionSampler, QuadTreeSet, SetError, SetOptions, Variant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn options(symmetries: bool) -> SetOptions {
    SetOptions {
        slices: 18,
        symmetries,
        ..SetOptions::default()
    }
}

fn random_direction(rng: &mut Xoshiro256PlusPlus) -> Vec3 {
    let z: f64 = rng.random_range(0.01..1.0);
    let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let s = (1.0 - z * z).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// `half` (built with symmetries) and `full` give the same pdf (relative 1e-4) at 2000 random
/// direction pairs of seed `seed`.
fn assert_same_pdfs(half: &QuadTreeSet, full: &QuadTreeSet, seed: u64, what: &str) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    for _ in 0..2000 {
        let (wo, wi) = (random_direction(&mut rng), random_direction(&mut rng));
        let (a, b) = (half.pdf(&wo, &wi), full.pdf(&wo, &wi));
        assert!(
            (a - b).abs() <= 1e-4 * b.max(1e-300),
            "{what}: pdf {a} with symmetries vs {b}"
        );
    }
}

#[test]
fn mirrored_sets_match_full_ones_for_about_half_the_evaluations() {
    for spec in ["phong:n=200", "htsg", "oren-nayar"] {
        let brdf: Arc<dyn brdf::Brdf> = Arc::from(brdf::parse_spec(spec).unwrap());
        assert!(brdf.is_mirror_symmetric(), "{spec}");
        let half = QuadTreeSet::build(brdf.clone(), Variant::Adaptive, &options(true)).unwrap();
        let full = QuadTreeSet::build(brdf, Variant::Adaptive, &options(false)).unwrap();
        let (h, f) = (half.grid_evaluations(), full.grid_evaluations());
        assert!(
            (h as f64) < 0.6 * f as f64,
            "{spec}: {h} evaluations mirrored vs {f}"
        );
        assert_same_pdfs(&half, &full, 3, spec);
    }
}

/// Isotropic but chiral: depends on the sign of `sin(φi − φo)`.
struct Chiral {
    declares: bool,
}

impl brdf::Brdf for Chiral {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        (1.0 + 0.5 * wo.cross(wi).z) / std::f64::consts::PI
    }
    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        self.declares
    }
}

#[test]
fn a_false_symmetry_declaration_is_a_typed_error() {
    let liar: Arc<dyn brdf::Brdf> = Arc::new(Chiral { declares: true });
    let err = QuadTreeSet::build(liar, Variant::Adaptive, &options(true)).unwrap_err();
    assert!(matches!(err, SetError::MirrorAsymmetry { .. }), "{err}");
    let honest: Arc<dyn brdf::Brdf> = Arc::new(Chiral { declares: false });
    QuadTreeSet::build(honest, Variant::Adaptive, &options(true)).unwrap();
}

#[test]
fn half_turn_sets_match_full_ones_with_half_the_trees() {
    // Anisotropic, half-turn symmetric: azimuths over [0, π) serve φo + π turned by π.
    let opts = |symmetries| SetOptions {
        anisotropic_slices: [6, 8],
        symmetries,
        ..SetOptions::default()
    };
    let brdf: Arc<dyn brdf::Brdf> =
        Arc::from(brdf::parse_spec("ward:alpha_x=0.08,alpha_y=0.3").unwrap());
    assert!(brdf.is_half_turn_symmetric() && !brdf.is_isotropic());
    let half = QuadTreeSet::build(brdf.clone(), Variant::Adaptive, &opts(true)).unwrap();
    let full = QuadTreeSet::build(brdf, Variant::Adaptive, &opts(false)).unwrap();
    assert_eq!((half.len(), full.len()), (24, 48));
    assert!(half.layout().half_turn && !full.layout().half_turn);
    assert_same_pdfs(&half, &full, 4, "half-turn");
}
