//! `brdf_lab.Brdf.from_callable`: a BRDF given as a Python callable `f(wo, wi)` on NumPy
//! batches, wrapped as a Rust [`brdf::Brdf`] (issue 31 item 3), so every sampler of the
//! registry can be built for it and the validation suite can judge it.
//!
//! Evaluation. The samplers' builds evaluate `f_r` one point at a time, from rayon workers,
//! through [`brdf::Brdf::eval`]: each such call takes the GIL ([`Python::attach`]), calls `f`
//! on a batch of one pair and releases it, so builds running with the GIL released (as every
//! entry point of the bindings does) never deadlock, whatever the thread count. The calls of
//! the bindings that know many pairs at once — `Brdf.eval`, the `f` of
//! `DirectionSampler.sample` — call `f` once on the whole batch ([`PyBrdf::eval_batch`]).
//!
//! Errors. An exception raised by `f`, a result of the wrong shape and a value that is NaN,
//! infinite or negative are recorded (the first one) and turn the evaluation into NaN; the
//! builds reject a NaN as an invalid sample (a typed `DensityError`), and the binding that ran
//! the call raises the recorded error as `ValueError` (with the exception as its cause).

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use brdf::Vec3;
use pyo3::prelude::*;

use crate::arrays::{dir_array, dir_rows, floats};
use crate::errors::invalid;

/// What `from_callable` declares about `f` (the samplers use these to save work; a wrong
/// claim gives a wrong sampler, as it would for a Rust model).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Claims {
    /// Invariant under rotations about the normal.
    pub(crate) isotropic: bool,
    /// Isotropic and even under `y ↦ −y` (see [`brdf::Brdf::is_mirror_symmetric`]).
    pub(crate) mirror_symmetric: bool,
    /// `f(wo, wi) = f(wi, wo)`.
    pub(crate) reciprocal: bool,
    /// Bounded as `θi → 90°`.
    pub(crate) bounded_at_horizon: bool,
}

/// The first error of a callable: its message and the Python exception, if one was raised.
type Recorded = (String, Option<PyErr>);

/// A Python callable as a [`brdf::Brdf`] (scalar: the callable's value is the luminance).
pub(crate) struct PyBrdf {
    f: Py<PyAny>,
    name: String,
    claims: Claims,
    failed: AtomicBool,
    error: Mutex<Option<Recorded>>,
    calls: AtomicU64,
    evaluations: AtomicU64,
}

impl PyBrdf {
    /// Wraps `f` (which must be callable).
    pub(crate) fn new(py: Python<'_>, f: Py<PyAny>, name: &str, claims: Claims) -> PyResult<Self> {
        if !f.bind(py).is_callable() {
            return Err(invalid(format!(
                "Brdf.from_callable needs a callable f(wo, wi) -> values, got {}",
                f.bind(py).get_type().name()?
            )));
        }
        if name.trim().is_empty() || name.contains(':') {
            return Err(invalid(format!(
                "a callable BRDF's name must be non-empty and without ':', got {name:?}"
            )));
        }
        Ok(Self {
            f,
            name: name.trim().to_owned(),
            claims: Claims {
                mirror_symmetric: claims.mirror_symmetric && claims.isotropic,
                ..claims
            },
            failed: AtomicBool::new(false),
            error: Mutex::new(None),
            calls: AtomicU64::new(0),
            evaluations: AtomicU64::new(0),
        })
    }

    /// The callable BRDF behind `b`, if it is one.
    pub(crate) fn of(b: &dyn brdf::Brdf) -> Option<&PyBrdf> {
        b.as_any().and_then(|a| a.downcast_ref::<PyBrdf>())
    }

    /// Number of calls of `f` and of pairs evaluated so far.
    pub(crate) fn counts(&self) -> (u64, u64) {
        (
            self.calls.load(Ordering::Relaxed),
            self.evaluations.load(Ordering::Relaxed),
        )
    }

    /// The first recorded error as a `ValueError` (its cause: the exception `f` raised), and
    /// clears it (so the object can be used again after a failed call).
    pub(crate) fn take_error(&self, py: Python<'_>) -> PyResult<()> {
        let recorded = self.error.lock().ok().and_then(|mut e| e.take());
        self.failed.store(false, Ordering::Relaxed);
        match recorded {
            None => Ok(()),
            Some((msg, cause)) => {
                let err = invalid(msg);
                err.set_cause(py, cause);
                Err(err)
            }
        }
    }

