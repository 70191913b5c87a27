//! Helpers shared by the models' unit tests.

use crate::geometry::{Vec3, direction_from_radians, mirror};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use std::f64::consts::PI;

/// Deviation of `new` from `reference` on `n_wo` `ωo` (θo uniform in [0°, 89°], seeded by
/// `seed`) × `n_wi` cosine-distributed `ωi`. The lobe peak of an `ωo` is the largest reference
/// value over its `ωi` and the mirror direction. Returns (worst ratio of the deviation to the
/// allowance `max(rel·|ref|, abs·peak)`, max relative deviation where `ref ≥ 10⁻⁶ peak`,
/// max |deviation|/peak).
pub(crate) fn compare_to_reference(
    new: impl Fn(&Vec3, &Vec3) -> f64,
    reference: impl Fn(&Vec3, &Vec3) -> f64,
    (seed, n_wo, n_wi): (u64, usize, usize),
    rel: f64,
    abs: f64,
) -> (f64, f64, f64) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut worst, mut max_rel, mut max_abs) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..n_wo {
        let wo = direction_from_radians(
            rng.random_range(0.0..89.0f64).to_radians(),
            rng.random_range(0.0..2.0 * PI),
        );
        let wis: Vec<Vec3> = (0..n_wi)
            .map(|_| {
                let u: f64 = rng.random();
                direction_from_radians(u.sqrt().asin(), rng.random_range(0.0..2.0 * PI))
            })
            .collect();
        let refs: Vec<f64> = wis.iter().map(|wi| reference(&wo, wi)).collect();
        let peak = refs
            .iter()
            .fold(reference(&wo, &mirror(&wo)), |m, &v| m.max(v));
        for (wi, &r) in wis.iter().zip(&refs) {
            let v = new(&wo, wi);
            assert!(v.is_finite(), "non-finite value at {wo:?} {wi:?}");
            let dev = (v - r).abs();
            worst = worst.max(dev / (rel * r.abs()).max(abs * peak));
            if r >= 1e-6 * peak {
                max_rel = max_rel.max(dev / r);
            }
            if peak > 0.0 {
                max_abs = max_abs.max(dev / peak);
            }
        }
    }
    (worst, max_rel, max_abs)
}

/// A SplitMix64 stream of uniforms in [0, 1) (53 bits) from `state` (fixed-seed test inputs).
pub(crate) fn splitmix_uniforms(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}
