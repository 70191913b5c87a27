//! BRDF sampling alone, light sampling alone and multiple importance sampling of one BRDF
//! sampler and one environment-map sampler (Veach 1997, balance and power heuristics).
//!
//! Two drivers share the same per-sample terms ([`MisHeuristic::weight`], [`mis_brdf_term`],
//! [`mis_light_term`]):
//! * [`estimate_brdf`], [`estimate_light`], [`estimate_mis`] — `N` samples of a
//!   [`ProductScene`] into one [`Estimate`] (the `product` command);
//! * [`MisPair`] and [`light_value`] — one value per call for a renderer or a study that
//!   averages values itself (a pair: one BRDF draw and one light draw, equal counts).

use std::time::Instant;

use brdf::Vec3;
use brdf_sampling::{DirectionSampler, EvalSample};
use envmap::EnvMapSampler;
use partition_sampler::UniformSource;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use crate::batch::{LightTechnique, Radiance, brdf_value, mis_term, mis_term_with};
use crate::estimate::{Estimate, Moments};
use crate::heuristic::MisHeuristic;
use crate::{EstimatorError, LocalFrame, ProductScene};

pub(crate) fn check_samples(
    estimator: &'static str,
    n: usize,
    min: usize,
) -> Result<(), EstimatorError> {
    if n < min {
        return Err(EstimatorError::TooFewSamples {
            estimator,
            min,
            got: n,
        });
    }
    Ok(())
}

/// The start of an estimate of `n` samples (at least `min`): its clock and its generator
/// seeded with `seed`.
pub(crate) fn begin(
    estimator: &'static str,
    n: usize,
    min: usize,
    seed: u64,
) -> Result<(Instant, Xoshiro256PlusPlus), EstimatorError> {
    check_samples(estimator, n, min)?;
    Ok((Instant::now(), Xoshiro256PlusPlus::seed_from_u64(seed)))
}

/// Queries per [`DirectionSampler::sample_eval_batch`] call of the one-point estimators.
pub(crate) const CHUNK: usize = 4096;

/// `(1/N) Σ g/p` with a BRDF direction sampler (local frame), drawn on the batch path
/// ([`DirectionSampler::sample_eval_batch`], [`CHUNK`] samples of `scene.wo` per call) with
/// the scene's BRDF, whose `f` the integrand uses: a sampler that evaluated `f` while sampling
/// (a rejection sampler built on that very BRDF object) saves the integrand's evaluation. For
/// a sampler without its own batch path the values are those of `N` calls of
/// [`DirectionSampler::sample`] with the same seed.
pub fn estimate_brdf(
    scene: &ProductScene<'_>,
    sampler: &dyn DirectionSampler,
    name: &str,
    n: usize,
    seed: u64,
) -> Result<Estimate, EstimatorError> {
    let (start, mut rng) = begin("brdf", n, 2, seed)?;
    let mut m = Moments::default();
    brdf_chunks(scene, sampler, n, &mut rng, |s| {
        m.push(brdf_value(s, |s| scene.integrand_with_f(&s.wi, s.f)));
    });
    Ok(Estimate::from_parts(
        name,
        m.mean(),
        n,
        start.elapsed().as_secs_f64(),
        &[(&m, 1.0 / n as f64)],
    ))
}

/// `n` samples of `sampler` at `scene.wo` with the scene's BRDF, [`CHUNK`] per batch call,
/// each handed to `each` in order.
fn brdf_chunks(
    scene: &ProductScene<'_>,
    sampler: &dyn DirectionSampler,
    n: usize,
    rng: &mut Xoshiro256PlusPlus,
    mut each: impl FnMut(&EvalSample),
) {
    let wos = vec![scene.wo; CHUNK.min(n)];
    let mut out = Vec::with_capacity(wos.len());
    let mut left = n;
    while left > 0 {
        let k = left.min(CHUNK);
        sampler.sample_eval_batch(scene.brdf, &wos[..k], rng, &mut out);
        out.iter().for_each(&mut each);
        left -= k;
    }
}

