//! envmap (stub)
