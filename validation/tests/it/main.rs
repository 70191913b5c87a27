//! Integration tests of `validation`: the quick tier, errors, references, reports, saved sets and skips.
//!
//! One test binary for the crate (each file under `tests/it/` is a module): the README's
//! test command compiles and links one binary here instead of one per file (docs/validation.md,
//! "What the test command runs").

mod byo;
mod errors;
mod quick_cornell;
mod quick_tier;
mod references;
mod report;
mod saved_sets;
mod skipped;