/// `(1/N) Σ g/p` with an environment-map sampler (world directions turned into the frame).
pub fn estimate_light(
    scene: &ProductScene<'_>,
    sampler: &EnvMapSampler,
    name: &str,
    n: usize,
    seed: u64,
) -> Result<Estimate, EstimatorError> {
    check_samples("light", n, 2)?;
    Ok(one_sample_estimate(scene, name, n, seed, |rng| {
        let s = sampler.sample(rng);
        (scene.frame.to_local(&Vec3::from(s.direction)), s.pdf_sa)
    }))
}

/// `(1/N) Σ g(ωi)/p(ωi)` over `n` draws `(ωi, p)` (local frame, solid-angle pdf) from one
/// generator seeded with `seed`; a draw with `p = 0` contributes 0.
fn one_sample_estimate(
    scene: &ProductScene<'_>,
    name: &str,
    n: usize,
    seed: u64,
    mut draw: impl FnMut(&mut Xoshiro256PlusPlus) -> (Vec3, f64),
) -> Estimate {
    let start = Instant::now();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut m = Moments::default();
    for _ in 0..n {
        let (wi, pdf) = draw(&mut rng);
        m.push(if pdf > 0.0 {
            scene.integrand(&wi) / pdf
        } else {
            0.0
        });
    }
    Estimate::from_parts(
        name,
        m.mean(),
        n,
        start.elapsed().as_secs_f64(),
        &[(&m, 1.0 / n as f64)],
    )
}

/// The MIS contribution of a BRDF-sampled direction: `w_brdf · g / p_brdf`, with
/// `w_brdf = weight(n_brdf p_brdf, n_light p_light)`; `g` is the integrand at the direction,
/// `light_pdf` is evaluated only where `g > 0`. 0 when `g` or `p_brdf` is not positive.
#[inline]
pub fn mis_brdf_term(
    heuristic: MisHeuristic,
    g: f64,
    brdf_pdf: f64,
    n_brdf: f64,
    n_light: f64,
    light_pdf: impl FnOnce() -> f64,
) -> f64 {
    mis_term(heuristic, g, brdf_pdf, n_brdf, n_light, light_pdf)
}

/// The MIS contribution of a light-sampled direction: `w_light · g / p_light`, `brdf_pdf`
/// evaluated only where `g > 0`. 0 when `g` or `p_light` is not positive.
#[inline]
pub fn mis_light_term(
    heuristic: MisHeuristic,
    g: f64,
    light_pdf: f64,
    n_light: f64,
    n_brdf: f64,
    brdf_pdf: impl FnOnce() -> f64,
) -> f64 {
    mis_term(heuristic, g, light_pdf, n_light, n_brdf, brdf_pdf)
}

/// MIS of a BRDF sampler and a map sampler: `⌈N/2⌉` and `⌊N/2⌋` samples,
/// `Σ_t (1/n_t) Σ_j w_t g / p_t`.
pub fn estimate_mis(
    scene: &ProductScene<'_>,
    brdf_sampler: &dyn DirectionSampler,
    light_sampler: &EnvMapSampler,
    heuristic: MisHeuristic,
    name: &str,
    n: usize,
    seed: u64,
) -> Result<Estimate, EstimatorError> {
    let (start, mut rng) = begin("mis", n, 4, seed)?;
    let (na, nb) = (n.div_ceil(2), n / 2);
    let light_pdf = |wi: &Vec3| {
        light_sampler.pdf_sa({
            let w = scene.frame.to_world(wi);
            [w.x, w.y, w.z]
        })
    };
    let mut ma = Moments::default();
    brdf_chunks(scene, brdf_sampler, na, &mut rng, |s| {
        let g = if s.wi.z > 0.0 {
            scene.integrand_with_f(&s.wi, s.f)
        } else {
            0.0
        };
        ma.push(mis_brdf_term(
            heuristic,
            g,
            s.pdf,
            na as f64,
            nb as f64,
            || light_pdf(&s.wi),
        ));
    });
    let mut mb = Moments::default();
    for _ in 0..nb {
        let s = light_sampler.sample(&mut rng);
        let wi = scene.frame.to_local(&Vec3::from(s.direction));
        let g = scene.integrand(&wi);
        mb.push(mis_light_term(
            heuristic,
            g,
            s.pdf_sa,
            nb as f64,
            na as f64,
            || brdf_sampler.pdf(&scene.wo, &wi),
        ));
    }
    Ok(Estimate::from_parts(
        name,
        ma.mean() + mb.mean(),
        n,
        start.elapsed().as_secs_f64(),
        &[(&ma, 1.0 / na as f64), (&mb, 1.0 / nb as f64)],
    ))
}

