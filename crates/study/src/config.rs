//! What a study runs: the grid of cells (sampler × mode × BRDF × outgoing angle × light), its
//! sample counts and repetitions, the presets (`--quick`, `--paper`) and shards.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::StudyError;

/// The papers' sample counts: N ∈ {1, 5², 10², 15², 20², 30², 40², 50²}.
pub const PAPER_N_GRID: [usize; 8] = [1, 25, 100, 225, 400, 900, 1600, 2500];

/// Preferred samplers of `--quick` and `--paper`, in report order: the registry's entries
/// that carry a study index (`samplers::SamplerEntry::study`), ordered by it, so a sampler
/// joins the presets (and gets its plot style) with its entry. A preset runs every
/// registered direction sampler of this list.
pub static PREFERRED_SAMPLERS: std::sync::LazyLock<Vec<&'static str>> =
    std::sync::LazyLock::new(samplers::study_samplers);

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

/// Outgoing polar angles of the default study: normal, moderate and grazing incidence.
pub const FULL_THETA_O_DEG: [f64; 5] = [0.0, 30.0, 60.0, 80.0, 88.0];

/// Directories of shared measured BRDFs (relative to the repository root's parent) with their
/// reader and file extension: the default study takes **every** file found in them.
pub const MEASURED_DIRS: [(&str, &str, &str); 3] = [
    ("rgl", "shared/data/measured/rgl", "bsdf"),
    ("cornell", "shared/data/measured/cornell", "brdf"),
    ("merl", "shared/data/merl", "binary"),
];

/// The MERL-100 fits of the default study (compiled in, no file needed): the two published
/// fits (SGD, Bagher et al. 2012; ABC, Low et al. 2012) of a glossy metallic paint and of a
/// near-diffuse fabric. `--all-merl-fits` takes every material of both fits instead
/// ([`all_merl_fits`]).
pub const DEFAULT_MERL_FITS: [&str; 4] = [
    "sgd:material=gold-metallic-paint",
    "abc:material=gold-metallic-paint",
    "sgd:material=red-fabric",
    "abc:material=red-fabric",
];

/// Every analytic model of the `brdf` registry (models built from numeric parameters, not
/// from a file or a fitted preset), by name with its default parameters, in registry order.
pub fn analytic_models() -> Vec<String> {
    brdf::models()
        .iter()
        .filter(|m| !m.needs_argument())
        .map(|m| m.name.to_string())
        .collect()
}

/// Every MERL-100 fit of the registry: `sgd:material=NAME` and `abc:material=NAME` for each
/// published material (200 specs), SGD first.
pub fn all_merl_fits() -> Vec<String> {
    ["sgd", "abc"]
        .iter()
        .flat_map(|model| {
            brdf::preset_names(model)
                .unwrap_or_default()
                .into_iter()
                .map(move |name| format!("{model}:material={name}"))
        })
        .collect()
}

