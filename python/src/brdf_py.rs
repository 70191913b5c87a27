//! `brdf_lab.Brdf` and `brdf_lab.models()`.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;

use crate::arrays::{ArrayIn, dirs, pair_len, rows, vec1};
use crate::errors::value_error;
use crate::threads::install;

/// A BRDF from a spec string, exactly as the CLI's `--brdf` accepts it.
///
/// Examples: ``"ggx:alpha=0.2"``, ``"ward:alpha_x=0.1,alpha_y=0.3"``, ``"rgl:PATH.bsdf"``,
/// ``"cornell:PATH.brdf"``, ``"merl:PATH.binary"``, ``"sgd:material=NAME"``,
/// ``"abc:material=NAME"``. Directions are in the local shading frame (z = normal); `wo` is
/// the outgoing (view) direction, `wi` the incident (light) one. Values are 0 when either
/// direction is at or below the horizon.
///
/// Raises ``ValueError`` with the parser's message for a bad spec.
#[pyclass(module = "brdf_lab._native", name = "Brdf", frozen)]
pub(crate) struct Brdf {
    pub(crate) inner: Arc<dyn brdf::Brdf>,
    pub(crate) spec: String,
}

impl Brdf {
    /// Parses `spec` (the library's error as `ValueError`).
    pub(crate) fn parse(spec: &str) -> PyResult<Self> {
        let inner = brdf::parse_spec(spec).map_err(|e| value_error(&e))?;
        Ok(Self {
            inner: Arc::from(inner),
            spec: spec.to_string(),
        })
    }

    /// `f(brdf, wo_k, wi_k)` over the query pairs, in parallel with the GIL released (0 where
    /// either direction is at or below the horizon).
    fn eval_pairs<T, F>(
        &self,
        py: Python<'_>,
        wo: &ArrayIn<'_>,
        wi: &ArrayIn<'_>,
        f: F,
    ) -> PyResult<Vec<T>>
    where
        F: Fn(&dyn brdf::Brdf, &brdf::Vec3, &brdf::Vec3) -> T + Sync + Send,
        T: Default + Send,
    {
        let wo = dirs(wo, "wo")?;
        let wi = dirs(wi, "wi")?;
        let n = pair_len(&wo, "wo", &wi, "wi")?;
        let b = Arc::clone(&self.inner);
        Ok(py.detach(|| {
            install(|| {
                let b = b.as_ref();
                (0..n)
                    .into_par_iter()
                    .with_min_len(1024)
                    .map(|k| {
                        let (o, i) = (wo.get(k), wi.get(k));
                        if o.z > 0.0 && i.z > 0.0 {
                            f(b, o, i)
                        } else {
                            T::default()
                        }
                    })
                    .collect()
            })
        }))
    }
}

#[pymethods]
impl Brdf {
    #[new]
    fn new(spec: &str) -> PyResult<Self> {
        Self::parse(spec)
    }

    /// The spec this BRDF was built from.
    #[getter]
    fn spec(&self) -> &str {
        &self.spec
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }

    /// Whether the BRDF is isotropic (invariant under rotations about the normal).
    #[getter]
    fn is_isotropic(&self) -> bool {
        self.inner.is_isotropic()
    }

    /// Luminance (Rec. 709) of f_r(wo, wi), shape (N,). `wo`, `wi`: (3,) or (N, 3).
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wo: ArrayIn<'py>,
        wi: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let out = self.eval_pairs(py, &wo, &wi, |b, o, i| b.eval(o, i))?;
        Ok(vec1(py, out))
    }

    /// Linear RGB f_r(wo, wi), shape (N, 3).
    fn eval_rgb<'py>(
        &self,
        py: Python<'py>,
        wo: ArrayIn<'py>,
        wi: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let out = self.eval_pairs(py, &wo, &wi, |b, o, i| b.eval_rgb(o, i))?;
        Ok(rows(py, out))
    }

    fn __repr__(&self) -> String {
        format!("Brdf({:?})", self.spec)
    }
}

/// Every BRDF model: a list of dicts with `name`, `aliases`, `summary`, `isotropic`
/// (``"always"``, ``"never"``, ``"when_params_equal"``), `needs_argument` (built from a path or
/// a material name rather than numbers) and `params` (each with `key`, `default` — a number,
/// or ``"=KEY"`` for "same as KEY" —, `min`, `max`, `min_open`, `max_open`, `range` as text,
/// and `doc`).
#[pyfunction]
pub(crate) fn models(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for m in brdf::models() {
        let d = PyDict::new(py);
        d.set_item("name", m.name)?;
        d.set_item("aliases", m.aliases.to_vec())?;
        d.set_item("summary", m.summary)?;
        d.set_item(
            "isotropic",
            match m.isotropic {
                brdf::Isotropy::Always => "always",
                brdf::Isotropy::Never => "never",
                brdf::Isotropy::WhenParamsEqual => "when_params_equal",
            },
        )?;
        d.set_item("needs_argument", m.needs_argument())?;
        let params = PyList::empty(py);
        for p in m.params {
            let pd = PyDict::new(py);
            pd.set_item("key", p.key)?;
            match p.default {
                brdf::ParamDefault::Value(v) => pd.set_item("default", v)?,
                brdf::ParamDefault::SameAs(k) => pd.set_item("default", format!("={k}"))?,
            }
            pd.set_item("min", p.range.min)?;
            pd.set_item("max", p.range.max)?;
            pd.set_item("min_open", p.range.min_open)?;
            pd.set_item("max_open", p.range.max_open)?;
            pd.set_item("range", p.range.to_string())?;
            pd.set_item("doc", p.doc)?;
            params.append(pd)?;
        }
        d.set_item("params", params)?;
        list.append(d)?;
    }
    Ok(list)
}
