//! The [`Brdf`] trait shared by every reflectance model.

use crate::analytic::AnalyticLobes;
use crate::geometry::Vec3;
use std::sync::Arc;

/// Rec. 709 luminance weights used to turn RGB reflectance into the scalar that is sampled
/// (re-exported from the `colour` crate, the project's one luminance formula).
pub use colour::LUMINANCE_WEIGHTS;

/// Luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` of a linear RGB triple (re-exported from
/// the `colour` crate).
pub use colour::luminance;

/// A bidirectional reflectance distribution function `f_r(ωo, ωi)` in units of 1/sr.
///
/// Frame: the surface normal is `n = (0, 0, 1)`, the tangent (anisotropy direction) is `x`.
/// Both `wo` (towards the viewer) and `wi` (towards the light) are **unit** vectors pointing
/// away from the surface. Reflected radiance is `L_r(ωo) = ∫_Ω f_r(ωo, ωi) L_i(ωi) cosθi dσ(ωi)`.
///
/// Contract for implementors: `eval` is finite and `≥ 0` for all unit vectors in the open upper
/// hemisphere and returns `0` when `wo.z ≤ 0` or `wi.z ≤ 0` (or either is NaN). It must not
/// allocate per call: samplers call it millions of times (a reader may build a bounded part of
/// an acceleration structure once, on first use, as the Cornell reader's search cells do).
pub trait Brdf: Send + Sync {
    /// Scalar BRDF value in 1/sr. For coloured models this is the luminance of
    /// [`eval_rgb`](Brdf::eval_rgb) (see [`luminance`]).
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64;

    /// Linear RGB BRDF value in 1/sr. The default is grey: `[eval; 3]`.
    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        let y = self.eval(wo, wi);
        [y, y, y]
    }

    /// `Some(c)` when the RGB value is the scalar one times a constant colour everywhere:
    /// [`eval_rgb`](Brdf::eval_rgb)`(ωo, ωi) = c ⊙ eval(ωo, ωi)` for every pair, bit for bit
    /// (`c = [1; 3]` for a grey model that keeps the default `eval_rgb`). A renderer holding
    /// `f = eval(ωo, ωi)` from a fused sample-and-evaluate then needs no RGB evaluation.
    /// Default `None` (the safe answer: the caller evaluates `eval_rgb`); a model that overrides
    /// `eval_rgb` keeps `None` unless its colour is constant.
    fn rgb_scale(&self) -> Option<[f64; 3]> {
        None
    }

    /// The values of `f_r(ωo, ·)` that depend on `ωo` alone, computed once for many
    /// evaluations at one outgoing direction (a sampler's trials at one query). The default
    /// keeps `ωo` only.
    fn prepare(&self, wo: &Vec3) -> Outgoing {
        Outgoing::new(*wo)
    }

    /// [`eval`](Brdf::eval) at `q.wo()` for `q` from this BRDF's [`prepare`](Brdf::prepare).
    /// Implementations return the same value as `eval(q.wo(), wi)`, bit for bit (samplers
    /// evaluate pdfs through both). With an `Outgoing` prepared by another BRDF the value is
    /// unspecified but finite and `≥ 0`.
    fn eval_prepared(&self, q: &Outgoing, wi: &Vec3) -> f64 {
        self.eval(q.wo(), wi)
    }

    /// `f_r(ωo, ·)` prepared for a **run** of many evaluations at one outgoing direction (a
    /// batch of queries that share `ωo`: a pixel's samples, a fixed-`ωo` benchmark), held by
    /// the caller for the run: its [`PreparedRun::eval`]`(wi)` equals
    /// [`eval`](Brdf::eval)`(wo, wi)` bit for bit. Worth asking only when the run is long
    /// enough to repay the preparation (a BRDF may precompute a whole slice of its tables).
    /// The default is `None`: callers then use [`prepare`](Brdf::prepare) and
    /// [`eval_prepared`](Brdf::eval_prepared).
    fn prepare_run(&self, wo: &Vec3) -> Option<Box<dyn PreparedRun + '_>> {
        let _ = wo;
        None
    }

    /// True when `f_r` is invariant under a common rotation of `wo` and `wi` about the normal.
    /// Default `false` (the safe answer for samplers).
    fn is_isotropic(&self) -> bool {
        false
    }

    /// True when `f_r` is isotropic **and** mirror-symmetric about the tangent–normal (xz)
    /// plane: `f_r(M ωo, M ωi) = f_r(ωo, ωi)` for the reflection `M(x, y, z) = (x, −y, z)`.
    /// Together these mean `f_r` depends on `φi − φo` only through `cos(φi − φo)`. Then, for `ωo`
    /// in the xz-plane (`φo = 0`, so `M ωo = ωo`), the slice `f_r(ωo, ·)` is even under
    /// `y ↦ −y` (`φi ↦ −φi`): a sampler may rotate `ωo` to `φo = 0`, evaluate one half of the
    /// slice and mirror it.
    ///
    /// Default `false` (the safe answer). Measured data keep `false` unless their table is
    /// symmetric: MERL's `φd` fold identifies `φd` with `φd + π` but not with `−φd`.
    fn is_mirror_symmetric(&self) -> bool {
        false
    }

    /// True when `f_r(R_π ωo, R_π ωi) = f_r(ωo, ωi)` for the half-turn about the normal,
    /// `R_π(x, y, z) = (−x, −y, z)`. Every isotropic BRDF has it; an anisotropic one has it when
    /// its anisotropy is elliptical (terms in `x²`, `y²`, `x x'`, `y y'` of the two directions or
    /// of the half vector). Then the slice at `φo + π` is the slice at `φo` turned by `π`, and a
    /// sampler of an anisotropic BRDF may store outgoing azimuths over `[0, π)` only.
    ///
    /// Default `false` (the safe answer).
    fn is_half_turn_symmetric(&self) -> bool {
        false
    }

    /// True when `f_r(ωo, ωi) = f_r(ωi, ωo)` (Helmholtz reciprocity). Default `false`.
    fn is_reciprocal(&self) -> bool {
        false
    }

    /// True when the directional albedo `∫_Ω f_r(ωo, ωi) cosθi dσ(ωi) ≤ 1` for every `ωo`
    /// (with the current parameters). Default `false`.
    fn conserves_energy(&self) -> bool {
        false
    }

    /// True when `f_r(ωo, ωi)` stays bounded as `θi → 90°`, for every `ωo` above the horizon
    /// (with the current parameters). Default `true`.
    ///
    /// Samplers that absorb `cos θi` into their measure (the projected disc, where the density
    /// is `f_r` itself) need a bounded `f_r`; models with `1/cos θi`-type factors (Strauss,
    /// Beard–Maxwell, Ward's normalised lobe, Minnaert with `k < 1`) return `false`, and the
    /// quadtree sets sample them on a measure whose density keeps the cosine.
    fn bounded_at_horizon(&self) -> bool {
        true
    }

    /// The model's diffuse and specular parts as a renderer's analytic importance sampler
    /// needs them (GGX/Beckmann visible normals, Phong and Blinn lobes, Ward), or `None` when
    /// the model has no standard analytic sampler. Default `None`.
    fn analytic_lobes(&self) -> Option<AnalyticLobes> {
        None
    }

    /// Short model name (the registry key, e.g. `"phong"`).
    fn name(&self) -> &str {
        "custom"
    }

    /// The implementing type as [`Any`](std::any::Any), for samplers that work only with one
    /// concrete BRDF type (e.g. the RGL format's own sampler). Default `None`.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }
}

