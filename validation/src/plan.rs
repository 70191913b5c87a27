//! Tiers, the user-facing configuration, and the resolved plan of a run.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use stats::QuadratureOptions;

use crate::domain::Resolution;

/// Suite tier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Tier {
    /// CI tier: a handful of BRDFs and angles, sample counts for a few minutes on 2 cores.
    Quick,
    /// Full tier: every model (and MERL files when present), angles up to 89°, larger N.
    Full,
}

impl Tier {
    /// `quick` or `full`.
    pub fn name(&self) -> &'static str {
        match self {
            Tier::Quick => "quick",
            Tier::Full => "full",
        }
    }
}

/// BRDF specs of the quick tier: five analytic models and the RGL fixture ([`QUICK_RGL`]).
pub const QUICK_BRDFS: &[&str] = &[
    "lambert",
    "phong:n=50",
    "ward",
    "ggx:alpha=0.2",
    "oren-nayar",
    QUICK_RGL,
];

/// The RGL fixture in the repository (`data/measured/rgl/paper_white_rgb.bsdf`, found from this
/// crate's source directory; provenance in `data/measured/README.md`).
pub const QUICK_RGL: &str = concat!(
    "rgl:",
    env!("CARGO_MANIFEST_DIR"),
    "/../data/measured/rgl/paper_white_rgb.bsdf"
);

/// The quick tier's Cornell material: `acryl_blue.brdf` of the project's shared measured data
/// (`../shared/data/measured/cornell/`, beside the repository; found from this crate's source
/// directory; its data carry no licence statement, so no copy is in the repository). Not in
/// [`QUICK_BRDFS`] (which must work in a user's clone, and where every sampler would run on
/// it at 60–120 CPU-s per case): `validation/tests/quick_cornell.rs` runs `adaptive` and
/// `adaptive-mixture` on it at 45° when the file is present (docs/validation.md says why the
/// other samplers are left out).
pub const QUICK_CORNELL: &str = concat!(
    "cornell:",
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/measured/cornell/acryl_blue.brdf"
);

/// Directory searched in the full tier for the shared measured materials (`rgl/*.bsdf`,
/// `cornell/*.brdf`), when
/// a MERL directory is searched too (relative to the working directory, like
/// [`DEFAULT_MERL_DIR`]).
pub const DEFAULT_MEASURED_DIR: &str = "../shared/data/measured";

/// The full tier's presets of fitted models (every MERL material's SGD fit), run at
/// [`PRESET_THETA_O`] only (there are 100 of them).
pub const FULL_PRESET_MODELS: &[&str] = &["sgd"];

/// Outgoing polar angles of the full tier's preset fits.
pub const PRESET_THETA_O: &[f64] = &[30.0, 75.0];

/// Outgoing polar angles (degrees, `φo = 0`) of the quick tier.
pub const QUICK_THETA_O: &[f64] = &[0.0, 45.0, 80.0];

/// Outgoing polar angles of the full tier.
pub const FULL_THETA_O: &[f64] = &[0.0, 30.0, 60.0, 75.0, 85.0, 89.0];

/// Samples per case of the quick tier.
pub const QUICK_SAMPLES: usize = 200_000;

/// Samples per case of the full tier.
pub const FULL_SAMPLES: usize = 2_000_000;

/// Smallest accepted sample count per case.
pub const MIN_SAMPLES: usize = 2_000;

/// Where the full tier looks for MERL `.binary` files by default (relative to the working
/// directory, i.e. the repository root).
pub const DEFAULT_MERL_DIR: &str = "../shared/data/merl";

/// What to validate: the library form of `brdf-lab validate`.
///
/// Empty lists mean "the tier's default". Standalone samplers (environment maps, the synthetic
/// grid) carry their own targets and ignore `brdfs` and `theta_o`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidateConfig {
    /// BRDF specs (`name` or `name:key=value,...`, `merl:PATH`).
    pub brdfs: Vec<String>,
    /// Sampler names (see [`crate::samplers`]).
    pub samplers: Vec<String>,
    /// Outgoing polar angles in degrees, each in `[0, 90)`; `φo = 0`.
    pub theta_o: Vec<f64>,
    /// Samples per case (one-sample draws; the batch tests draw half as many more).
    pub samples: Option<usize>,
    /// Master seed: every case derives its generators from it and its own label.
    pub seed: u64,
    /// Quick (CI) tier instead of the full tier.
    pub quick: bool,
    /// Also run the mutant samplers and require that every one is caught.
    pub mutants: bool,
    /// Family-wise significance level of the whole run (Šidák-corrected per test).
    pub alpha: f64,
    /// Directory searched for MERL `.binary` files in the full tier (when `brdfs` is empty).
    pub merl_dir: Option<PathBuf>,
    /// Saved adaptive sets (`brdf-lab build --out FILE`) to validate, each with the BRDF of
    /// its stored spec at the run's angles. With sets and no `samplers`, only the sets run.
    #[serde(default)]
    pub sets: Vec<PathBuf>,
}

