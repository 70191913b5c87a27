//! Reflectance functions for brdf-lab: the [`Brdf`] trait, twenty analytic models, the spec
//! parser used by the command line, and the MERL measured-BRDF format.
//!
//! # Conventions
//! * Local frame: normal `n = (0, 0, 1)`, tangent `x` (the anisotropy axis). Directions are unit
//!   [`Vec3`]s; both `ωo` (viewer) and `ωi` (light) point **away** from the surface;
//!   `ωo = (sinθ cosφ, sinθ sinφ, cosθ)` ([`direction_from_angles`]); the mirror direction is
//!   `(−ωo.x, −ωo.y, ωo.z)` ([`mirror`]).
//! * [`Brdf::eval`] returns `f_r(ωo, ωi)` in 1/sr (luminance `Y = 0.2126R + 0.7152G + 0.0722B`
//!   for coloured models), and 0 when either direction is at or below the horizon. Reflected
//!   radiance is `L_r(ωo) = ∫_Ω f_r(ωo, ωi) L_i(ωi) cosθi dσ(ωi)`; the directional albedo is
//!   `∫_Ω f_r cosθi dσ` ([`directional_albedo`]).
//!
//! # Specs
//! `name` or `name:key=value,...` (e.g. `phong:n=50,ks=0.7,kd=0.3`), or `merl:PATH`; see
//! [`parse_spec`] and [`models()`] for the registry (keys, defaults, ranges).
//!
//! # Example
//! ```
//! use brdf::{Brdf, direction_from_angles, directional_albedo, mirror, parse_spec};
//!
//! let phong = parse_spec("phong:n=50,ks=0.7,kd=0.3")?;
//! let wo = direction_from_angles(30.0, 0.0);
//! // The specular peak is in the mirror direction.
//! let peak = phong.eval(&wo, &mirror(&wo));
//! let off = phong.eval(&wo, &direction_from_angles(30.0, 90.0));
//! assert!(peak > 10.0 * off);
//! // Energy conservation: albedo ≤ kd + ks = 1.
//! let albedo = directional_albedo(phong.as_ref(), &wo, 64, 256);
//! assert!(albedo <= 1.0 + 1e-6 && albedo > 0.9);
//! // Typed errors name the problem.
//! let err = parse_spec("phong:q=1").err().map(|e| e.to_string()).unwrap_or_default();
//! assert!(err.contains("valid keys: n, ks, kd"));
//! # Ok::<(), brdf::SpecError>(())
//! ```

// `!(x > 0.0)` is the house style for checks that must also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod analytic;
mod brdf;
pub mod counting;
pub mod fresnel;
mod geometry;
pub mod measured;
pub mod merl;
pub mod models;
mod params;
pub mod plausibility;
pub mod quadrature;
mod registry;
pub mod special;
#[cfg(test)]
mod test_support;

pub use crate::brdf::{Brdf, LUMINANCE_WEIGHTS, Outgoing, PreparedRun, luminance};
pub use analytic::{AnalyticLobes, SpecularLobe};
pub use counting::{CountingBrdf, thread_evaluations};
pub use geometry::{
    Vec3, angles_of, direction_from_angles, direction_from_radians, half_vector, mirror,
    reflect_about, rotate_y, rotate_z,
};
pub use measured::cornell::{CornellBrdf, CornellError};
pub use measured::rgl::{RglBrdf, RglError};
pub use merl::{MerlBrdf, MerlError, write_merl};
pub use params::{ParamDefault, ParamError, ParamInfo, Range};
pub use plausibility::energy_warnings;
pub use quadrature::{directional_albedo, projected_hemisphere_integral};
pub use registry::{
    Isotropy, ModelInfo, SEED_003_MODELS, SpecError, find_model, models, parse_spec, preset_names,
};
