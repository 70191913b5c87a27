//! What a study runs: the grid of cells (sampler × mode × BRDF × outgoing angle × light), its
//! sample counts and repetitions, the presets (`--quick`, `--paper`) and shards.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::StudyError;

/// The papers' sample counts: N ∈ {1, 5², 10², 15², 20², 30², 40², 50²}.
pub const PAPER_N_GRID: [usize; 8] = [1, 25, 100, 225, 400, 900, 1600, 2500];

/// Preferred samplers of `--quick` and `--paper`, in report order. A preset runs **every
/// registered direction sampler of this list that exists** in the registry, so baselines
/// registered later join the presets without a code change, and names not (yet) registered
/// are skipped.
pub const PREFERRED_SAMPLERS: [&str; 15] = [
    "uniform",
    "cosine",
    "lobe-sphere",
    "lobe-hemisphere",
    "analytic",
    "tabulated-cdf",
    "cascade-cdf",
    "factored",
    "srbf",
    "rgl-native",
    "adaptive",
    "adaptive-mixture",
    "adaptive-exact",
    "adaptive-paper",
    "adaptive-paper-mixture",
];

/// BRDFs of `--quick`: a glossy Phong, an anisotropic Ward, a rough GGX microfacet, a
/// Cook–Torrance; a measured one is added when a MERL file is found ([`MEASURED_CANDIDATES`]).
pub const QUICK_BRDFS: [&str; 4] = ["phong:n=50,ks=0.7,kd=0.3", "ward", "ggx", "cook-torrance"];

/// Measured BRDFs tried by `--quick`: `(reader, path relative to the repository root's
/// parent)`. The first whose file exists and whose spec `reader:PATH` parses (its reader is
/// registered in `brdf`) joins the study.
pub const MEASURED_CANDIDATES: [(&str, &str); 4] = [
    ("merl", "shared/data/merl/gold-metallic-paint.binary"),
    ("rgl", "shared/data/measured/rgl/paper_white_rgb.bsdf"),
    ("cornell", "shared/data/measured/cornell/acryl_blue.brdf"),
    ("rgl", "shared/data/measured/rgl/cc_ibiza_sunset_rgb.bsdf"),
];

/// Real environment maps tried by `--quick`, in order (relative to the repository root's
/// parent); when none is readable the quick study uses the procedural sky and says so.
pub const MAP_CANDIDATES: [&str; 2] = [
    "shared/data/envmaps/grace_probe_latlong.hdr",
    "shared/data/envmaps/railway_bridge_02_1k.hdr",
];

/// Default repetitions of a batch-mode cell at every N: with `R` near-normal estimates the
/// MSE's 95 % interval is about `±1.96 √(2/R)`, ±17 % at 256 (±49 % at the 32 of the
/// one-sample mode's error curves).
pub const BATCH_REPETITIONS: usize = 256;

/// How the samples of one estimate are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// `N` independent calls of `sample`.
    OneSample,
    /// One `sample_batch(ωo, N)` call (stratified for batch-mode samplers; its pdfs keep the
    /// estimator unbiased).
    Batch,
}

impl Mode {
    /// `one-sample` or `batch`.
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::OneSample => "one-sample",
            Mode::Batch => "batch",
        }
    }
}

/// Everything that defines a study's numbers. Two runs with equal configs give equal
/// non-timing results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyConfig {
    /// Preset name (`quick`, `paper`) or `custom`.
    pub preset: String,
    /// Registered direction-sampler names.
    pub samplers: Vec<String>,
    /// BRDF specs (`brdf::parse_spec`).
    pub brdfs: Vec<String>,
    /// Outgoing polar angles θo (degrees, φo = 0).
    pub theta_o_deg: Vec<f64>,
    /// Light specs (`crate::Light::parse`).
    pub lights: Vec<String>,
    /// Sample counts N of the error curves (strictly increasing).
    pub n_grid: Vec<usize>,
    /// Independent estimates per N (for the 95 % confidence intervals).
    pub repetitions: usize,
    /// Independent estimates per N in batch mode, whose MSE rests on them alone (the
    /// one-sample mode's rests on every value drawn): `max(repetitions, batch_repetitions)`.
    pub batch_repetitions: usize,
    /// One-sample values drawn for the per-sample variance.
    pub variance_samples: usize,
    /// Samples per timing run.
    pub timing_samples: usize,
    /// Timing runs; the median is reported.
    pub timing_repeats: usize,
    /// Outgoing slices of the adaptive sets.
    pub slices: usize,
    /// Master seed; cell `i` uses `distributions::chunk_seed(seed, i)`.
    pub seed: u64,
}

