//! MERL reader, lookup and writer on synthetic files (no MERL data is shipped).

use brdf::merl::{
    self, CELLS, CHANNEL_SCALE, FILE_BYTES, MerlIndex, RES_PHI_D, RES_THETA_D, RES_THETA_H,
};
use brdf::models::Lambert;
use brdf::{Brdf, MerlBrdf, MerlError, Vec3, luminance, parse_spec, rotate_z};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

/// Raw table whose values encode their own bin: R = flat index, G = θh bin, B = 1000 θd + φd
/// (so the expected lookup can be predicted exactly). Every 7th cell is marked unmeasured by
/// negating its green channel.
fn index_table() -> Vec<f64> {
    let mut raw = vec![0.0; 3 * CELLS];
    for th in 0..RES_THETA_H {
        for td in 0..RES_THETA_D {
            for pd in 0..RES_PHI_D {
                let idx = pd + RES_PHI_D * td + RES_PHI_D * RES_THETA_D * th;
                raw[idx] = idx as f64;
                raw[CELLS + idx] = if idx.is_multiple_of(7) {
                    -(th as f64) - 1.0
                } else {
                    th as f64
                };
                raw[2 * CELLS + idx] = (1000 * td + pd) as f64;
            }
        }
    }
    raw
}

/// Independent computation of the expected bin: the difference vector is the light direction
/// expressed in the frame (u, v, h) obtained by rotating the standard axes by Rz(φh)·Ry(θh);
/// indices by the hand-written MERL formulas. Returns `None` near a bin edge (where two
/// floating-point paths may legitimately round differently).
fn expected_bin(wo: &Vec3, wi: &Vec3) -> Option<(usize, usize, usize)> {
    let s = wo + wi;
    let h = s / s.norm();
    let theta_h = (h.x.hypot(h.y)).atan2(h.z);
    let phi_h = h.y.atan2(h.x);
    let u = Vec3::new(
        theta_h.cos() * phi_h.cos(),
        theta_h.cos() * phi_h.sin(),
        -theta_h.sin(),
    );
    let v = Vec3::new(-phi_h.sin(), phi_h.cos(), 0.0);
    let (du, dv, dh) = (wi.dot(&u), wi.dot(&v), wi.dot(&h));
    let theta_d = (du.hypot(dv)).atan2(dh);
    let mut phi_d = dv.atan2(du);
    if phi_d < 0.0 {
        phi_d += PI;
    }
    let xh = (theta_h / FRAC_PI_2).sqrt() * 90.0;
    let xd = theta_d / FRAC_PI_2 * 90.0;
    let xp = phi_d / PI * 180.0;
    let near_edge = |x: f64| (x - x.round()).abs() < 1e-7;
    if near_edge(xh) || near_edge(xd) || near_edge(xp) {
        return None;
    }
    Some((
        (xh as usize).min(89),
        (xd as usize).min(89),
        (xp as usize).min(179),
    ))
}

fn random_dir(rng: &mut Xoshiro256PlusPlus) -> Vec3 {
    let ct: f64 = rng.random_range(1e-3..1.0);
    let phi: f64 = rng.random_range(0.0..2.0 * PI);
    let st = (1.0 - ct * ct).sqrt();
    Vec3::new(st * phi.cos(), st * phi.sin(), ct)
}

