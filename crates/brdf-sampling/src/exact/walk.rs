//! Per-query arithmetic of the exact sampler's lookup without trigonometry (issue 29): the
//! rotation from an azimuth cell's frame to a query's.

use brdf::Vec3;

use crate::layout::Turn;

/// The rotation by `φo − φ_k` about the normal, from `ωo`'s azimuth `(cos φo, sin φo) =
/// (x, y)/r` and the cell's `(cos φ_k, sin φ_k)` (`cell`): the angle-difference identities
/// instead of `sin_cos(φo − φ_k)`. At the normal (`r = 0`) `φo` is taken as 0, as `atan2(0, 0)`
/// does.
#[inline]
pub(super) fn turn_from_cell(wo: &Vec3, cell: Turn) -> Turn {
    let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
    let (c, s) = if r > 0.0 {
        (wo.x / r, wo.y / r)
    } else {
        (1.0, 0.0)
    };
    Turn {
        cos: c * cell.cos + s * cell.sin,
        sin: s * cell.cos - c * cell.sin,
    }
}

/// Largest `tan h` (cell half-width `h` ≈ 26.6°) for which [`cell_offset`] takes `δ` from
/// [`atan_halved`]; wider cells keep `atan2`. Half-turn-symmetric sets of 4 or more cells
/// over π (anisotropic Ward's default: 4, `h` = 22.5°) and full-turn sets of 7 or more
/// qualify.
pub(super) const TAN_HALF_MAX: f64 = 0.5;

/// Terms of [`atan_small`]'s series: for `|t| ≤ 0.25` the first omitted term is
/// below `0.25^26 / 27 < 2^−56` relative to `t`.
const ATAN_TERMS: usize = 13;

/// `(−1)^j / (2j + 1)`, the coefficients of `atan t = t Σ_j (−1)^j t^{2j} / (2j + 1)`.
const ATAN_COEFFS: [f64; ATAN_TERMS] = {
    let mut c = [0.0; ATAN_TERMS];
    let mut j = 0;
    while j < ATAN_TERMS {
        let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
        c[j] = sign / (2 * j + 1) as f64;
        j += 1;
    }
    c
};

/// `atan t` for `|t| ≤ 0.25` (also a little beyond), by its Taylor series
/// (Estrin's scheme in `t²`): within a few ulp of libm's `atan`, without the call.
#[inline]
pub(super) fn atan_small(t: f64) -> f64 {
    // Estrin's scheme in `s = t²` (pairs, then pairs of pairs by `s²`, `s⁴`, `s⁸`): the same
    // polynomial as Horner's rule with a dependency chain of 4 multiply-adds instead of 12
    // (the query's `δ` and `θo` wait on it; issue 29).
    let c = &ATAN_COEFFS;
    let s = t * t;
    let (s2, s4) = (s * s, s * s * (s * s));
    let s8 = s4 * s4;
    let (p01, p23, p45) = (c[0] + c[1] * s, c[2] + c[3] * s, c[4] + c[5] * s);
    let (p67, p89, pab) = (c[6] + c[7] * s, c[8] + c[9] * s, c[10] + c[11] * s);
    let (q0, q1, q2) = (p01 + p23 * s2, p45 + p67 * s2, p89 + pab * s2);
    let (r0, r1) = (q0 + q1 * s4, q2 + c[12] * s4);
    t * (r0 + r1 * s8)
}

/// `atan t` for `|t| ≤` [`TAN_HALF_MAX`]: `2 atan(t / (1 + √(1 + t²)))`, the half angle's
/// tangent being at most 0.25 there ([`atan_small`]). Within a few ulp of libm's `atan`.
#[inline]
pub(super) fn atan_halved(t: f64) -> f64 {
    2.0 * atan_small(t / (1.0 + (1.0 + t * t).sqrt()))
}

/// The polar angle `θ = acos z` of a unit direction with `z = cos θ ≥ 0` and `r = √(x² + y²) =
/// sin θ`, without `acos` (issue 29: a libm call with branches and a table, on every
/// anisotropic query): `tan(θ/2) = r / (1 + z) ≤ 1`, halved once more to `≤ tan(π/8) < 0.5`,
/// then [`atan_halved`], so `θ = 4 atan_halved(·)`. Branch-free; within a few ulp of
/// `z.acos()` (tested).
#[inline]
pub(super) fn theta_of(z: f64, r: f64) -> f64 {
    let t = r / (1.0 + z);
    4.0 * atan_halved(t / (1.0 + (1.0 + t * t).sqrt()))
}

