//! The tabulated function an SRBF mixture is fitted to ([`FitTarget`]): shared by the
//! greedy guess and NNLS of `fit.rs` and the Levenberg–Marquardt refinement of `lm.rs`.

use brdf::Vec3;

use super::SrbfError;
use super::vmf::SgLobe;

/// A tabulated non-negative function on (part of) the sphere: directions, their solid-angle
/// quadrature weights and values.
#[derive(Debug, Clone, PartialEq)]
pub struct FitTarget {
    pub(super) directions: Vec<Vec3>,
    pub(super) weights: Vec<f64>,
    pub(super) values: Vec<f64>,
    spacing: Option<f64>,
}

impl FitTarget {
    /// A target from unit `directions`, solid-angle `weights` `A_i` and `values` `f_i`.
    ///
    /// Errors: lengths differ or are zero; a NaN, infinite or negative value or weight;
    /// ([`SrbfError::BlackTarget`]) every `A_i f_i` zero.
    pub fn new(
        directions: Vec<Vec3>,
        weights: Vec<f64>,
        values: Vec<f64>,
    ) -> Result<Self, SrbfError> {
        if directions.is_empty()
            || directions.len() != weights.len()
            || weights.len() != values.len()
        {
            return Err(SrbfError::TargetShape {
                directions: directions.len(),
                weights: weights.len(),
                values: values.len(),
            });
        }
        for (index, (&value, &weight)) in values.iter().zip(&weights).enumerate() {
            if !(value >= 0.0 && value.is_finite() && weight >= 0.0 && weight.is_finite()) {
                return Err(SrbfError::BadTarget {
                    index,
                    value,
                    weight,
                });
            }
        }
        if !values.iter().zip(&weights).any(|(v, w)| v * w > 0.0) {
            return Err(SrbfError::BlackTarget);
        }
        Ok(Self {
            directions,
            weights,
            values,
            spacing: None,
        })
    }

    /// The same target declaring its angular sample spacing `Δ` (radians): fits then cap the
    /// bandwidth at `4/Δ²`, i.e. a lobe's angular width `1/√λ` at least `Δ/2` (a narrower lobe
    /// can slip between samples, where the least-squares objective cannot see its mass; a cap of
    /// `1/Δ²` was tried and over-smoothed the procedural sky's sun, +31 % mass).
    pub fn with_spacing(mut self, spacing: f64) -> Self {
        self.spacing = (spacing > 0.0 && spacing.is_finite()).then_some(spacing);
        self
    }

    /// The bandwidth cap `4/Δ²` of the declared spacing, if any.
    pub fn lambda_cap(&self) -> Option<f64> {
        self.spacing.map(|d| 4.0 / (d * d))
    }

    /// The sample directions.
    pub(crate) fn directions(&self) -> &[Vec3] {
        &self.directions
    }

    /// The solid-angle weights `A_i`.
    pub(crate) fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The values `f_i`.
    pub(crate) fn values(&self) -> &[f64] {
        &self.values
    }

    /// Number of sample directions.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no samples (never, for a constructed target).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// `Σ A_i f_i`, the quadrature of the target's integral.
    pub fn integral(&self) -> f64 {
        self.values
            .iter()
            .zip(&self.weights)
            .map(|(v, w)| v * w)
            .sum()
    }

    /// Relative L2 and L1 errors of `lobes` on the target:
    /// `(√(Σ A r²/Σ A f²), Σ A|r| / Σ A f)` with `r_i = Σ_k c_k G_ik − f_i`.
    pub fn errors(&self, lobes: &[SgLobe]) -> (f64, f64) {
        let (mut r2, mut f2, mut r1, mut f1) = (0.0, 0.0, 0.0, 0.0);
        for ((d, &a), &f) in self.directions.iter().zip(&self.weights).zip(&self.values) {
            let r = lobes.iter().map(|l| l.eval(d)).sum::<f64>() - f;
            r2 += a * r * r;
            f2 += a * f * f;
            r1 += a * r.abs();
            f1 += a * f;
        }
        ((r2 / f2).sqrt(), r1 / f1)
    }
}
