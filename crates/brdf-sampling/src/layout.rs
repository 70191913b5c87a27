//! Where the slices of a set sit, and which slice (or pair of slices) serves an outgoing
//! direction.
//!
//! Slice `(j, k)` has the outgoing direction `ωo_jk = (θ_j, φ_k)` with θ at bin centres
//! `θ_j = (j + ½) · (π/2) / nθ` and `φ_k = k · P / nφ` (`nφ = 1`, `φ_0 = 0` for isotropic
//! BRDFs), where the azimuth period `P` is 2π, or π for a half-turn-symmetric BRDF
//! ([`brdf::Brdf::is_half_turn_symmetric`]: the slice of `φo + π` is the slice of `φo` turned
//! by π, so only `[0, π)` is stored). An outgoing direction `ωo = (θo, φo)` is served by the slice with the nearest θ and
//! the nearest φ (circularly); the sampled direction is rotated about the normal by
//! `Δ = φo − φ_k`. For isotropic BRDFs this is the papers' "rotate ωo to φ = 0, sample, rotate
//! back"; for anisotropic ones it keeps the mirror direction of `ωo` exact and errs only in the
//! orientation of the tangent frame (by at most `π/nφ`). The choice depends only on `ωo`, so the
//! pdf of a direction is always evaluated with the slice that sampled it.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use brdf::Vec3;
use serde::{Deserialize, Serialize};

/// The slice grid of a set: `theta × phi` outgoing directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SliceLayout {
    /// θ slices `nθ`.
    pub theta: usize,
    /// φ slices `nφ` (1 for isotropic BRDFs).
    pub phi: usize,
    /// The φ slices cover `[0, π)` instead of `[0, 2π)` (half-turn-symmetric BRDFs).
    pub half_turn: bool,
}

/// A rotation about the normal (the z axis) by an angle `Δ`, held as `(cos Δ, sin Δ)` so that
/// applying it needs no trigonometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turn {
    /// `cos Δ`.
    pub cos: f64,
    /// `sin Δ`.
    pub sin: f64,
}

impl Turn {
    /// No rotation (`Δ = 0`).
    pub const IDENTITY: Turn = Turn { cos: 1.0, sin: 0.0 };

    /// The rotation by `wo`'s azimuth without trigonometry: `(cos φo, sin φo) = (x, y) / r`
    /// for `r = |(wo.x, wo.y)|` (given), the identity at `r = 0` (the normal).
    #[inline]
    pub fn of_azimuth(wo: &Vec3, r: f64) -> Turn {
        if r > 0.0 {
            Turn {
                cos: wo.x / r,
                sin: wo.y / r,
            }
        } else {
            Turn::IDENTITY
        }
    }

    /// The rotation by `angle` radians (counter-clockwise seen from +z).
    pub fn from_angle(angle: f64) -> Turn {
        let (sin, cos) = angle.sin_cos();
        Turn { cos, sin }
    }

    /// The angle `Δ ∈ (−π, π]` (radians).
    pub fn angle(&self) -> f64 {
        self.sin.atan2(self.cos)
    }

    /// `R_z(Δ) v`: from the slice's frame to the world's.
    #[inline]
    pub fn apply(&self, v: &Vec3) -> Vec3 {
        Vec3::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
            v.z,
        )
    }

    /// `R_z(−Δ) v`: from the world's frame to the slice's.
    #[inline]
    pub fn undo(&self, v: &Vec3) -> Vec3 {
        Vec3::new(
            self.cos * v.x + self.sin * v.y,
            self.cos * v.y - self.sin * v.x,
            v.z,
        )
    }
}

/// One slice chosen for an outgoing direction, with its mixture weight and azimuthal rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliceChoice {
    /// Slice index `j · nφ + k`.
    pub index: usize,
    /// Mixture weight (1 for the nearest-slice rule).
    pub weight: f64,
    /// Rotation `Δ = φo − φ_k` applied to samples of this slice.
    pub rotation: Turn,
}

