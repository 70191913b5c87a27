//! Samplers written in Python (issue 31): any object with `sample(wo, u) -> (wi, pdf[, f])` and
//! `pdf(wo, wi)` on NumPy batches, wrapped as a Rust [`DirectionSampler`] and added to a
//! [`Registry`], so `validate` and `study` run it beside the built-in samplers.
//!
//! Calls into Python take the GIL; draws are batched: the validation suite's one-sample sets
//! come through [`DirectionSampler::sample_many`] (one call per chunk of
//! `validation::DRAW_CHUNK` draws) and its pdf-consistency check through
//! [`DirectionSampler::pdf_many`]. Single draws and the quadratures' pdf queries are one call
//! each (their cost is the object's cost, measured as it is by the study).

use std::collections::HashSet;
use std::sync::{Arc, Mutex};

use brdf::Vec3;
use brdf_sampling::{DirSample, DirectionSampler, SamplerDiagnostics};
use partition_sampler::UniformSource;
use pyo3::prelude::*;
use samplers::{Capabilities, Registry, SamplerEntry, Support};

use crate::arrays::{dir_array, dir_rows, flat_rows, floats};
use crate::errors::invalid;

/// A Python sampler object as a [`DirectionSampler`] (pdf w.r.t. solid angle, on the sphere:
/// samples below the horizon are allowed and count as zero contributions).
pub(crate) struct PySampler {
    obj: Py<PyAny>,
    name: String,
    /// The first error a call raised or a result's shape: reported after the run.
    error: Mutex<Option<String>>,
}

impl PySampler {
    /// Wraps `obj` (checks that it has callable `sample` and `pdf`).
    pub(crate) fn new(py: Python<'_>, name: &str, obj: Py<PyAny>) -> PyResult<Self> {
        for method in ["sample", "pdf"] {
            let callable = obj
                .bind(py)
                .getattr(method)
                .map(|m| m.is_callable())
                .unwrap_or(false);
            if !callable {
                return Err(invalid(format!(
                    "sampler `{name}` must have a callable `{method}` method (sample(wo, u) -> (wi, pdf) and pdf(wo, wi) on NumPy batches)"
                )));
            }
        }
        Ok(Self {
            obj,
            name: name.to_owned(),
            error: Mutex::new(None),
        })
    }

    /// Its registered name.
    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    /// The first error recorded during calls, if any.
    pub(crate) fn take_error(&self) -> Option<String> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    fn record(&self, what: &str, e: String) {
        if let Ok(mut slot) = self.error.lock()
            && slot.is_none()
        {
            *slot = Some(format!("sampler `{}`: {what}: {e}", self.name));
        }
    }

    /// `obj.sample(wo, u)` for the flat uniforms `u` (2 per sample).
    fn call_sample(&self, wo: &Vec3, u: Vec<f64>) -> Result<Vec<DirSample>, String> {
        let n = u.len() / 2;
        Python::attach(|py| {
            let (wo, u) = (dir_array(py, wo), flat_rows(py, u, 2));
            let out = self
                .obj
                .bind(py)
                .call_method1("sample", (wo, u))
                .map_err(|e| e.to_string())?;
            let parts: Vec<Bound<'_, PyAny>> = out.extract().map_err(|_| {
                "sample(wo, u) must return a tuple (wi, pdf) or (wi, pdf, f)".to_owned()
            })?;
            if !(2..=3).contains(&parts.len()) {
                return Err(format!(
                    "sample(wo, u) must return (wi, pdf) or (wi, pdf, f), got {} values",
                    parts.len()
                ));
            }
            let wi = floats(&parts[0], "wi", &[n, 3])?;
            let pdf = floats(&parts[1], "pdf", &[n])?;
            Ok((0..n)
                .map(|k| DirSample {
                    wi: Vec3::new(wi[3 * k], wi[3 * k + 1], wi[3 * k + 2]),
                    pdf: pdf[k],
                })
                .collect())
        })
    }

    /// `obj.pdf(wo, wi)` for the directions `wi`.
    fn call_pdf(&self, wo: &Vec3, wi: &[Vec3]) -> Result<Vec<f64>, String> {
        let n = wi.len();
        Python::attach(|py| {
            let (wo, wi) = (dir_array(py, wo), dir_rows(py, wi));
            let out = self
                .obj
                .bind(py)
                .call_method1("pdf", (wo, wi))
                .map_err(|e| e.to_string())?;
            floats(&out, "pdf", &[n])
        })
    }
}

