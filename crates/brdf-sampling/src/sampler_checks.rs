//! Checks of a direction sampler against its BRDF: the albedo estimator
//! `f_r(ωo, ωi) cos θi / p(ωi)` averaged over its samples (the Monte Carlo check against a
//! quadrature albedo, and the per-sample variance the studies compare), and `∫ p dσ` over the
//! upper hemisphere by the midpoint rule.

use brdf::{Brdf, Vec3};
use partition_sampler::UniformSource;
use rayon::prelude::*;

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

/// `∫ g dσ` over the upper hemisphere by the midpoint rule on `n_cos × n_phi` equal cells in
/// `(cos θ, φ)` (equal solid angles, so the rule is the mean of `g` at the cell centres times
/// 2π). Rows in parallel, summed in order: the result does not depend on the thread count.
pub fn upper_hemisphere_integral(
    g: &(dyn Fn(&Vec3) -> f64 + Sync),
    n_cos: usize,
    n_phi: usize,
) -> f64 {
    let cell = (1.0 / n_cos as f64) * (std::f64::consts::TAU / n_phi as f64);
    let rows: Vec<f64> = (0..n_cos)
        .into_par_iter()
        .map(|i| {
            let z = (i as f64 + 0.5) / n_cos as f64;
            let r = (1.0 - z * z).sqrt();
            (0..n_phi)
                .map(|j| {
                    let phi = (j as f64 + 0.5) / n_phi as f64 * std::f64::consts::TAU;
                    g(&Vec3::new(r * phi.cos(), r * phi.sin(), z))
                })
                .sum::<f64>()
        })
        .collect();
    rows.iter().sum::<f64>() * cell
}

/// `∫ g dσ` over the upper hemisphere by the midpoint rule on `2n × 2n` equal-area cells:
/// Shirley and Chiu's concentric map of `[−1, 1]²` to the disc, lifted to the hemisphere by
/// `z = 1 − r²` (`dσ = (π/2) du dv`), so every cell has the same solid angle and the rule's
/// resolution is uniform over the hemisphere, the pole included (unlike a grid in
/// `(cos θ, φ)`, [`upper_hemisphere_integral`]). Rows in parallel, summed in order: the
/// result does not depend on the thread count.
pub fn equal_area_hemisphere_integral(g: &(dyn Fn(&Vec3) -> f64 + Sync), n: usize) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
    let m = 2 * n;
    let rows: Vec<f64> = (0..m)
        .into_par_iter()
        .map(|i| {
            let a = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
            (0..m)
                .map(|j| {
                    let b = -1.0 + 2.0 * (j as f64 + 0.5) / m as f64;
                    let (r, phi) = if a.abs() > b.abs() {
                        (a, FRAC_PI_4 * (b / a))
                    } else {
                        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
                    };
                    let z = 1.0 - r * r;
                    let s = r * (2.0 - r * r).max(0.0).sqrt();
                    g(&Vec3::new(s * phi.cos(), s * phi.sin(), z))
                })
                .sum::<f64>()
        })
        .collect();
    FRAC_PI_2 * (2.0 / m as f64).powi(2) * rows.iter().sum::<f64>()
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
    fn cosine_sampling_of_lambert_has_zero_variance_and_a_wrong_pdf_shows_in_the_mean() {
        let lambert = brdf::parse_spec("lambert:rho=0.6").unwrap();
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        // A pdf reported twice too high halves the estimate.
        for (pdf_scale, albedo) in [(1.0, 0.6), (2.0, 0.3)] {
            let e = sampled_albedo(&Cosine { pdf_scale }, lambert.as_ref(), &wo, 1000, &mut rng);
            assert!((e.mean - albedo).abs() < 1e-12, "{e:?}");
            assert!(e.variance < 1e-20 && e.std_error() < 1e-10, "{e:?}");
        }
    }

    #[test]
    fn the_midpoint_rule_integrates_cos_and_the_cosine_pdf() {
        // ∫ cos θ dσ = π; the cosine pdf integrates to 1, twice that pdf to 2.
        let cos = upper_hemisphere_integral(&|w| w.z, 64, 128);
        assert!((cos - std::f64::consts::PI).abs() < 1e-3, "{cos}");
        for scale in [1.0, 2.0] {
            let s = Cosine { pdf_scale: scale };
            let wo = Vec3::new(0.0, 0.0, 1.0);
            let total = upper_hemisphere_integral(&|w| s.pdf(&wo, w), 64, 128);
            assert!((total - scale).abs() < 1e-3, "{total}");
        }
    }

    #[test]
    fn the_equal_area_rule_integrates_constants_and_cos() {
        // Equal solid angles per cell: ∫ 1 dσ = 2π to rounding; ∫ cos θ dσ = π; a lobe
        // about the pole (∫ cos^n θ dσ = 2π/(n + 1)); x², which depends on φ (2π/3).
        use std::f64::consts::PI;
        let one = equal_area_hemisphere_integral(&|_| 1.0, 64);
        assert!((one - 2.0 * PI).abs() < 1e-12, "{one}");
        for (g, exact) in [
            (&(|w: &Vec3| w.z) as &(dyn Fn(&Vec3) -> f64 + Sync), PI),
            (&|w: &Vec3| w.z.powi(20), 2.0 * PI / 21.0),
            (&|w: &Vec3| w.x * w.x, 2.0 * PI / 3.0),
        ] {
            // The midpoint rule's O(h²) error on 256 × 256 cells: 1.1e-4 on the cos^20 lobe.
            let v = equal_area_hemisphere_integral(g, 128);
            assert!((v / exact - 1.0).abs() < 5e-4, "{v} vs {exact}");
        }
    }
}
