//! Integration tests of `brdf`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs"). `cargo test --release -p brdf --test it NAME` runs
//! what `--test NAME` ran before.

mod common;
mod cornell;
mod energy;
mod fits;
mod half_turn;
mod horizon;
mod merl;
mod mirror;
mod models;
mod rgl;
mod spec;
