//! Generic 2D adaptive-partition sampler (stub: being written).
pub mod sampler;
pub use sampler::{AsDistribution, InvertibleSampler2D, Point2, Sample2, Sampler2D, UniformSequence, UniformSource};