/// A coarse `atan2(s, c)` for `(c, s)` ≠ 0 (the octant, then
/// `z (π/4 + 0.273 (1 − z))` for `z ∈ [0, 1]`): within 0.005 rad of the true angle, in
/// `[−π, π]`. Only picks the cell [`cell_offset`] starts from.
#[inline]
fn coarse_angle(c: f64, s: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (ax, ay) = (c.abs(), s.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    let z = if hi > 0.0 { lo / hi } else { 0.0 };
    let mut a = z * (FRAC_PI_4 + 0.273 * (1.0 - z));
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if c < 0.0 {
        a = PI - a;
    }
    a.copysign(s)
}

/// The azimuth cell of a query and its offset from the cell's centre without `atan2`
/// (issue 29): `(k, turn, δ)` with `turn` the rotation by `φo − φ_k` ([`turn_from_cell`]) and
/// `tan δ`, `δ ∈ [−h, h]` (to rounding) its angle reduced modulo the `period`. The cell comes
/// from a coarse angle ([`coarse_angle`]) and is moved to a neighbour when `|tan δ| > tan h`;
/// `δ` itself is `atan(tan δ)` ([`atan_halved`]: `|tan δ| ≤ tan h` is small), which is the
/// offset reduced modulo π, and modulo 2π too since `|δ| < π/2` — left to the caller: the
/// strip search of [`super::layout::Cell::interval_of`] and the normaliser grid
/// ([`super::aniso_record::AnisoRecord`]) take `tan δ`, so a drawing query needs no `atan`
/// (issue 29). `None` when the cells are
/// wider than [`TAN_HALF_MAX`] allows or the coarse cell is more than one cell off (the caller
/// then takes `atan2`). `phi_turns[k]` is cell `k`'s `(cos φ_k, sin φ_k)`, `φ_k = k · period / n`.
#[inline]
pub(super) fn cell_offset(
    wo: &Vec3,
    period: f64,
    tan_half: f64,
    phi_turns: impl Fn(usize) -> Turn,
    n: usize,
) -> Option<(usize, Turn, f64)> {
    if !(tan_half <= TAN_HALF_MAX) || n < 2 {
        return None;
    }
    // The cell and `tan δ` from `(x, y)` itself (both are invariant to its scale): the strip
    // search and the walk need not wait for the square root and divisions of the rotation.
    let r2 = wo.x * wo.x + wo.y * wo.y;
    let (x, y) = if r2 > 0.0 { (wo.x, wo.y) } else { (1.0, 0.0) };
    let r = r2.sqrt();
    let (c, s) = if r2 > 0.0 {
        (wo.x / r, wo.y / r)
    } else {
        (1.0, 0.0)
    };
    // The coarse cell: `φ / step` by a multiplication (the reciprocal does not wait for the
    // angle) and `mod n` by a comparison (`φ < period`, so the index is at most `n`); a cell
    // one off is corrected below.
    let per_step = n as f64 / period;
    let phi = rem_period(coarse_angle(x, y), period);
    let mut k = round_index(phi * per_step);
    if k >= n {
        k = 0;
    }
    for _ in 0..2 {
        let cell = phi_turns(k);
        let turn = Turn {
            cos: c * cell.cos + s * cell.sin,
            sin: s * cell.cos - c * cell.sin,
        };
        let t = (y * cell.cos - x * cell.sin) / (x * cell.cos + y * cell.sin);
        if t > tan_half {
            k = if k + 1 == n { 0 } else { k + 1 };
        } else if t < -tan_half {
            k = if k == 0 { n - 1 } else { k - 1 };
        } else {
            return Some((k, turn, t));
        }
    }
    None
}

/// `x.rem_euclid(p)` for `p > 0`, bit for bit, without the `fmod` call when `|x| < 2p` (a
/// query's azimuth and its offset from a cell: `atan2` is within `[−π, π]`): there `x % p` is
/// `x` or `x ∓ p`, exact (Sterbenz), with the sign of `x` (also for a zero result, as `fmod`).
#[inline]
pub(super) fn rem_period(x: f64, p: f64) -> f64 {
    let a = x.abs();
    let r = if a < p {
        x
    } else if a < 2.0 * p {
        (x - p.copysign(x)).copysign(x)
    } else {
        x % p
    };
    if r < 0.0 { r + p } else { r }
}

/// `t.round() as usize` (halves away from zero) for `t ≥ 0` below `2^52` and NaN (0), without
/// the `round` call: `t − ⌊t⌋` is exact there.
#[inline]
pub(super) fn round_index(t: f64) -> usize {
    let whole = t as i64;
    (whole + i64::from(t - whole as f64 >= 0.5)) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The same rotation as `Turn::from_angle(φo − φ_k)` to rounding, at any azimuths and
        /// polar angle (including the normal, where φo is 0).
        #[test]
        fn turn_is_the_angle_difference(phi in -7.0f64..7.0, phik in -7.0f64..7.0,
                                        theta in 0.0f64..1.57) {
            let wo = brdf::direction_from_radians(theta, phi);
            let t = turn_from_cell(&wo, Turn::from_angle(phik));
            let want = Turn::from_angle(wo.y.atan2(wo.x) - phik);
            prop_assert!((t.cos - want.cos).abs() < 1e-14 && (t.sin - want.sin).abs() < 1e-14,
                "{t:?} vs {want:?}");
        }
    }

    /// The cell and offset of the `atan2` path `locate` takes for wide cells.
    fn reference(wo: &Vec3, period: f64, n: usize) -> (usize, f64) {
        use super::super::walk::{rem_period, round_index};
        let phi = wo.y.atan2(wo.x);
        let step = period / n as f64;
        let k = round_index(rem_period(phi, period) / step) % n;
        let mut delta = rem_period(phi - k as f64 * period / n as f64, period);
        if delta > 0.5 * period {
            delta -= period;
        }
        (k, delta)
    }

    proptest! {
        /// The series is libm's `atan` to a few ulp over the range it serves (and a little
        /// beyond, where rounding may put `|tan δ|`).
        #[test]
        fn atan_small_is_atan(t in -0.2501f64..0.2501) {
            let (got, want) = (atan_small(t), t.atan());
            prop_assert!((got - want).abs() <= 4.0 * f64::EPSILON * want.abs(),
                "{t}: {got:e} vs {want:e}");
        }

        /// The same for the halved form over the cells it serves.
        #[test]
        fn atan_halved_is_atan(t in -0.5001f64..0.5001) {
            let (got, want) = (atan_halved(t), t.atan());
            prop_assert!((got - want).abs() <= 6.0 * f64::EPSILON * want.abs(),
                "{t}: {got:e} vs {want:e}");
        }

        /// `θ` without `acos`: within 8 ulp (relative) of the polar angle the direction was made
        /// from, normal and horizon included, and within 4 ulp of π/2 of libm's `acos` where
        /// `acos` is well conditioned (θ ≥ 0.1; near the normal `acos z` itself loses digits).
        #[test]
        fn theta_of_is_acos(theta in 0.0f64..=std::f64::consts::FRAC_PI_2, phi in -3.2f64..3.2) {
            let wo = brdf::direction_from_radians(theta, phi);
            let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
            let got = theta_of(wo.z, r);
            prop_assert!((got - theta).abs() <= 8.0 * f64::EPSILON * theta,
                "θ {theta}: {got:e}");
            if theta >= 0.1 {
                let want = wo.z.acos();
                prop_assert!((got - want).abs() <= 4.0 * f64::EPSILON * std::f64::consts::FRAC_PI_2,
                    "θ {theta}: {got:e} vs acos {want:e}");
            }
        }

        /// Without `atan2`, the same cell as the `atan2` path (but within 1e-12 rad of a cell
        /// edge, where either neighbour is right), the same rotation, and `δ` to 2e-15 rad (the
        /// `atan2` path's own rounding near π),
        /// inside `[−h, h]`: half-turn periods with 4–64 cells and full turns with 7–64.
        #[test]
        fn cell_offset_is_the_atan2_path(theta in 0.0f64..1.57, phi in -7.0f64..7.0,
                                         n in 4usize..=64, full in proptest::bool::ANY,
                                         edge in proptest::bool::ANY, side in -1.0f64..1.0) {
            use std::f64::consts::{PI, TAU};
            let (period, n) = if full { (TAU, n.max(7)) } else { (PI, n) };
            let step = period / n as f64;
            let half = 0.5 * step;
            // Half the cases right at a cell edge (within 1e-9 rad), where the coarse angle
            // lands in the wrong cell.
            let phi = if edge { (phi / step).round() * step + half + 1e-9 * side } else { phi };
            let wo = brdf::direction_from_radians(theta, phi);
            let turns = |k: usize| Turn::from_angle(k as f64 * period / n as f64);
            let got = cell_offset(&wo, period, half.tan(), turns, n);
            let (k, t, tan) = got.expect("cells this narrow are always served");
            let delta = atan_halved(tan);
            prop_assert!((tan - t.sin / t.cos).abs() <= 4.0 * f64::EPSILON, "tan δ {tan:e}");
            let (k_ref, d_ref) = reference(&wo, period, n);
            prop_assert_eq!(t, turn_from_cell(&wo, turns(k)));
            prop_assert!(delta.abs() <= half * (1.0 + 1e-12), "δ {delta} outside ±{half}");
            if k == k_ref {
                prop_assert!((delta - d_ref).abs() <= 2e-15, "δ {delta:e} vs {d_ref:e}");
            } else {
                prop_assert!((d_ref.abs() - half).abs() < 1e-12,
                    "cell {k} vs {k_ref} with δ {d_ref} inside the cell (h = {half})");
            }
        }
    }

    /// Cells wider than the series serves, or a single cell, keep the `atan2` path.
    #[test]
    fn wide_cells_keep_atan2() {
        let wo = brdf::direction_from_angles(40.0, 100.0);
        let turns = |k: usize| Turn::from_angle(k as f64);
        let h = std::f64::consts::PI / 6.0; // 3 cells over π
        assert!(cell_offset(&wo, std::f64::consts::PI, h.tan(), turns, 3).is_none());
        assert!(cell_offset(&wo, std::f64::consts::TAU, 0.1, turns, 1).is_none());
    }

    #[test]
    fn at_the_normal_the_azimuth_is_zero() {
        let t = turn_from_cell(&Vec3::new(0.0, 0.0, 1.0), Turn::from_angle(0.7));
        let want = Turn::from_angle(-0.7);
        assert!((t.cos - want.cos).abs() < 1e-15 && (t.sin - want.sin).abs() < 1e-15);
    }
}
