//! Deliberately broken samplers: the suite must reject every one (its power), while the
//! unbroken base of each (its control) passes.
//!
//! | mutant | bug |
//! |---|---|
//! | `pdf-off-3pct-in-region` | reported pdf 3 % too high where `ωi.y > 0`, 3 % too low elsewhere |
//! | `lobe-rotated-2deg` | lobe sampled around an axis tilted by 2°, pdf of the untilted lobe |
//! | `cosine-as-uniform` | cosine-weighted samples reported with the uniform pdf `1/(2π)` |
//! | `leaf-bound-too-low` | quadtree leaf bounds 0.7 × the honest ones (safety factor < 1) |
//! | `batch-floor-split` | batch counts `⌊N p_i⌋`, remainder given to the first leaf |
//! | `batch-remainder-dropped` | batch counts `⌊N p_i⌋`, remainder dropped |
//! | `mixture-not-renormalised` | mixture pdf with weights summing to 1.2 |
//! | `pdf-on-neighbour-slice` | samples from slice `θ_j`, pdf evaluated with slice `θ_{j+1}` |
//! | `support-hole` | cosine sampling truncated at 80°, renormalised: no samples near the horizon |

mod bases;
mod direction;
mod planar;

use std::sync::Arc;

use brdf::{Brdf, Vec3};
use brdf_sampling::DirectionSampler;
use partition_sampler::QuadTreeBuilder;

pub use bases::{CosineHemisphere, LobeMixture, cosine_direction, cosine_pdf};
pub use direction::{CosineReportedUniform, RegionScaledPdf, TruncatedCosine};
pub use planar::{FloorSplit, Remainder, ScaledBounds};

use crate::adapters::{DirectionAtWo, QuadTreePlanar};
use crate::domain::Domain;
use crate::registry::{quadtree_disc_density, quadtree_disc_sampler};
use crate::subject::AnySubject;
use crate::targets::{BrdfReferences, brdf_direction_subject, brdf_disc_subject};

/// A mutant and its control, ready to run.
pub struct MutantCase {
    /// The broken sampler.
    pub mutant: AnySubject,
    /// Its unbroken base in the same setting.
    pub control: AnySubject,
}

type MutantBuild = fn(&Arc<dyn Brdf>, &Vec3, &BrdfReferences) -> Result<MutantCase, String>;

/// A registered mutant: a broken sampler, the setting it is tested in, and its control.
#[derive(Clone, Copy)]
pub struct Mutant {
    /// Name.
    pub name: &'static str,
    /// The bug.
    pub description: &'static str,
    /// BRDF spec of the setting.
    pub brdf: &'static str,
    /// Outgoing polar angle of the setting (degrees, `φo = 0`).
    pub theta_o: f64,
    build: MutantBuild,
}

impl std::fmt::Debug for Mutant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mutant")
            .field("name", &self.name)
            .field("brdf", &self.brdf)
            .field("theta_o", &self.theta_o)
            .finish_non_exhaustive()
    }
}

impl Mutant {
    /// Builds the mutant and its control for `brdf` at `wo` with references `refs`.
    ///
    /// # Errors
    /// A sampler that cannot be built, as text.
    pub fn build(
        &self,
        brdf: &Arc<dyn Brdf>,
        wo: &Vec3,
        refs: &BrdfReferences,
    ) -> Result<MutantCase, String> {
        (self.build)(brdf, wo, refs)
    }
}

fn direction_pair(
    mutant: impl DirectionSampler + 'static,
    control: impl DirectionSampler + 'static,
    domain: Domain,
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
    refs: &BrdfReferences,
) -> MutantCase {
    let wrap = |s: Arc<dyn DirectionSampler>| {
        AnySubject::Direction(brdf_direction_subject(
            Arc::new(DirectionAtWo::new(s, *wo)),
            domain,
            Arc::clone(brdf),
            *wo,
            refs,
        ))
    };
    MutantCase {
        mutant: wrap(Arc::new(mutant)),
        control: wrap(Arc::new(control)),
    }
}

/// Phong-like mixture used by the lobe mutants: cosine weight 0.3, exponent 50.
fn phong_mixture() -> LobeMixture {
    LobeMixture::correct(0.3, 50.0)
}

fn control_disc(brdf: &Arc<dyn Brdf>, wo: &Vec3, refs: &BrdfReferences) -> Result<AnySubject, String> {
    Ok(AnySubject::Planar(brdf_disc_subject(
        Arc::new(QuadTreePlanar(quadtree_disc_sampler(brdf, wo)?)),
        Arc::clone(brdf),
        *wo,
        refs,
    )))
}