/// One light-sampling value `g(ω)/p(ω)` for a map sampler in the frame `frame` (0 where the
/// pdf is 0): `g` is the integrand at a local direction.
pub fn light_value(
    light_sampler: &EnvMapSampler,
    frame: &LocalFrame,
    g: impl Fn(&Vec3) -> f64,
    rng: &mut dyn UniformSource,
) -> f64 {
    let s = light_sampler.sample(rng);
    if s.pdf_sa > 0.0 {
        g(&frame.to_local(&Vec3::from(s.direction))) / s.pdf_sa
    } else {
        0.0
    }
}

/// A renderer's MIS sample: one draw of the BRDF sampler and one of the light technique,
/// equal counts (`n_brdf = n_light`), so that the mean of `N` values is [`estimate_mis`]'s
/// estimator with `N` samples of each technique. Directions are local to `frame`; the light
/// (an environment-map sampler by default, any [`LightTechnique`]) is world-space. The values
/// may be luminances or RGB ([`Radiance`]); the terms are [`mis_term`]'s.
pub struct MisPair<'a, L: LightTechnique + ?Sized = EnvMapSampler> {
    /// The BRDF technique.
    pub brdf_sampler: &'a dyn DirectionSampler,
    /// The light technique.
    pub light_sampler: &'a L,
    /// The shading frame.
    pub frame: LocalFrame,
    /// The weights.
    pub heuristic: MisHeuristic,
}

// Copy whatever `L` is (the fields are references): no `L: Copy` bound as a derive would add.
impl<L: LightTechnique + ?Sized> Clone for MisPair<'_, L> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<L: LightTechnique + ?Sized> Copy for MisPair<'_, L> {}

impl<L: LightTechnique + ?Sized> std::fmt::Debug for MisPair<'_, L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MisPair")
            .field("frame", &self.frame)
            .field("heuristic", &self.heuristic)
            .finish_non_exhaustive()
    }
}

