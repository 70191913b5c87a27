//! Measured reflectance formats beyond MERL: the RGL material database's `.bsdf` tensor files
//! ([`rgl`]) and the Cornell pbrt-v2 `.brdf` spectral samples ([`cornell`]); the MERL table's
//! albedo integrated over its own bins ([`merl_albedo`]).

pub mod cornell;
pub mod merl_albedo;
pub mod rgl;
mod rgl_error;
pub mod tensor;
pub mod warp;
