//! Estimators of reflected radiance under an environment map (Tsai et al. 2008, baselines.md
//! §C.4): `L_r(ωo) = ∫_Ω L(ωi) f_r(ωo, ωi) cos θi dσ(ωi)`, with `L` the map's luminance.
//!
//! The shading point has an explicit [`LocalFrame`] (normal and a rotation about it); the map is
//! world-space, so a local direction `ω` sees the radiance `L(frame.to_world(ω))`. Every
//! estimator's numerator is this true integrand; fitted SRBFs only shape pdfs.
//!
//! * [`estimate_srbf_product`] — product lobes of the map's and the BRDF slice's SRBFs in closed
//!   form, pruned to the largest masses, `N` split over them by the partition sampler's
//!   largest-remainder allocator (at least 2 each, so every lobe's variance is estimated), vMF
//!   draws, multi-sample balance heuristic `Σ_m Σ_j f / Σ_k n_k p_k` over the **kept** lobes with
//!   their **actual** counts (unbiased for any fixed allocation: the mixture is positive on the
//!   whole sphere).
//! * [`estimate_brdf`] — any BRDF direction sampler alone; [`estimate_light`] — an environment
//!   map sampler alone; [`estimate_mis`] — one of each, `N/2` samples each, balance or power
//!   heuristic (Veach 1997).
//!
//! Standard errors are from the per-technique (per-lobe) sample variances.

use std::time::Instant;

use brdf::{Brdf, Vec3};
use brdf_sampling::DirectionSampler;
use envmap::latlong::direction_to_uv;
use envmap::{EnvMap, EnvMapSampler, luminance};
use partition_sampler::{AllocationMode, allocate};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use super::SrbfError;
use super::envfit::EnvSrbf;
use super::sampler::SrbfSampler;
use super::vmf::{SgLobe, orthonormal_basis, vmf_pdf, vmf_sample};

/// The shading frame: world-space normal `n` and tangents `t`, `b` (right-handed, `t × b = n`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl LocalFrame {
    /// The frame of `normal` (normalised here) whose tangent is the branchless basis's
    /// (Duff et al. 2017) turned by `rotation` radians about the normal.
    ///
    /// Errors: [`SrbfError::BadNormal`] for a zero-length or non-finite normal.
    pub fn new(normal: [f64; 3], rotation: f64) -> Result<Self, SrbfError> {
        let v = Vec3::from(normal);
        let len = v.norm();
        if !(len > 0.0 && len.is_finite() && rotation.is_finite()) {
            return Err(SrbfError::BadNormal {
                x: normal[0],
                y: normal[1],
                z: normal[2],
            });
        }
        let n = v / len;
        let (t0, b0) = orthonormal_basis(&n);
        let (s, c) = rotation.sin_cos();
        Ok(Self {
            t: t0 * c + b0 * s,
            b: b0 * c - t0 * s,
            n,
        })
    }

    /// A world direction in local coordinates (`z` along the normal).
    pub fn to_local(&self, w: &Vec3) -> Vec3 {
        Vec3::new(w.dot(&self.t), w.dot(&self.b), w.dot(&self.n))
    }

    /// A local direction in world coordinates.
    pub fn to_world(&self, l: &Vec3) -> Vec3 {
        self.t * l.x + self.b * l.y + self.n * l.z
    }
}

/// One shading configuration: BRDF, map, frame and the local outgoing direction.
#[derive(Clone, Copy)]
pub struct ProductScene<'a> {
    /// The BRDF (luminance `eval`).
    pub brdf: &'a dyn Brdf,
    /// The world-space environment map.
    pub map: &'a EnvMap,
    /// The shading frame.
    pub frame: LocalFrame,
    /// The outgoing direction in the local frame (unit, `z > 0`).
    pub wo: Vec3,
}

impl std::fmt::Debug for ProductScene<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProductScene")
            .field("brdf", &self.brdf.name())
            .field("frame", &self.frame)
            .field("wo", &self.wo)
            .finish_non_exhaustive()
    }
}

impl<'a> ProductScene<'a> {
    /// A scene; `wo` is normalised and must be above the local horizon.
    pub fn new(
        brdf: &'a dyn Brdf,
        map: &'a EnvMap,
        frame: LocalFrame,
        wo: Vec3,
    ) -> Result<Self, SrbfError> {
        let wo = wo.normalize();
        if !(wo.z > 0.0) {
            return Err(SrbfError::BelowHorizon { cos_theta: wo.z });
        }
        Ok(Self {
            brdf,
            map,
            frame,
            wo,
        })
    }