impl Default for ValidateConfig {
    /// The full tier with seed 1 and `α = 0.01`.
    fn default() -> Self {
        Self {
            brdfs: Vec::new(),
            samplers: Vec::new(),
            theta_o: Vec::new(),
            samples: None,
            seed: 1,
            quick: false,
            mutants: false,
            alpha: 0.01,
            merl_dir: Some(PathBuf::from(DEFAULT_MERL_DIR)),
            sets: Vec::new(),
        }
    }
}

impl ValidateConfig {
    /// The quick tier with defaults (seed 1, `α = 0.01`).
    pub fn quick() -> Self {
        Self {
            quick: true,
            ..Self::default()
        }
    }

    /// The full tier with defaults.
    pub fn full() -> Self {
        Self::default()
    }

    /// The tier selected by `quick`.
    pub fn tier(&self) -> Tier {
        if self.quick { Tier::Quick } else { Tier::Full }
    }
}

/// One part of a sharded run (`brdf-lab validate --shard K/N`): the cases `i` of the full plan
/// (in its fixed order, mutants last) with `i mod N = K − 1`. Every case is seeded from the
/// master seed and its own label, so its tests give the same statistics and p-values in any
/// shard as in a single run; [`crate::merge`] recombines the parts and judges them together.
pub use partition_sampler::Shard;

/// Sample counts, binning and tolerances of a run (resolved from the tier and the config).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Tier.
    pub tier: Tier,
    /// One-sample draws per case.
    pub samples: usize,
    /// Samples per batch of the batch tests.
    pub batch_size: usize,
    /// Number of batches (`samples / (2 · batch_size)`, at least 50).
    pub batches: usize,
    /// Bins per domain.
    pub resolution: Resolution,
    /// Quadrature options of the expected counts, KS CDFs, normalisation and support tests.
    pub quadrature: QuadratureOptions,
    /// Normalisation: `|∫ pdf − 1| ≤` this.
    pub normalisation_tolerance: f64,
    /// Relative tolerance of the pdf-consistency check.
    pub pdf_rel_tol: f64,
    /// Sub-cells per bin side of the support-coverage check.
    pub support_resolution: usize,
    /// Relative systematic allowance of the unbiasedness z-tests: the standard error is
    /// combined with `allowance · |reference|` (the pdf normaliser of grid-based samplers is
    /// itself an estimate, bounded by the normalisation test).
    pub unbiasedness_allowance: f64,
}

impl Plan {
    /// The plan of `tier` with `samples` one-sample draws per case.
    pub fn new(tier: Tier, samples: usize) -> Self {
        let batch_size = 256;
        let resolution = match tier {
            Tier::Quick => Resolution {
                directions: [16, 32],
                disc: 24,
                square: [32, 16],
            },
            Tier::Full => Resolution {
                directions: [24, 48],
                disc: 32,
                square: [64, 32],
            },
        };
        Self {
            tier,
            samples,
            batch_size,
            batches: (samples / (2 * batch_size)).max(50),
            resolution: resolution.for_samples(samples),
            quadrature: QuadratureOptions::default(),
            // The same for both tiers.
            normalisation_tolerance: 1e-3,
            pdf_rel_tol: 1e-6,
            support_resolution: 3,
            unbiasedness_allowance: 0.0,
        }
    }

    /// Default sample count of a tier.
    pub fn default_samples(tier: Tier) -> usize {
        match tier {
            Tier::Quick => QUICK_SAMPLES,
            Tier::Full => FULL_SAMPLES,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition_the_cases() {
        assert_eq!(Shard::parse("2/3").unwrap(), Shard { index: 2, count: 3 });
        for bad in ["0/3", "4/3", "1", "a/2", "1/0", "-1/2"] {
            assert!(
                matches!(Shard::parse(bad), Err(partition_sampler::ShardError(_))),
                "{bad}"
            );
        }
        let shards: Vec<Shard> = (1..=3).map(|k| Shard { index: k, count: 3 }).collect();
        for i in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.contains(i)).count(), 1);
        }
    }

    #[test]
    fn small_sample_counts_get_coarser_bins() {
        // The tiers' own counts keep their resolutions.
        for tier in [Tier::Quick, Tier::Full] {
            let p = Plan::new(tier, Plan::default_samples(tier));
            let base = match tier {
                Tier::Quick => [16, 32],
                Tier::Full => [24, 48],
            };
            assert_eq!(p.resolution.directions, base);
        }
        // MIN_SAMPLES on the full tier: the sphere's cells expect ≥ 5 samples of an even
        // density (24 × 48 hemisphere bins would expect 1.7 each: one pooled χ² cell).
        let p = Plan::new(Tier::Full, MIN_SAMPLES);
        let [nc, np] = p.resolution.directions;
        assert!(
            2 * nc * np <= MIN_SAMPLES / 5 && nc * np >= 16,
            "{:?}",
            p.resolution
        );
        assert!(p.resolution.disc.pow(2) <= MIN_SAMPLES / 5);
        assert!(p.resolution.square[0] * p.resolution.square[1] <= MIN_SAMPLES / 5);
    }
}
