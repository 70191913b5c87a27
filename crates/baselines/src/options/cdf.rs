//! Options of the cdf baselines.

/// Options of the cdf baselines (fields are added with the samplers that use them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CdfOptions {}
