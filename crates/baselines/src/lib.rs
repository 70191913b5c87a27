//! baselines (stub)
