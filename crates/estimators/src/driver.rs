//! The `product` experiment (design.md §5): reflected radiance at one shading point under a
//! map, estimated side by side by SRBF product sampling, BRDF sampling, light sampling and MIS
//! (balance and power) of every BRDF sampler with every map sampler, against a converged MIS
//! reference. The command only parses its arguments, calls [`ProductExperiment::run`] and
//! prints the [`ProductOutcome`].
//!
//! Seeds: each estimator draws from its own stream `chunk_seed(seed, k)`: `k = 0` the
//! reference, `1` the product estimator, then the BRDF samplers, the map samplers and the MIS
//! pairs (BRDF-major, balance before power) in the order given.

use std::sync::Arc;

use baselines::srbf::{EnvSrbf, SrbfReport, fit_envmap};
use baselines::{BaselineOptions, SrbfOptions, SrbfSampler};
use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, SetOptions};
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler};

use crate::{
    Estimate, EstimatorError, LocalFrame, MisHeuristic, ProductScene, ProductStats, estimate_brdf,
    estimate_light, estimate_mis, estimate_srbf_product,
};

/// Everything the experiment needs; samplers are named as in the `samplers` registry.
#[derive(Clone)]
pub struct ProductExperiment<'a> {
    /// The BRDF.
    pub brdf: Arc<dyn Brdf>,
    /// Its spec (recorded by the samplers built from it).
    pub spec: &'a str,
    /// The world-space map.
    pub map: &'a EnvMap,
    /// The shading frame.
    pub frame: LocalFrame,
    /// The outgoing direction in the local frame.
    pub wo: Vec3,
    /// Samples per estimator.
    pub n: usize,
    /// Samples of the reference (MIS, balance, of the first BRDF and map samplers).
    pub reference_samples: usize,
    /// Master seed.
    pub seed: u64,
    /// BRDF direction samplers (registry names), at least one.
    pub brdf_samplers: &'a [String],
    /// BRDF direction samplers already built (e.g. loaded from saved sets), with their names:
    /// compared after `brdf_samplers` (which may then be empty).
    pub saved_brdf_samplers: &'a [(String, Arc<dyn DirectionSampler>)],
    /// Map samplers (registry names), at least one.
    pub light_samplers: &'a [String],
    /// Options of the adaptive sets.
    pub set_options: SetOptions,
    /// Options of the baseline samplers (the SRBF fits among them).
    pub baselines: BaselineOptions,
}

impl std::fmt::Debug for ProductExperiment<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProductExperiment")
            .field("spec", &self.spec)
            .field("frame", &self.frame)
            .field("wo", &self.wo)
            .field("n", &self.n)
            .field("seed", &self.seed)
            .finish_non_exhaustive()
    }
}

/// What the experiment measured.
#[derive(Debug, Clone)]
pub struct ProductOutcome {
    /// The reference (`reference mis-balance:BRDF+MAP`).
    pub reference: Estimate,
    /// `srbf-product`, then `brdf:NAME`, `light:NAME`, `mis-balance:B+L` / `mis-power:B+L`.
    pub estimates: Vec<Estimate>,
    /// The BRDF's SRBF fit.
    pub brdf_fit: SrbfReport,
    /// The map's SRBF fit.
    pub map_fit: EnvSrbf,
    /// What the product estimator did.
    pub stats: ProductStats,
}

/// Distinct seeds per estimator.
fn stream(seed: u64, k: u64) -> u64 {
    partition_sampler::chunk_seed(seed, k)
}

impl ProductExperiment<'_> {
    /// Builds the samplers and the fits (not timed in the estimates), then runs every
    /// estimator (see the module docs).
    ///
    /// Errors: an unknown or unbuildable sampler, no sampler of a kind, a bad frame, too few
    /// samples, a refused SRBF setting.
    pub fn run(&self) -> Result<ProductOutcome, EstimatorError> {
        if self.brdf_samplers.is_empty() && self.saved_brdf_samplers.is_empty() {
            return Err(EstimatorError::NoSampler("BRDF"));
        }
        if self.light_samplers.is_empty() {
            return Err(EstimatorError::NoSampler("light"));
        }
        let srbf_options: SrbfOptions = self.baselines.srbf.clone();
        let scene = ProductScene::new(self.brdf.as_ref(), self.map, self.frame, self.wo)?;
        let sampler_error = |e: samplers::RegistryError| EstimatorError::Sampler(e.to_string());
        let mut brdf_samplers: Vec<(&str, Arc<dyn DirectionSampler>)> = Vec::new();
        for name in self.brdf_samplers {
            let request =
                samplers::DirectionRequest::new(Arc::clone(&self.brdf), &self.set_options)
                    .with_baselines(self.baselines.clone())
                    .with_spec(self.spec);
            let built = samplers::build_direction(name, &request).map_err(sampler_error)?;
            brdf_samplers.push((name, built.sampler));
        }
        for (name, s) in self.saved_brdf_samplers {
            brdf_samplers.push((name, Arc::clone(s)));
        }
        let mut light_samplers: Vec<(&str, EnvMapSampler)> = Vec::new();
        for name in self.light_samplers {
            let entry = samplers::find(name).map_err(sampler_error)?;
            let sampler = entry
                .build_envmap(self.map, &AdaptiveOptions::default())
                .map_err(sampler_error)?;
            light_samplers.push((name, sampler));
        }
        let brdf_fit = SrbfSampler::build(self.brdf.as_ref(), &srbf_options)?;
        let map_fit = fit_envmap(self.map, &srbf_options)?;

        let reference = estimate_mis(
            &scene,
            brdf_samplers[0].1.as_ref(),
            &light_samplers[0].1,
            MisHeuristic::Balance,
            &format!(
                "reference mis-balance:{}+{}",
                brdf_samplers[0].0, light_samplers[0].0
            ),
            self.reference_samples,
            stream(self.seed, 0),
        )?;
        let n = self.n;
        let mut estimates: Vec<Estimate> = Vec::new();
        let (product, stats) = estimate_srbf_product(
            &scene,
            &brdf_fit,
            &map_fit,
            &light_samplers[0].1,
            &srbf_options.product_settings(),
            n,
            stream(self.seed, 1),
        )?;
        estimates.push(product);
        let mut k = 2;
        for (name, s) in &brdf_samplers {
            let name = format!("brdf:{name}");
            estimates.push(estimate_brdf(
                &scene,
                s.as_ref(),
                &name,
                n,
                stream(self.seed, k),
            )?);
            k += 1;
        }
        for (name, s) in &light_samplers {
            let name = format!("light:{name}");
            estimates.push(estimate_light(&scene, s, &name, n, stream(self.seed, k))?);
            k += 1;
        }
        for (bname, b) in &brdf_samplers {
            for (lname, l) in &light_samplers {
                for h in MisHeuristic::ALL {
                    let name = format!("{}:{bname}+{lname}", h.estimator_name());
                    estimates.push(estimate_mis(
                        &scene,
                        b.as_ref(),
                        l,
                        h,
                        &name,
                        n,
                        stream(self.seed, k),
                    )?);
                    k += 1;
                }
            }
        }
        Ok(ProductOutcome {
            reference,
            estimates,
            brdf_fit: brdf_fit.report(),
            map_fit,
            stats,
        })
    }
}
