//! BRDF importance samplers built on the generic partition sampler (being written).
mod direction_sampler;
pub mod disc;
pub use disc::DiscBrdf;
pub use direction_sampler::{DirSample, DirectionSampler};
