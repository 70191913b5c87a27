//! The shading configuration of the map estimators: an explicit [`LocalFrame`] and the
//! [`ProductScene`] whose integrand `L(ωi)·f_r(ωo, ωi)·cos⁺θi` every estimator of this crate
//! integrates, and its deterministic quadrature reference.

use baselines::srbf::vmf::orthonormal_basis;
use brdf::{Brdf, Vec3};
use envmap::latlong::direction_to_uv;
use envmap::{EnvMap, luminance};

use crate::EstimatorError;

/// The shading frame: world-space normal `n` and tangents `t`, `b` (right-handed, `t × b = n`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl LocalFrame {
    /// The frame of `normal` (normalised here) whose tangent is the branchless basis's
    /// (Duff et al. 2017) turned by `rotation` radians about the normal.
    ///
    /// Errors: [`EstimatorError::BadNormal`] for a zero-length or non-finite normal.
    pub fn new(normal: [f64; 3], rotation: f64) -> Result<Self, EstimatorError> {
        let v = Vec3::from(normal);
        let len = v.norm();
        if !(len > 0.0 && len.is_finite() && rotation.is_finite()) {
            return Err(EstimatorError::BadNormal {
                x: normal[0],
                y: normal[1],
                z: normal[2],
            });
        }
        let n = v / len;
        let (t0, b0) = orthonormal_basis(&n);
        let (s, c) = rotation.sin_cos();
        Ok(Self {
            t: t0 * c + b0 * s,
            b: b0 * c - t0 * s,
            n,
        })
    }

    /// The world frame itself (`t = x`, `b = y`, `n = z`): local and world directions agree.
    pub fn identity() -> Self {
        Self {
            t: Vec3::new(1.0, 0.0, 0.0),
            b: Vec3::new(0.0, 1.0, 0.0),
            n: Vec3::new(0.0, 0.0, 1.0),
        }
    }

    /// The frame of the given axes (world space): `t`, `b`, `n` must be orthonormal and
    /// right-handed (`t × b = n`) to within 1e-9.
    ///
    /// Errors: [`EstimatorError::NotOrthonormal`] otherwise (or for a non-finite component).
    pub fn from_axes(t: Vec3, b: Vec3, n: Vec3) -> Result<Self, EstimatorError> {
        let tol = 1e-9;
        let ok = (t.norm() - 1.0).abs() < tol
            && (b.norm() - 1.0).abs() < tol
            && (n.norm() - 1.0).abs() < tol
            && t.dot(&b).abs() < tol
            && (t.cross(&b) - n).norm() < tol;
        if !ok {
            return Err(EstimatorError::NotOrthonormal);
        }
        Ok(Self { t, b, n })
    }

    /// A world direction in local coordinates (`z` along the normal).
    pub fn to_local(&self, w: &Vec3) -> Vec3 {
        Vec3::new(w.dot(&self.t), w.dot(&self.b), w.dot(&self.n))
    }

    /// A local direction in world coordinates.
    pub fn to_world(&self, l: &Vec3) -> Vec3 {
        self.t * l.x + self.b * l.y + self.n * l.z
    }
}

/// One shading configuration: BRDF, map, frame and the local outgoing direction.
#[derive(Clone, Copy)]
pub struct ProductScene<'a> {
    /// The BRDF (luminance `eval`).
    pub brdf: &'a dyn Brdf,
    /// The world-space environment map.
    pub map: &'a EnvMap,
    /// The shading frame.
    pub frame: LocalFrame,
    /// The outgoing direction in the local frame (unit, `z > 0`).
    pub wo: Vec3,
}

impl std::fmt::Debug for ProductScene<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProductScene")
            .field("brdf", &self.brdf.name())
            .field("frame", &self.frame)
            .field("wo", &self.wo)
            .finish_non_exhaustive()
    }
}

impl<'a> ProductScene<'a> {
    /// A scene; `wo` is normalised and must be above the local horizon.
    pub fn new(
        brdf: &'a dyn Brdf,
        map: &'a EnvMap,
        frame: LocalFrame,
        wo: Vec3,
    ) -> Result<Self, EstimatorError> {
        let wo = wo.normalize();
        if !(wo.z > 0.0) {
            return Err(EstimatorError::BelowHorizon { cos_theta: wo.z });
        }
        Ok(Self {
            brdf,
            map,
            frame,
            wo,
        })
    }

    /// Luminance radiance arriving from the local direction `wi`.
    pub fn radiance(&self, wi: &Vec3) -> f64 {
        let w = self.frame.to_world(wi);
        let (u, v) = direction_to_uv([w.x, w.y, w.z]);
        luminance(self.map.radiance_uv(u, v))
    }

