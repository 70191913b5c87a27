//! The tables' cells: outgoing cells (rows), the `(θp, φp)` cells of the reparametrised
//! direction (columns), and the half-angle / spherical maps between `ωp` and `ωi`.

use std::f64::consts::{FRAC_PI_2, TAU};

use brdf::Vec3;

use crate::options::Reparam;

/// `n` bands uniform in `θ` over `[0, π/2]`, with the cosines of their edges
/// (`cos θ_0 = 1 > … > cos θ_n = 0`) and their solid angles per unit azimuth
/// `Ω_a = cos θ_a − cos θ_{a+1}`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ThetaBands {
    pub(crate) cos_edges: Vec<f64>,
    pub(crate) measure: Vec<f64>,
}

impl ThetaBands {
    pub(crate) fn new(n: usize) -> Self {
        let cos_edges: Vec<f64> = (0..=n)
            .map(|a| {
                if a == n {
                    0.0
                } else {
                    (FRAC_PI_2 * a as f64 / n as f64).cos()
                }
            })
            .collect();
        let measure = cos_edges.windows(2).map(|e| e[0] - e[1]).collect();
        Self { cos_edges, measure }
    }

    pub(crate) fn len(&self) -> usize {
        self.measure.len()
    }

    /// Polar angle of the middle of band `a`.
    pub(crate) fn centre(&self, a: usize) -> f64 {
        FRAC_PI_2 * (a as f64 + 0.5) / self.len() as f64
    }

    /// The band holding `cos θ = z` (`cos θ_{a+1} ≤ z ≤ cos θ_a`, clamped to `[0, 1]`).
    pub(crate) fn band_of(&self, z: f64) -> usize {
        // cos_edges is decreasing: count the inner edges strictly above z.
        let inner = &self.cos_edges[1..self.len()];
        inner.partition_point(|&c| c > z)
    }
}

/// `n` azimuth bins of width `Δφ = 2π/n` over `[0, 2π)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PhiBins {
    pub(crate) n: usize,
    pub(crate) width: f64,
}

impl PhiBins {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            width: TAU / n as f64,
        }
    }

    pub(crate) fn centre(&self, b: usize) -> f64 {
        (b as f64 + 0.5) * self.width
    }

    /// The bin of azimuth `phi` (any real; wrapped into `[0, 2π)`).
    pub(crate) fn bin_of(&self, phi: f64) -> usize {
        let t = phi.rem_euclid(TAU) / self.width;
        (t as usize).min(self.n - 1)
    }
}

/// The rows: outgoing cells `θo × φo` (uniform in `θo` over `[0, π/2]` and `φo` over
/// `[0, 2π)`), or `θo` only with the frame rotated by `φo` (isotropic BRDFs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OutgoingCells {
    pub(crate) n_theta: usize,
    pub(crate) phi: PhiBins,
    pub(crate) theta_only: bool,
}

impl OutgoingCells {
    pub(crate) fn rows(&self) -> usize {
        if self.theta_only {
            self.n_theta
        } else {
            self.n_theta * self.phi.n
        }
    }

    /// The row of `wo` (nearest cell, the same lookup for `sample` and `pdf`) and the turn
    /// about the normal of the row's frame (by `φo` in the θo-only variant, else none).
    pub(crate) fn cell(&self, wo: &Vec3) -> (usize, Turn) {
        let theta = wo.z.clamp(-1.0, 1.0).acos();
        let t = ((theta / FRAC_PI_2) * self.n_theta as f64) as usize;
        let it = t.min(self.n_theta - 1);
        if self.theta_only {
            (it, Turn::to_azimuth_of(wo))
        } else {
            let phi = wo.y.atan2(wo.x);
            (it * self.phi.n + self.phi.bin_of(phi), Turn::NONE)
        }
    }

    /// The centre direction of `row`, in the row's frame.
    pub(crate) fn centre(&self, row: usize) -> Vec3 {
        let (it, phi) = if self.theta_only {
            (row, 0.0)
        } else {
            (row / self.phi.n, self.phi.centre(row % self.phi.n))
        };
        let theta = FRAC_PI_2 * (it as f64 + 0.5) / self.n_theta as f64;
        direction(theta.cos(), phi)
    }
}