impl StudyConfig {
    /// A custom study of the given grid with the default counts (the papers' N grid, 32
    /// repetitions).
    pub fn new(
        samplers: Vec<String>,
        brdfs: Vec<String>,
        theta_o_deg: Vec<f64>,
        lights: Vec<String>,
    ) -> Self {
        Self {
            preset: "custom".into(),
            samplers,
            brdfs,
            theta_o_deg,
            lights,
            n_grid: PAPER_N_GRID.to_vec(),
            repetitions: 32,
            batch_repetitions: BATCH_REPETITIONS,
            variance_samples: 20_000,
            timing_samples: 4096,
            timing_repeats: 9,
            slices: brdf_sampling::SetOptions::default().slices,
            seed: 1,
        }
    }

    /// The `--quick` study: the [`PREFERRED_SAMPLERS`] that are registered, [`QUICK_BRDFS`]
    /// (plus a measured one when found under `root`'s parent), θo ∈ {30°, 60°}, one real map
    /// (or the procedural sky when no map file is found), 32 repetitions. `root` is the
    /// repository root (where `../shared` is looked for). Returns the config and notes for the
    /// report (what was not found).
    pub fn quick(root: Option<&std::path::Path>) -> (Self, Vec<String>) {
        let mut notes = Vec::new();
        let mut brdfs: Vec<String> = QUICK_BRDFS.iter().map(|s| s.to_string()).collect();
        let measured = root.and_then(|root| {
            MEASURED_CANDIDATES.iter().find_map(|(reader, path)| {
                // Canonical, so reports and plot titles name `/…/shared/…`, not `…/repo/../shared/…`.
                let path = root.join("..").join(path);
                let path = std::fs::canonicalize(&path).unwrap_or(path);
                let spec = format!("{reader}:{}", path.display());
                brdf::parse_spec(&spec).is_ok().then_some(spec)
            })
        });
        match measured {
            Some(spec) => brdfs.push(spec),
            None => notes.push(
                "no readable measured BRDF found (../shared/data/merl, ../shared/data/measured, or their readers are not registered yet); the quick study uses analytic models only".to_string(),
            ),
        }
        let light = match find_candidate(root, &MAP_CANDIDATES) {
            Some(p) => format!("envmap:{}", p.display()),
            None => {
                notes.push(format!(
                    "no environment map file found (looked for ../{}); the quick study uses the built-in procedural sky instead",
                    MAP_CANDIDATES[0]
                ));
                "sky".into()
            }
        };
        let mut c = Self::new(registered_preferred(), brdfs, vec![30.0, 60.0], vec![light]);
        c.preset = "quick".into();
        (c, notes)
    }

    /// The `--paper` sphere-table study at reduced size: the [`PREFERRED_SAMPLERS`] that are
    /// registered, Phong and Ward under the area light and the sky, θo ∈ {15°, 45°, 75°}.
    pub fn paper() -> Self {
        let mut c = Self::new(
            registered_preferred(),
            vec!["phong:n=50,ks=0.7,kd=0.3".into(), "ward".into()],
            vec![15.0, 45.0, 75.0],
            vec!["area".into(), "sky".into()],
        );
        c.preset = "paper".into();
        c
    }

