//! BRDF importance sampling with sets of adaptive quadtrees on the projected disc
//! (Montes, Ureña, García & Lastra, GRAPP 2008 §3; CEIG 2008 §3).
//!
//! # Math
//! * **Disc adapter** ([`disc`]): a direction `v` maps to the unit disc by `h(v) = (v.x, v.y)`,
//!   `h⁻¹(x, y) = (x, y, √(1 − x² − y²))`. Area on the disc is projected solid angle
//!   (`dA = cos θ dσ`), so the disc density `x ↦ f_r(ωo, h⁻¹(x))` ([`DiscBrdf`]) is
//!   proportional to `f_r cos θi` with respect to solid angle and the sampler never evaluates
//!   the cosine. Public pdfs are with respect to **solid angle**:
//!   `p_σ(ωi) = p_A(h(ωi)) · cos θi` ([`area_pdf_to_solid_angle`]); 0 below the horizon.
//! * **Equal-area slices** ([`DiscMap`], [`DiscMapPolicy`]): the projected density is `f_r`
//!   itself, unbounded for models with `1/cos θi` factors, and the map squeezes θ near the rim
//!   (`dθ/dr = 1/cos θ`). By default ([`DiscMapPolicy::Auto`]) slices with
//!   `θo ≥ 80°` ([`SetOptions::equal_area_from_deg`]) and every slice of a BRDF with
//!   [`brdf::Brdf::bounded_at_horizon`] `= false` use the Lambert azimuthal equal-area map
//!   `h_e(v) = (v.x, v.y)/√(1 + v.z)`, `dσ = 2 dA`, density `2 f_r cos θi`,
//!   `p_σ = p_A / 2`. Measured (docs/benchmarks.md): Strauss 480 → 1.6 trials per sample,
//!   Beard–Maxwell 562 → 1.5, Ashikhmin–Shirley's grazing slices 19.6 → 2.2.
//! * **Slices** ([`SliceLayout`]): one quadtree per outgoing direction `ωo_j` with
//!   `θ_j = (j + ½) · 90° / slices` (bin centres; default 90 slices). Isotropic BRDFs: `ωo` is
//!   rotated to `φ = 0`, the slice with the nearest θ is sampled and the sample rotated back;
//!   the pdf is evaluated with the same slice (the choice depends only on `ωo`), so
//!   `f_r L cos / p` stays an unbiased estimator wherever `p > 0` covers `f_r(ωo, ·)`.
//!   Anisotropic BRDFs use a `(θ, φ)` grid (default 32 × 16; samples are rotated by
//!   `φo − φ_k`, which keeps the mirror direction exact); a half-turn-symmetric one
//!   ([`brdf::Brdf::is_half_turn_symmetric`]) stores the azimuths of `[0, π)` only (32 × 8). Optional **mixture** of the two
//!   θ-neighbouring slices with linear weights in θ and the exact pdf `Σ w_k p_k`.
//! * **Trees** (partition-sampler): each slice's tree is built from the papers' image map
//!   ([`partition_sampler::SampledGridDensity`], `grid²` cells over `[-1, 1]²`, finer than the
//!   deepest leaf: `2^(max_depth+1) ≤ grid`) — for the adaptive variant refined by curvature
//!   ([`SetOptions::grid_refinement`]: smooth 32² blocks keep 9 values, the mirror direction's
//!   neighbourhood is always resolved) and, for a
//!   [`brdf::Brdf::is_mirror_symmetric`] BRDF, evaluated on the half `y ≤ 0` and mirrored
//!   ([`SetOptions::symmetries`]) — with the rectangle adjustment of seed 000 §3.8
//!   (rejection rectangles shrunk to the bounding box of cell ∩ disc), plus a **rim band**
//!   that samples `f` densely in `cos θi ∈ (10⁻⁶, 2/√grid]` so that bounds near the horizon
//!   hold (see `image_map.rs`; without it every tested glossy model violated its bounds at
//!   θo ≥ 85°). Slices whose expected trials exceed [`SetOptions::refine_threshold`] are
//!   rebuilt up to [`SetOptions::refine_levels`] levels deeper (grid doubled each time).
//!
//! # Variants ([`Variant`]; named samplers are registered in the `samplers` crate)
//! * `adaptive` — [`Variant::Adaptive`]: envelope scheme (leaf ∝ `V_i`, restart on
//!   rejection), alias leaf choice. Exact: samples have density `f / ∫ f` whenever the bounds
//!   hold; the reported pdf is `f / Î` with `Î` integrated over the tree's leaves by an
//!   order-8 Gauss–Legendre rule (`normalisation.rs`; relative error estimated against order 5
//!   and reported).
//! * `adaptive-paper` — [`Variant::Paper`]: leaf ∝ `I_i` by the per-node CDF descent, rejection
//!   inside the leaf, image-map bounds and rectangle adjustment; exact only when the `I_i` are,
//!   so after the build they are replaced by the leaf quadrature's per-leaf integrals whenever
//!   its error estimate beats the image map's (at grazing angles the image map's `I_i` left
//!   `∫ pdf` 0.1–0.9 % off and failed chi-square for Beard–Maxwell at 89°).
//! * `adaptive-mixture`, `adaptive-paper-mixture` — the same with the two-slice mixture.
//!
//! Every trial with `f > M_i` is counted ([`SetReport::bound_violations`]). BRDFs whose `f_r`
//! is unbounded at the horizon (terms in `1/cos θi`, e.g. Strauss, Beard–Maxwell) cannot be
//! bounded on the projected disc; with [`DiscMapPolicy::Projected`] (the papers' method
//! verbatim) their grazing slices need hundreds of trials per sample.
//!
//! # Example
//! ```
//! use std::sync::Arc;
//! use brdf::{Brdf, direction_from_angles, parse_spec};
//! use brdf_sampling::{DirectionSampler, QuadTreeSet, SetOptions, Variant};
//! use rand::{SeedableRng, rngs::Xoshiro256PlusPlus};
//!
//! let brdf: Arc<dyn Brdf> = Arc::from(parse_spec("phong:n=50")?);
//! let opts = SetOptions { slices: 9, ..SetOptions::default() };
//! let sampler = QuadTreeSet::build(brdf.clone(), Variant::Adaptive, &opts)?;
//!
//! let wo = direction_from_angles(30.0, 45.0);
//! let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
//! let s = sampler.sample(&wo, &mut rng);
//! assert!(s.wi.z > 0.0 && s.pdf > 0.0);
//! // The pdf (w.r.t. solid angle) is the one `sample` reported.
//! assert!((sampler.pdf(&wo, &s.wi) - s.pdf).abs() <= 1e-9 * s.pdf);
//! // One-sample estimate of the directional albedo ∫ f cos dσ.
//! let _estimate = brdf.eval(&wo, &s.wi) * s.wi.z / s.pdf;
//!
//! // Sets can be saved and re-attached to the same BRDF spec.
//! let set = QuadTreeSet::build(brdf.clone(), Default::default(), &opts)?.with_spec("phong:n=50");
//! let back = QuadTreeSet::from_bytes(&set.to_bytes(), brdf, "phong:n=50")?;
//! assert_eq!(back.report().trees, 9);
//! assert_eq!(set.report().bound_violations, 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// `!(x > 0.0)`-style checks are deliberate: they reject NaN along with out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod direction_sampler;
pub mod disc;
mod error;
pub mod exact;
mod image_map;
mod layout;
mod normalisation;
mod options;
mod pdf_cells;
mod persist;
mod reference;
mod report;
mod sampler_checks;
mod set;

