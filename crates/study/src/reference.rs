//! The reference value of `L_r(ωo) = ∫_Ω f_r(ωo, ωi) L(ωi) cosθi dσ(ωi)` by deterministic
//! quadrature (luminance of the RGB integral), with an error estimate.
//!
//! * **Maps** (files and the sky): the map is piecewise constant per pixel, so
//!   `L_r = Σ_pixels L_p ∫_p f_r cosθ dσ`; each pixel's integral uses the `k × k` midpoint rule
//!   in `(u, v)` with `dσ = 2π² sin(πv) du dv`, for `k = 2`; the error estimate is the
//!   difference from `k = 1`.
//! * **Area light**: Gauss–Legendre in `cos α ∈ [cos r, 1]` (α the angle from the disc's axis)
//!   times the periodic trapezoid rule in the azimuth about the axis, at 48 × 96 nodes; the
//!   error estimate is the difference from 24 × 48 nodes.
//! * **Constant**: radiance times the directional albedo of `brdf::plausibility`'s adaptive
//!   rule (refined at the mirror direction), with its own error estimate.
//!
//! Sums run in a fixed order (per-row partial sums, added in row order), so the reference does
//! not depend on the thread count.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use brdf::quadrature::GaussLegendre;
use brdf::{Brdf, Vec3};

use crate::Light;

/// A reference value and how it was obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// `L_r(ωo)` (luminance).
    pub value: f64,
    /// Estimated absolute error of `value`.
    pub abs_err: f64,
    /// The quadrature used.
    pub method: String,
}

/// The reference `L_r(wo)` of `brdf` under `light` (see the module docs).
pub fn reference(brdf: &dyn Brdf, wo: &Vec3, light: &Light) -> Reference {
    match light {
        Light::Map { map, .. } => map_reference(brdf, wo, map),
        Light::Area {
            axis,
            radius,
            radiance,
        } => {
            let fine = cone_integral(brdf, wo, axis, *radius, 48, 96);
            let coarse = cone_integral(brdf, wo, axis, *radius, 24, 48);
            let value = colour::luminance(fine) * radiance;
            Reference {
                value,
                abs_err: (value - colour::luminance(coarse) * radiance).abs(),
                method: "Gauss-Legendre 48 (cos α) × trapezoid 96 (azimuth) over the disc; error: difference from 24 × 48".into(),
            }
        }
        Light::Constant { radiance } => {
            let (albedo, err) = brdf::plausibility::adaptive_albedo_rgb(brdf, wo);
            Reference {
                value: colour::luminance(albedo) * radiance,
                abs_err: colour::luminance(err) * radiance,
                method: "radiance × directional albedo (adaptive Gauss rule refined at the mirror direction, its error estimate)".into(),
            }
        }
    }
}

fn map_reference(brdf: &dyn Brdf, wo: &Vec3, map: &envmap::EnvMap) -> Reference {
    let (w, h) = (map.width(), map.height());
    // Rows reaching into the upper hemisphere (v < 1/2); points below the horizon give f_r = 0.
    let rows = (0..h).filter(|&y| 2 * y < h).collect::<Vec<_>>();
    let sums: Vec<(f64, f64)> = rows
        .par_iter()
        .map(|&y| {
            let (mut fine, mut coarse) = (0.0, 0.0);
            for x in 0..w {
                let Some(l) = map.pixel(x, y) else { continue };
                let l = [f64::from(l[0]), f64::from(l[1]), f64::from(l[2])];
                if l == [0.0; 3] {
                    continue;
                }
                let at = |u: f64, v: f64, area: f64| {
                    let d = envmap::latlong::uv_to_direction(u, v);
                    let wi = Vec3::new(d[0], d[1], d[2]);
                    if !(wi.z > 0.0) {
                        return 0.0;
                    }
                    let f = brdf.eval_rgb(wo, &wi);
                    let weight = wi.z
                        * envmap::latlong::TWO_PI_SQUARED
                        * (std::f64::consts::PI * v).sin()
                        * area;
                    colour::luminance([f[0] * l[0], f[1] * l[1], f[2] * l[2]]) * weight
                };
                let area = 1.0 / (w * h) as f64;
                coarse += at(
                    (x as f64 + 0.5) / w as f64,
                    (y as f64 + 0.5) / h as f64,
                    area,
                );
                for sy in 0..2 {
                    for sx in 0..2 {
                        let u = (x as f64 + 0.25 + 0.5 * sx as f64) / w as f64;
                        let v = (y as f64 + 0.25 + 0.5 * sy as f64) / h as f64;
                        fine += at(u, v, 0.25 * area);
                    }
                }
            }
            (fine, coarse)
        })
        .collect();
    let (fine, coarse) = sums
        .iter()
        .fold((0.0, 0.0), |(a, b), (f, c)| (a + f, b + c));
    Reference {
        value: fine,
        abs_err: (fine - coarse).abs(),
        method: format!(
            "sum over the {w}×{h} map's pixels of radiance × 2×2 midpoint rule of f·cos per pixel; error: difference from the 1×1 rule"
        ),
    }
}

