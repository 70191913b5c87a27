//! The disc parametrisation of the hemisphere and the BRDF density on it.
//!
//! `h(v) = (v.x, v.y)` maps the upper hemisphere Ω onto the unit disc D; its inverse is
//! `h⁻¹(x, y) = (x, y, √(1 − x² − y²))`. Area on D equals projected solid angle on Ω,
//! `dx dy = cos θ dσ`, so a density on D proportional to `f_r(ωo, h⁻¹(x))` is proportional to
//! `f_r cos θ` with respect to solid angle, and the sampler never evaluates the cosine.
//!
//! That density is `f_r` itself, so it is unbounded for models with `1/cos θi`-type factors
//! ([`brdf::Brdf::bounded_at_horizon`] is `false`), and near the rim the map squeezes θ without
//! bound (`dθ/dr = 1/cos θ`). [`DiscMap::EqualArea`] is the alternative for such slices: the
//! Lambert azimuthal equal-area map `h_e(v) = (v.x, v.y)/√(1 + v.z)`, inverse
//! `h_e⁻¹(x, y) = (x √(2 − r²), y √(2 − r²), 1 − r²)` with `r² = x² + y²`, for which
//! `dσ = 2 dx dy`. Its density `2 f_r cos θi` keeps the cosine (bounded whenever `f_r cos θi`
//! is) and integrates to the same directional albedo as the projected one.

use std::cell::Cell;
use std::sync::Arc;

use brdf::{Brdf, Outgoing, Vec3};
use partition_sampler::{
    Density, DensityShape, Domain, IntegralSource, Point2, Rect, RegionEstimate, RegionStats,
};
use serde::{Deserialize, Serialize};

/// How a slice maps the upper hemisphere onto the unit disc.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DiscMap {
    /// `h(v) = (v.x, v.y)` (design.md §2, the papers' map): `dx dy = cos θ dσ`, density `f_r`.
    #[default]
    Projected,
    /// Lambert azimuthal equal-area map `h_e(v) = (v.x, v.y)/√(1 + v.z)`: `dx dy = dσ / 2`,
    /// density `2 f_r cos θi`.
    EqualArea,
}

impl DiscMap {
    /// Short name (`"projected"`, `"equal-area"`).
    pub fn name(self) -> &'static str {
        match self {
            DiscMap::Projected => "projected",
            DiscMap::EqualArea => "equal-area",
        }
    }

    /// The disc point of a direction (meaningful for `v.z ≥ 0`).
    #[inline]
    pub fn to_disc(self, v: &Vec3) -> Point2 {
        match self {
            DiscMap::Projected => [v.x, v.y],
            DiscMap::EqualArea => {
                let s = 1.0 / (1.0 + v.z.max(0.0)).sqrt();
                [v.x * s, v.y * s]
            }
        }
    }

    /// The direction of a disc point (`z = 0` on and outside the circle).
    #[inline]
    pub fn to_direction(self, p: Point2) -> Vec3 {
        match self {
            DiscMap::Projected => disc_to_direction(p),
            DiscMap::EqualArea => {
                let r2 = (p[0] * p[0] + p[1] * p[1]).min(1.0);
                let s = (2.0 - r2).sqrt();
                Vec3::new(p[0] * s, p[1] * s, 1.0 - r2)
            }
        }
    }

    /// `dσ / dA` at a direction above the horizon: `1/cos θ` (projected) or 2 (equal-area).
    /// Converts a density w.r.t. area on the disc at `to_disc(ωi)` into one w.r.t. solid angle:
    /// `p_σ = p_A · dA/dσ` (0 at or below the horizon).
    #[inline]
    pub fn area_to_solid_angle(self, pdf_area: f64, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        match self {
            DiscMap::Projected => pdf_area * wi.z,
            DiscMap::EqualArea => pdf_area * 0.5,
        }
    }

    /// Inverse of [`DiscMap::area_to_solid_angle`] (0 at or below the horizon).
    #[inline]
    pub fn solid_angle_to_area(self, pdf_sa: f64, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        match self {
            DiscMap::Projected => pdf_sa / wi.z,
            DiscMap::EqualArea => pdf_sa * 2.0,
        }
    }
}

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

/// Adds `n` to the calling thread's [`thread_evaluations`] (for densities evaluated outside
/// [`DiscBrdf`], e.g. the exact sampler's query density).
#[inline]
pub(crate) fn count_evaluations(n: u64) {
    EVALUATIONS.with(|c| c.set(c.get() + n));
}

