//! The shared core of the half-vector lobe models ([`Blinn`](super::Blinn),
//! [`Lewis`](super::Lewis)): `f_r = kd/π + ks · norm(n) · (n·h)^n`, `h = (ωo+ωi)/|ωo+ωi|`.
//! The models differ only in `norm(n)`; each has its own parameter type
//! ([`BlinnParams`](super::BlinnParams), [`LewisParams`](super::LewisParams)).

use crate::geometry::{Vec3, both_above};
use std::f64::consts::FRAC_1_PI;

/// `kd/π + ks·norm·(n·h)^n` with its constants precomputed.
#[derive(Debug, Clone)]
pub(crate) struct HalfVectorLobe {
    /// Half-vector exponent `n`.
    n: f64,
    diffuse: f64,
    spec_scale: f64,
    /// `kd + ks`, the bound of the albedo.
    albedo_bound: f64,
}

impl HalfVectorLobe {
    /// The lobe for validated `n`, `ks`, `kd` and the model's normalisation `norm`.
    pub(crate) fn new(n: f64, ks: f64, kd: f64, norm: f64) -> Self {
        Self {
            n,
            diffuse: kd * FRAC_1_PI,
            spec_scale: ks * norm,
            albedo_bound: kd + ks,
        }
    }

    /// `f_r(ωo, ωi)`, 0 unless both directions are above the horizon.
    #[inline]
    pub(crate) fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !both_above(wo, wi) {
            return 0.0;
        }
        let h = wo + wi;
        let nh = h.z / h.norm();
        self.diffuse + self.spec_scale * nh.powf(self.n)
    }

    /// Both models' albedo is at most `kd + ks` (checked numerically in their tests).
    pub(crate) fn conserves_energy(&self) -> bool {
        self.albedo_bound <= 1.0
    }
}

/// A half-vector lobe model from its parameter type (fields `n`, `ks`, `kd`), its registry
/// name and its normalisation `norm(n)`: the model struct, `new` (validation, then the lobe),
/// `properties`, the common scaffolding and the `Brdf` impl. Blinn and Lewis differ only in
/// these.
macro_rules! half_vector_model {
    ($(#[$meta:meta])* $Model:ident($Params:ident), $name:expr, norm = $norm:expr) => {
        $(#[$meta])*
        #[derive(Debug, Clone)]
        pub struct $Model {
            params: $Params,
            lobe: $crate::models::half_vector_lobe::HalfVectorLobe,
        }

        impl $Model {
            /// Validate the parameters and build the model.
            pub fn new(params: $Params) -> Result<Self, $crate::params::ParamError> {
                params.validate($name)?;
                let norm: fn(f64) -> f64 = $norm;
                Ok(Self {
                    params,
                    lobe: $crate::models::half_vector_lobe::HalfVectorLobe::new(
                        params.n,
                        params.ks,
                        params.kd,
                        norm(params.n),
                    ),
                })
            }

            /// Symmetries and energy: `n·h` only (isotropic, even under `y ↦ −y`), reciprocal;
            /// conserves energy iff `kd + ks ≤ 1`.
            pub fn properties(&self) -> $crate::models::Properties {
                use $crate::models::Properties;
                Properties::ISOTROPIC_SYMMETRIC
                    | Properties::RECIPROCAL
                    | Properties::CONSERVES_ENERGY.when(self.lobe.conserves_energy())
            }
        }

        $crate::models::model_common!($Model($Params));

        impl $crate::brdf::Brdf for $Model {
            #[inline]
            fn eval(&self, wo: &$crate::geometry::Vec3, wi: &$crate::geometry::Vec3) -> f64 {
                self.lobe.eval(wo, wi)
            }
            $crate::models::brdf_properties!($name);
            /// Grey: the default `eval_rgb`, `[eval; 3]`.
            fn rgb_scale(&self) -> Option<[f64; 3]> {
                Some([1.0; 3])
            }
            fn analytic_lobes(&self) -> Option<$crate::AnalyticLobes> {
                Some($crate::AnalyticLobes {
                    diffuse: self.params.kd,
                    specular: self.params.ks,
                    lobe: Some($crate::SpecularLobe::HalfVector {
                        exponent: self.params.n,
                    }),
                })
            }
        }
    };
}
pub(crate) use half_vector_model;