    /// Checks the numeric settings (not the names: [`crate::StudyPlan::new`] resolves those).
    pub fn check(&self) -> Result<(), StudyError> {
        if self.n_grid.is_empty()
            || self.n_grid[0] == 0
            || self.n_grid.windows(2).any(|w| w[0] >= w[1])
        {
            return Err(StudyError::SampleGridNotIncreasing(self.n_grid.clone()));
        }
        for &t in &self.theta_o_deg {
            if !((0.0..90.0).contains(&t)) {
                return Err(StudyError::ThetaOutOfRange(t));
            }
        }
        for (what, min, got) in [
            ("repetitions", 2, self.repetitions),
            ("variance samples", 2, self.variance_samples),
            ("timing samples", 1, self.timing_samples),
            ("timing repeats", 1, self.timing_repeats),
            ("slices", 1, self.slices),
        ] {
            if got < min {
                return Err(StudyError::TooFew { what, min, got });
            }
        }
        for (what, empty) in [
            ("sampler", self.samplers.is_empty()),
            ("BRDF", self.brdfs.is_empty()),
            ("outgoing angle", self.theta_o_deg.is_empty()),
            ("light", self.lights.is_empty()),
        ] {
            if empty {
                return Err(StudyError::EmptyGrid(what));
            }
        }
        Ok(())
    }
}

/// The [`PREFERRED_SAMPLERS`] that are registered direction samplers.
pub fn registered_preferred() -> Vec<String> {
    PREFERRED_SAMPLERS
        .iter()
        .filter(|n| samplers::find(n).is_ok_and(|e| e.is_direction()))
        .map(|n| n.to_string())
        .collect()
}

/// The first candidate (relative to `root/..`) that is a readable file.
fn find_candidate(root: Option<&std::path::Path>, candidates: &[&str]) -> Option<PathBuf> {
    let parent = root?.join("..");
    candidates
        .iter()
        .map(|c| parent.join(c))
        .find(|p| std::fs::File::open(p).is_ok())
        .map(|p| std::fs::canonicalize(&p).unwrap_or(p))
}

/// One part of a study run on its own: cells `i` with `i % count == index - 1`.
pub use distributions::Shard;

/// One cell of the grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellSpec {
    /// Position in the full grid (the seed's second half).
    pub index: usize,
    /// Sampler name.
    pub sampler: String,
    /// How samples are drawn.
    pub mode: Mode,
    /// BRDF spec.
    pub brdf: String,
    /// Outgoing polar angle (degrees, φo = 0).
    pub theta_o_deg: f64,
    /// Light spec.
    pub light: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_cells() {
        let shards: Vec<Shard> = (1..=3)
            .map(|k| Shard::parse(&format!("{k}/3")).unwrap())
            .collect();
        for i in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.contains(i)).count(), 1);
        }
        for bad in ["0/3", "4/3", "1", "a/b", "1/0", "-1/2"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn numeric_settings_are_checked() {
        let ok = StudyConfig::new(
            vec!["cosine".into()],
            vec!["lambert".into()],
            vec![30.0],
            vec!["sky".into()],
        );
        assert!(ok.check().is_ok());
        for grid in [vec![], vec![0, 5], vec![5, 5], vec![25, 5]] {
            let c = StudyConfig {
                n_grid: grid,
                ..ok.clone()
            };
            assert!(matches!(
                c.check(),
                Err(StudyError::SampleGridNotIncreasing(_))
            ));
        }
        let c = StudyConfig {
            theta_o_deg: vec![f64::NAN],
            ..ok.clone()
        };
        assert!(c.check().is_err());
        let c = StudyConfig {
            theta_o_deg: vec![90.0],
            ..ok.clone()
        };
        assert!(c.check().is_err());
        let c = StudyConfig {
            repetitions: 1,
            ..ok
        };
        assert!(c.check().is_err());
    }

    #[test]
    fn presets_use_registered_samplers_only() {
        let names = registered_preferred();
        assert!(names.iter().any(|n| n == "adaptive"));
        assert!(names.iter().all(|n| samplers::find(n).is_ok()));
    }
}
