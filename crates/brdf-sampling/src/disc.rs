//! The disc parametrisation of the hemisphere and the BRDF density on it.
//!
//! `h(v) = (v.x, v.y)` maps the upper hemisphere Ω onto the unit disc D; its inverse is
//! `h⁻¹(x, y) = (x, y, √(1 − x² − y²))`. Area on D equals projected solid angle on Ω,
//! `dx dy = cos θ dσ`, so a density on D proportional to `f_r(ωo, h⁻¹(x))` is proportional to
//! `f_r cos θ` with respect to solid angle, and the sampler never evaluates the cosine.

use std::cell::Cell;
use std::sync::Arc;

use brdf::{Brdf, Vec3};
use partition_sampler::{
    Density, DensityShape, Domain, IntegralSource, Point2, Rect, RegionEstimate, RegionStats,
};

/// `h(v) = (v.x, v.y)`: the disc point of a direction (meaningful for `v.z ≥ 0`).
#[inline]
pub fn direction_to_disc(v: &Vec3) -> Point2 {
    [v.x, v.y]
}

/// `h⁻¹(x, y) = (x, y, √(1 − x² − y²))`, with `z = 0` on and outside the circle.
#[inline]
pub fn disc_to_direction(p: Point2) -> Vec3 {
    let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
    Vec3::new(p[0], p[1], if z2 > 0.0 { z2.sqrt() } else { 0.0 })
}

/// Converts a density with respect to area on the disc at `h(ωi)` into one with respect to solid
/// angle at `ωi`: `p_σ(ωi) = p_A(h(ωi)) · cos θi` (0 at or below the horizon).
#[inline]
pub fn area_pdf_to_solid_angle(pdf_area: f64, wi: &Vec3) -> f64 {
    if wi.z > 0.0 { pdf_area * wi.z } else { 0.0 }
}

/// Converts a density with respect to solid angle at `ωi` into one with respect to area on the
/// disc: `p_A = p_σ / cos θi` (0 at or below the horizon).
#[inline]
pub fn solid_angle_pdf_to_area(pdf_sa: f64, wi: &Vec3) -> f64 {
    if wi.z > 0.0 { pdf_sa / wi.z } else { 0.0 }
}

thread_local! {
    /// BRDF evaluations made through [`DiscBrdf`] on this thread (read by cost measurements).
    static EVALUATIONS: Cell<u64> = const { Cell::new(0) };
}

/// BRDF evaluations made through [`DiscBrdf::eval`] on the calling thread so far (a
/// monotone counter; differences measure the cost of a sequential run).
pub fn thread_evaluations() -> u64 {
    EVALUATIONS.with(Cell::get)
}

/// The density `x ↦ f_r(ωo, h⁻¹(x))` on the unit disc for one fixed outgoing direction
/// (0 outside the disc and on its boundary circle, where `h⁻¹(x)` is on the horizon).
///
/// With respect to area on the disc this is proportional to `f_r · cos θi` with respect to
/// solid angle. Every call increments the calling thread's [`thread_evaluations`] counter.
#[derive(Clone)]
pub struct DiscBrdf {
    brdf: Arc<dyn Brdf>,
    wo: Vec3,
}

impl std::fmt::Debug for DiscBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DiscBrdf")
            .field("brdf", &self.brdf.name())
            .field("wo", &self.wo)
            .finish()
    }
}

impl DiscBrdf {
    /// The density of `brdf` for the outgoing direction `wo` (unit, `wo.z > 0`).
    pub fn new(brdf: Arc<dyn Brdf>, wo: Vec3) -> Self {
        Self { brdf, wo }
    }

    /// The outgoing direction.
    pub fn wo(&self) -> &Vec3 {
        &self.wo
    }

    /// The BRDF.
    pub fn brdf(&self) -> &Arc<dyn Brdf> {
        &self.brdf
    }
}

impl Density for DiscBrdf {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
        if !(z2 > 0.0) {
            return 0.0;
        }
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        let wi = Vec3::new(p[0], p[1], z2.sqrt());
        self.brdf.eval(&self.wo, &wi)
    }
}

/// The density a built (or loaded) slice tree is attached to: [`DiscBrdf`] plus the shape of
/// the grid the tree was built from. It evaluates pointwise only; region queries return an
/// infinite bound, so it can never be used to build a tree (that needs the grid).
#[derive(Clone, Debug)]
pub struct SliceDensity {
    pub(crate) f: DiscBrdf,
    pub(crate) shape: DensityShape,
}

impl SliceDensity {
    /// The disc density `x ↦ f_r(ωo_slice, h⁻¹(x))`.
    pub fn disc_brdf(&self) -> &DiscBrdf {
        &self.f
    }
}

impl Density for SliceDensity {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.f.eval(p)
    }
}

impl RegionStats for SliceDensity {
    fn domain(&self) -> Domain {
        Domain::UnitDisc
    }
    fn region(&self, _cell: &Rect) -> RegionEstimate {
        RegionEstimate {
            max_bound: f64::INFINITY,
            integral: 0.0,
            integral_rel_err: None,
        }
    }
    fn integral_source(&self) -> IntegralSource {
        IntegralSource::GridEstimate
    }
    fn shape(&self) -> DensityShape {
        self.shape
    }
    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn round_trip_and_conversions() {
        let v = brdf::direction_from_angles(40.0, 120.0);
        let p = direction_to_disc(&v);
        assert_relative_eq!(disc_to_direction(p), v, epsilon = 1e-15);
        assert_relative_eq!(area_pdf_to_solid_angle(2.0, &v), 2.0 * v.z);
        assert_relative_eq!(
            solid_angle_pdf_to_area(area_pdf_to_solid_angle(2.0, &v), &v),
            2.0
        );
        assert_eq!(area_pdf_to_solid_angle(2.0, &Vec3::new(1.0, 0.0, 0.0)), 0.0);
        assert_eq!(disc_to_direction([1.0, 1.0]).z, 0.0);
    }

    #[test]
    fn disc_density_is_brdf_and_zero_outside() {
        let b: Arc<dyn Brdf> = Arc::from(brdf::parse_spec("phong:n=20").unwrap());
        let wo = brdf::direction_from_angles(30.0, 0.0);
        let d = DiscBrdf::new(b.clone(), wo);
        let wi = brdf::direction_from_angles(25.0, 170.0);
        let before = thread_evaluations();
        assert_relative_eq!(
            d.eval(direction_to_disc(&wi)),
            b.eval(&wo, &wi),
            max_relative = 1e-12
        );
        assert_eq!(thread_evaluations(), before + 1);
        assert_eq!(d.eval([0.8, 0.8]), 0.0);
        assert_eq!(d.eval([f64::NAN, 0.0]), 0.0);
    }
}
