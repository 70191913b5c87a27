//! The RGL format's coordinates of a direction (`u = (√(2θ/π), (φ + π)/(2π))`) and the
//! evaluation path's angles: a leaf module, read by the reader (`rgl.rs`) and its block
//! evaluation (`rgl/lanes.rs`).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::geometry::Vec3;

/// Elevation of a unit vector, `acos z`, computed as `2 asin(|d − n|/2)` (accurate near the
/// normal).
pub fn elevation(d: &Vec3) -> f64 {
    let dist = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
    2.0 * (0.5 * dist).clamp(-1.0, 1.0).asin()
}

/// `θ ↦ u = √(2θ/π)`.
pub fn theta_to_u(theta: f64) -> f64 {
    (theta.max(0.0) / FRAC_PI_2).sqrt()
}

/// `u ↦ θ = u² π/2`.
pub fn u_to_theta(u: f64) -> f64 {
    u * u * FRAC_PI_2
}

/// `φ ↦ u = (φ + π)/(2π)`.
pub fn phi_to_u(phi: f64) -> f64 {
    (phi + PI) / TAU
}

/// `u ↦ φ = (2u − 1)π`.
pub fn u_to_phi(u: f64) -> f64 {
    (2.0 * u - 1.0) * PI
}

/// The angles of the evaluation path (`Brdf::prepare` and `Brdf::eval_prepared`) with the
/// `libm` crate's `atan2` and `asin` (FreeBSD's msun: errors below 1 ulp, as glibc's, for
/// fewer instructions: per call `asin` 33 against 54, `atan2` 100 against 112, cachegrind,
/// docs/benchmarks.md §20.8). The results differ from `std`'s by an ulp or two: the
/// interpolant is the same to 1e-12 relative up to 85° from the normal, and to the
/// interpolant's own 1-ulp conditioning beyond (tested against the `std` path on 10⁵ pairs).
pub(super) mod fast {
    use super::phi_to_u;
    use crate::geometry::Vec3;

    /// `atan2(y, x)`.
    #[inline]
    pub(in crate::measured) fn atan2(y: f64, x: f64) -> f64 {
        libm::atan2(y, x)
    }

    /// [`super::elevation`] with `libm`'s `asin`.
    #[inline]
    pub(in crate::measured) fn elevation(d: &Vec3) -> f64 {
        let dist = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
        2.0 * libm::asin((0.5 * dist).clamp(-1.0, 1.0))
    }

    /// `√(x² + y²)`, through `hypot` only when the plain sum would overflow or lose precision
    /// to underflow.
    #[inline]
    pub(in crate::measured) fn hypot(x: f64, y: f64) -> f64 {
        let s = x * x + y * y;
        if s.is_finite() && s >= f64::MIN_POSITIVE {
            s.sqrt()
        } else {
            x.hypot(y)
        }
    }

    /// `frac(phi_to_u(φ))` without the `floor` call for `φ ∈ [−π, π)` (the range of `atan2`),
    /// where the fraction is the value itself.
    #[inline]
    pub(in crate::measured) fn unit_azimuth(phi: f64) -> f64 {
        let u = phi_to_u(phi);
        if (0.0..1.0).contains(&u) {
            u
        } else {
            u - u.floor()
        }
    }
}
