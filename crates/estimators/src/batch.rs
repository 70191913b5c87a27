//! The estimators on the batch path: many query points (a row of pixels, each with its own
//! `ωo` and shading frame) × `spp` samples drawn by **one**
//! [`DirectionSampler::sample_eval_batch`] call, and the per-sample terms of BRDF sampling and
//! MIS for any value a caller integrates — a luminance (`f64`) or an RGB radiance
//! (`[f64; 3]`), see [`Radiance`]. The one-query forms of this crate ([`crate::estimate_brdf`],
//! [`crate::estimate_mis`], [`crate::MisPair`]) use the same terms.
//!
//! **Order of the uniforms.** A batch draws the BRDF samples of every query in one call (a
//! sampler may consume the uniforms in its own order, grouped by its structure), then — for
//! MIS — the light samples, query-major, from the same generator. The law of each sample is the
//! one-query law; the values differ from a one-query-at-a-time loop with the same seed.

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, EvalSample};
use envmap::EnvMapSampler;
use partition_sampler::UniformSource;

use crate::LocalFrame;
use crate::heuristic::MisHeuristic;

/// A value an estimator averages: a scalar (luminance) or a linear RGB triple. Values are
/// non-negative integrands divided by densities.
pub trait Radiance: Copy + Default + Send + Sync {
    /// `self · k`.
    fn scale(self, k: f64) -> Self;
    /// `self + other`.
    fn plus(self, other: Self) -> Self;
    /// Whether any channel is positive (where a term can be non-zero; the MIS terms evaluate
    /// the other technique's density only there).
    fn any_positive(&self) -> bool;
}

impl Radiance for f64 {
    #[inline]
    fn scale(self, k: f64) -> Self {
        self * k
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        self + other
    }
    #[inline]
    fn any_positive(&self) -> bool {
        *self > 0.0
    }
}

impl Radiance for [f64; 3] {
    #[inline]
    fn scale(self, k: f64) -> Self {
        self.map(|c| c * k)
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        [self[0] + other[0], self[1] + other[1], self[2] + other[2]]
    }
    #[inline]
    fn any_positive(&self) -> bool {
        self.iter().any(|c| *c > 0.0)
    }
}

/// A light technique of MIS: directions drawn in **world** space with their solid-angle
/// density (an environment-map sampler, a renderer's area light).
pub trait LightTechnique: Sync {
    /// A world direction and its solid-angle pdf, or `None` when the light has nothing to
    /// sample (then no uniform is consumed).
    fn sample_world(&self, u: &mut dyn UniformSource) -> Option<(Vec3, f64)>;
    /// The solid-angle density of the world direction `w` (the one `sample_world` reports).
    fn pdf_world(&self, w: &Vec3) -> f64;
}

impl LightTechnique for EnvMapSampler {
    #[inline]
    fn sample_world(&self, u: &mut dyn UniformSource) -> Option<(Vec3, f64)> {
        let s = self.sample(u);
        Some((Vec3::from(s.direction), s.pdf_sa))
    }
    #[inline]
    fn pdf_world(&self, w: &Vec3) -> f64 {
        self.pdf_sa([w.x, w.y, w.z])
    }
}

/// The BRDF-sampling value `g / p` of a drawn sample (0 where `p = 0`, below the horizon or
/// where `g` is 0); `g` is the integrand at the sample.
#[inline]
pub fn brdf_value<V: Radiance>(s: &EvalSample, g: impl FnOnce(&EvalSample) -> V) -> V {
    if s.pdf > 0.0 && s.wi.z > 0.0 {
        g(s).scale(1.0 / s.pdf)
    } else {
        V::default()
    }
}

/// The MIS contribution of one technique's sample: `w · g / p_own` with
/// `w = heuristic.weight(n_own p_own, n_other p_other)`; `other_pdf` is evaluated only where
/// `g` is positive. 0 when `g` is 0 or `p_own` is not positive. [`crate::mis_brdf_term`],
/// [`crate::mis_light_term`], [`crate::MisPair`] and [`Batch::mis`] all go through it.
#[inline]
pub fn mis_term<V: Radiance>(
    heuristic: MisHeuristic,
    g: V,
    own_pdf: f64,
    n_own: f64,
    n_other: f64,
    other_pdf: impl FnOnce() -> f64,
) -> V {
    mis_term_with(g, own_pdf, n_own, n_other, other_pdf, &|a, b| {
        heuristic.weight(a, b)
    })
}

