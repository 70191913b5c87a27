//! Options of the factored baselines.

/// Options of the factored baselines (fields are added with the samplers that use them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FactoredOptions {}
