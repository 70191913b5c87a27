//! Runnable examples of brdf-lab; see the `[[example]]` entries of this package:
//! `cargo run --release -p brdf-lab-examples --example custom_density` (also `environment_map`, `merl`).
