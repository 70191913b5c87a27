//! Integration tests of `partition-sampler`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs").

mod allocation;
mod batch_path;
mod chi_square;
mod common;
mod errors_and_persistence;
mod leaf_integrals;
mod negative;
mod parallel;
mod piecewise_constant;
mod properties;
mod refined_grid;