    /// Luminance radiance arriving from the local direction `wi`.
    pub fn radiance(&self, wi: &Vec3) -> f64 {
        let w = self.frame.to_world(wi);
        let (u, v) = direction_to_uv([w.x, w.y, w.z]);
        luminance(self.map.radiance_uv(u, v))
    }

    /// The integrand `L(ωi)·f_r(ωo, ωi)·cos⁺θi` at the local direction `wi` (0 below the horizon).
    pub fn integrand(&self, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let f = self.brdf.eval(&self.wo, wi);
        if f == 0.0 {
            0.0
        } else {
            self.radiance(wi) * f * wi.z
        }
    }
}

/// One estimator's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The estimator's name.
    pub estimator: String,
    /// The estimate of `L_r(ωo)`.
    pub estimate: f64,
    /// Its standard error.
    pub std_err: f64,
    /// Samples drawn.
    pub samples: usize,
    /// Wall time in seconds (sampling and evaluation; fits and sampler builds excluded).
    pub seconds: f64,
}

impl Estimate {
    /// Seconds per sample.
    pub fn seconds_per_sample(&self) -> f64 {
        self.seconds / self.samples.max(1) as f64
    }

    /// Variance × time, `σ²_per-sample · t_per-sample = std_err² · seconds` (lower is better).
    pub fn variance_time(&self) -> f64 {
        self.std_err * self.std_err * self.seconds
    }
}

/// Running mean and variance of one technique's per-sample contributions.
#[derive(Debug, Default, Clone, Copy)]
struct Moments {
    n: usize,
    sum: f64,
    sum2: f64,
}

impl Moments {
    fn push(&mut self, y: f64) {
        self.n += 1;
        self.sum += y;
        self.sum2 += y * y;
    }
    fn mean(&self) -> f64 {
        self.sum / self.n.max(1) as f64
    }
    /// Unbiased sample variance of one contribution.
    fn variance(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let m = self.mean();
        ((self.sum2 - self.n as f64 * m * m) / (self.n - 1) as f64).max(0.0)
    }
}

fn check_samples(estimator: &'static str, n: usize, min: usize) -> Result<(), SrbfError> {
    if n < min {
        return Err(SrbfError::TooFewSamples {
            estimator,
            min,
            got: n,
        });
    }
    Ok(())
}

/// `(1/N) Σ g/p` with a BRDF direction sampler (local frame).
pub fn estimate_brdf(
    scene: &ProductScene<'_>,
    sampler: &dyn DirectionSampler,
    name: &str,
    n: usize,
    seed: u64,
) -> Result<Estimate, SrbfError> {
    check_samples("brdf", n, 2)?;
    Ok(one_sample_estimate(scene, name, n, seed, |rng| {
        let s = sampler.sample(&scene.wo, rng);
        (s.wi, s.pdf)
    }))
}

