//! The lat-long parametrisation and its Jacobian.
//!
//! `(u, v) ∈ [0,1)²`, θ = πv (polar angle from +z), φ = 2πu (azimuth from +x towards +y),
//! direction `ω = (sinθ cosφ, sinθ sinφ, cosθ)`. Area on the square and solid angle are related
//! by `dω = 2π² sin(πv) du dv`, so `p_σ(ω) = p_uv(u, v) / (2π² sin(πv))`.

use std::f64::consts::PI;

/// `2π²`, the Jacobian `dω / (du dv)` divided by `sin θ`.
pub const TWO_PI_SQUARED: f64 = 2.0 * PI * PI;

/// The unit direction of lat-long coordinates `(u, v)`.
#[inline]
pub fn uv_to_direction(u: f64, v: f64) -> [f64; 3] {
    let (sin_t, cos_t) = (PI * v).sin_cos();
    let (sin_p, cos_p) = (2.0 * PI * u).sin_cos();
    [sin_t * cos_p, sin_t * sin_p, cos_t]
}

/// The lat-long coordinates `(u, v) ∈ [0,1)×[0,1]` of a direction (normalised here; the zero
/// vector and NaN map to `(0, 0)`).
pub fn direction_to_uv(d: [f64; 3]) -> (f64, f64) {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return (0.0, 0.0);
    }
    let z = (d[2] / len).clamp(-1.0, 1.0);
    let v = z.acos() / PI;
    let mut u = d[1].atan2(d[0]) / (2.0 * PI);
    if u < 0.0 {
        u += 1.0;
    }
    if u >= 1.0 {
        u = 0.0;
    }
    (u, v)
}

/// Converts a density w.r.t. area on `[0,1]²` at row coordinate `v` to a density w.r.t. solid
/// angle: `p_uv / (2π² sin(πv))`; 0 at the poles, where the lat-long map is singular.
#[inline]
pub fn pdf_uv_to_solid_angle(pdf_uv: f64, v: f64) -> f64 {
    let s = (PI * v).sin();
    if s > 0.0 {
        pdf_uv / (TWO_PI_SQUARED * s)
    } else {
        0.0
    }
}

/// `∫ sin(πv) dv` over `[v0, v1]`, i.e. `(cos πv0 − cos πv1)/π`: the exact row weight of a
/// lat-long pixel row: a pixel of width `Δu` spans the solid angle `2π² Δu · sin_integral(v0, v1)`.
pub fn sin_integral(v0: f64, v1: f64) -> f64 {
    ((PI * v0).cos() - (PI * v1).cos()) / PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn round_trip() {
        for &(u, v) in &[(0.1, 0.2), (0.9, 0.7), (0.5, 0.5), (0.0, 0.99)] {
            let (u2, v2) = direction_to_uv(uv_to_direction(u, v));
            assert_relative_eq!(u, u2, epsilon = 1e-12);
            assert_relative_eq!(v, v2, epsilon = 1e-12);
        }
        assert_eq!(uv_to_direction(0.0, 0.0), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn sphere_area_from_rows() {
        // Σ rows 2π · ∫sin = 4π.
        let total: f64 = (0..7)
            .map(|j| 2.0 * PI * PI * sin_integral(j as f64 / 7.0, (j + 1) as f64 / 7.0))
            .sum();
        assert_relative_eq!(total, 4.0 * PI, epsilon = 1e-12);
    }
}
