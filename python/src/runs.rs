//! `validate(...)` and `study(...)`: the library's suites, returning their JSON (parsed into
//! Python objects by `brdf_lab`) and writing the same files as the CLI.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use study::{Shard, StudyConfig, StudyPlan};
use validation::ValidateConfig;

use crate::brdf_py::Brdf;
use crate::callable::PyBrdf;
use crate::errors::{invalid, value_error};
use crate::threads::install;
use crate::user::{check_errors, registry_with};

fn write(path: &Path, bytes: &[u8]) -> PyResult<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| PyOSError::new_err(format!("cannot create {}: {e}", dir.display())))?;
    }
    std::fs::write(path, bytes)
        .map_err(|e| PyOSError::new_err(format!("cannot write {}: {e}", path.display())))
}

/// Runs the validation suite (`brdf-lab validate`) and returns its report as JSON (schema in
/// design.md §5); `json` / `report` write the CLI's `--json` / `--report` files. Empty lists
/// take the tier's defaults (`quick`: the CI tier).
#[pyfunction]
#[pyo3(signature = (samplers, brdfs, theta_o, samples = None, seed = 1, quick = true, mutants = false, alpha = 0.01, json = None, report = None, sets = Vec::new(), user = Vec::new(), objects = Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn validate_json(
    py: Python<'_>,
    samplers: Vec<String>,
    brdfs: Vec<String>,
    theta_o: Vec<f64>,
    samples: Option<usize>,
    seed: u64,
    quick: bool,
    mutants: bool,
    alpha: f64,
    json: Option<PathBuf>,
    report: Option<PathBuf>,
    sets: Vec<PathBuf>,
    user: Vec<(String, Py<PyAny>)>,
    objects: Vec<Py<Brdf>>,
) -> PyResult<String> {
    // BRDFs that no spec names (Python callables): validated as objects, labelled by spec.
    let given: Vec<(String, Arc<dyn brdf::Brdf>)> = objects
        .iter()
        .map(|b| {
            let b = b.get();
            (b.spec.clone(), Arc::clone(&b.inner))
        })
        .collect();
    let (registry, wrapped) = registry_with(py, user)?;
    let base = if quick {
        ValidateConfig::quick()
    } else {
        ValidateConfig::default()
    };
    let config = ValidateConfig {
        brdfs: if brdfs.is_empty() {
            base.brdfs.clone()
        } else {
            brdfs
        },
        samplers: if samplers.is_empty() {
            base.samplers.clone()
        } else {
            samplers
        },
        theta_o: if theta_o.is_empty() {
            base.theta_o.clone()
        } else {
            theta_o
        },
        samples: samples.or(base.samples),
        seed,
        quick,
        mutants,
        alpha,
        sets,
        ..base
    };
    let rep = py
        .detach(|| {
            install(|| {
                validation::run_with_brdfs(&registry, &config, &given, &|_| {}).map_err(Box::new)
            })
        })
        .map_err(|e| value_error(e.as_ref()))?;
    check_errors(&wrapped)?;
    for (_, b) in &given {
        if let Some(c) = PyBrdf::of(b.as_ref()) {
            c.take_error(py)?;
        }
    }
    let text = rep.to_json();
    if let Some(p) = &json {
        write(p, text.as_bytes())?;
    }
    if let Some(p) = &report {
        write(p, rep.to_markdown().as_bytes())?;
    }
    Ok(text)
}

/// Runs a variance-versus-cost study (`brdf-lab study`) and returns its results as JSON;
/// `out` writes the CLI's `results.json`, `results.csv`, `report.md` and `plots/` there (the
/// sphere images are not rendered: `brdf-lab study` makes them). `preset`: ``"quick"`` (the
/// CLI's `--quick`, looking for ../shared from `root`) or ``"custom"``; non-empty lists and
/// given counts override it.
#[pyfunction]
#[pyo3(signature = (samplers, brdfs, theta_o, lights, preset = "quick", n_grid = None, repetitions = None, seed = 1, shard = None, out = None, root = None, user = Vec::new(), variance_samples = None, timing_samples = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn study_json(
    py: Python<'_>,
    samplers: Vec<String>,
    brdfs: Vec<String>,
    theta_o: Vec<f64>,
    lights: Vec<String>,
    preset: &str,
    n_grid: Option<Vec<usize>>,
    repetitions: Option<usize>,
    seed: u64,
    shard: Option<String>,
    out: Option<PathBuf>,
    root: Option<PathBuf>,
    user: Vec<(String, Py<PyAny>)>,
    variance_samples: Option<usize>,
    timing_samples: Option<usize>,
) -> PyResult<String> {
    let (registry, wrapped) = registry_with(py, user)?;
    let (mut config, notes) = match preset {
        "quick" => StudyConfig::quick(root.as_deref()),
        "custom" => {
            let (q, _) = StudyConfig::quick(None);
            let mut c = StudyConfig::new(q.samplers, q.brdfs, q.theta_o_deg, vec!["sky".into()]);
            c.preset = "custom".into();
            (c, Vec::new())
        }
        other => {
            return Err(invalid(format!(
                "preset must be \"quick\" or \"custom\", got {other:?}"
            )));
        }
    };
    if !samplers.is_empty() {
        config.samplers = samplers;
    }
    // Python samplers join the selection (or the preset's samplers).
    for s in &wrapped {
        if !config.samplers.iter().any(|n| n == s.name()) {
            config.samplers.push(s.name().to_owned());
        }
    }
    if !brdfs.is_empty() {
        config.brdfs = brdfs;
    }
    if !theta_o.is_empty() {
        config.theta_o_deg = theta_o;
    }
    if !lights.is_empty() {
        config.lights = lights;
    }
    if let Some(g) = n_grid {
        config.n_grid = g;
    }
    if let Some(r) = repetitions {
        config.repetitions = r;
    }
    if let Some(v) = variance_samples {
        config.variance_samples = v;
    }
    if let Some(t) = timing_samples {
        config.timing_samples = t;
    }
    config.seed = seed;
    let shard = shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(|e| value_error(&e))?;
    let plan = StudyPlan::with_registry(config, notes, &registry).map_err(|e| value_error(&e))?;
    let results = py.detach(|| install(|| plan.run(shard, &|_| {})));
    check_errors(&wrapped)?;
    let text = results.to_json();
    if let Some(dir) = &out {
        let plots = py
            .detach(|| study::study_plots(&results))
            .map_err(|e| value_error(&e))?;
        let mut assets = study::ReportAssets::default();
        for p in plots {
            let png = format!("plots/{}.png", p.stem);
            write(&dir.join(&png), &p.png)?;
            write(&dir.join(format!("plots/{}.svg", p.stem)), p.svg.as_bytes())?;
            assets.plots.push((p.slug, p.caption, png));
        }
        write(&dir.join("results.json"), text.as_bytes())?;
        write(&dir.join("results.csv"), results.to_csv().as_bytes())?;
        write(
            &dir.join("report.md"),
            study::report_markdown(&results, &assets).as_bytes(),
        )?;
    }
    Ok(text)
}
