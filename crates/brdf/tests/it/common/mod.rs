//! Shared by the symmetry checks (`mirror.rs`, `half_turn.rs`): seeded direction pairs and the
//! relative comparison; and by the measured-format and fit tests (`rgl.rs`, `cornell.rs`,
//! `fits.rs`): seeded pairs away from grazing.

use brdf::{Vec3, direction_from_angles, direction_from_radians};
use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
use std::f64::consts::TAU;

/// Relative tolerance of the symmetry checks.
pub(crate) const TOL: f64 = 1e-12;

/// Number of random direction pairs.
pub(crate) const PAIRS: usize = 2000;

/// `PAIRS` seeded pairs in the upper hemisphere: θ uniform in [0°, 89.9°], except every
/// fourth pair whose two directions are both grazing (θ in [85°, 89.9°]); φ uniform.
pub(crate) fn direction_pairs(seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let max = 89.9f64.to_radians();
    (0..PAIRS)
        .map(|k| {
            let lo = if k % 4 == 3 { 85f64.to_radians() } else { 0.0 };
            let mut dir =
                || direction_from_radians(rng.random_range(lo..max), rng.random_range(0.0..TAU));
            (dir(), dir())
        })
        .collect()
}

/// `|a − b| ≤ TOL · max(1, |a|)`.
pub(crate) fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= TOL * a.abs().max(1.0)
}

/// `n` seeded pairs with θ uniform in [0°, 85°] and φ uniform in [0°, 360°] (in degrees, drawn
/// θo, φo, θi, φi in that order).
pub(crate) fn pairs_below_85(seed: u64, n: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut dir = || direction_from_angles(85.0 * rng.random::<f64>(), 360.0 * rng.random::<f64>());
    (0..n).map(|_| (dir(), dir())).collect()
}