/// `∫ f_r(wo, ω) cosθ dσ` (RGB) over the cone of half-angle `radius` about `axis`.
fn cone_integral(
    brdf: &dyn Brdf,
    wo: &Vec3,
    axis: &Vec3,
    radius: f64,
    n_t: usize,
    n_phi: usize,
) -> [f64; 3] {
    let helper = if axis.x.abs() < 0.9 {
        Vec3::new(1.0, 0.0, 0.0)
    } else {
        Vec3::new(0.0, 1.0, 0.0)
    };
    let t1 = axis.cross(&helper).normalize();
    let t2 = axis.cross(&t1);
    let rule = GaussLegendre::new(n_t);
    let (a, b) = (radius.cos(), 1.0);
    let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
    let mut acc = [0.0; 3];
    for (x, wt) in rule.nodes().iter().zip(rule.weights()) {
        let c = mid + half * x;
        let s = (1.0 - c * c).max(0.0).sqrt();
        for k in 0..n_phi {
            let phi = std::f64::consts::TAU * k as f64 / n_phi as f64;
            let d = axis * c + t1 * (s * phi.cos()) + t2 * (s * phi.sin());
            if !(d.z > 0.0) {
                continue;
            }
            let f = brdf.eval_rgb(wo, &d);
            let weight = wt * half * std::f64::consts::TAU / n_phi as f64 * d.z;
            for ch in 0..3 {
                acc[ch] += f[ch] * weight;
            }
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn lambert_references_match_closed_forms() {
        let lambert = brdf::parse_spec("lambert").unwrap();
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let albedo = lambert.eval(&wo, &wo) * std::f64::consts::PI;
        // Constant light: L_r = radiance × albedo.
        let r = reference(
            lambert.as_ref(),
            &wo,
            &Light::parse("constant:radiance=2").unwrap(),
        );
        assert_relative_eq!(r.value, 2.0 * albedo, max_relative = 1e-6);
        // Disc light about the normal: ∫ cosθ dσ over the cone = π sin²(r).
        let r = reference(
            lambert.as_ref(),
            &wo,
            &Light::parse("area:theta=0,radius=10,radiance=3").unwrap(),
        );
        let exact = albedo / std::f64::consts::PI
            * 3.0
            * std::f64::consts::PI
            * 10f64.to_radians().sin().powi(2);
        assert_relative_eq!(r.value, exact, max_relative = 1e-9);
        // A white map: the upper half of the sky integrates cosθ to π.
        let map = envmap::EnvMap::new(64, 32, vec![[1.0; 3]; 64 * 32]).unwrap();
        let r = reference(
            lambert.as_ref(),
            &wo,
            &Light::Map {
                map,
                label: "white".into(),
            },
        );
        assert_relative_eq!(r.value, albedo, max_relative = 1e-3);
        assert!(r.abs_err < 1e-2 * albedo);
    }
}
