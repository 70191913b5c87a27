//! RGL `.bsdf` reader and evaluation on the real fixture (`data/measured/rgl/`), the other
//! shared materials when `../shared` is present, and malformed variants of the fixture.

use crate::common::pairs_below_85;
use brdf::measured::rgl::{self, RglBrdf, RglError};
use brdf::measured::tensor::{DTYPE_F32, TensorFile};
use brdf::{
    Brdf, SpecError, Vec3, direction_from_angles, directional_albedo, parse_spec, rotate_z,
};
use proptest::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::path::PathBuf;

fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixture_path() -> PathBuf {
    repo_root().join("data/measured/rgl/paper_white_rgb.bsdf")
}

fn fixture_bytes() -> Vec<u8> {
    std::fs::read(fixture_path()).expect("the RGL fixture is in the repository")
}

fn fixture() -> RglBrdf {
    RglBrdf::from_bytes(&fixture_bytes()).expect("fixture reads")
}

/// The shared RGL materials (`../shared/data/measured/rgl/*.bsdf`), or `None` with a notice.
fn shared_materials() -> Option<Vec<PathBuf>> {
    let dir = repo_root().join("../shared/data/measured/rgl");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        println!(
            "notice: {} absent, shared RGL materials skipped",
            dir.display()
        );
        return None;
    };
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .collect();
    v.sort();
    Some(v)
}

#[test]
fn fixture_header_and_tables() {
    let b = fixture();
    assert_eq!(b.description(), "White A4 paper (160 gsm)");
    assert_eq!(b.theta_slices().len(), 8);
    approx::assert_abs_diff_eq!(b.theta_slices()[0], 0.0);
    approx::assert_abs_diff_eq!(
        b.theta_slices()[7],
        std::f64::consts::FRAC_PI_2,
        epsilon = 1e-6
    );
    assert_eq!(b.clamped(), None, "paper_white has no negative entries");
    assert!(b.is_isotropic() && b.is_half_turn_symmetric());
    assert!(!b.is_reciprocal() && !b.bounded_at_horizon());
    let spec = format!("rgl:{}", fixture_path().display());
    let parsed = parse_spec(&spec).expect("spec parses");
    assert_eq!(parsed.name(), "rgl");
    let wo = direction_from_angles(30.0, 10.0);
    let wi = direction_from_angles(50.0, 200.0);
    assert_eq!(parsed.eval(&wo, &wi), b.eval(&wo, &wi));
}

/// The VNDF warp of the real data is a bijection: sampling the inverse of a half-vector
/// coordinate gives it back, and the two report the same density.
#[test]
fn vndf_warp_round_trips_on_real_data() {
    let b = fixture();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    for _ in 0..2000 {
        let theta = 1.5 * rng.random::<f64>();
        let u = [rng.random::<f64>(), rng.random::<f64>()];
        let (p, pdf) = b.vndf().sample(u, theta);
        if pdf < 1e-6 {
            continue;
        }
        let (back, pdf2) = b.vndf().invert(p, theta);
        approx::assert_abs_diff_eq!(back[0], u[0], epsilon = 1e-7);
        approx::assert_abs_diff_eq!(back[1], u[1], epsilon = 1e-7);
        approx::assert_relative_eq!(pdf, pdf2, max_relative = 1e-7);
    }
}

/// Independent plausibility: white paper reflects 70–95 % of the light in every channel at
/// every angle (its albedo by quadrature of f·cos), the values are positive and finite.
#[test]
fn white_paper_albedo_is_plausible() {
    let b = fixture();
    for th in [0.0, 30.0, 60.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        let a = directional_albedo(&b, &wo, 64, 128);
        assert!((0.7..0.95).contains(&a), "θo {th}: albedo {a}");
    }
    for (wo, wi) in pairs_below_85(3, 2000) {
        let f = b.eval_rgb(&wo, &wi);
        assert!(f.iter().all(|v| v.is_finite() && *v > 0.0), "{f:?}");
        // The luminance table gives the luminance of the RGB value.
        approx::assert_relative_eq!(b.eval(&wo, &wi), brdf::luminance(f), max_relative = 1e-12);
    }
}