/// `(1/N) Σ g/p` with an environment-map sampler (world directions turned into the frame).
pub fn estimate_light(
    scene: &ProductScene<'_>,
    sampler: &EnvMapSampler,
    name: &str,
    n: usize,
    seed: u64,
) -> Result<Estimate, SrbfError> {
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
    Estimate {
        estimator: name.to_string(),
        estimate: m.mean(),
        std_err: (m.variance() / n as f64).sqrt(),
        samples: n,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// The multiple-importance-sampling weight of a technique.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MisHeuristic {
    /// `w_a = n_a p_a / Σ_k n_k p_k`.
    Balance,
    /// `w_a = (n_a p_a)² / Σ_k (n_k p_k)²`.
    Power,
}

impl MisHeuristic {
    fn weight(self, own: f64, other: f64) -> f64 {
        match self {
            MisHeuristic::Balance => own / (own + other),
            MisHeuristic::Power => own * own / (own * own + other * other),
        }
    }
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
) -> Result<Estimate, SrbfError> {
    check_samples("mis", n, 4)?;
    let start = Instant::now();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (na, nb) = (n.div_ceil(2), n / 2);
    let light_pdf = |wi: &Vec3| {
        light_sampler.pdf_sa({
            let w = scene.frame.to_world(wi);
            [w.x, w.y, w.z]
        })
    };
    let mut ma = Moments::default();
    for _ in 0..na {
        let s = brdf_sampler.sample(&scene.wo, &mut rng);
        let g = scene.integrand(&s.wi);
        ma.push(if g > 0.0 && s.pdf > 0.0 {
            let w = heuristic.weight(na as f64 * s.pdf, nb as f64 * light_pdf(&s.wi));
            w * g / s.pdf
        } else {
            0.0
        });
    }
    let mut mb = Moments::default();
    for _ in 0..nb {
        let s = light_sampler.sample(&mut rng);
        let wi = scene.frame.to_local(&Vec3::from(s.direction));
        let g = scene.integrand(&wi);
        mb.push(if g > 0.0 && s.pdf_sa > 0.0 {
            let w = heuristic.weight(
                nb as f64 * s.pdf_sa,
                na as f64 * brdf_sampler.pdf(&scene.wo, &wi),
            );
            w * g / s.pdf_sa
        } else {
            0.0
        });
    }
    Ok(Estimate {
        estimator: name.to_string(),
        estimate: ma.mean() + mb.mean(),
        std_err: (ma.variance() / na as f64 + mb.variance() / nb as f64).sqrt(),
        samples: n,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// What the SRBF product estimator did besides its estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProductStats {
    /// Product lobes formed (map lobes × BRDF-slice lobes).
    pub product_lobes: usize,
    /// Product lobes kept after pruning (each got ≥ 2 samples when `N` allows).
    pub kept: usize,
    /// Share of the total product mass `Σ I_m` the kept lobes hold.
    pub kept_mass_fraction: f64,
    /// Defensive components (the BRDF slice's lobes) sampled besides the product lobes.
    pub defensive_lobes: usize,
}

/// Settings of the SRBF product estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProductSettings {
    /// Product lobes kept (largest masses `I_m`), ≥ 1.
    pub keep: usize,
    /// Share `δ ∈ [0, 1)` of the samples given to the BRDF slice's own lobes (the `srbf`
    /// mixture) as defensive components of the same balance-heuristic mixture [D]. `0` is
    /// Tsai's estimator as published; see [`estimate_srbf_product`] for why the default is not.
    pub defensive: f64,
}

impl Default for ProductSettings {
    fn default() -> Self {
        Self {
            keep: 32,
            defensive: 0.2,
        }
    }
}

/// How the denominator is formed; only [`Denominator::ActualCounts`] is unbiased. The other
/// exists so that the tests can show they detect the pitfall of baselines.md §C.5.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Denominator {
    /// `Σ_k n_k p_k` over the components actually sampled, with their actual counts.
    ActualCounts,
    /// Every product lobe (pruned ones too) at its pre-pruning mass share (biased).
    #[cfg_attr(
        not(test),
        allow(dead_code, reason = "the mutant the tests must detect")
    )]
    AllLobesPrePruningMass,
}

/// SRBF product importance sampling (module docs) with `n` samples.
///
/// Components: the `settings.keep` product lobes of largest mass, and — unless
/// `settings.defensive = 0` — the BRDF slice's lobes (normalised, mass-weighted). Sample
/// shares: `(1 − δ)·I_m/Σ_kept I` and `δ·I_b/Σ I_b`, split by largest remainders with a floor
/// of 2 per component; estimate `Σ_k Σ_j g / Σ_k' n_k' p_k'` (balance heuristic, actual counts).
///
/// Why a defensive share: the product lobes come from fits of the map and the BRDF slice. Where
/// both fits miss energy (a dim but wide background behind a few bright lamps gets no map lobe),
/// the product mixture's density is a vMF tail, `~e^{−2λ}`: still positive, so the estimator is
/// unbiased in theory, but its variance is effectively infinite and finite runs underestimate
/// (measured: half the reference with all 24 product lobes kept on a two-lamp map). The
/// BRDF-slice lobes cover the BRDF's support, bounding the weights by `L_max·g/p_brdf`.
pub fn estimate_srbf_product(
    scene: &ProductScene<'_>,
    brdf_fit: &SrbfSampler,
    map_fit: &EnvSrbf,
    settings: &ProductSettings,
    n: usize,
    seed: u64,
) -> Result<(Estimate, ProductStats), SrbfError> {
    srbf_product(
        scene,
        brdf_fit,
        map_fit,
        settings,
        n,
        seed,
        Denominator::ActualCounts,
    )
}

