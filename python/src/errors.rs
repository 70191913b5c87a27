//! Library errors as Python `ValueError`s carrying the library's message (and its causes).

use pyo3::PyErr;
use pyo3::exceptions::PyValueError;

/// `ValueError` with `e`'s message followed by its chain of sources.
pub(crate) fn value_error(e: &(dyn std::error::Error + 'static)) -> PyErr {
    let mut msg = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let s_msg = s.to_string();
        if !msg.contains(&s_msg) {
            msg.push_str(": ");
            msg.push_str(&s_msg);
        }
        source = s.source();
    }
    PyValueError::new_err(msg)
}

/// `ValueError` with a message of ours.
pub(crate) fn invalid(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}