/// A failed draw: a NaN direction with pdf NaN (the suite reports it; the run raises the
/// recorded error afterwards).
const FAILED: DirSample = DirSample {
    wi: Vec3::new(f64::NAN, f64::NAN, f64::NAN),
    pdf: f64::NAN,
};

impl DirectionSampler for PySampler {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        self.sample_many(wo, 1, u)
            .first()
            .copied()
            .unwrap_or(FAILED)
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.pdf_many(wo, std::slice::from_ref(wi))
            .first()
            .copied()
            .unwrap_or(f64::NAN)
    }

    fn sample_many(&self, wo: &Vec3, n: usize, u: &mut dyn UniformSource) -> Vec<DirSample> {
        let uniforms: Vec<f64> = (0..2 * n).map(|_| u.next_uniform()).collect();
        self.call_sample(wo, uniforms).unwrap_or_else(|e| {
            self.record("sample", e);
            vec![FAILED; n]
        })
    }

    /// Independent draws (a Python sampler has no stratified batch mode): one call.
    fn sample_batch(&self, wo: &Vec3, n: usize, u: &mut dyn UniformSource) -> Vec<DirSample> {
        self.sample_many(wo, n, u)
    }

    fn pdf_many(&self, wo: &Vec3, wi: &[Vec3]) -> Vec<f64> {
        self.call_pdf(wo, wi).unwrap_or_else(|e| {
            self.record("pdf", e);
            vec![f64::NAN; wi.len()]
        })
    }

    fn prefers_batches(&self) -> bool {
        true
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

impl SamplerDiagnostics for PySampler {}

/// Registered names of Python samplers (leaked once per distinct name: entries are named by
/// `&'static str`).
static NAMES: Mutex<Option<HashSet<&'static str>>> = Mutex::new(None);

fn static_name(name: &str) -> &'static str {
    let mut guard = NAMES.lock().unwrap_or_else(|p| p.into_inner());
    let set = guard.get_or_insert_with(HashSet::new);
    match set.get(name) {
        Some(n) => n,
        None => {
            let leaked: &'static str = Box::leak(name.to_owned().into_boxed_str());
            set.insert(leaked);
            leaked
        }
    }
}

/// The built-in registry plus the Python samplers `user` (name, object), and the wrapped
/// samplers (to collect their errors after a run).
///
/// Errors: a name that is empty or a built-in sampler's, given twice, or an object without
/// `sample`/`pdf`.
pub(crate) fn registry_with(
    py: Python<'_>,
    user: Vec<(String, Py<PyAny>)>,
) -> PyResult<(Registry, Vec<Arc<PySampler>>)> {
    let mut registry = Registry::builtin();
    let mut wrapped = Vec::with_capacity(user.len());
    let mut seen = HashSet::new();
    for (name, obj) in user {
        let name = name.trim().to_owned();
        if name.is_empty() || registry.contains(&name) && !seen.contains(&name) {
            return Err(invalid(format!(
                "a Python sampler needs a name of its own, not {name:?} (empty or a built-in sampler's)"
            )));
        }
        if !seen.insert(name.clone()) {
            return Err(invalid(format!("two Python samplers are named {name:?}")));
        }
        let sampler = Arc::new(PySampler::new(py, &name, obj)?);
        let shared = Arc::clone(&sampler);
        registry = registry.with(SamplerEntry::direction(
            static_name(&name),
            "a Python object (sample(wo, u), pdf(wo, wi) on NumPy batches)",
            Capabilities::default(),
            Support::Sphere,
            move |_| Ok(Arc::clone(&shared) as Arc<dyn DirectionSampler>),
        ));
        wrapped.push(sampler);
    }
    Ok((registry, wrapped))
}

/// The first error any wrapped sampler recorded, as a `ValueError`.
pub(crate) fn check_errors(wrapped: &[Arc<PySampler>]) -> PyResult<()> {
    match wrapped.iter().find_map(|s| s.take_error()) {
        Some(e) => Err(invalid(e)),
        None => Ok(()),
    }
}