/// Helmholtz reciprocity is not built into the format, but a measured diffuse-like material
/// is close to reciprocal: the median relative asymmetry is small. This also catches a
/// missing or doubled `cos θi` (either makes f(ωo, ωi)/f(ωi, ωo) = cos ratio, far from 1).
#[test]
fn paper_is_nearly_reciprocal() {
    let b = fixture();
    let mut rel: Vec<f64> = pairs_below_85(5, 3000)
        .iter()
        .filter(|(wo, wi)| wo.z > 0.2 && wi.z > 0.2)
        .map(|(wo, wi)| {
            let (a, c) = (b.eval(wo, wi), b.eval(wi, wo));
            (a - c).abs() / (a + c)
        })
        .collect();
    rel.sort_by(f64::total_cmp);
    let median = rel[rel.len() / 2];
    assert!(median < 0.02, "median asymmetry {median}");
}

#[test]
fn declared_isotropy_holds() {
    let b = fixture();
    let mut worst: f64 = 0.0;
    for (k, (wo, wi)) in pairs_below_85(7, 2000).iter().enumerate() {
        let angle = 0.37 + k as f64;
        let (a, r) = (
            b.eval(wo, wi),
            b.eval(&rotate_z(wo, angle), &rotate_z(wi, angle)),
        );
        worst = worst.max((a - r).abs() / a.max(1e-12));
    }
    assert!(worst < 1e-6, "worst relative change under rotation {worst}");
}

/// The prepared evaluation (one `atan2`, the half vector's azimuth turned into `ωo`'s frame)
/// agrees with the format's coordinates computed pair by pair (`half_coords`, two `atan2`s),
/// and `eval` is `eval_prepared` of `prepare`, bit for bit. Also at the normal, where `φo`
/// is undefined.
#[test]
fn prepared_evaluation_matches_the_pairwise_coordinates() {
    let b = fixture();
    let mut pairs = pairs_below_85(21, 20_000);
    pairs.push((Vec3::new(0.0, 0.0, 1.0), direction_from_angles(40.0, 75.0)));
    let mut worst: f64 = 0.0;
    for (wo, wi) in pairs {
        let q = b.prepare(&wo);
        let fast = b.eval_prepared(&q, &wi);
        assert_eq!(fast.to_bits(), b.eval(&wo, &wi).to_bits());
        let c = RglBrdf::half_coords(&wo, &wi).expect("both above the horizon");
        let reference = b.luminance_cos_at(&c) / wi.z;
        let rgb = b.eval_rgb(&wo, &wi);
        let rgb_ref = b.rgb_cos_at(&c).map(|v| v / wi.z);
        for (x, r) in std::iter::once((fast, reference)).chain(rgb.into_iter().zip(rgb_ref)) {
            assert!(x.is_finite() && x >= 0.0);
            worst = worst.max((x - r).abs() / r.abs().max(1e-3));
        }
    }
    assert!(worst < 1e-9, "worst relative difference {worst}");
    // An `Outgoing` this BRDF did not prepare gives a finite value ≥ 0, never a panic.
    let wi = direction_from_angles(30.0, 10.0);
    for cache in [
        [1.0; 8],
        [1.0, 0.0, 0.0, 1e300, f64::NAN, 0.0, 0.0, 0.0],
        [-5.0; 8],
    ] {
        let q = brdf::Outgoing::with_cache(direction_from_angles(20.0, 0.0), cache);
        let v = b.eval_prepared(&q, &wi);
        assert!(v.is_finite() && v >= 0.0, "{cache:?}: {v}");
    }
}

#[test]
fn below_the_horizon_is_zero() {
    let b = fixture();
    let up = direction_from_angles(30.0, 0.0);
    let down = Vec3::new(0.3, 0.1, -0.5).normalize();
    assert_eq!(b.eval_rgb(&up, &down), [0.0; 3]);
    assert_eq!(b.eval_rgb(&down, &up), [0.0; 3]);
    assert_eq!(b.eval(&Vec3::new(f64::NAN, 0.0, 1.0), &up), 0.0);
}

/// Every shared material (when `../shared` is present) reads within the time goal's order of
/// magnitude and has a finite, positive albedo; the one with negative entries reports them.
#[test]
fn shared_materials_read() {
    let Some(paths) = shared_materials() else {
        return;
    };
    assert_eq!(paths.len(), 4);
    for p in paths {
        let b = RglBrdf::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let wo = direction_from_angles(30.0, 0.0);
        let a = directional_albedo(&b, &wo, 48, 96);
        assert!(a > 0.05 && a < 1.2, "{}: albedo {a}", p.display());
        if p.ends_with("cc_ibiza_sunset_rgb.bsdf") {
            let c = b.clamped().expect("ibiza has negative entries");
            assert!(c.count > 0 && c.min < 0.0 && c.min > -0.1, "{c:?}");
        }
    }
}

// ---- malformed files -------------------------------------------------------------------

