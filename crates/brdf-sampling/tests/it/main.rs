//! Integration tests of `brdf-sampling`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs"). `cargo test --release -p brdf-sampling --test it NAME` runs
//! what `--test NAME` ran before.

mod chi_square;
mod common;
mod merl;
mod mirror;
mod moving_support;
mod negative;
mod persistence;
mod properties;