/// Every readable measured file of [`MEASURED_DIRS`] under `root/..` whose spec parses, as
/// `reader:CANONICAL_PATH`, sorted by reader then file name; notes say which directories are
/// missing and which files could not be read.
pub fn shared_measured(root: Option<&std::path::Path>) -> (Vec<String>, Vec<String>) {
    let mut specs = Vec::new();
    let mut notes = Vec::new();
    let Some(root) = root else {
        notes.push("no shared data directory found: the study has no measured BRDF files".into());
        return (specs, notes);
    };
    for (reader, dir, ext) in MEASURED_DIRS {
        let path = root.join("..").join(dir);
        let Ok(entries) = std::fs::read_dir(&path) else {
            notes.push(format!(
                "no {reader} directory ({dir}): none of its files is studied"
            ));
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == ext))
            .map(|p| std::fs::canonicalize(&p).unwrap_or(p))
            .collect();
        files.sort();
        for f in files {
            let spec = format!("{reader}:{}", f.display());
            match brdf::parse_spec(&spec) {
                Ok(_) => specs.push(spec),
                Err(e) => notes.push(format!(
                    "{} is not studied: {e}",
                    crate::names::short_brdf(&spec)
                )),
            }
        }
    }
    (specs, notes)
}

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
    /// Independent estimates per N (for the 95 % confidence intervals). One-sample cells draw
    /// them nested: each repetition is one stream of `N_max` (the grid's last N) values, its
    /// estimate at each N the mean of the stream's first N (independent across repetitions,
    /// correlated across the N of one repetition).
    pub repetitions: usize,
    /// Independent estimates per N in batch mode, whose MSE rests on them alone (the
    /// one-sample mode's rests on every value drawn): `max(repetitions, batch_repetitions)`.
    pub batch_repetitions: usize,
    /// One-sample values drawn for the per-sample variance and the MSE at the budget, beyond
    /// the repetitions' streams (`repetitions × N_max` values, which they also use).
    pub variance_samples: usize,
    /// Samples per timing run.
    pub timing_samples: usize,
    /// Timing runs; the median is reported.
    pub timing_repeats: usize,
    /// Outgoing slices of the adaptive sets.
    pub slices: usize,
    /// Master seed; cell `i` uses `distributions::chunk_seed(seed, i)`.
    pub seed: u64,
    /// Estimators besides BRDF sampling alone, run under the map lights (the sky and map
    /// files) only: `light` (each of [`Self::light_samplers`] alone), `mis-balance`,
    /// `mis-power` (each BRDF sampler of [`Self::mis_samplers`] with each map sampler, one
    /// draw of each per sample). Their cells follow every BRDF-only cell, so adding them
    /// changes no BRDF-only cell's seed.
    #[serde(default)]
    pub estimators: Vec<String>,
    /// Map samplers (registry names) of the `light` and MIS estimators.
    #[serde(default)]
    pub light_samplers: Vec<String>,
    /// BRDF samplers inside MIS (each must be in [`Self::samplers`]); empty: all of them.
    #[serde(default)]
    pub mis_samplers: Vec<String>,
}

/// The estimators of a study besides BRDF sampling alone.
pub const EXTRA_ESTIMATORS: [&str; 3] = ["light", "mis-balance", "mis-power"];

/// Map samplers of the light and MIS estimators in the default and quick studies.
pub const LIGHT_SAMPLERS: [&str; 2] = ["envmap-adaptive", "envmap-cdf"];