/// The unit vector with `cos θ = z` and azimuth `phi`.
pub(crate) fn direction(z: f64, phi: f64) -> Vec3 {
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = phi.sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// `ωi` of the reparametrised direction `wp` (upper hemisphere) given `wo`: `wp` itself
/// (spherical) or the reflection of `wo` about `wp = ωh`, `2(ωo·ωh)ωh − ωo` (half-angle).
pub(crate) fn incoming(reparam: Reparam, wo: &Vec3, wp: &Vec3) -> Vec3 {
    match reparam {
        Reparam::Spherical => *wp,
        Reparam::HalfAngle => (2.0 * wo.dot(wp) * wp - wo).normalize(),
    }
}

/// The reparametrised direction of `wi` (upper hemisphere) and the Jacobian
/// `|dωp/dωi|`, or `None` where the factored density is zero.
///
/// Half-angle: `ωh = normalize(ωi + ωo)`, flipped to the upper hemisphere. The map
/// `ωh ↦ 2(ωo·ωh)ωh − ωo` is one-to-one from the upper hemisphere of `ωh` onto the sphere
/// (up to null sets): `ωh` with `ωo·ωh > 0` gives the `ωi` whose half vector is `ωh`,
/// `ωo·ωh < 0` gives the (below-horizon) `ωi` whose half vector is `−ωh`; either way
/// `|dωh/dωi| = 1/(4|ωi·ωh|)`. So the density below the horizon is the density of the
/// samples that land there, and the pdf integrates to 1 over the sphere.
/// Spherical: `ωp = ωi`, Jacobian 1, zero below the horizon.
pub(crate) fn reparametrised(reparam: Reparam, wo: &Vec3, wi: &Vec3) -> Option<(Vec3, f64)> {
    match reparam {
        Reparam::Spherical => (wi.z > 0.0).then_some((*wi, 1.0)),
        Reparam::HalfAngle => {
            let s = wo + wi;
            let norm = s.norm();
            if !(norm > 1e-12) {
                return None;
            }
            let mut h = s / norm;
            if h.z < 0.0 {
                h = -h;
            }
            let c = wi.dot(&h).abs();
            (c > 0.0).then(|| (h, 1.0 / (4.0 * c)))
        }
    }
}

/// A turn about the normal by the angle with cosine `c` and sine `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Turn {
    c: f64,
    s: f64,
}

impl Turn {
    /// No turn.
    pub(crate) const NONE: Turn = Turn { c: 1.0, s: 0.0 };

    /// The turn by the azimuth of `v` (none when `v` is on the normal).
    pub(crate) fn to_azimuth_of(v: &Vec3) -> Turn {
        let r = v.x.hypot(v.y);
        if r > 0.0 {
            Turn {
                c: v.x / r,
                s: v.y / r,
            }
        } else {
            Turn::NONE
        }
    }

    /// The angle of the turn, in `(−π, π]`.
    pub(crate) fn angle(&self) -> f64 {
        self.s.atan2(self.c)
    }

    /// `v` in the turned frame (rotated by minus the angle).
    pub(crate) fn local_to_row(&self, v: &Vec3) -> Vec3 {
        Vec3::new(
            self.c * v.x + self.s * v.y,
            -self.s * v.x + self.c * v.y,
            v.z,
        )
    }

    /// `v` from the turned frame back to the local frame.
    pub(crate) fn row_to_local(&self, v: &Vec3) -> Vec3 {
        Vec3::new(
            self.c * v.x - self.s * v.y,
            self.s * v.x + self.c * v.y,
            v.z,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_measures_sum_to_one_and_lookup_inverts_edges() {
        let bands = ThetaBands::new(7);
        assert!((bands.measure.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for a in 0..7 {
            let z = bands.centre(a).cos();
            assert_eq!(bands.band_of(z), a);
        }
        assert_eq!(bands.band_of(1.0), 0);
        assert_eq!(bands.band_of(0.0), 6);
        let phi = PhiBins::new(8);
        assert_eq!(phi.bin_of(-1e-9), 7);
        assert_eq!(phi.bin_of(phi.centre(3)), 3);
    }

    #[test]
    fn half_angle_round_trip_and_jacobian() {
        let wo = direction(0.4, 0.3);
        for (z, phi) in [(0.9, 0.1), (0.2, 2.0), (0.05, 4.0)] {
            let h = direction(z, phi);
            let wi = incoming(Reparam::HalfAngle, &wo, &h);
            let (back, jac) = reparametrised(Reparam::HalfAngle, &wo, &wi).unwrap();
            assert!((back - h).norm() < 1e-12, "{back} {h}");
            assert!((jac - 1.0 / (4.0 * wo.dot(&h).abs())).abs() < 1e-9 * jac);
        }
    }

    #[test]
    fn outgoing_cells_round_trip() {
        let cells = OutgoingCells {
            n_theta: 5,
            phi: PhiBins::new(6),
            theta_only: false,
        };
        for row in 0..cells.rows() {
            assert_eq!(cells.cell(&cells.centre(row)).0, row);
        }
        let turned = OutgoingCells {
            theta_only: true,
            ..cells
        };
        let wo = direction(0.5, 2.0);
        let (_, turn) = turned.cell(&wo);
        let local = turn.local_to_row(&wo);
        assert!(local.y.abs() < 1e-15 && local.x > 0.0);
        assert!((turn.row_to_local(&local) - wo).norm() < 1e-15);
    }
}
