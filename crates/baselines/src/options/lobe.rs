//! Options of the lobe baselines.

/// Options of the lobe baselines (fields are added with the samplers that use them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LobeOptions {}
