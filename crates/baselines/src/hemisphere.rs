//! BRDF-blind direction samplers on the upper hemisphere: uniform and cosine-weighted.
//!
//! Both ignore `ωo` and the BRDF; they are the simplest baselines of the seed papers' studies.
//! Pdfs are with respect to **solid angle**.
//!
//! The warps themselves stand side by side as in Mitsuba's `warp.h`: for each target,
//! `square_to_X` (the warp of `[0,1)²`), `square_to_X_pdf` (its density, solid angle) and
//! `X_to_square` (the inverse warp), with round trips and the Jacobian tested in this module.

use std::f64::consts::{FRAC_1_PI, PI, TAU};

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;

/// Uniform directions on the upper hemisphere Ω: `p(ωi) = 1/(2π)` for `ωi.z > 0`.
///
/// Its `pdf` depends only on the sign of `wi.z`, so it is the same for any positive multiple
/// of `wi` ([`DirectionSampler::pdf`] asks for unit vectors).
///
/// Warp: `cosθ = u₁`, `φ = 2πu₂` (equal-area in `(cosθ, φ)`).
#[derive(Debug, Clone, Copy, Default)]
pub struct UniformHemisphere;

/// Cosine-weighted directions on Ω: `p(ωi) = cosθi/π` for `ωi.z > 0`.
///
/// Its `pdf` takes `cos θi = wi.z / |wi|`, so it is the same for any positive multiple of
/// `wi` ([`DirectionSampler::pdf`] asks for unit vectors).
///
/// Warp: a uniform point of the unit disc (polar, `r = √u₁`, `φ = 2πu₂`) lifted to the
/// hemisphere (Malley's method: area on the disc is projected solid angle).
#[derive(Debug, Clone, Copy, Default)]
pub struct CosineHemisphere;

/// Uniform warp of `u ∈ [0,1)²` to the upper hemisphere: `cosθ = 1 − u₁` (in `(0, 1]`, so never
/// exactly on the horizon), `φ = 2πu₂`. Equal-area in `(cosθ, φ)`.
pub fn square_to_uniform_hemisphere(u: [f64; 2]) -> Vec3 {
    let z = 1.0 - u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`square_to_uniform_hemisphere`] w.r.t. solid angle: `1/(2π)` above the horizon
/// (`v.z > 0`), 0 elsewhere. Depends only on the sign of `v.z`.
pub fn square_to_uniform_hemisphere_pdf(v: &Vec3) -> f64 {
    if v.z > 0.0 { 1.0 / (2.0 * PI) } else { 0.0 }
}

/// Inverse of [`square_to_uniform_hemisphere`] for a unit `v` with `v.z > 0`:
/// `u₁ = 1 − cosθ`, `u₂ = φ/(2π) ∈ [0, 1)`.
pub fn uniform_hemisphere_to_square(v: &Vec3) -> [f64; 2] {
    [1.0 - v.z, azimuth_fraction(v)]
}

/// Cosine-weighted warp (Malley's method) of `u ∈ [0,1)²` to the upper hemisphere: a uniform
/// point of the unit disc in polar form (`r = √u₁`, `φ = 2πu₂`) lifted to `z = √(1 − r²)`.
pub fn square_to_cosine_hemisphere(u: [f64; 2]) -> Vec3 {
    let r2 = u[0];
    let r = r2.sqrt();
    let phi = TAU * u[1];
    let z = (1.0 - r2).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`square_to_cosine_hemisphere`] w.r.t. solid angle: `cosθ/π` with
/// `cosθ = v.z/|v|` above the horizon, 0 elsewhere (the same for any positive multiple of `v`).
pub fn square_to_cosine_hemisphere_pdf(v: &Vec3) -> f64 {
    if v.z > 0.0 {
        v.z / v.norm() * FRAC_1_PI
    } else {
        0.0
    }
}

/// Inverse of [`square_to_cosine_hemisphere`] for a unit `v` with `v.z > 0`:
/// `u₁ = r² = x² + y²`, `u₂ = φ/(2π) ∈ [0, 1)`.
pub fn cosine_hemisphere_to_square(v: &Vec3) -> [f64; 2] {
    [(v.x * v.x + v.y * v.y).min(1.0), azimuth_fraction(v)]
}

/// `φ/(2π) ∈ [0, 1)` of the azimuth of `v` (0 on the pole).
fn azimuth_fraction(v: &Vec3) -> f64 {
    let t = v.y.atan2(v.x) / TAU;
    let t = if t < 0.0 { t + 1.0 } else { t };
    if t >= 1.0 { 0.0 } else { t }
}

impl UniformHemisphere {
    /// Warps `u ∈ [0,1)²` to a direction and its solid-angle pdf
    /// ([`square_to_uniform_hemisphere`]).
    pub fn sample_square(u: [f64; 2]) -> DirSample {
        let wi = square_to_uniform_hemisphere(u);
        DirSample {
            pdf: square_to_uniform_hemisphere_pdf(&wi),
            wi,
        }
    }
}

impl CosineHemisphere {
    /// Warps `u ∈ [0,1)²` to a direction and its solid-angle pdf
    /// ([`square_to_cosine_hemisphere`]).
    pub fn sample_square(u: [f64; 2]) -> DirSample {
        let wi = square_to_cosine_hemisphere(u);
        DirSample {
            pdf: wi.z * FRAC_1_PI,
            wi,
        }
    }
}

