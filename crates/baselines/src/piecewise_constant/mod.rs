//! Piecewise-constant densities sampled by CDF inversion (the pbrt-style baseline).

mod cdf;
mod error;
mod one_d;
mod two_d;

pub use error::TabulatedError;
pub use one_d::{PiecewiseConstant1D, Sample1};
pub use two_d::PiecewiseConstant2D;