/// The density of `f_r(ωo, ·) cos θi` on the unit disc for one fixed outgoing direction,
/// under a [`DiscMap`]: `x ↦ f_r(ωo, h⁻¹(x))` (projected) or `x ↦ 2 f_r(ωo, h_e⁻¹(x)) cos θi`
/// (equal-area); 0 outside the disc and on its boundary circle (the horizon).
///
/// Either way its integral over the disc is the directional albedo `∫ f_r cos θi dσ`. Every
/// call inside the disc increments the calling thread's [`thread_evaluations`] counter.
///
/// A **zero floor** `c ≥ 0` ([`DiscBrdf::with_zero_floor`], 0 by default) replaces the value
/// wherever it is exactly 0 inside the disc: the density is then `g(x) = f(x)` where `f(x) ≠ 0`
/// and `g(x) = c` where `f(x) = 0`, so a sampler proportional to `g` is positive on the whole
/// open disc (see [`crate::SUPPORT_FLOOR`] for why the sets use it).
#[derive(Clone)]
pub struct DiscBrdf {
    brdf: Arc<dyn Brdf>,
    /// `ωo` as the BRDF prepared it ([`Brdf::prepare`]).
    wo: Outgoing,
    map: DiscMap,
    zero_floor: f64,
    /// `brdf` at `wo` as a function of the incident direction, evaluated in blocks (see
    /// [`DiscBrdf::with_blocks`]).
    blocks: Option<Arc<dyn DirectionBlock>>,
}

/// A function of the incident direction alone that evaluates many directions at once: an
/// `adaptive-exact` interval's envelope `F(ωi) = max_n f_r(ωo_n, R_{δ_n} ωi)`.
pub(crate) trait DirectionBlock: Send + Sync {
    /// `out[k] = F(wi[k])` for `k < min(wi.len(), out.len())`.
    fn eval_directions(&self, wi: &[Vec3], out: &mut [f64]);
}

/// Directions per [`DirectionBlock::eval_directions`] call of [`DiscBrdf`]'s `eval_block`.
pub(crate) const DIRECTION_BLOCK: usize = 64;

impl std::fmt::Debug for DiscBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DiscBrdf")
            .field("brdf", &self.brdf.name())
            .field("wo", self.wo.wo())
            .field("map", &self.map)
            .field("zero_floor", &self.zero_floor)
            .finish()
    }
}

impl DiscBrdf {
    /// The projected-disc density of `brdf` for the outgoing direction `wo` (unit, `wo.z > 0`).
    pub fn new(brdf: Arc<dyn Brdf>, wo: Vec3) -> Self {
        Self::with_map(brdf, wo, DiscMap::Projected)
    }

    /// The density of `brdf` for `wo` under `map`.
    pub fn with_map(brdf: Arc<dyn Brdf>, wo: Vec3, map: DiscMap) -> Self {
        Self {
            wo: brdf.prepare(&wo),
            brdf,
            map,
            zero_floor: 0.0,
            blocks: None,
        }
    }

    /// The same density, its block evaluation through `blocks`, which must be
    /// `brdf.eval_prepared(wo, ·)` bit for bit (an interval's envelope built as its own
    /// `Brdf`).
    pub(crate) fn with_blocks(mut self, blocks: Arc<dyn DirectionBlock>) -> Self {
        self.blocks = Some(blocks);
        self
    }

    /// The same density with the value `floor` wherever it is exactly 0 inside the disc (see the
    /// type's docs). A negative or non-finite `floor` is taken as 0.
    pub fn with_zero_floor(mut self, floor: f64) -> Self {
        self.zero_floor = if floor.is_finite() && floor > 0.0 {
            floor
        } else {
            0.0
        };
        self
    }

    /// The zero floor `c` (0 when none).
    pub fn zero_floor(&self) -> f64 {
        self.zero_floor
    }

    /// The hemisphere-to-disc map.
    pub fn map(&self) -> DiscMap {
        self.map
    }

    /// The outgoing direction.
    pub fn wo(&self) -> &Vec3 {
        self.wo.wo()
    }

    /// The BRDF.
    pub fn brdf(&self) -> &Arc<dyn Brdf> {
        &self.brdf
    }
}