fn write_bytes(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn lookup_matches_independent_index_computation() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("index.binary");
    let table = MerlBrdf::from_raw(&index_table()).unwrap();
    table.write(&path).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len() as usize, FILE_BYTES);
    // No temporary files are left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    let m = MerlBrdf::load(&path).unwrap();
    assert_eq!(m.unmeasured_count(), CELLS.div_ceil(7));

    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2024);
    let mut checked = 0;
    let mut small_theta_h = 0;
    for _ in 0..20_000 {
        let (wo, wi) = (random_dir(&mut rng), random_dir(&mut rng));
        let Some((th, td, pd)) = expected_bin(&wo, &wi) else {
            continue;
        };
        let idx = pd + 180 * td + 180 * 90 * th;
        let raw = m.lookup_raw_rgb(&wo, &wi);
        assert_eq!(
            raw[0],
            idx as f64 * CHANNEL_SCALE[0],
            "R (flat index) for {wo:?} {wi:?}"
        );
        let g = if idx.is_multiple_of(7) {
            -(th as f64) - 1.0
        } else {
            th as f64
        };
        assert_eq!(raw[1], g * CHANNEL_SCALE[1]);
        assert_eq!(raw[2], (1000 * td + pd) as f64 * CHANNEL_SCALE[2]);
        // Clamping policy and the measured flag.
        assert_eq!(m.is_measured(&wo, &wi), !idx.is_multiple_of(7));
        let rgb = m.eval_rgb(&wo, &wi);
        assert_eq!(rgb[1], g.max(0.0) * CHANNEL_SCALE[1]);
        assert_eq!(m.eval(&wo, &wi), luminance(rgb));
        // Reciprocity and isotropy of the lookup.
        assert_eq!(merl::index_of(&wi, &wo), merl::index_of(&wo, &wi));
        let a = rng.random_range(0.0..2.0 * PI);
        assert_eq!(
            merl::index_of(&rotate_z(&wo, a), &rotate_z(&wi, a)),
            merl::index_of(&wo, &wi)
        );
        if th < 10 {
            small_theta_h += 1;
        }
        checked += 1;
    }
    assert!(checked > 19_000, "too many edge cases skipped: {checked}");
    assert!(small_theta_h > 0);
}

#[test]
fn theta_h_index_is_nonlinear_and_phi_d_folds() {
    // θh = (π/2)(i/90)² starts bin i.
    for i in [0usize, 1, 2, 10, 45, 89] {
        let start = FRAC_PI_2 * (i as f64 / 90.0).powi(2);
        let mid = FRAC_PI_2 * ((i as f64 + 0.5) / 90.0).powi(2);
        assert_eq!(merl::index_from_angles(mid, 0.3, 0.1).theta_h, i);
        if i > 0 {
            assert_eq!(
                merl::index_from_angles(start * (1.0 + 1e-9), 0.3, 0.1).theta_h,
                i
            );
            assert_eq!(
                merl::index_from_angles(start * (1.0 - 1e-9), 0.3, 0.1).theta_h,
                i - 1
            );
        }
    }
    // First bin spans about 0.011°.
    assert_eq!(
        merl::index_from_angles(0.0111f64.to_radians(), 0.0, 0.0).theta_h,
        0
    );
    assert_eq!(
        merl::index_from_angles(0.0112f64.to_radians(), 0.0, 0.0).theta_h,
        1
    );
    // φd < 0 folds by +π.
    let a = merl::index_from_angles(0.5, 0.5, -0.25);
    let b = merl::index_from_angles(0.5, 0.5, PI - 0.25);
    assert_eq!(a, b);
    // Clamping at the ends.
    let e = merl::index_from_angles(FRAC_PI_2, FRAC_PI_2, PI);
    assert_eq!(
        e,
        MerlIndex {
            theta_h: 89,
            theta_d: 89,
            phi_d: 179
        }
    );
    assert_eq!(MerlIndex::from_flat(e.flat()), e);
}

#[test]
fn tabulated_analytic_model_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blinn.binary");
    let model = parse_spec("blinn:n=20,ks=0.5,kd=0.3").unwrap();
    MerlBrdf::tabulate(model.as_ref()).write(&path).unwrap();
    let m = parse_spec(&format!("merl:{}", path.display())).unwrap();
    assert_eq!(m.name(), "merl");
    assert!(m.is_isotropic() && m.is_reciprocal());
    // At every bin centre the table reproduces the analytic value.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let mut n = 0;
    while n < 2000 {
        let idx = MerlIndex {
            theta_h: rng.random_range(0..90),
            theta_d: rng.random_range(0..90),
            phi_d: rng.random_range(0..180),
        };
        let (th, td, pd) = merl::bin_center(idx);
        let (wo, wi) = merl::half_diff_to_directions(th, td, pd);
        if wo.z <= 1e-6 || wi.z <= 1e-6 {
            continue;
        }
        assert_eq!(merl::index_of(&wo, &wi), idx);
        let (a, b) = (m.eval(&wo, &wi), model.eval(&wo, &wi));
        assert!((a - b).abs() <= 1e-12 * b.abs(), "{idx:?}: {a} vs {b}");
        n += 1;
    }
}

