//! A deterministic procedural sky with a sun, for runs without a map file.

use std::f64::consts::PI;

use crate::latlong::uv_to_direction;
use crate::{EnvMap, EnvMapError};

/// Lat-long coordinates `(u, v)` of the sun centre: azimuth φ = 0.3 · 2π (108°), polar angle
/// θ = 55° (elevation 35° above the horizon).
pub const SUN_UV: (f64, f64) = (0.3, 55.0 / 180.0);

/// The unit direction of the sun centre (see [`SUN_UV`]).
pub fn sun_direction() -> [f64; 3] {
    uv_to_direction(SUN_UV.0, SUN_UV.1)
}

/// Angular radius of the sun disc (radians): 1.5°.
pub const SUN_RADIUS: f64 = 1.5 * PI / 180.0;

/// Radiance of the sun disc (linear RGB).
pub const SUN_RADIANCE: [f64; 3] = [5200.0, 4900.0, 4400.0];

/// A `width × height` lat-long sky: a smooth blue-to-white gradient above the horizon, a dim
/// brown ground below it, a soft glow around the sun and a 1.5°-radius sun disc about 5000 times
/// brighter than the sky (it carries most of the map's power, a hard case for samplers).
///
/// Each pixel is evaluated at its centre, except the disc edge, whose coverage is the fraction
/// of a 4×4 grid of sub-pixel points inside the disc. Deterministic: the same size always gives
/// the same pixels. Errors: zero or oversized dimensions.
pub fn procedural_sky(width: usize, height: usize) -> Result<EnvMap, EnvMapError> {
    crate::map::check_dimensions(width, height)?;
    let mut rgb = Vec::with_capacity(width * height);
    let cos_radius = SUN_RADIUS.cos();
    let sun = sun_direction();
    // Pixels farther than this from the sun cannot touch the disc.
    let margin = SUN_RADIUS + PI * (2.0 / height as f64 + 4.0 / width as f64);
    for y in 0..height {
        for x in 0..width {
            let (u, v) = (
                (x as f64 + 0.5) / width as f64,
                (y as f64 + 0.5) / height as f64,
            );
            let d = uv_to_direction(u, v);
            let mut c = sky_radiance(d, sun);
            let angle = dot(d, sun).clamp(-1.0, 1.0).acos();
            if angle < margin {
                let mut inside = 0;
                for sy in 0..4 {
                    for sx in 0..4 {
                        let su = (x as f64 + (sx as f64 + 0.5) / 4.0) / width as f64;
                        let sv = (y as f64 + (sy as f64 + 0.5) / 4.0) / height as f64;
                        inside += usize::from(dot(uv_to_direction(su, sv), sun) >= cos_radius);
                    }
                }
                let coverage = inside as f64 / 16.0;
                for (ch, s) in c.iter_mut().zip(SUN_RADIANCE) {
                    *ch += coverage * s;
                }
            }
            rgb.push([c[0] as f32, c[1] as f32, c[2] as f32]);
        }
    }
    EnvMap::new(width, height, rgb)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Sky without the disc: gradient, horizon brightening, ground, and a glow around the sun.
fn sky_radiance(d: [f64; 3], sun: [f64; 3]) -> [f64; 3] {
    let z = d[2];
    let base = if z >= 0.0 {
        let t = z.sqrt(); // 0 at the horizon, 1 at the zenith
        let zenith = [0.18, 0.32, 0.85];
        let horizon = [0.85, 0.9, 1.0];
        [0, 1, 2].map(|i| horizon[i] + (zenith[i] - horizon[i]) * t)
    } else {
        let t = (-z).min(1.0);
        [0.12 - 0.04 * t, 0.1 - 0.03 * t, 0.08 - 0.03 * t]
    };
    let cos_sun = dot(d, sun).clamp(-1.0, 1.0);
    let glow = 8.0 * ((cos_sun - 1.0) * 40.0).exp() + 0.6 * (1.0 + cos_sun * cos_sun) * 0.5;
    let above = if z >= 0.0 { 1.0 } else { 0.2 };
    [0, 1, 2].map(|i| base[i] * (1.0 + above * glow * [1.0, 0.85, 0.6][i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::latlong::direction_to_uv;

    #[test]
    fn sun_direction_round_trips() {
        let (u, v) = direction_to_uv(sun_direction());
        assert!((u - SUN_UV.0).abs() < 1e-12 && (v - SUN_UV.1).abs() < 1e-12);
    }

    #[test]
    fn sky_is_deterministic_and_sun_dominates() {
        let a = procedural_sky(256, 128).unwrap();
        assert_eq!(a, procedural_sky(256, 128).unwrap());
        // Power (∫ Y dω) of the sun pixels versus the rest.
        let lum = a.luminance();
        let (mut sun, mut rest) = (0.0, 0.0);
        for (i, y) in lum.iter().enumerate() {
            let v = ((i / 256) as f64 + 0.5) / 128.0;
            let w = y * (PI * v).sin();
            if *y > 1000.0 { sun += w } else { rest += w }
        }
        let share = sun / (sun + rest);
        assert!(share > 0.5 && share < 0.95, "sun share {share}");
        let (sx, sy) = a.pixel_at(SUN_UV.0, SUN_UV.1);
        assert!(lum[sy * 256 + sx] > 4000.0);
    }

    #[test]
    fn empty_sizes_are_errors() {
        assert!(matches!(
            procedural_sky(0, 4),
            Err(EnvMapError::Empty { .. })
        ));
    }
}