/// `f_r(ωo, ·)` at one outgoing direction, prepared by [`Brdf::prepare_run`] for a run of
/// evaluations there and held by the caller (no thread-local or shared state).
pub trait PreparedRun: Send + Sync {
    /// `f_r(ωo, ωi)` at the run's `ωo`: [`Brdf::eval`]`(wo, wi)` bit for bit.
    fn eval(&self, wi: &Vec3) -> f64;

    /// `out[k] = f_r(ωo, wi[k])` for `k < min(wi.len(), out.len())`: [`eval`](Self::eval)
    /// of each direction, bit for bit (`out`'s other entries are left alone). A run may
    /// evaluate the block in vector lanes (RGL files do); default: one `eval` per direction.
    fn eval_block(&self, wi: &[Vec3], out: &mut [f64]) {
        for (w, o) in wi.iter().zip(out.iter_mut()) {
            *o = self.eval(w);
        }
    }

    /// Whether [`eval_block`](Self::eval_block) is cheaper per direction than
    /// [`eval`](Self::eval) (vector lanes), so a sampler should gather its evaluations into
    /// blocks. Default `false`.
    fn prefers_blocks(&self) -> bool {
        false
    }
}

/// An outgoing direction `ωo` with up to [`Outgoing::CACHE_LEN`] values a BRDF derived from it
/// in [`Brdf::prepare`] (their meaning is private to that BRDF). Plain data: `Copy`, no heap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outgoing {
    wo: Vec3,
    cache: [f64; Outgoing::CACHE_LEN],
}

impl Outgoing {
    /// Number of cached values.
    pub const CACHE_LEN: usize = 8;

    /// `ωo` with an empty (zero) cache.
    pub fn new(wo: Vec3) -> Self {
        Self {
            wo,
            cache: [0.0; Self::CACHE_LEN],
        }
    }

    /// `ωo` with the values a BRDF computed from it.
    pub fn with_cache(wo: Vec3, cache: [f64; Self::CACHE_LEN]) -> Self {
        Self { wo, cache }
    }

    /// The outgoing direction.
    pub fn wo(&self) -> &Vec3 {
        &self.wo
    }