#[test]
fn below_horizon_cells_are_unmeasured_and_read_as_zero() {
    let lambert = Lambert::default();
    let m = MerlBrdf::tabulate(&lambert);
    assert!(m.unmeasured_count() > 0 && m.unmeasured_count() < CELLS);
    let v = 0.8 / PI;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    for _ in 0..2000 {
        let (wo, wi) = (random_dir(&mut rng), random_dir(&mut rng));
        let f = m.eval(&wo, &wi);
        if m.is_measured(&wo, &wi) {
            assert!((f - v).abs() < 1e-12);
        } else {
            assert_eq!(f, 0.0);
            assert!(m.lookup_raw_rgb(&wo, &wi).iter().all(|&c| c < 0.0));
        }
    }
    // write_merl tabulates a function of the half/difference angles.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fn.binary");
    merl::write_merl(&p, &|th, _td, _pd| [th, 2.0 * th, -1.0]).unwrap();
    let back = MerlBrdf::load(&p).unwrap();
    assert_eq!(back.unmeasured_count(), CELLS);
    let idx = MerlIndex {
        theta_h: 30,
        theta_d: 5,
        phi_d: 7,
    };
    let (th, _, _) = merl::bin_center(idx);
    let c = back.cell(idx);
    assert!((c[0] - th).abs() < 1e-15 && (c[1] - 2.0 * th).abs() < 1e-15 && c[2] < 0.0);
}

#[test]
fn every_error_variant() {
    let dir = tempfile::tempdir().unwrap();
    let good = MerlBrdf::from_fn(|_, _, _| [1.0, 1.0, 1.0]).to_bytes();
    assert_eq!(good.len(), FILE_BYTES);

    // Truncated data and truncated header.
    let p = write_bytes(dir.path(), "trunc", &good[..good.len() - 100]);
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::Truncated { expected: FILE_BYTES, actual }) if actual == FILE_BYTES - 100
    ));
    let p = write_bytes(dir.path(), "header", &good[..5]);
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::Truncated {
            expected: 12,
            actual: 5
        })
    ));

    // Trailing bytes.
    let mut longer = good.clone();
    longer.extend_from_slice(&[0u8; 8]);
    let p = write_bytes(dir.path(), "long", &longer);
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::WrongSize { .. })
    ));

    // Dims whose product is wrong, negative dims, and a permuted layout.
    let with_dims = |d: [i32; 3]| {
        let mut b = good.clone();
        for (k, v) in d.iter().enumerate() {
            b[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        b
    };
    let p = write_bytes(dir.path(), "dims", &with_dims([90, 90, 90]));
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::DimsProduct {
            product: 729_000,
            ..
        })
    ));
    let p = write_bytes(dir.path(), "neg", &with_dims([-90, -90, 180]));
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::DimsProduct { .. })
    ));
    let p = write_bytes(dir.path(), "perm", &with_dims([180, 90, 90]));
    assert!(matches!(
        MerlBrdf::load(&p),
        Err(MerlError::WrongDims {
            dims: [180, 90, 90]
        })
    ));

    // NaN and infinity, reported with channel and cell.
    for (value, channel, cell) in [(f64::NAN, 1usize, 12_345usize), (f64::INFINITY, 2, 0)] {
        let mut b = good.clone();
        let off = 12 + 8 * (channel * CELLS + cell);
        b[off..off + 8].copy_from_slice(&value.to_le_bytes());
        let p = write_bytes(dir.path(), "nan", &b);
        match MerlBrdf::load(&p) {
            Err(MerlError::NonFinite {
                channel: c, index, ..
            }) => {
                assert_eq!((c, index), (channel, cell));
            }
            other => panic!("expected NonFinite, got {other:?}"),
        }
    }

    // Missing file; raw table of the wrong length; writing into a missing directory.
    assert!(matches!(
        MerlBrdf::load(&dir.path().join("none")),
        Err(MerlError::Io { .. })
    ));
    assert!(matches!(
        MerlBrdf::from_raw(&[0.0; 10]),
        Err(MerlError::RawLength { .. })
    ));
    let bad = dir.path().join("no/such/dir/out.binary");
    assert!(matches!(
        MerlBrdf::from_fn(|_, _, _| [0.0; 3]).write(&bad),
        Err(MerlError::Io { .. })
    ));
    // Error messages name the problem.
    let msg = MerlError::DimsProduct {
        dims: [1, 2, 3],
        product: 6,
    }
    .to_string();
    assert!(msg.contains("1458000"), "{msg}");
}

