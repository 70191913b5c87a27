//! Integration tests of `envmap`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs"). `cargo test --release -p envmap --test it NAME` runs
//! what `--test NAME` ran before.

mod load;
mod sampling;
#[path = "../../benches/support/mod.rs"]
mod support;