impl<L: LightTechnique + ?Sized> MisPair<'_, L> {
    /// `w_b g(ω_b)/p_b(ω_b) + w_l g(ω_l)/p_l(ω_l)` for one BRDF draw `ω_b` (first) and one
    /// light draw `ω_l` from `rng`; `g` is the integrand at a local direction (0 below the
    /// horizon).
    pub fn value<V: Radiance>(
        &self,
        wo: &Vec3,
        g: impl Fn(&Vec3) -> V,
        rng: &mut dyn UniformSource,
    ) -> V {
        let h = self.heuristic;
        self.value_with(wo, g, rng, &|own, other| h.weight(own, other))
    }

    /// [`Self::value`] with the weight `weight(own, other)` (the tests give it broken ones).
    fn value_with<V: Radiance>(
        &self,
        wo: &Vec3,
        g: impl Fn(&Vec3) -> V,
        rng: &mut dyn UniformSource,
        weight: &impl Fn(f64, f64) -> f64,
    ) -> V {
        let s = self.brdf_sampler.sample(wo, rng);
        let a = mis_term_with(
            g(&s.wi),
            s.pdf,
            1.0,
            1.0,
            || self.light_sampler.pdf_world(&self.frame.to_world(&s.wi)),
            weight,
        );
        let Some((d, pl)) = self.light_sampler.sample_world(rng) else {
            return a;
        };
        let wi = self.frame.to_local(&d);
        let b = mis_term_with(
            g(&wi),
            pl,
            1.0,
            1.0,
            || self.brdf_sampler.pdf(wo, &wi),
            weight,
        );
        a.plus(b)
    }

    /// The two draws alone (no integrand, no weights): the sampling cost of [`Self::value`].
    pub fn draw(&self, wo: &Vec3, rng: &mut dyn UniformSource) -> (Vec3, Vec3) {
        let s = self.brdf_sampler.sample(wo, rng);
        let l = self
            .light_sampler
            .sample_world(rng)
            .map_or(Vec3::zeros(), |(d, _)| self.frame.to_local(&d));
        (s.wi, l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature_reference;
    use baselines::CosineHemisphere;
    use proptest::prelude::*;

    proptest! {
        /// Unbiasedness of MIS needs `w_a(ω) + w_b(ω) = 1` wherever `p_a + p_b > 0`.
        #[test]
        fn weights_sum_to_one(a in 0.0..1e6f64, b in 0.0..1e6f64) {
            prop_assume!(a + b > 0.0);
            for h in MisHeuristic::ALL {
                let (wa, wb) = (h.weight(a, b), h.weight(b, a));
                prop_assert!((0.0..=1.0).contains(&wa) && (0.0..=1.0).contains(&wb));
                prop_assert!((wa + wb - 1.0).abs() < 1e-12, "{h:?}: {wa} + {wb}");
            }
        }
    }

    /// A small map (dim background, one bright patch), a glossy Phong, a tilted frame: the MIS
    /// pair's mean and `estimate_mis` against the pixel quadrature, z at a 4σ level (a
    /// two-sided 6·10⁻⁵ false-alarm rate per check, fixed seeds); a pair whose weights do not
    /// sum to one (the light technique's weight forgets that the counts are equal and halves
    /// the BRDF technique's density) is caught.
    #[test]
    fn mis_agrees_with_the_quadrature_and_a_broken_weight_is_caught() {
        let (map, brdf, frame, wo) = crate::batch::tests::scene_parts();
        let scene = ProductScene::new(brdf.as_ref(), &map, frame, wo).unwrap();
        let (q, q_err) = quadrature_reference(&scene, 4);
        assert!(q > 0.0 && q_err < 1e-3 * q, "{q} ± {q_err}");
        let light = EnvMapSampler::piecewise_constant(&map).unwrap();
        let pair = |heuristic| MisPair {
            brdf_sampler: &CosineHemisphere,
            light_sampler: &light,
            frame,
            heuristic,
        };
        let n = 20_000;
        let z_of = |values: &[f64]| {
            let m = values.iter().sum::<f64>() / n as f64;
            let v = values.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (n - 1) as f64;
            (m - q) / (v / n as f64).sqrt()
        };
        let g = |wi: &Vec3| scene.integrand(wi);
        for (k, heuristic) in MisHeuristic::ALL.into_iter().enumerate() {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(11 + k as u64);
            let p = pair(heuristic);
            let values: Vec<f64> = (0..n).map(|_| p.value(&wo, g, &mut rng)).collect();
            let z = z_of(&values);
            assert!(z.abs() < 4.0, "{heuristic:?} pair: z = {z}");
            let e = estimate_mis(
                &scene,
                &CosineHemisphere,
                &light,
                heuristic,
                "mis",
                n,
                21 + k as u64,
            )
            .unwrap();
            let z = (e.estimate - q) / e.std_err;
            assert!(
                z.abs() < 4.0 && !e.heavy_tailed,
                "{heuristic:?}: {e:?} vs {q}"
            );
        }
        // The broken weight: w(own, other) = own / (own + other / 2), so w_a + w_b > 1.
        let broken = |own: f64, other: f64| own / (own + 0.5 * other);
        assert!(broken(1.0, 1.0) + broken(1.0, 1.0) > 1.3);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let p = pair(MisHeuristic::Balance);
        let values: Vec<f64> = (0..n)
            .map(|_| p.value_with(&wo, g, &mut rng, &broken))
            .collect();
        let z = z_of(&values);
        assert!(z.abs() > 4.0, "broken weight not caught: z = {z}");
    }
}