#[test]
fn half_diff_round_trip() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    for _ in 0..1000 {
        let (wo, wi) = (random_dir(&mut rng), random_dir(&mut rng));
        let (th, td, pd) = merl::half_diff_angles(&wo, &wi);
        let (o2, i2) = merl::half_diff_to_directions(th, td, pd);
        // Equal up to the rotation by φh about the normal.
        let phi_h = (wo + wi).y.atan2((wo + wi).x);
        assert!((rotate_z(&o2, phi_h) - wo).norm() < 1e-9);
        assert!((rotate_z(&i2, phi_h) - wi).norm() < 1e-9);
    }
}

/// A 12-byte header claiming 2^40 cells (or the legal dims without data) gets a typed error
/// before any allocation: the dims are checked first, then the file size.
#[test]
fn huge_claims_are_refused_before_allocating() {
    let header = |d: [i32; 3]| d.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    let t = std::time::Instant::now();
    let r = MerlBrdf::from_bytes(&header([1 << 20, 1 << 20, 1]));
    assert!(matches!(r, Err(MerlError::DimsProduct { .. })), "{r:?}");
    let r = MerlBrdf::from_bytes(&header([90, 90, 180]));
    assert!(
        matches!(r, Err(MerlError::Truncated { actual: 12, .. })),
        "{r:?}"
    );
    assert!(t.elapsed().as_secs_f64() < 0.5);
}

mod bytes {
    use super::*;
    use proptest::prelude::*;
    use std::sync::OnceLock;

    fn good() -> &'static [u8] {
        static GOOD: OnceLock<Vec<u8>> = OnceLock::new();
        GOOD.get_or_init(|| MerlBrdf::from_fn(|th, _, _| [1.0 + th, 2.0, 0.5]).to_bytes())
    }

    fn check(bytes: &[u8]) {
        if let Ok(m) = MerlBrdf::from_bytes(bytes) {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
            for _ in 0..10 {
                let (wo, wi) = (random_dir(&mut rng), random_dir(&mut rng));
                let v = m.eval(&wo, &wi);
                assert!(v.is_finite() && v >= 0.0, "{v}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
        /// Header edits and any length: a typed error (or, at the legal size with legal dims,
        /// a valid table), never a panic.
        #[test]
        fn header_and_size_edits(edits in proptest::collection::vec((0usize..12, any::<u8>()), 0..6),
                                 len in 0usize..FILE_BYTES + 64) {
            let good = good();
            let mut head = good[..12].to_vec();
            for (i, v) in edits {
                head[i] = v;
            }
            let mut b = head;
            b.extend_from_slice(&good[12..len.clamp(12, FILE_BYTES)]);
            b.resize(len.max(12), 0);
            b.truncate(len);
            check(&b);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]
        /// Special doubles anywhere in the data at the legal size: a typed error for NaN/inf,
        /// otherwise finite non-negative values (negative = unmeasured, read as 0).
        #[test]
        fn special_values(words in proptest::collection::vec((0usize..3 * CELLS, 0usize..6), 1..30)) {
            let special = [f64::NAN, f64::INFINITY, -1.0, 1e300, 1e38, -1e-300];
            let mut b = good().to_vec();
            for (w, k) in words {
                let at = 12 + 8 * w;
                b[at..at + 8].copy_from_slice(&special[k].to_le_bytes());
            }
            check(&b);
        }
    }
}
