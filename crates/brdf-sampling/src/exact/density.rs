//! The two densities of an exact-sampler interval, both on the unit disc of the interval's
//! [`DiscMap`]: the query density at one outgoing direction, and the envelope over the
//! interval that the tree is built from.

use std::sync::Arc;

use brdf::{Brdf, Vec3, rotate_z};
use partition_sampler::{Density, Point2};

use crate::disc::{DiscMap, count_evaluations};
use crate::layout::Turn;

/// The disc density of `f_r(ωo, R_rot ·) cos θi` at one outgoing direction:
/// `g(x) = f_r(ωo, R_rot h⁻¹(x))` (projected map) or `2 f_r(ωo, R_rot h_e⁻¹(x)) cos θi`
/// (equal-area map), 0 off the open disc. `R_rot` is the rotation about the normal by `rot`
/// (the tree's frame is the interval's azimuth; isotropic BRDFs use `ωo` at φ = 0 and
/// `rot = 0`). Its integral over the disc is the directional albedo at `ωo`. Every evaluation is
/// counted in [`crate::disc::thread_evaluations`].
#[derive(Clone, Copy)]
pub(crate) struct QueryDensity<'a> {
    brdf: &'a dyn Brdf,
    wo: Vec3,
    /// `(sin, cos)` of `rot`; `None` for no rotation.
    rot: Option<(f64, f64)>,
    map: DiscMap,
}

impl<'a> QueryDensity<'a> {
    /// The density of `brdf` at `wo` in a frame turned by `rot`. An isotropic BRDF is evaluated
    /// at `R_{−rot} ωo` instead (the same value, `f(ωo, R ωi) = f(R⁻¹ωo, ωi)`), which saves
    /// the rotation of every trial point.
    pub(crate) fn new(brdf: &'a dyn Brdf, wo: Vec3, rot: f64, map: DiscMap) -> Self {
        Self::in_frame(brdf, &wo, Turn::from_angle(rot), map)
    }

    /// [`QueryDensity::new`] for the rotation `turn` held as `(cos, sin)`: an isotropic BRDF is
    /// evaluated at `R_{−turn} ωo` (no trigonometry), an anisotropic one rotates the trial
    /// points.
    #[inline]
    pub(crate) fn in_frame(brdf: &'a dyn Brdf, wo: &Vec3, turn: Turn, map: DiscMap) -> Self {
        if turn == Turn::IDENTITY {
            Self {
                brdf,
                wo: *wo,
                rot: None,
                map,
            }
        } else if brdf.is_isotropic() {
            Self {
                brdf,
                wo: turn.undo(wo),
                rot: None,
                map,
            }
        } else {
            Self {
                brdf,
                wo: *wo,
                rot: Some((turn.sin, turn.cos)),
                map,
            }
        }
    }

    #[inline]
    pub(crate) fn at(&self, p: Point2) -> f64 {
        let r2 = p[0] * p[0] + p[1] * p[1];
        if !(r2 < 1.0) {
            return 0.0;
        }
        count_evaluations(1);
        let v = self.map.to_direction(p);
        let wi = match self.rot {
            None => v,
            Some((s, c)) => Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z),
        };
        let f = self.brdf.eval(&self.wo, &wi);
        match self.map {
            DiscMap::Projected => f,
            DiscMap::EqualArea => 2.0 * v.z * f,
        }
    }
}

impl Density for QueryDensity<'_> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        self.at(p)
    }
}

/// The envelope of an interval as a BRDF of the incident direction only:
/// `F(ωi) = max_n f_r(ωo_n, R_{δ_n} ωi)` over the interval's bound nodes
/// `(θ_n, φ_k + δ_n)` (the outgoing argument of [`Brdf::eval`] is ignored). Wrapped in a
/// [`crate::DiscBrdf`] it is the density the interval's tree is built from, with the set's image
/// map, rim band, safety factor and audit.
pub(crate) struct IntervalEnvelope {
    pub(crate) brdf: Arc<dyn Brdf>,
    /// `(ωo_n, δ_n)`.
    pub(crate) nodes: Vec<(Vec3, f64)>,
}

impl Brdf for IntervalEnvelope {
    fn eval(&self, _wo: &Vec3, wi: &Vec3) -> f64 {
        self.nodes.iter().fold(0.0f64, |m, (wo, d)| {
            let w = if *d == 0.0 { *wi } else { rotate_z(wi, *d) };
            m.max(self.brdf.eval(wo, &w))
        })
    }
    fn is_mirror_symmetric(&self) -> bool {
        // Every node lies in the xz-plane (isotropic layouts): the max of even functions of y
        // is even.
        self.brdf.is_mirror_symmetric() && self.nodes.iter().all(|(wo, d)| wo.y == 0.0 && *d == 0.0)
    }
    fn bounded_at_horizon(&self) -> bool {
        self.brdf.bounded_at_horizon()
    }
    fn name(&self) -> &str {
        "interval-envelope"
    }
}
