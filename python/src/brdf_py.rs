//! `brdf_lab.Brdf` and `brdf_lab.models()`.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::{ArrayIn, Dirs, dirs, pair_len, rows, vec1};
use crate::callable::{Claims, PyBrdf};
use crate::errors::value_error;
use crate::threads::par_map;

/// A BRDF from a spec string, exactly as the CLI's `--brdf` accepts it.
///
/// Examples: ``"ggx:alpha=0.2"``, ``"ward:alpha_x=0.1,alpha_y=0.3"``, ``"rgl:PATH.bsdf"``,
/// ``"cornell:PATH.brdf"``, ``"merl:PATH.binary"``, ``"sgd:material=NAME"``,
/// ``"abc:material=NAME"``. Directions are in the local shading frame (z = normal); `wo` is
/// the outgoing (view) direction, `wi` the incident (light) one. Values are 0 when either
/// direction is at or below the horizon.
///
/// Raises ``ValueError`` with the parser's message for a bad spec. A BRDF written in Python:
/// :meth:`Brdf.from_callable`.
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

    /// The callable BRDF's values at the pairs, in one call of the callable with the GIL
    /// held (its error as `ValueError`).
    fn eval_callable(py: Python<'_>, c: &PyBrdf, wo: &Dirs, wi: &Dirs) -> PyResult<Vec<f64>> {
        let n = pair_len(wo, "wo", wi, "wi")?;
        let wis: Vec<brdf::Vec3> = (0..n).map(|k| *wi.get(k)).collect();
        let wos: Vec<brdf::Vec3> = if wo.single && n > 0 {
            vec![*wo.get(0)]
        } else {
            (0..n).map(|k| *wo.get(k)).collect()
        };
        let out = c.eval_batch(py, &wos, &wis);
        c.take_error(py)?;
        Ok(out)
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
        if let Some(c) = PyBrdf::of(self.inner.as_ref()) {
            // Grey: `f(brdf, ·)` of a callable BRDF is built from its scalar value.
            let v = Self::eval_callable(py, c, &wo, &wi)?;
            return Ok(v
                .into_iter()
                .map(|y| {
                    f(
                        &Constant(y),
                        &brdf::Vec3::new(0.0, 0.0, 1.0),
                        &brdf::Vec3::new(0.0, 0.0, 1.0),
                    )
                })
                .collect());
        }
        let n = pair_len(&wo, "wo", &wi, "wi")?;
        let b = self.inner.as_ref();
        let ks: Vec<usize> = (0..n).collect();
        Ok(par_map(py, &ks, |&k| {
            let (o, i) = (wo.get(k), wi.get(k));
            if o.z > 0.0 && i.z > 0.0 {
                f(b, o, i)
            } else {
                T::default()
            }
        }))
    }
}

#[pymethods]
impl Brdf {
    #[new]
    fn new(spec: &str) -> PyResult<Self> {
        Self::parse(spec)
    }

    /// A BRDF written in Python: ``f(wo, wi)`` takes NumPy float64 arrays, ``wo`` of shape
    /// (3,) (shared by every pair) or (N, 3) and ``wi`` of shape (N, 3), unit vectors in the
    /// local frame (z = normal, both above the horizon), and returns the N values of f_r in
    /// 1/sr (finite, ≥ 0). The samplers' builds call it one pair at a time (taking the GIL for
    /// each call, from their worker threads); ``eval`` and the ``f`` of
    /// ``DirectionSampler.sample`` call it once per batch. An exception it raises, a result of
    /// another shape, or a NaN, infinite or negative value makes the calling method raise
    /// ``ValueError`` (the exception as its ``__cause__``).
    ///
    /// The claims (``isotropic``, ``mirror_symmetric`` — isotropic and even under y ↦ −y —,
    /// ``reciprocal``, ``bounded_at_horizon``) let samplers save work, as for the built-in
    /// models: a false claim gives a wrong sampler. The spec is ``"python:NAME"``.
    #[staticmethod]
    #[pyo3(signature = (f, *, name = "python", isotropic = false, mirror_symmetric = false, reciprocal = false, bounded_at_horizon = true))]
    fn from_callable(
        py: Python<'_>,
        f: Py<PyAny>,
        name: &str,
        isotropic: bool,
        mirror_symmetric: bool,
        reciprocal: bool,
        bounded_at_horizon: bool,
    ) -> PyResult<Self> {
        let claims = Claims {
            isotropic,
            mirror_symmetric,
            reciprocal,
            bounded_at_horizon,
        };
        let b = PyBrdf::new(py, f, name, claims)?;
        let spec = format!("python:{}", brdf::Brdf::name(&b));
        Ok(Self {
            inner: Arc::new(b),
            spec,
        })
    }

    /// Whether this BRDF is a Python callable (:meth:`from_callable`).
    #[getter]
    fn is_callable(&self) -> bool {
        PyBrdf::of(self.inner.as_ref()).is_some()
    }

    /// ``(calls, pairs)``: how many times a callable BRDF's function was called and on how
    /// many (wo, wi) pairs in all (None for the built-in models).
    #[getter]
    fn callable_counts(&self) -> Option<(u64, u64)> {
        PyBrdf::of(self.inner.as_ref()).map(PyBrdf::counts)
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

/// A BRDF of one value (the grey RGB of a callable BRDF's value).
struct Constant(f64);

impl brdf::Brdf for Constant {
    fn eval(&self, _wo: &brdf::Vec3, _wi: &brdf::Vec3) -> f64 {
        self.0
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
