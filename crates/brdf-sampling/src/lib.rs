//! BRDF importance sampling with sets of adaptive quadtrees on the projected disc
//! (Montes, Ureña et al., GRAPP 2008 §3 / CEIG 2008 §3).
//!
//! TODO crate docs.

mod direction_sampler;
pub mod disc;
mod error;
mod factory;
mod image_map;
mod layout;
mod options;
mod persist;
mod report;
mod set;

pub use direction_sampler::{DirSample, DirectionSampler};
pub use disc::{DiscBrdf, SliceDensity, area_pdf_to_solid_angle, disc_to_direction, direction_to_disc, solid_angle_pdf_to_area};
pub use error::{PersistError, SamplerError, SetError};
pub use factory::{SAMPLER_NAMES, build_sampler, build_sampler_with_progress, build_set, parse_sampler_name};
pub use layout::{SliceChoice, SliceLayout};
pub use options::*;
pub use persist::SET_FORMAT_VERSION;
pub use report::{CostMeasurement, SetReport};
pub use set::{Progress, QuadTreeSet, Variant, layout_for};