/// One field of a tensor file, with its raw data.
struct Raw {
    name: String,
    dtype: u8,
    shape: Vec<usize>,
    data: Vec<u8>,
}

fn raw_fields(bytes: &[u8]) -> Vec<Raw> {
    let tf = TensorFile::parse(bytes).expect("fixture parses");
    tf.fields()
        .iter()
        .map(|f| {
            let size = if f.dtype == DTYPE_F32 { 4 } else { 1 };
            let n = f.len().expect("small") * size;
            Raw {
                name: f.name.clone(),
                dtype: f.dtype,
                shape: f.shape.clone(),
                data: bytes[f.offset..f.offset + n].to_vec(),
            }
        })
        .collect()
}

fn write_tensor(fields: &[Raw], version: (u8, u8)) -> Vec<u8> {
    let header: usize = 18
        + fields
            .iter()
            .map(|f| 2 + f.name.len() + 2 + 1 + 8 + 8 * f.shape.len())
            .sum::<usize>();
    let mut out = b"tensor_file\0".to_vec();
    out.extend([version.0, version.1]);
    out.extend((fields.len() as u32).to_le_bytes());
    let mut offset = header;
    for f in fields {
        out.extend((f.name.len() as u16).to_le_bytes());
        out.extend(f.name.as_bytes());
        out.extend((f.shape.len() as u16).to_le_bytes());
        out.push(f.dtype);
        out.extend((offset as u64).to_le_bytes());
        for &e in &f.shape {
            out.extend((e as u64).to_le_bytes());
        }
        offset += f.data.len();
    }
    for f in fields {
        out.extend(&f.data);
    }
    out
}

fn edited(edit: impl FnOnce(&mut Vec<Raw>)) -> Result<RglBrdf, RglError> {
    let mut fields = raw_fields(&fixture_bytes());
    edit(&mut fields);
    RglBrdf::from_bytes(&write_tensor(&fields, (1, 0)))
}

fn field<'a>(fields: &'a mut [Raw], name: &str) -> &'a mut Raw {
    fields.iter_mut().find(|f| f.name == name).expect("field")
}

