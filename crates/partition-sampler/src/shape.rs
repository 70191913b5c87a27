//! The identity of a density as a stored tree records it (provider kind, domain, dimensions,
//! fingerprint): a leaf module, so that errors and densities can both name it.

use serde::{Deserialize, Serialize};

use crate::rect::Domain;

/// Which provider built a tree: used to check that a stored tree is re-attached to a
/// compatible density.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ProviderKind {
    /// [`crate::TabulatedDensity`].
    Tabulated,
    /// [`crate::SampledGridDensity`].
    SampledGrid,
    /// [`crate::UserBoundDensity`].
    UserBound,
    /// Any other implementation of [`RegionStats`].
    Custom,
}

/// Identity of a density as far as a stored tree is concerned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DensityShape {
    /// The provider type.
    pub kind: ProviderKind,
    /// The domain.
    pub domain: Domain,
    /// Grid dimensions (width, height), or quadrature resolution, or `[0, 0]`.
    pub dims: [u64; 2],
    /// A provider-defined fingerprint of the data (e.g. the bits of the total integral);
    /// 0 when the provider has none.
    pub fingerprint: u64,
}
