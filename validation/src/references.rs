//! Reference values for the unbiasedness tests: directional albedo and reflected radiance under
//! an analytic environment, by adaptive Gauss–Legendre quadrature; and the stored table of the
//! quick tier's values (`references/albedo.json`).

use brdf::{Brdf, Vec3};
use serde::{Deserialize, Serialize};
use stats::{QuadratureOptions, SphereBinning, StatsError, integrate};

use crate::subject::{Dir3, Reference};

/// The analytic environment of the "lit" estimand: `L(ω) = 1 + ½ ω_x + ¼ ω_y` (positive on
/// the sphere, with a gradient so that the lit integrand is never proportional to `f_r cos θ`).
pub fn environment(w: Dir3) -> f64 {
    1.0 + 0.5 * w[0] + 0.25 * w[1]
}

/// `(cos θ, φ)` bins of the reference quadrature.
pub const REFERENCE_BINS: [usize; 2] = [16, 32];

/// Absolute tolerance of the reference quadrature (shared by all bins).
pub const REFERENCE_TOLERANCE: f64 = 1e-8;

/// Description of the reference rule, stored with every reference.
pub const REFERENCE_RULE: &str = "adaptive tensor Gauss-Legendre quadrature (stats::integrate) of the integrand w.r.t. \
solid angle over the upper hemisphere in (cos theta, phi), 16 x 32 bins, order 8, refinement depth <= 12, \
total absolute tolerance 1e-8";

fn reference_options() -> QuadratureOptions {
    QuadratureOptions {
        order: 8,
        min_depth: 1,
        max_depth: 12,
        rel_floor: 1e-13,
        max_evaluations_per_bin: 2_000_000,
        ..QuadratureOptions::default()
    }
}

/// Absolute tolerance of the reference quadrature for BRDFs interpolated from scattered
/// samples (`cornell:`), instead of [`REFERENCE_TOLERANCE`]. Their interpolant is only
/// continuous, with kinks along the boundaries of ~1439 samples' neighbour regions, where
/// Gauss–Legendre converges slowly: on `acryl_blue` at θo = 45° the albedo to `10⁻⁶` took
/// 8.7·10⁶ evaluations (25 s on a loaded core), to `10⁻⁸` it did not finish in 10 min. The
/// estimated error is part of the reference and of the unbiasedness z-tests' yardstick.
pub const SCATTERED_REFERENCE_TOLERANCE: f64 = 1e-6;

/// The reference tolerance for `brdf`: [`SCATTERED_REFERENCE_TOLERANCE`] for `cornell`,
/// [`REFERENCE_TOLERANCE`] otherwise.
pub fn reference_tolerance(brdf: &dyn Brdf) -> f64 {
    if brdf.name() == "cornell" {
        SCATTERED_REFERENCE_TOLERANCE
    } else {
        REFERENCE_TOLERANCE
    }
}

/// `∫_Ω g(ω) dσ(ω)` over the upper hemisphere by the reference rule ([`REFERENCE_RULE`]).
///
/// # Errors
/// Invalid quadrature settings (not expected).
pub fn hemisphere_integral(g: &(dyn Fn(Dir3) -> f64 + Sync)) -> Result<Reference, StatsError> {
    hemisphere_integral_to(g, REFERENCE_TOLERANCE)
}

/// [`hemisphere_integral`] to the absolute tolerance `tolerance` (stated in the rule when it is
/// not [`REFERENCE_TOLERANCE`]).
///
/// # Errors
/// Invalid quadrature settings or tolerance.
pub fn hemisphere_integral_to(
    g: &(dyn Fn(Dir3) -> f64 + Sync),
    tolerance: f64,
) -> Result<Reference, StatsError> {
    let bins = SphereBinning::hemisphere(REFERENCE_BINS[0], REFERENCE_BINS[1])?;
    let r = integrate(g, &bins, tolerance, &reference_options())?;
    let rule = if tolerance == REFERENCE_TOLERANCE {
        REFERENCE_RULE.to_owned()
    } else {
        REFERENCE_RULE.replace("tolerance 1e-8", &format!("tolerance {tolerance:e}"))
    };
    Ok(Reference {
        value: r.value,
        abs_error: r.error_estimate.max(tolerance),
        rule: format!(
            "{rule}; {} evaluations, {}converged",
            r.evaluations,
            if r.converged { "" } else { "NOT " }
        ),
    })
}