fn set_f32(f: &mut Raw, index: usize, v: f32) {
    f.data[4 * index..4 * index + 4].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn rewritten_fixture_reads_identically() {
    let b = edited(|_| {}).expect("identity rewrite");
    let a = fixture();
    for (wo, wi) in pairs_below_85(9, 50) {
        assert_eq!(a.eval_rgb(&wo, &wi), b.eval_rgb(&wo, &wi));
    }
}

#[test]
fn bad_headers_are_typed_errors() {
    let bytes = fixture_bytes();
    let mut garbage = bytes.clone();
    garbage[0] = b'X';
    assert!(matches!(
        RglBrdf::from_bytes(&garbage),
        Err(RglError::BadMagic)
    ));
    let fields = raw_fields(&bytes);
    assert!(matches!(
        RglBrdf::from_bytes(&write_tensor(&fields, (2, 0))),
        Err(RglError::UnsupportedVersion { major: 2, minor: 0 })
    ));
    for cut in [0, 5, 13, 17, 30, 200, 411, 5000, bytes.len() - 1] {
        let r = RglBrdf::from_bytes(&bytes[..cut]);
        assert!(
            matches!(r, Err(RglError::Truncated { .. })),
            "cut {cut}: {r:?}"
        );
    }
    assert!(matches!(
        RglBrdf::from_bytes(b"hello"),
        Err(RglError::Truncated { .. })
    ));
}

#[test]
fn inconsistent_fields_are_typed_errors() {
    let r = edited(|f| f.retain(|x| x.name != "vndf"));
    assert!(
        matches!(r, Err(RglError::MissingField { ref name }) if name == "vndf"),
        "{r:?}"
    );
    // rgb with a wrong channel count (same number of bytes).
    let r = edited(|f| field(f, "rgb").shape = vec![1, 8, 1, 96, 32]);
    assert!(
        matches!(r, Err(RglError::WrongShape { ref field, .. }) if field == "rgb"),
        "{r:?}"
    );
    // luminance slices that do not match theta_i.
    let r = edited(|f| field(f, "luminance").shape = vec![1, 4, 64, 32]);
    assert!(matches!(r, Err(RglError::WrongShape { ref field, .. }) if field == "luminance"));
    let r = edited(|f| field(f, "sigma").dtype = 1);
    assert!(matches!(
        r,
        Err(RglError::WrongType { .. }) | Err(RglError::Truncated { .. })
    ));
    let r = edited(|f| {
        let p = field(f, "phi_i");
        p.shape = vec![2];
        p.data.extend(1.0f32.to_le_bytes());
    });
    assert!(
        matches!(r, Err(RglError::Anisotropic { n_phi: 2 })),
        "{r:?}"
    );
    let r = edited(|f| set_f32(field(f, "theta_i"), 3, 0.1));
    assert!(matches!(r, Err(RglError::OutOfRange { ref field, .. }) if field == "theta_i"));
}

#[test]
fn bad_values_are_typed_errors_and_negatives_are_clamped() {
    let r = edited(|f| set_f32(field(f, "vndf"), 1234, f32::NAN));
    assert!(matches!(r, Err(RglError::NonFinite { ref field, index: 1234 }) if field == "vndf"));
    let r = edited(|f| set_f32(field(f, "luminance"), 10, -1.0));
    assert!(matches!(r, Err(RglError::OutOfRange { ref field, .. }) if field == "luminance"));
    let r = edited(|f| set_f32(field(f, "sigma"), 0, 0.0));
    assert!(matches!(r, Err(RglError::OutOfRange { ref field, .. }) if field == "sigma"));
    let r = edited(|f| {
        let v = field(f, "vndf");
        for i in 0..128 * 128 {
            set_f32(v, i, 0.0);
        }
    });
    assert!(
        matches!(r, Err(RglError::ZeroSlice { slice: 0, .. })),
        "{r:?}"
    );
    let b = edited(|f| {
        let v = field(f, "rgb");
        set_f32(v, 7, -0.08);
        set_f32(v, 900, -0.02);
    })
    .expect("negative rgb entries are clamped, not refused");
    let c = b.clamped().expect("reported");
    assert_eq!(c.count, 2);
    approx::assert_abs_diff_eq!(c.min, -0.08, epsilon = 1e-7);
}

#[test]
fn spec_errors_name_the_file() {
    assert!(matches!(
        parse_spec("rgl"),
        Err(SpecError::MissingFile { model: "rgl" })
    ));
    let e = parse_spec("rgl:/nonexistent/x.bsdf")
        .err()
        .map(|e| e.to_string());
    assert!(e.is_some_and(|e| e.contains("/nonexistent/x.bsdf")));
}

#[test]
fn coordinate_maps_invert_each_other() {
    for k in 0..50 {
        let t = k as f64 / 49.0 * std::f64::consts::FRAC_PI_2;
        approx::assert_abs_diff_eq!(rgl::u_to_theta(rgl::theta_to_u(t)), t, epsilon = 1e-12);
        let p = -3.0 + 6.0 * k as f64 / 49.0;
        approx::assert_abs_diff_eq!(rgl::u_to_phi(rgl::phi_to_u(p)), p, epsilon = 1e-12);
        let d = direction_from_angles(t.to_degrees(), 33.0);
        approx::assert_abs_diff_eq!(rgl::elevation(&d), t, epsilon = 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    /// Random byte edits of the header and random truncations never panic.
    #[test]
    fn fuzzed_files_never_panic(edits in proptest::collection::vec((0usize..600, any::<u8>()), 1..8),
                                cut in 0usize..700_000) {
        let mut bytes = fixture_bytes();
        for (i, v) in edits {
            bytes[i] = v;
        }
        bytes.truncate(cut);
        let _ = RglBrdf::from_bytes(&bytes);
    }
}

// ---- absurd but finite tables (issue 27), memory bounded by the file -------------------

/// `f·cos` at a few direction pairs: finite and non-negative for any file that reads.
fn evaluations_are_finite(b: &RglBrdf) {
    for (wo, wi) in pairs_below_85(21, 12) {
        let v = b.eval(&wo, &wi);
        assert!(v.is_finite() && v >= 0.0, "eval {v}");
        for c in b.eval_rgb(&wo, &wi) {
            assert!(c.is_finite() && c >= 0.0, "eval_rgb {c}");
        }
    }
}

fn is_implausible(r: &Result<RglBrdf, RglError>, name: &str) -> bool {
    matches!(r, Err(RglError::Implausible { field, .. }) if field == name)
}

/// Single values set to 1e38 (or σ to 1e-30) in each table: each breaks one of the physical
/// rules and gets a typed error at read time instead of a build running for minutes.
#[test]
fn absurd_but_finite_values_are_refused() {
    let r = edited(|f| set_f32(field(f, "rgb"), 5, 1e38));
    assert!(is_implausible(&r, "rgb"), "{:?}", r.as_ref().err());
    let r = edited(|f| set_f32(field(f, "ndf"), 3, 1e38));
    assert!(is_implausible(&r, "ndf"), "{:?}", r.as_ref().err());
    let r = edited(|f| set_f32(field(f, "sigma"), 5, 1e38));
    assert!(is_implausible(&r, "sigma"), "{:?}", r.as_ref().err());
    let r = edited(|f| set_f32(field(f, "sigma"), 200, 1e-30));
    assert!(is_implausible(&r, "sigma"), "{:?}", r.as_ref().err());
    for name in ["vndf", "luminance"] {
        let r = edited(|f| {
            for i in 0..4 {
                set_f32(field(f, name), 17 * i, 1e38);
            }
        });
        assert!(is_implausible(&r, name), "{name}: {:?}", r.as_ref().err());
    }
    // Large but plausible values still read (an rgb spike of 1000 in one cell keeps every
    // slice's albedo below the limit) and evaluate to finite values.
    let b = edited(|f| set_f32(field(f, "rgb"), 5, 1000.0)).expect("a plausible spike reads");
    evaluations_are_finite(&b);
}

/// The mutants of issue 27: 200 of the fixture's 4-byte words set to 1e38 (fixed seeds).
/// Before the physical checks most of them were accepted and `sample --sampler adaptive`
/// on them ran for minutes (anisotropic layout from a spiked `ndf`/`sigma`, trees at full
/// depth around every spike); now every one gets a typed error at read time.
#[test]
fn words_set_to_1e38_are_refused_at_read_time() {
    let original = fixture_bytes();
    let mut implausible = 0;
    for seed in 0..12 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut bytes = original.clone();
        for _ in 0..200 {
            let i = 4 * rng.random_range(0..bytes.len() / 4);
            bytes[i..i + 4].copy_from_slice(&1e38f32.to_le_bytes());
        }
        let r = RglBrdf::from_bytes(&bytes);
        assert!(r.is_err(), "seed {seed}: a 1e38 mutant was accepted");
        implausible += usize::from(matches!(r, Err(RglError::Implausible { .. })));
    }
    // Most words land in the tables (the header is 0.05 % of the file).
    assert!(
        implausible >= 10,
        "{implausible} of 12 refused by the physical rules"
    );
}

/// A tiny file whose one field claims 2^40 elements gets a typed error without allocating.
#[test]
fn a_claim_of_2_pow_40_elements_is_refused_before_allocating() {
    let huge = Raw {
        name: "rgb".into(),
        dtype: DTYPE_F32,
        shape: vec![1 << 20, 1 << 20],
        data: vec![0; 64],
    };
    let bytes = write_tensor(&[huge], (1, 0));
    let t = std::time::Instant::now();
    let r = RglBrdf::from_bytes(&bytes);
    assert!(matches!(r, Err(RglError::Truncated { .. })), "{r:?}");
    assert!(t.elapsed().as_secs_f64() < 0.5);
    // Many distinct field names: the duplicate check stays linear (65,536 fields, 1 MB).
    let fields: Vec<Raw> = (0..65_536u32)
        .map(|k| Raw {
            name: format!("{:04x}", k),
            dtype: 1,
            shape: vec![0],
            data: Vec::new(),
        })
        .collect();
    let bytes = write_tensor(&fields, (1, 0));
    let t = std::time::Instant::now();
    assert!(matches!(
        TensorFile::parse(&bytes),
        Ok(ref tf) if tf.fields().len() == 65_536
    ));
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
}

/// Special values in every kind of position of the fixture (fixed seeds): no panic, and a file
/// that reads evaluates to finite non-negative values.
const SPECIAL: [f32; 9] = [
    f32::NAN,
    f32::INFINITY,
    -1.0,
    1e38,
    -1e38,
    f32::MAX,
    0.0,
    1e-38,
    7.5,
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]
    #[test]
    fn special_words_and_bytes_give_a_typed_error_or_a_valid_material(
        words in proptest::collection::vec((0usize..164_732, 0usize..SPECIAL.len()), 0..40),
        bytes in proptest::collection::vec((0usize..658_928, any::<u8>()), 0..4),
        cut in proptest::option::of(0usize..658_928),
    ) {
        let mut b = fixture_bytes();
        for (w, k) in words {
            b[4 * w..4 * w + 4].copy_from_slice(&SPECIAL[k].to_le_bytes());
        }
        for (i, v) in bytes {
            b[i] = v;
        }
        if let Some(c) = cut {
            b.truncate(c);
        }
        if let Ok(m) = RglBrdf::from_bytes(&b) {
            evaluations_are_finite(&m);
        }
    }
}