/// [`mis_term`] with the weight `weight(n_own p_own, n_other p_other)` (the tests give it
/// broken ones).
#[inline]
pub(crate) fn mis_term_with<V: Radiance>(
    g: V,
    own_pdf: f64,
    n_own: f64,
    n_other: f64,
    other_pdf: impl FnOnce() -> f64,
    weight: &impl Fn(f64, f64) -> f64,
) -> V {
    if g.any_positive() && own_pdf > 0.0 {
        let w = weight(n_own * own_pdf, n_other * other_pdf());
        g.scale(w / own_pdf)
    } else {
        V::default()
    }
}

/// One query point of a batch: its outgoing direction (local, unit, `z > 0`) and its frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Query {
    /// `ωo` in the local frame.
    pub wo: Vec3,
    /// The shading frame (local ↔ world).
    pub frame: LocalFrame,
}

/// A batch of query points and the sampler that serves them: one
/// [`DirectionSampler::sample_eval_batch`] call per estimate, `spp` queries per point
/// (point-major), outputs in the points' order.
pub struct Batch<'a> {
    /// The BRDF technique.
    pub sampler: &'a dyn DirectionSampler,
    /// The BRDF given to [`DirectionSampler::sample_eval_batch`] (its `f` reaches `g` as
    /// [`EvalSample::f`]). A caller that needs another value than this BRDF's `f` (RGB) may pass
    /// a cheap stand-in so that no evaluation is wasted.
    pub brdf: &'a dyn Brdf,
    /// Samples per point (of each technique for MIS).
    pub spp: usize,
}

impl std::fmt::Debug for Batch<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Batch")
            .field("spp", &self.spp)
            .finish_non_exhaustive()
    }
}

