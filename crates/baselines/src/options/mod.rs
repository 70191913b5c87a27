//! Options of the BRDF baselines, one struct per family; the registry hands them to the
//! samplers' constructors ([`BaselineOptions`]), the CLI fills them from its flags.

mod cdf;
mod factored;
mod lobe;
mod srbf;

pub use cdf::{CdfOptions, CdfOptionsError};
pub use factored::{FactoredOptions, FactoredOptionsError, NmfCost, Reparam};
pub use lobe::LobeOptions;
pub use srbf::SrbfOptions;

/// Options of every BRDF baseline (each family's defaults are the papers' or measured ones).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BaselineOptions {
    /// Cosine-lobe and analytic samplers.
    pub lobe: LobeOptions,
    /// Tabulated and Douglas–Peucker-compressed cascade CDFs.
    pub cdf: CdfOptions,
    /// Lawrence 2004 NMF factorisation.
    pub factored: FactoredOptions,
    /// Tsai 2008 SRBF fits and product sampling.
    pub srbf: SrbfOptions,
}