/// `f_r(ωo, ωi) cos θi` (0 below the horizon) at `ωi = w`.
pub fn projected_brdf(brdf: &dyn Brdf, wo: &Vec3, w: Dir3) -> f64 {
    if !(w[2] > 0.0) {
        return 0.0;
    }
    brdf.eval(wo, &Vec3::new(w[0], w[1], w[2])) * w[2]
}

/// Directional albedo `ρ(ωo) = ∫_Ω f_r(ωo, ωi) cos θi dσ(ωi)` by the reference rule (to
/// [`reference_tolerance`]).
///
/// # Errors
/// See [`hemisphere_integral`].
pub fn albedo_reference(brdf: &dyn Brdf, wo: &Vec3) -> Result<Reference, StatsError> {
    hemisphere_integral_to(&|w| projected_brdf(brdf, wo, w), reference_tolerance(brdf))
}

/// Reflected radiance under [`environment`]: `L_r(ωo) = ∫_Ω f_r cos θi L(ωi) dσ(ωi)` (to
/// [`reference_tolerance`]).
///
/// # Errors
/// See [`hemisphere_integral`].
pub fn lit_reference(brdf: &dyn Brdf, wo: &Vec3) -> Result<Reference, StatsError> {
    hemisphere_integral_to(
        &|w| projected_brdf(brdf, wo, w) * environment(w),
        reference_tolerance(brdf),
    )
}

/// One stored reference: a BRDF spec at an outgoing polar angle (azimuth 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredReference {
    /// BRDF spec.
    pub brdf: String,
    /// Outgoing polar angle in degrees (`φo = 0`).
    pub theta_o: f64,
    /// Directional albedo.
    pub albedo: f64,
    /// Its estimated absolute error.
    pub albedo_error: f64,
    /// Reflected radiance under [`environment`].
    pub lit: f64,
    /// Its estimated absolute error.
    pub lit_error: f64,
    /// Independent cross-check of the albedo: `brdf::directional_albedo` with 256 θ panels
    /// (8-point Gauss–Legendre each) and 1024 φ points.
    pub albedo_check: f64,
}

/// The stored reference table (`validation/references/albedo.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredReferences {
    /// How the values were computed.
    pub rule: String,
    /// The environment of the lit values.
    pub environment: String,
    /// The command that regenerates the file.
    pub generated_by: String,
    /// One entry per quick-tier (BRDF, θo).
    pub entries: Vec<StoredReference>,
}

/// The environment formula as stored.
pub const ENVIRONMENT_FORMULA: &str = "L(w) = 1 + 0.5 w_x + 0.25 w_y";

/// Computes the stored entry of `spec` at `theta_o` degrees.
///
/// # Errors
/// A bad spec or a quadrature failure, as text.
pub fn compute_stored(spec: &str, theta_o: f64) -> Result<StoredReference, String> {
    let brdf = brdf::parse_spec(spec).map_err(|e| e.to_string())?;
    let wo = brdf::direction_from_angles(theta_o, 0.0);
    let a = albedo_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?;
    let l = lit_reference(brdf.as_ref(), &wo).map_err(|e| e.to_string())?;
    Ok(StoredReference {
        brdf: portable_spec(spec),
        theta_o,
        albedo: a.value,
        albedo_error: a.abs_error,
        lit: l.value,
        lit_error: l.abs_error,
        albedo_check: brdf::directional_albedo(brdf.as_ref(), &wo, 256, 1024),
    })
}

/// The repository root as seen from this crate's sources (measured fixtures live under it).
const REPO_ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../");

/// A spec as stored in the table: a measured file under the repository root
/// (`rgl:/…/validation/../data/…`) becomes repository-relative (`rgl:data/…`), so the table
/// does not depend on where the repository is checked out. Other specs are unchanged.
pub fn portable_spec(spec: &str) -> String {
    match spec.split_once(':') {
        Some((model, path)) if model == "rgl" => match path.strip_prefix(REPO_ROOT) {
            Some(rel) => format!("{model}:{rel}"),
            None => spec.to_owned(),
        },
        _ => spec.to_owned(),
    }
}

/// The inverse of [`portable_spec`]: a repository-relative measured spec made loadable from
/// any working directory.
pub fn local_spec(stored: &str) -> String {
    match stored.split_once(':') {
        Some((model, path)) if model == "rgl" && !path.starts_with('/') => {
            format!("{model}:{REPO_ROOT}{path}")
        }
        _ => stored.to_owned(),
    }
}

/// The stored table shipped with the crate.
///
/// # Errors
/// The file does not parse (a packaging error).
pub fn stored_references() -> Result<StoredReferences, serde_json::Error> {
    serde_json::from_str(include_str!("../references/albedo.json"))
}
