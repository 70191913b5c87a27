//! The albedo estimator of a direction sampler: `f_r(ωo, ωi) cos θi / p(ωi)` averaged over its
//! samples, the Monte Carlo check of a sampler against a quadrature albedo and the per-sample
//! variance the studies compare.

use brdf::{Brdf, Vec3};
use partition_sampler::UniformSource;

use crate::DirectionSampler;

/// Mean and per-sample variance of the weights `f_r cos θi / p` of [`sampled_albedo`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledAlbedo {
    /// Mean weight: the estimate of the directional albedo `∫ f_r cos θi dωi`.
    pub mean: f64,
    /// Per-sample variance of the weights (`E[w²] − E[w]²`, clamped at 0 against rounding).
    pub variance: f64,
    /// Number of samples.
    pub samples: usize,
}

impl SampledAlbedo {
    /// Standard error of [`SampledAlbedo::mean`], `√(variance / samples)`.
    pub fn std_error(&self) -> f64 {
        (self.variance / self.samples as f64).sqrt()
    }
}

/// Draws `n` samples of `sampler` at `wo` from `u` and returns the moments of their weights
/// `w = f_r(ωo, ωi) cos θi / p(ωi)`; a sample with `p = 0` or below the horizon weighs 0 (the
/// estimator of the albedo is unbiased exactly where `p > 0` covers the support of `f_r cos`).
pub fn sampled_albedo(
    sampler: &dyn DirectionSampler,
    brdf: &dyn Brdf,
    wo: &Vec3,
    n: usize,
    u: &mut dyn UniformSource,
) -> SampledAlbedo {
    let (mut sum, mut sq) = (0.0, 0.0);
    for _ in 0..n {
        let d = sampler.sample(wo, u);
        let w = if d.wi.z > 0.0 && d.pdf > 0.0 {
            brdf.eval(wo, &d.wi) * d.wi.z / d.pdf
        } else {
            0.0
        };
        sum += w;
        sq += w * w;
    }
    let mean = sum / n as f64;
    SampledAlbedo {
        mean,
        variance: (sq / n as f64 - mean * mean).max(0.0),
        samples: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DirSample, SamplerDiagnostics};
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// Cosine-weighted hemisphere sampling, optionally reporting a wrong pdf.
    struct Cosine {
        pdf_scale: f64,
    }

    impl DirectionSampler for Cosine {
        fn sample(&self, _wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
            let (u0, u1) = (u.next_uniform(), u.next_uniform());
            let (r, phi) = (u0.sqrt(), std::f64::consts::TAU * u1);
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u0).max(0.0).sqrt());
            DirSample {
                pdf: self.pdf_scale * wi.z / std::f64::consts::PI,
                wi,
            }
        }
        fn pdf(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
            self.pdf_scale * wi.z.max(0.0) / std::f64::consts::PI
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    impl SamplerDiagnostics for Cosine {}

    #[test]
    fn cosine_sampling_of_lambert_has_zero_variance_and_a_wrong_pdf_shows() {
        let lambert = brdf::parse_spec("lambert:rho=0.6").unwrap();
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let exact = sampled_albedo(
            &Cosine { pdf_scale: 1.0 },
            lambert.as_ref(),
            &wo,
            1000,
            &mut rng,
        );
        assert!((exact.mean - 0.6).abs() < 1e-12, "{exact:?}");
        assert!(
            exact.variance < 1e-20 && exact.std_error() < 1e-10,
            "{exact:?}"
        );
        let wrong = sampled_albedo(
            &Cosine { pdf_scale: 2.0 },
            lambert.as_ref(),
            &wo,
            1000,
            &mut rng,
        );
        assert!((wrong.mean - 0.3).abs() < 1e-12, "{wrong:?}");
    }
}
