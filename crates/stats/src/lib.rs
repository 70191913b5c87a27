//! Statistical validation of samplers: do the samples follow the density the sampler reports?
//!
//! The crate is sampler-agnostic: it tests points against densities on binned domains
//! ([`RectBinning`] for images and rectangles, [`DiscBinning`] for the unit disc,
//! [`SphereBinning`] for the hemisphere and the sphere in `(cos θ, φ)`). Planar points are
//! `[f64; 2]` with densities with respect to area; directions are `[f64; 3]` with densities
//! with respect to solid angle.
//!
//! - [`chi_square_gof`] / [`chi_square_test`]: Pearson chi-square with pooling of cells that
//!   expect fewer than 5 samples; expected counts by adaptive Gauss–Legendre quadrature
//!   ([`expected_masses`]) whose error stays a small fraction of `√E` for any sample count.
//! - [`ks_onesample`], [`ks_twosample`], [`projection_cdf`], [`ks_projection_test`]:
//!   Kolmogorov–Smirnov tests (exact p-values for small samples, Stephens-corrected
//!   asymptotics for large ones) on 1D projections whose CDF is tabulated by quadrature.
//! - [`PiecewiseConstant`]: densities constant on known cells, whose bin masses and
//!   projection CDFs are exact overlap sums (no quadrature; for pdfs with thousands of jumps).
//! - [`pdf_consistency`], [`normalisation`], [`support_coverage`], [`mean_z_test`]: the
//!   deterministic checks and the estimator z-test.
//! - [`Suite`] applies the Šidák correction ([`sidak_level`]) over its tests;
//!   [`calibrate`] measures the false-rejection rate over many seeds.
//!
//! # Example
//!
//! Cosine-weighted hemisphere sampling, tested against its pdf `cos θ / π`, and the classic
//! bug of reporting the uniform pdf `1/(2π)` for the same samples:
//!
//! ```
//! use rand::{RngExt, SeedableRng, rngs::Xoshiro256PlusPlus};
//! use stats::{Axis, QuadratureOptions, SphereBinning, Suite, chi_square_test, ks_projection_test};
//!
//! let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
//! let points: Vec<[f64; 3]> = (0..20_000)
//!     .map(|_| {
//!         let (u1, u2): (f64, f64) = (rng.random(), rng.random());
//!         let (r, phi) = (u1.sqrt(), std::f64::consts::TAU * u2);
//!         [r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt()]
//!     })
//!     .collect();
//! let cosine = |d: [f64; 3]| d[2].max(0.0) / std::f64::consts::PI;
//! let uniform = |_: [f64; 3]| 0.5 / std::f64::consts::PI;
//!
//! let bins = SphereBinning::hemisphere(10, 20)?;
//! let opts = QuadratureOptions::default();
//! let mut suite = Suite::new(0.01)?;
//! suite.push(chi_square_test(&bins, &cosine, &points, &opts)?.outcome("chi-square", 0.01));
//! suite.push(ks_projection_test(&bins, &cosine, &points, Axis::U, 0.01, &opts)?);
//! assert!(suite.report().passed);
//!
//! let wrong = chi_square_test(&bins, &uniform, &points, &opts)?;
//! assert!(wrong.p_value < 1e-10);
//! # Ok::<(), stats::StatsError>(())
//! ```

// `!(x >= 0.0)`-style checks are deliberate: they reject NaN along with out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod binning;
mod calibration;
mod cdf;
mod cells;
mod checks;
mod chi_square;
mod error;
mod ks;
mod outcome;
mod quadrature;
pub mod singular;

pub use binning::{
    Axis, Binning, Direction, DiscBinning, Edge, Grid, Histogram, Patch, Point2, RectBinning,
    SphereBinning, histogram,
};
pub use calibration::{Calibration, calibrate};
pub use cdf::{
    MarginalMemo, Projection, TabulatedCdf, project, projection_cdf, projection_cdf_with_memo,
    projection_cdf_with_singularities,
};
pub use cells::{CellRow, PiecewiseConstant};
pub use checks::{
    COVERAGE_MASS_TOLERANCE, chi_square_test, ks_projection_test, ks_projection_test_with_memo,
    ks_projection_test_with_singularities, mean_variance, mean_z_test, normalisation,
    pdf_consistency, support_coverage, two_sided_z,
};
pub use chi_square::{ChiSquareResult, DEFAULT_MIN_EXPECTED, chi_square_gof, chi_square_sf};
pub use error::StatsError;
pub use ks::{
    KS_EXACT_MAX_CELLS, KS_EXACT_MAX_N, KsMethod, KsResult, kolmogorov_cdf, kolmogorov_sf,
    ks_onesample, ks_onesample_p_value, ks_statistic, ks_twosample, ks_twosample_p_value,
};
pub use outcome::{Suite, SuiteReport, TestOutcome, sidak_level};
pub use quadrature::{
    Integral, MassTable, QuadratureOptions, expected_masses, expected_masses_with, integrate,
    integrate_bins, integrate_rect,
};