/// BRDF samplers inside MIS in the quick study (those registered and in the study): a
/// baseline without fit, the models' own lobes, a fitted mixture and the adaptive set.
pub const QUICK_MIS_SAMPLERS: [&str; 4] = ["cosine", "analytic", "srbf", "adaptive"];

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
            estimators: EXTRA_ESTIMATORS.iter().map(|s| s.to_string()).collect(),
            light_samplers: LIGHT_SAMPLERS.iter().map(|s| s.to_string()).collect(),
            mis_samplers: Vec::new(),
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
                "no readable measured BRDF found (shared/data/merl or shared/data/measured beside the repository, or their readers are not registered yet); the quick study uses analytic models only".to_string(),
            ),
        }
        let light = match find_candidate(root, &MAP_CANDIDATES) {
            Some(p) => format!("envmap:{}", p.display()),
            None => {
                notes.push(format!(
                    "no environment map file found (looked for {} beside the repository); the quick study uses the built-in procedural sky instead",
                    MAP_CANDIDATES[0]
                ));
                "sky".into()
            }
        };
        let mut c = Self::new(registered_preferred(), brdfs, vec![30.0, 60.0], vec![light]);
        c.preset = "quick".into();
        // A small slice: the map samplers alone and the balance heuristic (the default study
        // runs the power heuristic too).
        c.estimators = vec!["light".into(), "mis-balance".into()];
        c.mis_samplers = QUICK_MIS_SAMPLERS
            .iter()
            .filter(|n| c.samplers.iter().any(|s| s == *n))
            .map(|n| n.to_string())
            .collect();
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
        // The papers' tables rank BRDF sampling alone; no light or MIS cells.
        c.estimators.clear();
        c
    }

    /// The default study (no preset flag): every analytic model ([`analytic_models`]), every
    /// shared measured file ([`shared_measured`]), the [`DEFAULT_MERL_FITS`] (every MERL-100
    /// fit with `all_merl_fits`), θo ∈ [`FULL_THETA_O_DEG`], under the first real map found
    /// (the procedural sky when none is, said in the notes); the [`PREFERRED_SAMPLERS`] that
    /// are registered; the papers' N grid with 32 repetitions (256 in batch mode). Returns the
    /// config and notes for the report.
    pub fn full(root: Option<&std::path::Path>, all_merl_fits: bool) -> (Self, Vec<String>) {
        let mut brdfs = analytic_models();
        let (measured, mut notes) = shared_measured(root);
        brdfs.extend(measured);
        if all_merl_fits {
            brdfs.extend(self::all_merl_fits());
        } else {
            brdfs.extend(DEFAULT_MERL_FITS.iter().map(|s| s.to_string()));
        }
        let light = match find_candidate(root, &MAP_CANDIDATES) {
            Some(p) => format!("envmap:{}", p.display()),
            None => {
                notes.push(format!(
                    "no environment map file found (looked for {} beside the repository); the study uses the built-in procedural sky instead",
                    MAP_CANDIDATES[0]
                ));
                "sky".into()
            }
        };
        let mut c = Self::new(
            registered_preferred(),
            brdfs,
            FULL_THETA_O_DEG.to_vec(),
            vec![light],
        );
        c.preset = "default".into();
        (c, notes)
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
        if let Some(bad) = self
            .estimators
            .iter()
            .find(|e| !EXTRA_ESTIMATORS.contains(&e.as_str()))
        {
            return Err(StudyError::UnknownEstimator(bad.clone()));
        }
        if let Some(bad) = self
            .mis_samplers
            .iter()
            .find(|m| !self.samplers.contains(m))
        {
            return Err(StudyError::UnknownEstimator(format!(
                "MIS sampler `{bad}` is not among the study's samplers"
            )));
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

/// One part of a study run on its own: the cells of the BRDFs `b` (config order) with
/// `b % count == index - 1` (`StudyPlan::shard_brdfs`).
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
    /// `brdf`, `light`, `mis-balance` or `mis-power`.
    pub estimator: String,
    /// The map sampler of a `light` or MIS cell.
    pub light_sampler: Option<String>,
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
    fn the_default_study_covers_every_material_and_grazing_angles() {
        let (c, notes) = StudyConfig::full(None, false);
        assert_eq!(c.preset, "default");
        assert!(c.check().is_ok());
        // Every analytic model of the registry, by name.
        for m in brdf::models().iter().filter(|m| !m.needs_argument()) {
            assert!(c.brdfs.iter().any(|b| b == m.name), "{} missing", m.name);
        }
        assert!(c.brdfs.iter().any(|b| b == "lambert") && c.brdfs.iter().any(|b| b == "ggx"));
        for f in DEFAULT_MERL_FITS {
            assert!(c.brdfs.iter().any(|b| b == f), "{f}");
            assert!(brdf::parse_spec(f).is_ok(), "{f}");
        }
        assert_eq!(c.theta_o_deg, [0.0, 30.0, 60.0, 80.0, 88.0]);
        // Without a data directory: the sky, and notes saying what is missing.
        assert_eq!(c.lights, ["sky"]);
        assert!(notes.iter().any(|n| n.contains("measured")), "{notes:?}");
        let (all, _) = StudyConfig::full(None, true);
        let fits = all_merl_fits();
        assert_eq!(fits.len(), 200);
        assert!(fits.iter().all(|f| all.brdfs.contains(f)));
        assert!(brdf::parse_spec(&fits[0]).is_ok() && brdf::parse_spec(&fits[199]).is_ok());
    }

    #[test]
    fn the_default_study_takes_every_shared_measured_file() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let data = root.join("../shared/data/measured");
        if !data.is_dir() {
            eprintln!("skipped: no shared data at {}", data.display());
            return;
        }
        let (specs, _) = shared_measured(Some(&root));
        for (reader, dir, ext) in MEASURED_DIRS {
            let Ok(entries) = std::fs::read_dir(root.join("..").join(dir)) else {
                continue;
            };
            let n = entries
                .filter_map(|e| e.ok())
                .filter(|e| e.path().extension().is_some_and(|x| x == ext))
                .count();
            let got = specs
                .iter()
                .filter(|s| s.starts_with(&format!("{reader}:")))
                .count();
            assert_eq!(got, n, "{reader}: {specs:?}");
        }
        assert!(specs.iter().all(|s| !s.contains("..")), "{specs:?}");
    }

    #[test]
    fn presets_use_registered_samplers_only() {
        let names = registered_preferred();
        assert!(names.iter().any(|n| n == "adaptive"));
        assert!(names.iter().all(|n| samplers::find(n).is_ok()));
    }
}
