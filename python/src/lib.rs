//! `brdf_lab._native`: the Python extension module of brdf-lab (pyo3 + numpy).
//!
//! The Python package `brdf_lab` (in `python/python/brdf_lab`) re-exports these classes and
//! functions; see `docs/python.md`. Every entry point:
//! * takes NumPy arrays (or anything `numpy.asarray` accepts) of float64, converting other
//!   dtypes and non-contiguous arrays;
//! * checks shapes and finiteness and raises `ValueError` with the reason (the library's own
//!   message for bad specs, names and options), never panics;
//! * releases the GIL while Rust works and runs rayon over fixed chunks of queries, each chunk
//!   with its own generator seeded from `(seed, chunk)`, so results depend on the seed and
//!   never on the thread count ([`threads`]).
#![allow(clippy::type_complexity)]

mod arrays;
mod brdf_py;
mod callable;
mod direction;
mod errors;
mod options;
mod planar;
mod runs;
mod threads;
mod user;

use pyo3::prelude::*;

/// The extension module `brdf_lab._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<brdf_py::Brdf>()?;
    m.add_class::<direction::DirectionSampler>()?;
    m.add_class::<planar::EnvMapSampler>()?;
    m.add_class::<planar::PartitionSampler>()?;
    m.add_function(wrap_pyfunction!(brdf_py::models, m)?)?;
    m.add_function(wrap_pyfunction!(direction::list_samplers, m)?)?;
    m.add_function(wrap_pyfunction!(direction::option_names, m)?)?;
    m.add_function(wrap_pyfunction!(runs::validate_json, m)?)?;
    m.add_function(wrap_pyfunction!(runs::study_json, m)?)?;
    m.add_function(wrap_pyfunction!(threads::set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(threads::num_threads, m)?)?;
    m.add("PAR_CHUNK", partition_sampler::PAR_CHUNK)?;
    Ok(())
}
