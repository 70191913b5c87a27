//! NumPy inputs (any array-like, converted to float64) checked into Rust vectors, and Rust
//! vectors handed back to NumPy without a copy.

use std::borrow::Cow;

use brdf::Vec3;
use numpy::ndarray::{Array1, Array2};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLikeDyn};
use pyo3::prelude::*;

use rayon::prelude::*;

use crate::errors::invalid;
use crate::threads::install;

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

/// The values of an array in C order: borrowed when it is C-contiguous, else copied.
fn c_order<'a>(view: &'a numpy::ndarray::ArrayViewD<'a, f64>) -> Cow<'a, [f64]> {
    match view.as_slice() {
        Some(s) => Cow::Borrowed(s),
        None => Cow::Owned(view.as_standard_layout().iter().copied().collect()),
    }
}

/// Reads directions of shape `(3,)` or `(N, 3)`: finite, non-zero, normalised here (in
/// parallel).
pub(crate) fn dirs(a: &ArrayIn<'_>, name: &str) -> PyResult<Dirs> {
    let view = a.as_array();
    let single = match view.shape() {
        [3] => true,
        [_, 3] => false,
        other => {
            return Err(invalid(format!(
                "{name} must have shape (3,) or (N, 3), got {other:?}"
            )));
        }
    };
    let flat = c_order(&view);
    let bad = |c: &[f64]| {
        let finite = c.iter().all(|x| x.is_finite());
        let norm = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        !finite || norm <= 0.0
    };
    if let Some(row) = install(|| flat.par_chunks_exact(3).position_first(bad)) {
        let c = &flat[3 * row..3 * row + 3];
        return Err(invalid(if c.iter().all(|x| x.is_finite()) {
            format!("{name} row {row} is the zero vector")
        } else {
            format!("{name} has a non-finite value (NaN or ±inf) in row {row}: {c:?}")
        }));
    }
    let v: Vec<Vec3> = install(|| {
        flat.par_chunks_exact(3)
            .with_min_len(4096)
            .map(|c| Vec3::new(c[0], c[1], c[2]).normalize())
            .collect()
    });
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

/// Uniforms of shape `(N, 2)` in `[0, 1]`, flat (2 per row), checked in parallel and borrowed
/// when the array is C-contiguous.
pub(crate) fn uniforms<'a>(
    view: &'a numpy::ndarray::ArrayViewD<'a, f64>,
    name: &str,
) -> PyResult<Cow<'a, [f64]>> {
    if !matches!(view.shape(), [_, 2]) {
        return Err(invalid(format!(
            "{name} must have shape (N, 2), got {:?}",
            view.shape()
        )));
    }
    let flat = c_order(view);
    let bad = install(|| {
        flat.par_chunks_exact(2)
            .position_first(|c| !((0.0..=1.0).contains(&c[0]) && (0.0..=1.0).contains(&c[1])))
    });
    if let Some(row) = bad {
        return Err(invalid(format!(
            "{name} must lie in [0, 1): row {row} is {:?}",
            &flat[2 * row..2 * row + 2]
        )));
    }
    Ok(flat)
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

/// `(N, k)` float64 array from a flat row-major vector of `N · k` values (no copy).
pub(crate) fn flat_rows(py: Python<'_>, v: Vec<f64>, k: usize) -> Bound<'_, PyArray2<f64>> {
    let n = v.len() / k;
    Array2::from_shape_vec((n, k), v)
        .expect("n rows of k values")
        .into_pyarray(py)
}

/// `(N, k)` float64 array from `N` rows of `k` (one copy).
pub(crate) fn rows<const K: usize>(py: Python<'_>, v: Vec<[f64; K]>) -> Bound<'_, PyArray2<f64>> {
    let n = v.len();
    let flat: Vec<f64> = v.into_iter().flatten().collect();
    Array2::from_shape_vec((n, K), flat)
        .expect("n rows of K values")
        .into_pyarray(py)
}

/// A direction as a `(3,)` float64 array.
pub(crate) fn dir_array<'py>(py: Python<'py>, v: &Vec3) -> Bound<'py, PyArray1<f64>> {
    vec1(py, vec![v.x, v.y, v.z])
}

/// Directions as an `(N, 3)` float64 array.
pub(crate) fn dir_rows<'py>(py: Python<'py>, v: &[Vec3]) -> Bound<'py, PyArray2<f64>> {
    flat_rows(py, v.iter().flat_map(|w| [w.x, w.y, w.z]).collect(), 3)
}

/// The values of an array-like returned by Python code, which must have `shape` (float64, C
/// order): the message names `name` otherwise.
pub(crate) fn floats(
    a: &Bound<'_, PyAny>,
    name: &str,
    shape: &[usize],
) -> Result<Vec<f64>, String> {
    let arr: ArrayIn<'_> = a
        .extract()
        .map_err(|e| format!("{name} must be a float array: {e}"))?;
    let view = arr.as_array();
    if view.shape() != shape {
        return Err(format!(
            "{name} must have shape {shape:?}, got {:?}",
            view.shape()
        ));
    }
    Ok(view.iter().copied().collect())
}