fn floor_split(
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
    refs: &BrdfReferences,
    remainder: Remainder,
) -> Result<MutantCase, String> {
    let broken = FloorSplit::new(quadtree_disc_sampler(brdf, wo)?, remainder);
    Ok(MutantCase {
        mutant: AnySubject::Planar(brdf_disc_subject(
            Arc::new(broken),
            Arc::clone(brdf),
            *wo,
            refs,
        )),
        control: control_disc(brdf, wo, refs)?,
    })
}

/// Every mutant.
pub static MUTANTS: &[Mutant] = &[
    Mutant {
        name: "pdf-off-3pct-in-region",
        description: "reported pdf 3 % too high where wi.y > 0 and 3 % too low elsewhere (still normalised and self-consistent)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let base = phong_mixture();
            Ok(direction_pair(
                RegionScaledPdf { base, factor: 1.03 },
                base,
                Domain::Sphere,
                b,
                wo,
                r,
            ))
        },
    },
    Mutant {
        name: "lobe-rotated-2deg",
        description: "specular lobe sampled around an axis tilted by 2 degrees in the plane of incidence; pdf of the untilted lobe",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let base = phong_mixture();
            let broken = LobeMixture {
                lobe_tilt_deg: 2.0,
                ..base
            };
            Ok(direction_pair(broken, base, Domain::Sphere, b, wo, r))
        },
    },
    Mutant {
        name: "cosine-as-uniform",
        description: "cosine-weighted hemisphere samples reported with the uniform pdf 1/(2 pi)",
        brdf: "lambert",
        theta_o: 30.0,
        build: |b, wo, r| {
            Ok(direction_pair(
                CosineReportedUniform,
                CosineHemisphere,
                Domain::Hemisphere,
                b,
                wo,
                r,
            ))
        },
    },
    Mutant {
        name: "leaf-bound-too-low",
        description: "disc quadtree whose leaf bounds are 0.7 x the honest ones (effective safety factor 0.875 < 1)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let density = quadtree_disc_density(b, wo)?;
            let broken = QuadTreeBuilder::new()
                .build(ScaledBounds {
                    inner: density,
                    factor: 0.7,
                })
                .map_err(|e| e.to_string())?;
            Ok(MutantCase {
                mutant: AnySubject::Planar(brdf_disc_subject(
                    Arc::new(QuadTreePlanar(broken)),
                    Arc::clone(b),
                    *wo,
                    r,
                )),
                control: control_disc(b, wo, r)?,
            })
        },
    },
    Mutant {
        name: "batch-floor-split",
        description: "batch mode allocates floor(N p_i) samples per leaf and gives the remainder to the first leaf",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| floor_split(b, wo, r, Remainder::ToFirstLeaf),
    },
    Mutant {
        name: "batch-remainder-dropped",
        description: "batch mode allocates floor(N p_i) samples per leaf and drops the remainder",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| floor_split(b, wo, r, Remainder::Dropped),
    },
    Mutant {
        name: "mixture-not-renormalised",
        description: "cosine + lobe mixture whose pdf uses weights 0.35 + 0.85 = 1.2 (selection uses them normalised)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let base = LobeMixture::correct(0.35 / 1.2, 50.0);
            let broken = LobeMixture {
                pdf_weights: [0.35, 0.85],
                ..base
            };
            Ok(direction_pair(broken, base, Domain::Sphere, b, wo, r))
        },
    },
    Mutant {
        name: "pdf-on-neighbour-slice",
        description: "lobe sampled around the mirror of slice theta_j (2 degree slices), pdf evaluated with slice theta_(j+1)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let base = LobeMixture {
                slice_step: Some(2.0),
                ..phong_mixture()
            };
            let broken = LobeMixture {
                pdf_slice_offset: 1,
                ..base
            };
            Ok(direction_pair(broken, base, Domain::Sphere, b, wo, r))
        },
    },
    Mutant {
        name: "support-hole",
        description: "cosine sampling truncated at theta = 80 degrees and renormalised: pdf 0 near the horizon where f cos > 0",
        brdf: "lambert",
        theta_o: 30.0,
        build: |b, wo, r| {
            Ok(direction_pair(
                TruncatedCosine {
                    theta_max_deg: 80.0,
                },
                CosineHemisphere,
                Domain::Hemisphere,
                b,
                wo,
                r,
            ))
        },
    },
];

/// Every mutant.
pub fn mutants() -> &'static [Mutant] {
    MUTANTS
}
