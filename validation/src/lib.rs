//! Validation suites (being written).
