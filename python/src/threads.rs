//! The thread pool the bindings run on, and the fixed chunking that makes results independent
//! of it.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, RwLock};

use pyo3::prelude::*;
use rayon::prelude::*;

use crate::errors::invalid;

/// The pool set by `set_num_threads` (`None`: rayon's global pool).
static POOL: RwLock<Option<Arc<rayon::ThreadPool>>> = RwLock::new(None);

/// Runs `f` on the configured pool (rayon's global pool by default).
pub(crate) fn install<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    let pool = POOL.read().ok().and_then(|p| p.clone());
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// Sets the number of worker threads of every later call (`None` or 0: rayon's default, one
/// per core or `RAYON_NUM_THREADS`). Results never depend on it.
#[pyfunction]
#[pyo3(signature = (n=None))]
pub(crate) fn set_num_threads(n: Option<usize>) -> PyResult<()> {
    let pool = match n {
        None | Some(0) => None,
        Some(n) => Some(Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| invalid(format!("cannot start {n} threads: {e}")))?,
        )),
    };
    *POOL
        .write()
        .map_err(|_| invalid("thread pool lock poisoned"))? = pool;
    Ok(())
}

/// The number of worker threads calls run on.
#[pyfunction]
pub(crate) fn num_threads() -> usize {
    install(rayon::current_num_threads)
}

/// The seed of the `call`-th call of an object seeded with `seed` (calls that give no seed of
/// their own draw fresh, reproducible streams).
pub(crate) fn call_seed(seed: u64, call: u64) -> u64 {
    partition_sampler::chunk_seed(seed ^ 0xB5AD_4ECE_DA1C_E2A9, call)
}

/// `given`, or else the seed of the next call of an object seeded with `seed` (its calls
/// counted in `calls`).
pub(crate) fn next_seed(seed: u64, calls: &AtomicU64, given: Option<u64>) -> u64 {
    given.unwrap_or_else(|| call_seed(seed, calls.fetch_add(1, Ordering::Relaxed)))
}

/// `f` of every item, in parallel on the configured pool with the GIL released.
pub(crate) fn par_map<T: Sync, R: Send>(
    py: Python<'_>,
    items: &[T],
    f: impl Fn(&T) -> R + Sync + Send,
) -> Vec<R> {
    py.detach(|| install(|| items.par_iter().with_min_len(1024).map(f).collect()))
}
