//! Direction helpers in the local shading frame (normal `n = (0,0,1)`, tangent `x`).

/// A 3-vector of `f64` (directions are unit vectors in the local frame).
pub type Vec3 = nalgebra::Vector3<f64>;

/// Unit direction from polar angle `θ` and azimuth `φ`, both in **degrees**:
/// `(sinθ cosφ, sinθ sinφ, cosθ)`.
pub fn direction_from_angles(theta_deg: f64, phi_deg: f64) -> Vec3 {
    direction_from_radians(theta_deg.to_radians(), phi_deg.to_radians())
}

/// Unit direction from polar angle `θ` and azimuth `φ` in radians.
pub fn direction_from_radians(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * cp, st * sp, ct)
}

/// Polar angle `θ ∈ [0, π]` and azimuth `φ ∈ (-π, π]` (radians) of a unit vector.
pub fn angles_of(v: &Vec3) -> (f64, f64) {
    (v.z.clamp(-1.0, 1.0).acos(), v.y.atan2(v.x))
}

/// Mirror direction of `wo` about the normal: `(-wo.x, -wo.y, wo.z)`.
#[inline]
pub fn mirror(wo: &Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// For a pair strictly above the surface ([`both_above`]): `ω_r·ωi` for the mirror direction
/// `ω_r` of `wo` ([`mirror`]), the cosine of Phong-type lobes; `None` otherwise. The start of
/// those models' `eval`.
#[inline]
pub(crate) fn above_with_mirror_cos(wo: &Vec3, wi: &Vec3) -> Option<f64> {
    both_above(wo, wi).then(|| -wo.x * wi.x - wo.y * wi.y + wo.z * wi.z)
}

/// Mirror direction of `v` about an arbitrary unit normal `n`: `2 (n·v) n − v`.
#[inline]
pub fn reflect_about(v: &Vec3, n: &Vec3) -> Vec3 {
    2.0 * n.dot(v) * n - v
}

/// Normalised half vector `h = (wo + wi) / |wo + wi|`.
///
/// Both inputs are assumed to lie in the upper hemisphere, so `wo + wi ≠ 0`.
#[inline]
pub fn half_vector(wo: &Vec3, wi: &Vec3) -> Vec3 {
    (wo + wi).normalize()
}

/// Rotate `v` about the normal (z axis) by `angle` radians (counter-clockwise seen from +z).
#[inline]
pub fn rotate_z(v: &Vec3, angle: f64) -> Vec3 {
    let (s, c) = angle.sin_cos();
    Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// Rotate `v` about the y axis by `angle` radians (right-handed).
#[inline]
pub fn rotate_y(v: &Vec3, angle: f64) -> Vec3 {
    let (s, c) = angle.sin_cos();
    Vec3::new(c * v.x + s * v.z, v.y, -s * v.x + c * v.z)
}

/// True when both directions are strictly above the surface (NaN fails).
#[inline]
pub(crate) fn both_above(wo: &Vec3, wi: &Vec3) -> bool {
    wo.z > 0.0 && wi.z > 0.0
}

/// For a pair strictly above the surface ([`both_above`]): `(cos θi, cos θo, h)` with `h` the
/// unit half vector of `wo` and `wi`; `None` otherwise. The start of the half-vector models'
/// `eval`.
#[inline]
pub(crate) fn above_with_half(wo: &Vec3, wi: &Vec3) -> Option<(f64, f64, Vec3)> {
    both_above(wo, wi).then(|| (wi.z, wo.z, (wo + wi).normalize()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn angles_round_trip() {
        let v = direction_from_angles(30.0, 45.0);
        assert_relative_eq!(v.norm(), 1.0, epsilon = 1e-15);
        let (t, p) = angles_of(&v);
        assert_relative_eq!(t.to_degrees(), 30.0, epsilon = 1e-12);
        assert_relative_eq!(p.to_degrees(), 45.0, epsilon = 1e-12);
    }

    #[test]
    fn mirror_matches_reflect_about_normal() {
        let v = direction_from_angles(40.0, 100.0);
        let n = Vec3::new(0.0, 0.0, 1.0);
        assert_relative_eq!(mirror(&v), reflect_about(&v, &n), epsilon = 1e-15);
    }

    #[test]
    fn rotations_preserve_length_and_axis() {
        let v = direction_from_angles(50.0, 10.0);
        let r = rotate_z(&v, 0.7);
        assert_relative_eq!(r.z, v.z, epsilon = 1e-15);
        assert_relative_eq!(r.norm(), 1.0, epsilon = 1e-14);
        let (_, p) = angles_of(&r);
        assert_relative_eq!(p, 10f64.to_radians() + 0.7, epsilon = 1e-12);
        // rotate_y by θ moves the normal towards +x.
        let n = rotate_y(&Vec3::new(0.0, 0.0, 1.0), 0.3);
        assert_relative_eq!(
            n,
            Vec3::new(0.3f64.sin(), 0.0, 0.3f64.cos()),
            epsilon = 1e-15
        );
    }
}
