//! NumPy inputs (any array-like, converted to float64) checked into Rust vectors, and Rust
//! vectors handed back to NumPy without a copy.

use brdf::Vec3;
use numpy::ndarray::{Array1, Array2};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLikeDyn};
use pyo3::prelude::*;

use crate::errors::invalid;

/// An array-like argument, converted to float64 by numpy when needed.
pub(crate) type ArrayIn<'py> = PyArrayLikeDyn<'py, f64, AllowTypeChange>;

/// Directions given as `(3,)` (one, `single`) or `(N, 3)`.
pub(crate) struct Dirs {
    /// Unit vectors (the inputs normalised).
    pub(crate) v: Vec<Vec3>,
    /// Whether the input was one `(3,)` vector (broadcast over the other argument's rows).
    pub(crate) single: bool,
}

impl Dirs {
    /// Row `i` (row 0 for a single direction).
    #[inline]
    pub(crate) fn get(&self, i: usize) -> &Vec3 {
        if self.single { &self.v[0] } else { &self.v[i] }
    }

    /// Number of rows (1 for a single direction).
    pub(crate) fn len(&self) -> usize {
        self.v.len()
    }
}

/// Reads directions of shape `(3,)` or `(N, 3)`: finite, non-zero, normalised here.
pub(crate) fn dirs(a: &ArrayIn<'_>, name: &str) -> PyResult<Dirs> {
    let view = a.as_array();
    let (n, single) = match view.shape() {
        [3] => (1, true),
        [n, 3] => (*n, false),
        other => {
            return Err(invalid(format!(
                "{name} must have shape (3,) or (N, 3), got {other:?}"
            )));
        }
    };
    let flat: Vec<f64> = match view.as_slice() {
        Some(s) => s.to_vec(),
        None => view.iter().copied().collect(),
    };
    let mut v = Vec::with_capacity(n);
    for (row, c) in flat.chunks_exact(3).enumerate() {
        let d = Vec3::new(c[0], c[1], c[2]);
        if !(d.x.is_finite() && d.y.is_finite() && d.z.is_finite()) {
            return Err(invalid(format!(
                "{name} has a non-finite value (NaN or ±inf) in row {row}: {c:?}"
            )));
        }
        let norm = d.norm();
        if norm.is_nan() || norm <= 0.0 {
            return Err(invalid(format!("{name} row {row} is the zero vector")));
        }
        v.push(d / norm);
    }
    Ok(Dirs { v, single })
}

/// The number of query rows of two direction arguments (a single one broadcasts).
pub(crate) fn pair_len(a: &Dirs, an: &str, b: &Dirs, bn: &str) -> PyResult<usize> {
    match (a.single, b.single) {
        (true, true) => Ok(1),
        (true, false) => Ok(b.len()),
        (false, true) => Ok(a.len()),
        (false, false) if a.len() == b.len() => Ok(a.len()),
        _ => Err(invalid(format!(
            "{an} has {} rows and {bn} has {}: give one row per query or a single (3,) direction",
            a.len(),
            b.len()
        ))),
    }
}

/// Uniforms of shape `(N, 2)` in `[0, 1]` (1 is mapped to the largest double below 1).
pub(crate) fn uniforms(a: &ArrayIn<'_>, name: &str) -> PyResult<Vec<[f64; 2]>> {
    let view = a.as_array();
    if !matches!(view.shape(), [_, 2]) {
        return Err(invalid(format!(
            "{name} must have shape (N, 2), got {:?}",
            view.shape()
        )));
    }
    let flat: Vec<f64> = match view.as_slice() {
        Some(s) => s.to_vec(),
        None => view.iter().copied().collect(),
    };
    let below_one = 1.0 - f64::EPSILON / 2.0;
    flat.chunks_exact(2)
        .enumerate()
        .map(|(row, c)| {
            let mut out = [0.0; 2];
            for k in 0..2 {
                let x = c[k];
                if !(0.0..=1.0).contains(&x) {
                    return Err(invalid(format!(
                        "{name} must lie in [0, 1): row {row} is {c:?}"
                    )));
                }
                out[k] = x.min(below_one);
            }
            Ok(out)
        })
        .collect()
}

/// Points of shape `(N, 2)`, finite.
pub(crate) fn points(a: &ArrayIn<'_>, name: &str) -> PyResult<Vec<[f64; 2]>> {
    let view = a.as_array();
    if !matches!(view.shape(), [_, 2]) {
        return Err(invalid(format!(
            "{name} must have shape (N, 2), got {:?}",
            view.shape()
        )));
    }
    let flat: Vec<f64> = view.iter().copied().collect();
    flat.chunks_exact(2)
        .enumerate()
        .map(|(row, c)| {
            if c.iter().all(|x| x.is_finite()) {
                Ok([c[0], c[1]])
            } else {
                Err(invalid(format!(
                    "{name} has a non-finite value in row {row}: {c:?}"
                )))
            }
        })
        .collect()
}

/// `(N,)` float64 array (no copy).
pub(crate) fn vec1(py: Python<'_>, v: Vec<f64>) -> Bound<'_, PyArray1<f64>> {
    Array1::from_vec(v).into_pyarray(py)
}

/// `(N, k)` float64 array from `N` rows of `k` (no copy).
pub(crate) fn rows<const K: usize>(py: Python<'_>, v: Vec<[f64; K]>) -> Bound<'_, PyArray2<f64>> {
    let n = v.len();
    let flat: Vec<f64> = v.into_iter().flatten().collect();
    Array2::from_shape_vec((n, K), flat)
        .expect("n rows of K values")
        .into_pyarray(py)
}