/// The [`DirectionSampler`] of a fixed warp of the unit square (`$sampler::sample_square`, two
/// uniforms per sample, independent of `ωo`) whose solid-angle density is `$pdf(ωi)`.
macro_rules! square_warp_sampler {
    ($sampler:ty, $pdf:path) => {
        impl DirectionSampler for $sampler {
            fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
                let u0 = u.next_uniform();
                let u1 = u.next_uniform();
                Self::sample_square([u0, u1])
            }
            fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
                $pdf(wi)
            }
            fn bytes_used(&self) -> usize {
                0
            }
        }

        impl SamplerDiagnostics for $sampler {}
    };
}

square_warp_sampler!(UniformHemisphere, square_to_uniform_hemisphere_pdf);
square_warp_sampler!(CosineHemisphere, square_to_cosine_hemisphere_pdf);

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    type Warp = (
        &'static str,
        fn([f64; 2]) -> Vec3,
        fn(&Vec3) -> f64,
        fn(&Vec3) -> [f64; 2],
    );

    const WARPS: [Warp; 2] = [
        (
            "uniform",
            square_to_uniform_hemisphere,
            square_to_uniform_hemisphere_pdf,
            uniform_hemisphere_to_square,
        ),
        (
            "cosine",
            square_to_cosine_hemisphere,
            square_to_cosine_hemisphere_pdf,
            cosine_hemisphere_to_square,
        ),
    ];

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// `X_to_square(square_to_X(u)) = u` (away from the pole, where φ is undefined), the
        /// image is a unit upper direction, and `square_to_X(X_to_square(v)) = v`.
        #[test]
        fn warps_round_trip(u0 in 1e-6f64..1.0, u1 in 0.0f64..1.0) {
            for (name, warp, _, inverse) in WARPS {
                let v = warp([u0, u1]);
                prop_assert!((v.norm() - 1.0).abs() < 1e-12 && v.z > 0.0, "{}", name);
                let back = inverse(&v);
                prop_assert!((back[0] - u0).abs() < 1e-9, "{} u0 {} -> {}", name, u0, back[0]);
                // The azimuth wraps: compare on the circle.
                let d = (back[1] - u1).abs();
                prop_assert!(d.min(1.0 - d) < 1e-9, "{} u1 {} -> {}", name, u1, back[1]);
                prop_assert!((0.0..1.0).contains(&back[1]), "{}", name);
                let again = warp(back);
                prop_assert!((again - v).norm() < 1e-9, "{} {:?} {:?}", name, v, again);
            }
        }

        /// The pdf is the warp's Jacobian: the solid angle of the image of a small square
        /// `h × h` (|∂v/∂u₁ × ∂v/∂u₂| h², by central differences) times the pdf is `h²`.
        #[test]
        fn pdf_is_the_inverse_jacobian(u0 in 0.01f64..0.99, u1 in 0.01f64..0.99) {
            let h = 1e-5;
            for (name, warp, pdf, _) in WARPS {
                let d0 = (warp([u0 + h, u1]) - warp([u0 - h, u1])) / (2.0 * h);
                let d1 = (warp([u0, u1 + h]) - warp([u0, u1 - h])) / (2.0 * h);
                let jac = d0.cross(&d1).norm();
                let p = pdf(&warp([u0, u1]));
                prop_assert!((p * jac - 1.0).abs() < 1e-4, "{} p {} jac {}", name, p, jac);
            }
        }
    }

    #[test]
    fn reported_pdf_matches_pdf_and_samples_are_unit_upper() {
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let samplers: [(&str, &dyn DirectionSampler); 2] = [
            ("uniform", &UniformHemisphere),
            ("cosine", &CosineHemisphere),
        ];
        for (name, s) in samplers {
            for _ in 0..10_000 {
                let d = s.sample(&wo, &mut rng);
                assert!((d.wi.norm() - 1.0).abs() < 1e-12 && d.wi.z > 0.0);
                let p = s.pdf(&wo, &d.wi);
                assert!(
                    (p - d.pdf).abs() <= 1e-12 * p.max(1.0),
                    "{name} {p} {}",
                    d.pdf
                );
            }
        }
    }

    #[test]
    fn pdf_is_the_same_for_any_positive_multiple_of_wi() {
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let wi = Vec3::new(0.3, 0.4, 0.5);
        let samplers: [(&str, &dyn DirectionSampler); 2] = [
            ("uniform", &UniformHemisphere),
            ("cosine", &CosineHemisphere),
        ];
        for (name, s) in samplers {
            let unit = s.pdf(&wo, &wi.normalize());
            for k in [0.5, 2.0, 1e3] {
                assert!((s.pdf(&wo, &(wi * k)) - unit).abs() <= 1e-15, "{name}");
            }
        }
    }

    #[test]
    fn cosine_estimator_of_projected_area_is_exact() {
        // E[cosθ / p] = π exactly for the cosine sampler (zero variance): a pdf off by any
        // factor would move it.
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        for _ in 0..1000 {
            let d = CosineHemisphere.sample(&wo, &mut rng);
            assert!((d.wi.z / d.pdf - PI).abs() < 1e-9);
        }
    }
}