/// A [`SliceLayout`] with the cosines of its θ-slice edges, for the nearest-slice rule without
/// `acos`: θ bin `j` holds `wo` when `cos((j+1)·Δθ) < wo.z ≤ cos(j·Δθ)` (found from a
/// polynomial guess corrected against the edges' cosines), and for isotropic layouts the
/// rotation is `(wo.x, wo.y)/|(wo.x, wo.y)|` — no trigonometry at all. It chooses the slice [`SliceLayout::nearest`] chooses (up to the
/// rounding of an edge's cosine).
#[derive(Debug, Clone, PartialEq)]
pub struct SliceLocator {
    layout: SliceLayout,
    /// `cos((j+1)·(π/2)/nθ)`, `j = 0..nθ−1` (decreasing).
    theta_edges_cos: Vec<f64>,
    /// `nθ / (π/2)`.
    bins_per_radian: f64,
}

impl SliceLocator {
    /// The locator of `layout`.
    pub fn new(layout: SliceLayout) -> Self {
        let theta_edges_cos = (1..layout.theta)
            .map(|j| (j as f64 * FRAC_PI_2 / layout.theta as f64).cos())
            .collect();
        Self {
            layout,
            theta_edges_cos,
            bins_per_radian: layout.theta as f64 / FRAC_PI_2,
        }
    }

    /// The layout.
    pub fn layout(&self) -> SliceLayout {
        self.layout
    }

    /// The slice serving `wo` under the nearest-slice rule (weight 1); `None` when `wo` is at or
    /// below the horizon or not finite.
    #[inline(always)]
    pub fn nearest(&self, wo: &Vec3) -> Option<SliceChoice> {
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite()) || self.layout.is_empty() {
            return None;
        }
        let j = self.theta_bin(wo.z);
        let (k, rotation) = self.layout.azimuth(wo);
        Some(SliceChoice {
            index: j * self.layout.phi + k,
            weight: 1.0,
            rotation,
        })
    }

    /// The θ bin `j` of `cos θo = z`: the number of edges whose cosine is `≥ z`. A first guess
    /// from a polynomial `acos` (Abramowitz & Stegun 4.4.45, error ≤ 6.7·10⁻⁵ rad, well below
    /// a bin) is corrected against the exact edge cosines, so the result is exact whatever the
    /// guess (a binary search's chain of dependent loads costs more than the polynomial).
    #[inline(always)]
    fn theta_bin(&self, z: f64) -> usize {
        let edges = &self.theta_edges_cos;
        let t = 1.0 - z;
        let theta = t.max(0.0).sqrt()
            * (1.570_728_8 + z * (-0.212_114_4 + z * (0.074_261 - z * 0.018_729_3)));
        let guess = theta * self.bins_per_radian;
        let mut j = (guess as usize).min(edges.len());
        while j > 0 && edges[j - 1] < z {
            j -= 1;
        }
        while j < edges.len() && edges[j] >= z {
            j += 1;
        }
        j
    }
}

impl SliceLayout {
    /// Number of slices `nθ · nφ`.
    pub fn len(&self) -> usize {
        self.theta * self.phi
    }

    /// `true` when there are no slices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `θ_j = (j + ½) · (π/2) / nθ` (radians).
    pub fn theta_of(&self, j: usize) -> f64 {
        (j as f64 + 0.5) * FRAC_PI_2 / self.theta as f64
    }

    /// The azimuth period `P` of the φ slices: π for a half-turn layout, else 2π.
    pub fn phi_period(&self) -> f64 {
        if self.half_turn { PI } else { TAU }
    }

    /// `φ_k = k · P / nφ` (radians).
    pub fn phi_of(&self, k: usize) -> f64 {
        k as f64 * self.phi_period() / self.phi as f64
    }

    /// `(θ_j, φ_k)` of slice `index` (radians).
    pub fn angles_of(&self, index: usize) -> (f64, f64) {
        (
            self.theta_of(index / self.phi),
            self.phi_of(index % self.phi),
        )
    }

    /// The outgoing direction of slice `index`.
    pub fn direction_of(&self, index: usize) -> Vec3 {
        let (t, p) = self.angles_of(index);
        brdf::direction_from_radians(t, p)
    }