    /// The cached values.
    pub fn cache(&self) -> &[f64; Self::CACHE_LEN] {
        &self.cache
    }
}

/// The [`Brdf`] methods other than the three evaluations (`prepare`, the property predicates,
/// `rgb_scale`, `analytic_lobes`, `name`, `as_any`), forwarded to `$inner`: what a wrapper
/// passes through unchanged (the pointer impls below; [`CountingBrdf`](crate::CountingBrdf), which counts
/// evaluations only). Used inside `impl Brdf for …` as `forward_brdf_queries!(self => inner)`.
macro_rules! forward_brdf_queries {
    ($self:ident => $inner:expr) => {
        #[inline]
        fn prepare(&$self, wo: &$crate::Vec3) -> $crate::Outgoing {
            $inner.prepare(wo)
        }
        $crate::brdf::forward_brdf_queries!(@predicates $self => $inner;
            is_isotropic, is_mirror_symmetric, is_half_turn_symmetric, is_reciprocal,
            conserves_energy, bounded_at_horizon);
        fn rgb_scale(&$self) -> Option<[f64; 3]> {
            $inner.rgb_scale()
        }
        fn analytic_lobes(&$self) -> Option<$crate::AnalyticLobes> {
            $inner.analytic_lobes()
        }
        fn name(&$self) -> &str {
            $inner.name()
        }
        fn as_any(&$self) -> Option<&dyn std::any::Any> {
            $inner.as_any()
        }
    };
    (@predicates $self:ident => $inner:expr; $($predicate:ident),+) => {
        $(
            fn $predicate(&$self) -> bool {
                $inner.$predicate()
            }
        )+
    };
}
pub(crate) use forward_brdf_queries;

macro_rules! forward_brdf {
    ($($ty:ty),*) => {$(
        impl<T: Brdf + ?Sized> Brdf for $ty {
            #[inline]
            fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
                (**self).eval(wo, wi)
            }
            #[inline]
            fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
                (**self).eval_rgb(wo, wi)
            }
            #[inline]
            fn eval_prepared(&self, q: &Outgoing, wi: &Vec3) -> f64 {
                (**self).eval_prepared(q, wi)
            }
            fn prepare_run(&self, wo: &Vec3) -> Option<Box<dyn PreparedRun + '_>> {
                (**self).prepare_run(wo)
            }
            forward_brdf_queries!(self => (**self));
        }
    )*};
}

forward_brdf!(Box<T>, Arc<T>, &T);

#[cfg(test)]
mod rgb_scale_tests {
    use super::*;
    use crate::{CountingBrdf, direction_from_angles, models, parse_spec, preset_names};

    /// Every model built from its defaults, and every `sgd`/`abc` preset.
    fn every_model() -> Vec<(String, Box<dyn Brdf>)> {
        let mut out = Vec::new();
        for m in models() {
            if !m.needs_argument() {
                out.push((m.name.to_string(), m.build(&[]).unwrap()));
            }
            for p in preset_names(m.name).unwrap_or_default() {
                let spec = format!("{}:material={p}", m.name);
                out.push((spec.clone(), parse_spec(&spec).unwrap()));
            }
        }
        out
    }

    /// A model that claims a constant colour has `eval_rgb = c ⊙ eval` bit for bit on a grid
    /// of direction pairs (both hemispheres' edges included); every model built from numeric
    /// parameters (the analytic ones, all grey) claims it, and the coloured presets do not. A
    /// wrapper forwards the claim. Checked against a broken claim: `abc` answering
    /// `Some([1; 3])` fails here (its channels differ).
    #[test]
    fn a_claimed_constant_colour_is_the_rgb_value_and_the_analytic_models_claim_it() {
        let (mut grey, mut coloured) = (0, 0);
        for (name, b) in every_model() {
            let by_values = models()
                .iter()
                .any(|m| m.name == name && !m.needs_argument());
            let Some(c) = b.rgb_scale() else {
                assert!(!by_values, "{name}: no rgb_scale");
                coloured += 1;
                continue;
            };
            grey += 1;
            for to in [0.0, 20.0, 45.0, 70.0, 89.0] {
                for (ti, pi) in [(0.0, 0.0), (30.0, 10.0), (60.0, 180.0), (85.0, 95.0)] {
                    let (wo, wi) = (
                        direction_from_angles(to, 0.0),
                        direction_from_angles(ti, pi),
                    );
                    let f = b.eval(&wo, &wi);
                    assert_eq!(
                        b.eval_rgb(&wo, &wi),
                        c.map(|k| k * f),
                        "{name} at θo {to}, θi {ti}, φi {pi}"
                    );
                }
            }
            let wrapped = CountingBrdf(std::sync::Arc::from(b));
            assert_eq!(wrapped.rgb_scale(), Some(c), "{name} through a wrapper");
        }
        assert!(
            grey >= 16 && coloured > 0,
            "{grey} grey, {coloured} coloured"
        );
    }
}