    /// [`Self::integrand`] with `f = f_r(ωo, ωi)` already known (a batch sample's `f`).
    pub fn integrand_with_f(&self, wi: &Vec3, f: f64) -> f64 {
        if !(wi.z > 0.0) || f == 0.0 {
            return 0.0;
        }
        self.radiance(wi) * f * wi.z
    }

    /// The integrand `L(ωi)·f_r(ωo, ωi)·cos⁺θi` at the local direction `wi` (0 below the horizon).
    pub fn integrand(&self, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let f = self.brdf.eval(&self.wo, wi);
        if f == 0.0 {
            0.0
        } else {
            self.radiance(wi) * f * wi.z
        }
    }
}

/// A deterministic reference for `L_r(ωo)`: the map's pixels in world space, each split into
/// `sub × sub` cells of equal `Δu`, `Δv`, midpoint rule with each cell's exact solid angle
/// `2π Δu (cos πv₀ − cos πv₁)`, the integrand [`ProductScene::integrand`] at the cell's centre
/// (radiance is constant per pixel, so only `f_r·cos⁺θ` is approximated). Returns the value at
/// `2·sub` and `|Q(2·sub) − Q(sub)|` as its error estimate (the midpoint rule converges as
/// `sub⁻²`, so the difference bounds the finer value's error by a factor ~3 for a smooth
/// integrand). Rows are summed in parallel and combined in row order (reproducible). Cost:
/// `5·w·h·sub²` integrand evaluations.
pub fn quadrature_reference(scene: &ProductScene<'_>, sub: usize) -> (f64, f64) {
    let fine = pixel_quadrature(scene, 2 * sub.max(1));
    let coarse = pixel_quadrature(scene, sub.max(1));
    (fine, (fine - coarse).abs())
}

fn pixel_quadrature(scene: &ProductScene<'_>, s: usize) -> f64 {
    use rayon::prelude::*;
    let (w, h) = (scene.map.width(), scene.map.height());
    let (ws, hs) = (w * s, h * s);
    let du = 1.0 / ws as f64;
    let rows: Vec<f64> = (0..hs)
        .into_par_iter()
        .map(|j| {
            let (v0, v1) = (j as f64 / hs as f64, (j + 1) as f64 / hs as f64);
            let area = std::f64::consts::TAU
                * du
                * ((std::f64::consts::PI * v0).cos() - (std::f64::consts::PI * v1).cos());
            let v = 0.5 * (v0 + v1);
            (0..ws)
                .map(|i| {
                    let d = envmap::latlong::uv_to_direction((i as f64 + 0.5) * du, v);
                    let wi = scene.frame.to_local(&Vec3::new(d[0], d[1], d[2]));
                    scene.integrand(&wi)
                })
                .sum::<f64>()
                * area
        })
        .collect();
    rows.iter().sum()
}

/// One estimator's result.
///
/// Besides the estimate and its standard error it says whether that standard error can be
/// trusted. Each estimator's variance estimate is a weighted sum of per-technique sample
/// variances, `V̂ = Σ_t a_t s²_t` (`a_t = 1/n_t` for one-sample and MIS techniques, `a_t = n_t`
/// for the product estimator's components, whose sum is not divided by the count).
/// * [`Self::tail_share`] — the largest share of `V̂` held by one sample's term
///   `a_t (y − ȳ_t)² / (n_t − 1)`: a heavy tail shows as one rare large value dominating.
/// * [`Self::variance_rel_ci95`] — the relative half-width of `V̂`'s 95 % interval,
///   `1.96 √(Σ_t a_t² (m₄,t − m₂,t²)/n_t) / V̂` (`m₂`, `m₄` the central moments): the
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_rejects_zero_normal() {
        let f = LocalFrame::new([0.2, -0.3, 0.9], 0.7).unwrap();
        let v = Vec3::new(0.3, 0.5, -0.2);
        assert!((f.to_world(&f.to_local(&v)) - v).norm() < 1e-12);
        assert!((f.to_world(&Vec3::z()) - Vec3::new(0.2, -0.3, 0.9).normalize()).norm() < 1e-12);
        assert!(matches!(
            LocalFrame::new([0.0; 3], 0.0),
            Err(EstimatorError::BadNormal { .. })
        ));
        assert!(matches!(
            LocalFrame::new([f64::NAN, 0.0, 1.0], 0.0),
            Err(EstimatorError::BadNormal { .. })
        ));
    }
}
