//! BRDF-blind direction samplers on the upper hemisphere: uniform and cosine-weighted.
//!
//! Both ignore `ωo` and the BRDF; they are the simplest baselines of the seed papers' studies.
//! Pdfs are with respect to **solid angle**.

use std::f64::consts::{FRAC_1_PI, PI, TAU};

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler};
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

impl UniformHemisphere {
    /// Warps `u ∈ [0,1)²` to a direction and its solid-angle pdf.
    pub fn sample_square(u: [f64; 2]) -> DirSample {
        let z = 1.0 - u[0]; // in (0, 1]: never exactly on the horizon
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = TAU * u[1];
        DirSample {
            wi: Vec3::new(r * phi.cos(), r * phi.sin(), z),
            pdf: 1.0 / TAU,
        }
    }
}

impl CosineHemisphere {
    /// Warps `u ∈ [0,1)²` to a direction and its solid-angle pdf.
    pub fn sample_square(u: [f64; 2]) -> DirSample {
        let r2 = u[0];
        let r = r2.sqrt();
        let phi = TAU * u[1];
        let z = (1.0 - r2).max(0.0).sqrt();
        DirSample {
            wi: Vec3::new(r * phi.cos(), r * phi.sin(), z),
            pdf: z * FRAC_1_PI,
        }
    }
}

impl DirectionSampler for UniformHemisphere {
    fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        Self::sample_square([u0, u1])
    }
    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        if wi.z > 0.0 { 1.0 / (2.0 * PI) } else { 0.0 }
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

impl DirectionSampler for CosineHemisphere {
    fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        Self::sample_square([u0, u1])
    }
    fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        if wi.z > 0.0 {
            wi.z / wi.norm() * FRAC_1_PI
        } else {
            0.0
        }
    }
    fn bytes_used(&self) -> usize {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

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