impl Density for DiscBrdf {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        let r2 = p[0] * p[0] + p[1] * p[1];
        if !(r2 < 1.0) {
            return 0.0;
        }
        EVALUATIONS.with(|c| c.set(c.get() + 1));
        let v = match self.map {
            DiscMap::Projected => {
                let wi = Vec3::new(p[0], p[1], (1.0 - r2).sqrt());
                self.brdf.eval_prepared(&self.wo, &wi)
            }
            DiscMap::EqualArea => {
                let s = (2.0 - r2).sqrt();
                let z = 1.0 - r2;
                let wi = Vec3::new(p[0] * s, p[1] * s, z);
                2.0 * z * self.brdf.eval_prepared(&self.wo, &wi)
            }
        };
        if v == 0.0 { self.zero_floor } else { v }
    }

    /// [`Density::eval`] of every point, bit for bit. With a [`DirectionBlock`] (an
    /// `adaptive-exact` interval's envelope, whose nodes' misses are then evaluated together —
    /// RGL: in vector lanes, `exact/density.rs`) in blocks of [`DIRECTION_BLOCK`]; else one
    /// point at a time.
    fn eval_block(&self, points: &[Point2], out: &mut [f64]) {
        let Some(blocks) = &self.blocks else {
            for (o, &p) in out.iter_mut().zip(points) {
                *o = self.eval(p);
            }
            return;
        };
        let mut wi = [Vec3::new(0.0, 0.0, 0.0); DIRECTION_BLOCK];
        let mut slot = [0usize; DIRECTION_BLOCK];
        let mut f = [0.0f64; DIRECTION_BLOCK];
        for (points, out) in points
            .chunks(DIRECTION_BLOCK)
            .zip(out.chunks_mut(DIRECTION_BLOCK))
        {
            let mut m = 0;
            for (k, (p, o)) in points.iter().zip(out.iter_mut()).enumerate() {
                let r2 = p[0] * p[0] + p[1] * p[1];
                *o = 0.0;
                if !(r2 < 1.0) {
                    continue;
                }
                wi[m] = match self.map {
                    DiscMap::Projected => Vec3::new(p[0], p[1], (1.0 - r2).sqrt()),
                    DiscMap::EqualArea => {
                        let s = (2.0 - r2).sqrt();
                        Vec3::new(p[0] * s, p[1] * s, 1.0 - r2)
                    }
                };
                slot[m] = k;
                m += 1;
            }
            EVALUATIONS.with(|c| c.set(c.get() + m as u64));
            blocks.eval_directions(&wi[..m], &mut f[..m]);
            for (j, &k) in slot[..m].iter().enumerate() {
                let v = match self.map {
                    DiscMap::Projected => f[j],
                    DiscMap::EqualArea => 2.0 * wi[j].z * f[j],
                };
                out[k] = if v == 0.0 { self.zero_floor } else { v };
            }
        }
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
    /// The disc density of the slice (see [`DiscBrdf`]).
    pub fn disc_brdf(&self) -> &DiscBrdf {
        &self.f
    }

    /// The slice's hemisphere-to-disc map.
    pub fn map(&self) -> DiscMap {
        self.f.map
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
    fn equal_area_map_round_trips_and_preserves_area() {
        let m = DiscMap::EqualArea;
        for (t, p) in [(0.0, 0.0), (40.0, 120.0), (85.0, 300.0), (89.99, 10.0)] {
            let v = brdf::direction_from_angles(t, p);
            let d = m.to_disc(&v);
            assert_relative_eq!(m.to_direction(d), v, epsilon = 1e-12);
            // r² = 1 − cos θ.
            assert_relative_eq!(d[0] * d[0] + d[1] * d[1], 1.0 - v.z, epsilon = 1e-12);
        }
        // dσ = 2 dA: the solid angle of the cap θ ≤ 60° (2π(1 − cos 60°) = π) is twice the
        // area of its disc image (radius² = 1 − cos 60° = ½, area π/2).
        let cap = brdf::direction_from_angles(60.0, 0.0);
        let r2 = m.to_disc(&cap)[0].powi(2);
        assert_relative_eq!(
            2.0 * std::f64::consts::PI * r2,
            std::f64::consts::PI,
            epsilon = 1e-12
        );
        let v = brdf::direction_from_angles(30.0, 0.0);
        assert_relative_eq!(m.area_to_solid_angle(3.0, &v), 1.5);
        assert_relative_eq!(m.solid_angle_to_area(1.5, &v), 3.0);
        assert_eq!(m.area_to_solid_angle(3.0, &Vec3::new(1.0, 0.0, 0.0)), 0.0);
    }

    #[test]
    fn both_maps_integrate_to_the_albedo() {
        // Midpoint rule over the disc: ∫ density dA = ∫ f cos dσ for both maps (Lambert ρ).
        let b: Arc<dyn Brdf> = Arc::from(brdf::parse_spec("lambert:rho=0.5").unwrap());
        let wo = brdf::direction_from_angles(20.0, 0.0);
        for map in [DiscMap::Projected, DiscMap::EqualArea] {
            let d = DiscBrdf::with_map(b.clone(), wo, map);
            let n = 1000;
            let h = 2.0 / n as f64;
            let mut s = 0.0;
            for j in 0..n {
                for i in 0..n {
                    s += d.eval([-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h]);
                }
            }
            assert_relative_eq!(s * h * h, 0.5, max_relative = 2e-3);
        }
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