impl Batch<'_> {
    /// The `spp` BRDF samples of every point in one call: `out[k·spp + j]` is sample `j` of
    /// point `k`.
    pub fn draw(&self, points: &[Query], u: &mut dyn UniformSource, out: &mut Vec<EvalSample>) {
        let wos: Vec<Vec3> = points
            .iter()
            .flat_map(|p| std::iter::repeat_n(p.wo, self.spp))
            .collect();
        self.sampler.sample_eval_batch(self.brdf, &wos, u, out);
    }

    /// BRDF sampling alone: per point `(1/spp) Σ_j g(k, s_kj) / p(s_kj)`, `g(k, s)` the
    /// integrand of point `k` at the drawn sample `s` (local frame; `s.f` is the batch BRDF's).
    pub fn brdf<V: Radiance>(
        &self,
        points: &[Query],
        g: impl Fn(usize, &EvalSample) -> V,
        u: &mut dyn UniformSource,
    ) -> Vec<V> {
        let mut out = Vec::new();
        self.draw(points, u, &mut out);
        self.reduce(points.len(), &out, |k, s| brdf_value(s, |s| g(k, s)))
    }

    /// Multiple importance sampling of the batch's sampler and `light`, `spp` samples of each
    /// per point (equal counts): per point
    /// `(1/spp) Σ_j [w_b g(ω_bj)/p_b(ω_bj) + w_l g(ω_lj)/p_l(ω_lj)]`. The BRDF samples of every
    /// point come first (one batch call), then the light samples, point-major. `g(k, ωi, f)`
    /// is point `k`'s integrand at the local direction `ωi`, with `f = Some(s.f)` at a BRDF
    /// sample and `None` at a light sample. The light's density is evaluated at the world
    /// direction `frame.to_world(ωi)`, the BRDF sampler's at the local one: per point, at its
    /// light samples where `g` is positive, by one [`DirectionSampler::pdf_many`] call.
    pub fn mis<V: Radiance, L: LightTechnique + ?Sized>(
        &self,
        points: &[Query],
        light: &L,
        heuristic: MisHeuristic,
        g: impl Fn(usize, &Vec3, Option<f64>) -> V,
        u: &mut dyn UniformSource,
    ) -> Vec<V> {
        self.mis_with(points, light, g, u, |own, other| {
            heuristic.weight(own, other)
        })
    }

    /// [`Self::mis`] for an integrand whose BRDF is the batch's (`self.brdf`, e.g. the luminance
    /// or a grey BRDF's colour times `f`): `g(k, ωi, f)` receives `f = f_r(ωo, ωi)` of
    /// `self.brdf` at every sample — the sampler's at a BRDF sample ([`EvalSample::f`]), one
    /// evaluation by the batch at a light sample above the horizon — and the BRDF sampler's pdf
    /// at a point's light samples is one [`DirectionSampler::pdf_many_given_f`] call with those
    /// `f`, so a sampler whose pdf is `f cos θi / A(ωo)` (`adaptive-exact`, built with
    /// `self.brdf`) evaluates nothing more. The same uniforms, samples and values as
    /// [`Self::mis`] with an integrand that evaluates `f` itself (bit for bit where
    /// `pdf_many_given_f` equals `pdf_many`, as its contract requires).
    pub fn mis_given_f<V: Radiance, L: LightTechnique + ?Sized>(
        &self,
        points: &[Query],
        light: &L,
        heuristic: MisHeuristic,
        g: impl Fn(usize, &Vec3, f64) -> V,
        u: &mut dyn UniformSource,
    ) -> Vec<V> {
        self.mis_core(
            points,
            light,
            |k, wi, f| g(k, wi, f.unwrap_or(0.0)),
            u,
            |own, other| heuristic.weight(own, other),
            true,
        )
    }

    /// [`Self::mis`] with the weight `weight(own, other)` (the tests give it broken ones).
    pub(crate) fn mis_with<V: Radiance, L: LightTechnique + ?Sized>(
        &self,
        points: &[Query],
        light: &L,
        g: impl Fn(usize, &Vec3, Option<f64>) -> V,
        u: &mut dyn UniformSource,
        weight: impl Fn(f64, f64) -> f64,
    ) -> Vec<V> {
        self.mis_core(points, light, g, u, weight, false)
    }

    /// [`Self::mis_with`]; with `known_f`, [`Self::mis_given_f`]'s light samples (`f` of
    /// `self.brdf` evaluated here and handed to `g` and to `pdf_many_given_f`).
    fn mis_core<V: Radiance, L: LightTechnique + ?Sized>(
        &self,
        points: &[Query],
        light: &L,
        g: impl Fn(usize, &Vec3, Option<f64>) -> V,
        u: &mut dyn UniformSource,
        weight: impl Fn(f64, f64) -> f64,
        known_f: bool,
    ) -> Vec<V> {
        let mut out = Vec::new();
        self.draw(points, u, &mut out);
        let mut acc = self.reduce(points.len(), &out, |k, s| {
            let p = &points[k];
            let gb = if s.wi.z > 0.0 {
                g(k, &s.wi, Some(s.f))
            } else {
                V::default()
            };
            mis_term_with(
                gb,
                s.pdf,
                1.0,
                1.0,
                || light.pdf_world(&p.frame.to_world(&s.wi)),
                &weight,
            )
        });
        let inv = 1.0 / self.spp.max(1) as f64;
        // Per point: its light samples, then the BRDF sampler's pdf at those that can
        // contribute in one `pdf_many` call at the point's ωo (a sampler that locates ωo in
        // its structure does so once per point). Zero terms are skipped: the sum is the same.
        let mut terms: Vec<(V, f64)> = Vec::with_capacity(self.spp);
        let mut wis: Vec<Vec3> = Vec::with_capacity(self.spp);
        let mut fs: Vec<f64> = Vec::with_capacity(if known_f { self.spp } else { 0 });
        for (k, p) in points.iter().enumerate() {
            terms.clear();
            wis.clear();
            fs.clear();
            for _ in 0..self.spp {
                let Some((d, pl)) = light.sample_world(u) else {
                    break;
                };
                let wi = p.frame.to_local(&d);
                if wi.z > 0.0 && pl > 0.0 {
                    let f = known_f.then(|| self.brdf.eval(&p.wo, &wi));
                    let gl = g(k, &wi, f);
                    if gl.any_positive() {
                        terms.push((gl, pl));
                        wis.push(wi);
                        if let Some(f) = f {
                            fs.push(f);
                        }
                    }
                }
            }
            if terms.is_empty() {
                continue;
            }
            let pdfs = if known_f {
                self.sampler.pdf_many_given_f(self.brdf, &p.wo, &wis, &fs)
            } else {
                self.sampler.pdf_many(&p.wo, &wis)
            };
            let mut sum = V::default();
            for (&(gl, pl), &pb) in terms.iter().zip(&pdfs) {
                sum = sum.plus(mis_term_with(gl, pl, 1.0, 1.0, || pb, &weight));
            }
            acc[k] = acc[k].plus(sum.scale(inv));
        }
        acc
    }

    /// Per point, the mean over its `spp` outputs of `term(k, s)`.
    fn reduce<V: Radiance>(
        &self,
        points: usize,
        out: &[EvalSample],
        term: impl Fn(usize, &EvalSample) -> V,
    ) -> Vec<V> {
        let inv = 1.0 / self.spp.max(1) as f64;
        (0..points)
            .map(|k| {
                out[k * self.spp..(k + 1) * self.spp]
                    .iter()
                    .fold(V::default(), |a, s| a.plus(term(k, s)))
                    .scale(inv)
            })
            .collect()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{ProductScene, estimate_brdf, quadrature_reference};
    use baselines::CosineHemisphere;
    use envmap::EnvMap;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// A dim map with a bright patch, a glossy Phong, a tilted frame (shared with `mis.rs`'s
    /// test).
    pub(crate) fn scene_parts() -> (EnvMap, Box<dyn Brdf>, LocalFrame, Vec3) {
        let (w, h) = (32, 16);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (3..6).contains(&y) && (20..24).contains(&x) {
                    [40.0; 3]
                } else {
                    [0.5; 3]
                }
            })
            .collect();
        (
            EnvMap::new(w, h, rgb).unwrap(),
            brdf::parse_spec("phong:n=20,ks=0.6,kd=0.3").unwrap(),
            LocalFrame::new([0.3, -0.2, 0.9], 0.4).unwrap(),
            brdf::direction_from_angles(35.0, 20.0),
        )
    }

    /// `estimate_brdf` on the batch path gives, for a sampler without its own batch path, the
    /// values of the one-sample loop it replaced (`sample`, then the integrand over the pdf)
    /// with the same seed, to rounding.
    #[test]
    fn estimate_brdf_on_the_batch_path_equals_the_one_sample_loop() {
        let (map, brdf, frame, wo) = scene_parts();
        let scene = ProductScene::new(brdf.as_ref(), &map, frame, wo).unwrap();
        let n = 5000; // more than one chunk
        let e = estimate_brdf(&scene, &CosineHemisphere, "brdf", n, 4).unwrap();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        let sum: f64 = (0..n)
            .map(|_| {
                let s = CosineHemisphere.sample(&scene.wo, &mut rng);
                if s.pdf > 0.0 {
                    scene.integrand(&s.wi) / s.pdf
                } else {
                    0.0
                }
            })
            .sum();
        approx::assert_relative_eq!(e.estimate, sum / n as f64, max_relative = 1e-12);
    }

    /// `Batch::mis` over points that share the scene's ωo and frame (one batch call for all
    /// of them) is unbiased: the mean over points against the pixel quadrature, |z| < 4
    /// (two-sided α ≈ 6·10⁻⁵, fixed seed); with a weight that does not sum to one it is not.
    #[test]
    fn batch_mis_agrees_with_the_quadrature_and_a_broken_weight_is_caught() {
        let (map, brdf, frame, wo) = scene_parts();
        let scene = ProductScene::new(brdf.as_ref(), &map, frame, wo).unwrap();
        let (q, _) = quadrature_reference(&scene, 4);
        let light = EnvMapSampler::piecewise_constant(&map).unwrap();
        let points = vec![
            Query {
                wo: scene.wo,
                frame
            };
            4000
        ];
        let batch = Batch {
            sampler: &CosineHemisphere,
            brdf: brdf.as_ref(),
            spp: 4,
        };
        let g = |_: usize, wi: &Vec3, f: Option<f64>| match f {
            Some(f) => scene.integrand_with_f(wi, f),
            None => scene.integrand(wi),
        };
        let z_of = |v: &[f64]| {
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (n - 1.0);
            (m - q) / (var / n).sqrt()
        };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(12);
        let v = batch.mis(&points, &light, MisHeuristic::Power, g, &mut rng);
        let z = z_of(&v);
        assert!(z.abs() < 4.0, "batch MIS: z = {z}");
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(12);
        let v = batch.mis_with(&points, &light, g, &mut rng, |own, other| {
            own / (own + 0.5 * other)
        });
        let z = z_of(&v);
        assert!(z.abs() > 4.0, "broken weight not caught: z = {z}");
    }

    /// `CosineHemisphere` whose `pdf_many` may hand its values back in reverse (broken).
    struct Cosine {
        reversed: bool,
    }

    impl brdf_sampling::SamplerDiagnostics for Cosine {}

    impl DirectionSampler for Cosine {
        fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> brdf_sampling::DirSample {
            CosineHemisphere.sample(wo, u)
        }
        fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            CosineHemisphere.pdf(wo, wi)
        }
        fn pdf_many(&self, wo: &Vec3, wi: &[Vec3]) -> Vec<f64> {
            let mut v: Vec<f64> = wi.iter().map(|w| self.pdf(wo, w)).collect();
            if self.reversed {
                v.reverse();
            }
            v
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    /// `Batch::mis` (the BRDF pdfs of a point's light samples from one `pdf_many` call) gives
    /// bit for bit the values of the per-sample loop it replaced (`pdf` at each light sample,
    /// in order, zero terms included); a `pdf_many` that returns its values in reverse
    /// order does not.
    #[test]
    fn batch_mis_light_pdfs_from_pdf_many_equal_the_per_sample_loop_and_a_misordered_one_fails() {
        let (map, brdf, frame, wo) = scene_parts();
        let scene = ProductScene::new(brdf.as_ref(), &map, frame, wo).unwrap();
        let light = EnvMapSampler::piecewise_constant(&map).unwrap();
        let points: Vec<Query> = (0..64)
            .map(|i| Query {
                wo: brdf::direction_from_angles(1.0 + i as f64, 7.0 * i as f64),
                frame,
            })
            .collect();
        let g = |_: usize, wi: &Vec3, _: Option<f64>| scene.integrand(wi);
        let spp = 6;
        // The loop before `pdf_many`: BRDF terms as `Batch::mis`, then per point and light
        // sample `mis_term` with the sampler's `pdf`.
        let before = |u: &mut Xoshiro256PlusPlus| -> Vec<f64> {
            let batch = Batch {
                sampler: &CosineHemisphere,
                brdf: brdf.as_ref(),
                spp,
            };
            let mut out = Vec::new();
            batch.draw(&points, u, &mut out);
            let mut acc = batch.reduce(points.len(), &out, |k, s| {
                let gb = if s.wi.z > 0.0 { g(k, &s.wi, None) } else { 0.0 };
                mis_term(MisHeuristic::Balance, gb, s.pdf, 1.0, 1.0, || {
                    light.pdf_world(&points[k].frame.to_world(&s.wi))
                })
            });
            for (k, p) in points.iter().enumerate() {
                let mut sum = 0.0;
                for _ in 0..spp {
                    let (d, pl) = light.sample_world(u).unwrap();
                    let wi = p.frame.to_local(&d);
                    let gl = if wi.z > 0.0 { g(k, &wi, None) } else { 0.0 };
                    sum += mis_term(MisHeuristic::Balance, gl, pl, 1.0, 1.0, || {
                        CosineHemisphere.pdf(&p.wo, &wi)
                    });
                }
                acc[k] += sum * (1.0 / spp as f64);
            }
            acc
        };
        let now = |reversed: bool, u: &mut Xoshiro256PlusPlus| -> Vec<f64> {
            Batch {
                sampler: &Cosine { reversed },
                brdf: brdf.as_ref(),
                spp,
            }
            .mis(&points, &light, MisHeuristic::Balance, g, u)
        };
        let seeded = || Xoshiro256PlusPlus::seed_from_u64(31);
        let want = before(&mut seeded());
        assert!(want.iter().filter(|v| **v > 0.0).count() > 40);
        assert_eq!(now(false, &mut seeded()), want);
        assert_ne!(
            now(true, &mut seeded()),
            want,
            "misordered pdf_many not caught"
        );
    }

    /// Cosine sampling whose `pdf_many_given_f` checks the `f` it is handed against
    /// `brdf.eval(ωo, ωi)` (counting mismatches) and may scale its pdf (broken).
    struct GivenF {
        brdf: Box<dyn Brdf>,
        mismatches: std::sync::atomic::AtomicUsize,
        calls: std::sync::atomic::AtomicUsize,
        scale: f64,
    }

    impl brdf_sampling::SamplerDiagnostics for GivenF {}

    impl DirectionSampler for GivenF {
        fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> brdf_sampling::DirSample {
            CosineHemisphere.sample(wo, u)
        }
        fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
            CosineHemisphere.pdf(wo, wi)
        }
        fn pdf_many_given_f(&self, _: &dyn Brdf, wo: &Vec3, wi: &[Vec3], f: &[f64]) -> Vec<f64> {
            use std::sync::atomic::Ordering::Relaxed;
            self.calls.fetch_add(1, Relaxed);
            if f.len() != wi.len() {
                self.mismatches.fetch_add(1, Relaxed);
            }
            for (w, &f) in wi.iter().zip(f) {
                if self.brdf.eval(wo, w).to_bits() != f.to_bits() {
                    self.mismatches.fetch_add(1, Relaxed);
                }
            }
            wi.iter().map(|w| self.scale * self.pdf(wo, w)).collect()
        }
        fn bytes_used(&self) -> usize {
            0
        }
    }

    /// `Batch::mis_given_f` (the integrand handed `f` at every sample, the BRDF pdf at the
    /// light samples from `pdf_many_given_f` with those `f`) gives bit for bit the values of
    /// `Batch::mis` with an integrand that evaluates `f` itself, handing the sampler each light
    /// sample's `f = brdf.eval(ωo, ωi)` in order; a `pdf_many_given_f` that departs from the
    /// pdf (× 1.5) changes the values (the path is used).
    #[test]
    fn batch_mis_given_f_equals_mis_and_hands_the_sampler_the_light_samples_f() {
        let (map, brdf, frame, _) = scene_parts();
        let light = EnvMapSampler::piecewise_constant(&map).unwrap();
        // The scenes' ωo (normalised by `ProductScene::new`) are the points' ωo.
        let scenes: Vec<ProductScene> = (0..64)
            .map(|i| {
                let wo = brdf::direction_from_angles(1.0 + i as f64, 7.0 * i as f64);
                ProductScene::new(brdf.as_ref(), &map, frame, wo).unwrap()
            })
            .collect();
        let points: Vec<Query> = scenes.iter().map(|s| Query { wo: s.wo, frame }).collect();
        let spp = 6;
        let sampler = |scale: f64| GivenF {
            brdf: brdf::parse_spec("phong:n=20,ks=0.6,kd=0.3").unwrap(),
            mismatches: 0.into(),
            calls: 0.into(),
            scale,
        };
        let seeded = || Xoshiro256PlusPlus::seed_from_u64(37);
        let s = sampler(1.0);
        let batch = Batch {
            sampler: &s,
            brdf: brdf.as_ref(),
            spp,
        };
        let want = batch.mis(
            &points,
            &light,
            MisHeuristic::Balance,
            |k, wi, f| match f {
                Some(f) => scenes[k].integrand_with_f(wi, f),
                None => scenes[k].integrand(wi),
            },
            &mut seeded(),
        );
        let got = batch.mis_given_f(
            &points,
            &light,
            MisHeuristic::Balance,
            |k, wi, f| scenes[k].integrand_with_f(wi, f),
            &mut seeded(),
        );
        assert!(want.iter().filter(|v| **v > 0.0).count() > 40);
        assert_eq!(got, want);
        use std::sync::atomic::Ordering::Relaxed;
        assert!(
            s.calls.load(Relaxed) > 40,
            "{} calls",
            s.calls.load(Relaxed)
        );
        assert_eq!(s.mismatches.load(Relaxed), 0);
        let broken = sampler(1.5);
        let got = Batch {
            sampler: &broken,
            brdf: brdf.as_ref(),
            spp,
        }
        .mis_given_f(
            &points,
            &light,
            MisHeuristic::Balance,
            |k, wi, f| scenes[k].integrand_with_f(wi, f),
            &mut seeded(),
        );
        assert_ne!(got, want, "pdf_many_given_f not used");
    }

    #[test]
    fn rgb_values_scale_add_and_test_positivity_per_channel() {
        let a = [1.0, 0.0, 2.0];
        assert_eq!(a.scale(0.5).plus([0.5; 3]), [1.0, 0.5, 1.5]);
        assert!(a.any_positive() && ![0.0; 3].any_positive() && !0.0f64.any_positive());
    }
}
