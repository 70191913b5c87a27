//! Integration tests of `cli`.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs"). `cargo test --release -p cli --test it NAME` runs
//! what `--test NAME` ran before.

mod bench;
mod cli;
mod import_cycles;
mod product;
mod readme;
mod study;
mod validate_shard;
