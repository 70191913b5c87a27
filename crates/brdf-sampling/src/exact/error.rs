//! Why an adaptive-exact set could not be built.

use crate::error::SetError;
use crate::options::OptionsError;

/// Why an [`ExactSet`](crate::ExactSet) could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ExactError {
    /// Invalid quadtree settings.
    #[error(transparent)]
    Options(#[from] OptionsError),
    /// An exact-sampler setting out of range.
    #[error("adaptive-exact: {what} = {value} is out of range")]
    Invalid {
        /// The setting and its range.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// An interval's image map or tree failed (the slice number is the interval's).
    #[error(transparent)]
    Set(#[from] SetError),
    /// An interval's normaliser is not positive and finite (the BRDF is zero or not finite
    /// there).
    #[error("adaptive-exact: ∫ f cos = {value} at θo = {theta_deg:.3}°, φo = {phi_deg:.3}°")]
    Normaliser {
        /// The integral found.
        value: f64,
        /// Where.
        theta_deg: f64,
        /// Where.
        phi_deg: f64,
    },
}
