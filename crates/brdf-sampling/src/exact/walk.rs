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

    #[test]
    fn at_the_normal_the_azimuth_is_zero() {
        let t = turn_from_cell(&Vec3::new(0.0, 0.0, 1.0), Turn::from_angle(0.7));
        let want = Turn::from_angle(-0.7);
        assert!((t.cos - want.cos).abs() < 1e-15 && (t.sin - want.sin).abs() < 1e-15);
    }
}