    fn record(&self, msg: String, cause: Option<PyErr>) {
        self.failed.store(true, Ordering::Relaxed);
        if let Ok(mut slot) = self.error.lock()
            && slot.is_none()
        {
            *slot = Some((format!("callable BRDF `{}`: {msg}", self.name), cause));
        }
    }

    /// `f(wo, wi)` for the pairs `(wo[k], wi[k])` (`wo` of length 1: shared), all above the
    /// horizon: one call with the GIL held by the caller. Values must be finite and `≥ 0`.
    fn call(&self, py: Python<'_>, wo: &[Vec3], wi: &[Vec3]) -> Result<Vec<f64>, Recorded> {
        let n = wi.len();
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.evaluations.fetch_add(n as u64, Ordering::Relaxed);
        let wo_arg = match wo {
            [one] => dir_array(py, one).into_any(),
            many => dir_rows(py, many).into_any(),
        };
        let out = self
            .f
            .bind(py)
            .call1((wo_arg, dir_rows(py, wi)))
            .map_err(|e| (format!("f(wo, wi) raised {e}"), Some(e)))?;
        let v = floats(&out, "f(wo, wi)", &[n]).map_err(|e| (e, None))?;
        if let Some(k) = v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            let (o, i) = (wo[if wo.len() == 1 { 0 } else { k }], wi[k]);
            return Err((
                format!(
                    "f(wo, wi) returned {} at wo = ({}, {}, {}), wi = ({}, {}, {}): BRDF values must be finite and ≥ 0",
                    v[k], o.x, o.y, o.z, i.x, i.y, i.z
                ),
                None,
            ));
        }
        Ok(v)
    }

    /// `f_r(wo[k], wi[k])` for every pair (`wo` of length 1: shared by every pair), 0 where
    /// either direction is at or below the horizon: one call of `f` on the pairs above it.
    /// NaN everywhere after an error (recorded; see [`take_error`](Self::take_error)).
    pub(crate) fn eval_batch(&self, py: Python<'_>, wo: &[Vec3], wi: &[Vec3]) -> Vec<f64> {
        let shared = wo.len() == 1;
        let wo_k = |k: usize| if shared { &wo[0] } else { &wo[k] };
        let keep: Vec<usize> = (0..wi.len())
            .filter(|&k| wo_k(k).z > 0.0 && wi[k].z > 0.0)
            .collect();
        let mut out = vec![0.0; wi.len()];
        if keep.is_empty() {
            return out;
        }
        if self.failed.load(Ordering::Relaxed) {
            return vec![f64::NAN; wi.len()];
        }
        let wis: Vec<Vec3> = keep.iter().map(|&k| wi[k]).collect();
        let wos: Vec<Vec3> = if shared {
            vec![wo[0]]
        } else {
            keep.iter().map(|&k| wo[k]).collect()
        };
        match self.call(py, &wos, &wis) {
            Ok(v) => {
                for (&k, x) in keep.iter().zip(v) {
                    out[k] = x;
                }
                out
            }
            Err((msg, cause)) => {
                self.record(msg, cause);
                vec![f64::NAN; wi.len()]
            }
        }
    }
}

impl brdf::Brdf for PyBrdf {
    /// One call of `f` on a batch of one pair, with the GIL taken for the call.
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        if self.failed.load(Ordering::Relaxed) {
            return f64::NAN;
        }
        Python::attach(|py| self.eval_batch(py, std::slice::from_ref(wo), std::slice::from_ref(wi)))
            .first()
            .copied()
            .unwrap_or(f64::NAN)
    }

    fn is_isotropic(&self) -> bool {
        self.claims.isotropic
    }

    fn is_mirror_symmetric(&self) -> bool {
        self.claims.mirror_symmetric
    }

    fn is_half_turn_symmetric(&self) -> bool {
        self.claims.isotropic
    }

    fn is_reciprocal(&self) -> bool {
        self.claims.reciprocal
    }

    fn bounded_at_horizon(&self) -> bool {
        self.claims.bounded_at_horizon
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}
