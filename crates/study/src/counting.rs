//! The counting BRDF wrapper lives in `brdf` (one wrapper for the study, `brdf-lab bench` and the
//! samplers' tests); re-exported here so `study::CountingBrdf` keeps its path.

pub use brdf::counting::{CountingBrdf, thread_evaluations};
