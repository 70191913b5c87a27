//! Integration tests of `stats`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs").

mod calibration;
mod cdf;
mod chi_square;
mod common;
mod ks;
mod power;
mod quadrature;
mod singular;