fn srbf_product(
    scene: &ProductScene<'_>,
    brdf_fit: &SrbfSampler,
    map_fit: &EnvSrbf,
    settings: &ProductSettings,
    n: usize,
    seed: u64,
    denominator: Denominator,
) -> Result<(Estimate, ProductStats), SrbfError> {
    if settings.keep == 0 {
        return Err(SrbfError::ZeroLobes {
            what: "kept product",
        });
    }
    let delta = settings.defensive;
    if !((0.0..1.0).contains(&delta)) {
        return Err(SrbfError::BadDefensive { value: delta });
    }
    check_samples("srbf-product", n, 4)?;
    let start = Instant::now();
    let brdf_lobes = brdf_fit.lobes_at(&scene.wo);
    let mut lobes: Vec<(SgLobe, f64)> = Vec::with_capacity(brdf_lobes.len() * map_fit.lobes.len());
    for e in &map_fit.lobes {
        let e_local = SgLobe {
            axis: scene.frame.to_local(&e.axis),
            ..*e
        };
        for b in &brdf_lobes {
            let m = e_local.product(b);
            let mass = m.integral();
            if mass > 0.0 && mass.is_finite() {
                lobes.push((m, mass));
            }
        }
    }
    let product_lobes = lobes.len();
    let mut delta = delta;
    if lobes.is_empty() {
        // Every product underflowed: the BRDF lobes alone still give a positive mixture.
        delta = 1.0;
    }
    let total_mass: f64 = lobes.iter().map(|l| l.1).sum();
    lobes.sort_by(|a, b| b.1.total_cmp(&a.1));
    let all = lobes.clone();
    let defensive: Vec<(SgLobe, f64)> = if delta > 0.0 {
        brdf_lobes
            .iter()
            .map(|l| (*l, l.integral()))
            .filter(|l| l.1 > 0.0 && l.1.is_finite())
            .collect()
    } else {
        Vec::new()
    };
    let budget = (n / 2).saturating_sub(defensive.len()).max(1);
    lobes.truncate(settings.keep.min(budget));
    let kept = lobes.len();
    let kept_mass: f64 = lobes.iter().map(|l| l.1).sum();
    let defensive_mass: f64 = defensive.iter().map(|l| l.1).sum();
    // Components and their sample shares.
    let mut components: Vec<SgLobe> = Vec::with_capacity(kept + defensive.len());
    let mut shares: Vec<f64> = Vec::with_capacity(kept + defensive.len());
    for (l, mass) in &lobes {
        components.push(*l);
        shares.push((1.0 - delta) * mass / kept_mass);
    }
    for (l, mass) in &defensive {
        components.push(*l);
        shares.push(delta * mass / defensive_mass);
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let floor = if n >= 2 * components.len() { 2 } else { 1 };
    let counts: Vec<usize> = allocate(
        n - floor * components.len(),
        &shares,
        AllocationMode::Hamilton,
        &mut rng,
    )
    .map_err(|_| SrbfError::TooFewSamples {
        estimator: "srbf-product",
        min: components.len(),
        got: n,
    })?
    .into_iter()
    .map(|c| c + floor)
    .collect();
    let density_times_n = |wi: &Vec3| -> f64 {
        let sum = |set: &[SgLobe], ns: &mut dyn Iterator<Item = f64>| -> f64 {
            set.iter()
                .zip(ns)
                .map(|(l, c)| c * vmf_pdf(l.axis.dot(wi), l.lambda))
                .sum()
        };
        match denominator {
            Denominator::ActualCounts => sum(&components, &mut counts.iter().map(|&c| c as f64)),
            Denominator::AllLobesPrePruningMass => {
                let product: f64 = all
                    .iter()
                    .map(|(l, mass)| {
                        (1.0 - delta) * n as f64 * mass / total_mass
                            * vmf_pdf(l.axis.dot(wi), l.lambda)
                    })
                    .sum();
                product
                    + sum(
                        &components[kept..],
                        &mut counts[kept..].iter().map(|&c| c as f64),
                    )
            }
        }
    };
    let (mut estimate, mut variance) = (0.0, 0.0);
    for (l, &c) in components.iter().zip(&counts) {
        let mut m = Moments::default();
        for _ in 0..c {
            let u: [f64; 2] = [
                rand::RngExt::random(&mut rng),
                rand::RngExt::random(&mut rng),
            ];
            let wi = vmf_sample(&l.axis, l.lambda, u);
            let g = scene.integrand(&wi);
            m.push(if g > 0.0 {
                g / density_times_n(&wi)
            } else {
                0.0
            });
        }
        estimate += m.sum;
        variance += c as f64 * m.variance();
    }
    Ok((
        Estimate {
            estimator: "srbf-product".to_string(),
            estimate,
            std_err: variance.sqrt(),
            samples: n,
            seconds: start.elapsed().as_secs_f64(),
        },
        ProductStats {
            product_lobes,
            kept,
            kept_mass_fraction: if total_mass > 0.0 {
                kept_mass / total_mass
            } else {
                0.0
            },
            defensive_lobes: defensive.len(),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SrbfOptions;
    use crate::srbf::fit_envmap;

    /// `|a − b| / √(σa² + σb²)`.
    fn z(a: &Estimate, b: &Estimate) -> f64 {
        (a.estimate - b.estimate).abs() / (a.std_err.powi(2) + b.std_err.powi(2)).sqrt()
    }

    #[test]
    fn frame_is_orthonormal_and_rejects_zero_normal() {
        let f = LocalFrame::new([0.2, -0.3, 0.9], 0.7).unwrap();
        let v = Vec3::new(0.3, 0.5, -0.2);
        assert!((f.to_world(&f.to_local(&v)) - v).norm() < 1e-12);
        assert!((f.to_world(&Vec3::z()) - Vec3::new(0.2, -0.3, 0.9).normalize()).norm() < 1e-12);
        assert!(matches!(
            LocalFrame::new([0.0; 3], 0.0),
            Err(SrbfError::BadNormal { .. })
        ));
        assert!(matches!(
            LocalFrame::new([f64::NAN, 0.0, 1.0], 0.0),
            Err(SrbfError::BadNormal { .. })
        ));
    }

    #[test]
    fn pruned_lobes_in_the_denominator_are_detected_and_the_correct_form_is_not() {
        // Few kept lobes of a map with a uniform background and two bright patches: the
        // pruned mass is large, so the mutant's bias is visible; the correct estimator agrees
        // with an independent MIS reference.
        let (w, h) = (128, 64);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let patch = (y / 8 == 2 && x / 8 == 1) || (y / 8 == 3 && x / 8 == 9);
                if patch { [30.0; 3] } else { [1.0; 3] }
            })
            .collect();
        let sky = EnvMap::new(w, h, rgb).unwrap();
        let brdf = brdf::parse_spec("phong:n=20,ks=0.5,kd=0.5").unwrap();
        let options = SrbfOptions {
            slices: 4,
            fit_rows: 12,
            brdf_lobes: 4,
            map_lobes: 6,
            map_fit_width: 64,
            ..SrbfOptions::default()
        };
        let brdf_fit = SrbfSampler::build(brdf.as_ref(), &options).unwrap();
        let map_fit = fit_envmap(&sky, &options).unwrap();
        let light = EnvMapSampler::piecewise_constant(&sky).unwrap();
        let frame = LocalFrame::new([0.3, 0.2, 1.0], 0.0).unwrap();
        let scene = ProductScene::new(
            brdf.as_ref(),
            &sky,
            frame,
            brdf::direction_from_angles(40.0, 30.0),
        )
        .unwrap();
        let reference = estimate_mis(
            &scene,
            &brdf_fit,
            &light,
            MisHeuristic::Balance,
            "ref",
            400_000,
            1,
        )
        .unwrap();
        // Tsai's estimator as published (no defensive share) is unbiased here too: the map
        // fit's floor lobe covers the background.
        let plain = ProductSettings {
            keep: 32,
            defensive: 0.0,
        };
        let (tsai, _) =
            estimate_srbf_product(&scene, &brdf_fit, &map_fit, &plain, 40_000, 2).unwrap();
        assert!(z(&tsai, &reference) < 4.0, "{tsai:?} vs {reference:?}");
        for keep in [1, 32] {
            let settings = ProductSettings {
                keep,
                defensive: 0.2,
            };
            let (good, stats) =
                estimate_srbf_product(&scene, &brdf_fit, &map_fit, &settings, 40_000, 2).unwrap();
            assert!(keep > 1 || stats.kept_mass_fraction < 0.8, "{stats:?}");
            assert!(
                z(&good, &reference) < 4.0,
                "keep {keep}: {good:?} vs {reference:?}"
            );
        }
        let settings = ProductSettings {
            keep: 1,
            defensive: 0.2,
        };
        let (bad, _) = srbf_product(
            &scene,
            &brdf_fit,
            &map_fit,
            &settings,
            40_000,
            2,
            Denominator::AllLobesPrePruningMass,
        )
        .unwrap();
        assert!(
            z(&bad, &reference) > 4.0,
            "mutant not detected: {bad:?} vs {reference:?}"
        );
    }
}