    /// Polar angle, nearest φ slice and rotation of `wo`; `None` when `wo` is at or below the
    /// horizon or not finite.
    fn polar(&self, wo: &Vec3) -> Option<(f64, usize, Turn)> {
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite()) {
            return None;
        }
        let (k, turn) = self.azimuth(wo);
        Some((wo.z.min(1.0).acos(), k, turn))
    }

    /// The nearest φ slice `k` of `wo` (circularly) and the rotation `Δ = φo − φ_k`. Isotropic
    /// layouts (`nφ = 1`) need no trigonometry: `(cos Δ, sin Δ) = (wo.x, wo.y)/|(wo.x, wo.y)|`
    /// (`Δ = 0` at the normal).
    #[inline(always)]
    fn azimuth(&self, wo: &Vec3) -> (usize, Turn) {
        let r = (wo.x * wo.x + wo.y * wo.y).sqrt();
        let (cos_o, sin_o) = if r > 0.0 {
            (wo.x / r, wo.y / r)
        } else {
            (1.0, 0.0)
        };
        if self.phi <= 1 {
            return (
                0,
                Turn {
                    cos: cos_o,
                    sin: sin_o,
                },
            );
        }
        let phi = sin_o.atan2(cos_o);
        let period = self.phi_period();
        let step = period / self.phi as f64;
        let k = ((phi.rem_euclid(period) / step).round() as usize) % self.phi;
        (k, Turn::from_angle(phi - self.phi_of(k)))
    }

    /// The nearest slice of `wo` (weight 1), or `None` below the horizon.
    pub fn nearest(&self, wo: &Vec3) -> Option<SliceChoice> {
        let (theta, k, rotation) = self.polar(wo)?;
        let j = ((theta / FRAC_PI_2 * self.theta as f64) as usize).min(self.theta - 1);
        Some(SliceChoice {
            index: j * self.phi + k,
            weight: 1.0,
            rotation,
        })
    }

    /// The two θ-neighbouring slices of `wo` with linear weights in θ (`w_a + w_b = 1`); below
    /// the first and above the last slice centre the end slice gets weight 1 (and the second
    /// entry repeats it with weight 0). `None` below the horizon.
    pub fn neighbours(&self, wo: &Vec3) -> Option<[SliceChoice; 2]> {
        let (theta, k, rotation) = self.polar(wo)?;
        let t = theta / FRAC_PI_2 * self.theta as f64 - 0.5;
        let last = self.theta - 1;
        let (ja, jb, wb) = if !(t > 0.0) {
            (0, 0, 0.0)
        } else if t >= last as f64 {
            (last, last, 0.0)
        } else {
            let ja = t.floor() as usize;
            (ja, ja + 1, t - ja as f64)
        };
        Some([
            SliceChoice {
                index: ja * self.phi + k,
                weight: 1.0 - wb,
                rotation,
            },
            SliceChoice {
                index: jb * self.phi + k,
                weight: wb,
                rotation,
            },
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use brdf::direction_from_angles;

    fn layout(theta: usize, phi: usize, half_turn: bool) -> SliceLayout {
        SliceLayout {
            theta,
            phi,
            half_turn,
        }
    }

    #[test]
    fn nearest_slice_and_rotation() {
        let l = layout(90, 1, false);
        let c = l.nearest(&direction_from_angles(30.2, 40.0)).unwrap();
        assert_eq!(c.index, 30);
        assert_relative_eq!(l.theta_of(30).to_degrees(), 30.5, epsilon = 1e-12);
        assert_relative_eq!(c.rotation.angle().to_degrees(), 40.0, epsilon = 1e-9);
        assert_eq!(l.nearest(&Vec3::new(0.0, 0.0, 1.0)).unwrap().index, 0);
        assert_eq!(
            l.nearest(&direction_from_angles(89.999, 0.0))
                .unwrap()
                .index,
            89
        );
        assert!(l.nearest(&Vec3::new(1.0, 0.0, 0.0)).is_none());
        assert!(l.nearest(&Vec3::new(f64::NAN, 0.0, 1.0)).is_none());
    }

    #[test]
    fn anisotropic_nearest_phi_wraps() {
        let l = layout(4, 8, false);
        // φ = 350° is nearest to φ_0 = 0 with Δ = −10°.
        let c = l.nearest(&direction_from_angles(50.0, 350.0)).unwrap();
        assert_eq!(c.index, 2 * 8);
        assert_relative_eq!(c.rotation.angle().to_degrees(), -10.0, epsilon = 1e-9);
        let c = l.nearest(&direction_from_angles(50.0, 100.0)).unwrap();
        assert_eq!(c.index % 8, 2);
        assert_relative_eq!(c.rotation.angle().to_degrees(), 10.0, epsilon = 1e-9);
        let (t, p) = l.angles_of(c.index);
        assert_relative_eq!(t.to_degrees(), 56.25, epsilon = 1e-9);
        assert_relative_eq!(p.to_degrees(), 90.0, epsilon = 1e-9);
    }

    #[test]
    fn half_turn_layout_serves_the_opposite_azimuth_turned_by_pi() {
        let l = layout(4, 4, true);
        // Slices at φ = 0°, 45°, 90°, 135°; φo = 227° is served by 45° turned by 182°, and
        // φo = 350° is nearest to 180° ≡ slice 0, turned by 350°.
        for (phi_o, slice, turn) in [(227.0, 1, 182.0), (350.0, 0, 350.0)] {
            let c = l.nearest(&direction_from_angles(50.0, phi_o)).unwrap();
            assert_eq!(c.index % 4, slice);
            assert_relative_eq!(
                c.rotation.angle().to_degrees().rem_euclid(360.0),
                turn,
                epsilon = 1e-9
            );
        }
        assert_relative_eq!(l.phi_of(3).to_degrees(), 135.0, epsilon = 1e-12);
    }

    #[test]
    fn neighbour_weights_are_linear_in_theta() {
        let l = layout(9, 1, false);
        // Centres at 5°, 15°, …, 85°.
        let [a, b] = l.neighbours(&direction_from_angles(12.5, 0.0)).unwrap();
        assert_eq!((a.index, b.index), (0, 1));
        assert_relative_eq!(a.weight, 0.25, epsilon = 1e-12);
        assert_relative_eq!(b.weight, 0.75, epsilon = 1e-12);
        let [a, b] = l.neighbours(&direction_from_angles(2.0, 0.0)).unwrap();
        assert_eq!((a.index, a.weight, b.weight), (0, 1.0, 0.0));
        let [a, b] = l.neighbours(&direction_from_angles(88.0, 0.0)).unwrap();
        assert_eq!((a.index, a.weight, b.weight), (8, 1.0, 0.0));
    }

    #[test]
    fn the_locator_chooses_the_layouts_nearest_slice_without_trigonometry() {
        for layout in [
            layout(90, 1, false),
            layout(7, 1, false),
            layout(5, 6, false),
            layout(32, 8, true),
        ] {
            let locator = SliceLocator::new(layout);
            for i in 0..5000 {
                let theta = (i as f64 * 0.618_034).fract() * 89.99;
                let phi = (i as f64 * 0.377_1).fract() * 720.0 - 360.0;
                let wo = direction_from_angles(theta, phi);
                let (a, b) = (layout.nearest(&wo).unwrap(), locator.nearest(&wo).unwrap());
                assert_eq!(a.index, b.index, "{layout:?} θ {theta} φ {phi}");
                assert_eq!(b.weight, 1.0);
                assert_relative_eq!(a.rotation.cos, b.rotation.cos, epsilon = 1e-12);
                assert_relative_eq!(a.rotation.sin, b.rotation.sin, epsilon = 1e-12);
                // The rotation takes the slice's φ_k to φo.
                let (_, phi_k) = layout.angles_of(b.index);
                assert_relative_eq!(
                    (phi_k + b.rotation.angle()).rem_euclid(TAU),
                    phi.to_radians().rem_euclid(TAU),
                    epsilon = 1e-9
                );
            }
            assert_eq!(locator.nearest(&Vec3::new(0.0, 0.0, 1.0)).unwrap().index, 0);
            assert!(locator.nearest(&Vec3::new(1.0, 0.0, 0.0)).is_none());
            assert!(locator.nearest(&Vec3::new(f64::NAN, 0.0, 1.0)).is_none());
        }
    }

    #[test]
    fn turns_apply_and_undo() {
        let t = Turn::from_angle(0.7);
        let v = direction_from_angles(33.0, 250.0);
        let w = t.apply(&v);
        assert_relative_eq!(t.undo(&w), v, epsilon = 1e-15);
        assert_relative_eq!(w, brdf::rotate_z(&v, 0.7), epsilon = 1e-15);
        assert_relative_eq!(t.angle(), 0.7, epsilon = 1e-15);
        assert_eq!(Turn::IDENTITY.apply(&v), v);
    }
}