pub use direction_sampler::{DirSample, DirectionSampler, EvalSample, SamplerDiagnostics};
pub use disc::{
    DiscBrdf, DiscMap, SliceDensity, area_pdf_to_solid_angle, direction_to_disc, disc_to_direction,
    solid_angle_pdf_to_area, thread_evaluations,
};
pub use error::{SetError, SetFileError};
pub use exact::{CellLayout, ExactError, ExactOptions, ExactReport, ExactSet};
pub use layout::{SliceChoice, SliceLayout, SliceLocator, Turn};
pub use options::{DiscMapPolicy, OptionsError, SetOptions, Variant, bad_slice_count};
pub use pdf_cells::{CellCoords, PdfCellRow, PdfCells};
pub use persist::{MAX_LOADED_MEAN_TRIALS, SET_FORMAT_VERSION};
pub use reference::{
    AlbedoEstimate, REFERENCE_BUDGET, ReferenceError, reference_albedo, reference_albedo_rgb,
    reference_albedo_with_budget,
};
pub use reference::{
    CORNELL_REFERENCE_REL_TOL, RGL_CELL_ORDER, cornell_reference_albedo, rgl_albedo_in_cells,
    rgl_reference_albedo,
};
pub use report::{CostMeasurement, SetReport};
pub use sampler_checks::{
    SampledAlbedo, equal_area_hemisphere_integral, sampled_albedo, upper_hemisphere_integral,
};
pub use set::{FLOOR_PROBES, Progress, QuadTreeSet, SUPPORT_FLOOR, layout_for};
