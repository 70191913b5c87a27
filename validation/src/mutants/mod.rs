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
//! | `tabulated-cdf-row-pdf-off` | `tabulated-cdf`'s pdf 2 × on its heaviest `cos θ` row, renormalised |
//! | `cascade-cdf-row-pdf-off` | the same for `cascade-cdf` |
//! | `factored-band-pdf-off` | the same for `factored`, on its heaviest half-vector `θh` band |
//! | `exact-normaliser-1pct` | `adaptive-exact` with `A(θo)` 1 % too large (pdf × 1/1.01) |
//! | `exact-envelope-too-low` | `adaptive-exact` with three 30° θ intervals, two bound nodes, safety 1 |

mod bases;
mod cells;
mod direction;
mod planar;

use std::sync::Arc;

use brdf::{Brdf, Vec3};
use brdf_sampling::DirectionSampler;
use partition_sampler::QuadTreeBuilder;

pub use bases::{CosineHemisphere, LobeMixture, cosine_direction, cosine_pdf};
pub use cells::RowScaledPdf;
pub use direction::{CosineReportedUniform, RegionScaledPdf, ScaledPdf, TruncatedCosine};
pub use planar::{FloorSplit, Remainder, ScaledBounds};

use crate::adapters::{DirectionAtWo, QuadTreePlanar};
use crate::builds::{build_direction, direction_domain, quadtree_disc_sampler};
use crate::domain::Domain;
use crate::subject::AnySubject;
use crate::targets::{BrdfReferences, brdf_direction_subject, brdf_disc_subject};
use samplers::quadtree_disc_density;

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
    shared_pair(Arc::new(mutant), Arc::new(control), domain, brdf, wo, refs)
}

/// A mutant/control pair of direction samplers on `domain`, each checked at `wo` against
/// `brdf`'s references `refs`.
fn shared_pair(
    mutant: Arc<dyn DirectionSampler>,
    control: Arc<dyn DirectionSampler>,
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
        mutant: wrap(mutant),
        control: wrap(control),
    }
}

/// The registered cell-declaring sampler `name` for `brdf` (control) and its
/// [`RowScaledPdf`] with factor 2 at `wo` (mutant), on the sampler's own domain.
fn row_scaled_pair(
    name: &str,
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
    refs: &BrdfReferences,
) -> Result<MutantCase, String> {
    let entry = samplers::find(name).map_err(|e| e.to_string())?;
    let domain = direction_domain(entry).ok_or("not a direction sampler")?;
    let base = build_direction(entry, brdf).map_err(|e| e.to_string())?;
    let broken: Arc<dyn DirectionSampler> =
        Arc::new(RowScaledPdf::new(Arc::clone(&base), wo, 2.0)?);
    Ok(shared_pair(broken, base, domain, brdf, wo, refs))
}

/// A lobe mutant on the sphere: `base` with `broken` applied to a copy of it, against `base`.
fn lobe_pair(
    base: LobeMixture,
    broken: impl FnOnce(&mut LobeMixture),
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
    refs: &BrdfReferences,
) -> Result<MutantCase, String> {
    let mut mutant = base;
    broken(&mut mutant);
    Ok(direction_pair(mutant, base, Domain::Sphere, brdf, wo, refs))
}

/// Phong-like mixture used by the lobe mutants: cosine weight 0.3, exponent 50.
fn phong_mixture() -> LobeMixture {
    LobeMixture::correct(0.3, 50.0)
}

fn control_disc(
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
    refs: &BrdfReferences,
) -> Result<AnySubject, String> {
    Ok(AnySubject::Planar(brdf_disc_subject(
        Arc::new(QuadTreePlanar(
            quadtree_disc_sampler(brdf, wo).map_err(|e| e.to_string())?,
        )),
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
    let broken = FloorSplit::new(
        quadtree_disc_sampler(brdf, wo).map_err(|e| e.to_string())?,
        remainder,
    );
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

/// `adaptive-exact` with default options, or with `broken` applied to them.
fn exact_set(
    brdf: &Arc<dyn Brdf>,
    broken: impl FnOnce(&mut brdf_sampling::ExactOptions),
) -> Result<Arc<dyn DirectionSampler>, String> {
    let mut opts = brdf_sampling::ExactOptions::default();
    broken(&mut opts);
    brdf_sampling::ExactSet::build(Arc::clone(brdf), &opts, None)
        .map(|s| Arc::new(s) as Arc<dyn DirectionSampler>)
        .map_err(|e| e.to_string())
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
        build: |b, wo, r| lobe_pair(phong_mixture(), |m| m.lobe_tilt_deg = 2.0, b, wo, r),
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
            let density = quadtree_disc_density(b, wo).map_err(|e| e.to_string())?;
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
            lobe_pair(base, |m| m.pdf_weights = [0.35, 0.85], b, wo, r)
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
            lobe_pair(base, |m| m.pdf_slice_offset = 1, b, wo, r)
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
    Mutant {
        name: "tabulated-cdf-row-pdf-off",
        description: "tabulated-cdf whose reported pdf is 2 x too high on its heaviest cos(theta) row and lower on the others (still normalised, self-consistent, cells still constant)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| row_scaled_pair("tabulated-cdf", b, wo, r),
    },
    Mutant {
        name: "cascade-cdf-row-pdf-off",
        description: "cascade-cdf whose reported pdf is 2 x too high on its heaviest fine cos(theta) row and lower on the others (still normalised, self-consistent, cells still constant)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| row_scaled_pair("cascade-cdf", b, wo, r),
    },
    Mutant {
        name: "factored-band-pdf-off",
        description: "factored whose reported pdf (above its defensive cosine part) is 2 x too high on its heaviest half-vector theta band and lower on the others (still normalised, self-consistent, cells still constant)",
        brdf: "ggx:alpha=0.2",
        theta_o: 45.0,
        build: |b, wo, r| row_scaled_pair("factored", b, wo, r),
    },
    Mutant {
        name: "exact-normaliser-1pct",
        description: "adaptive-exact whose tabulated normaliser A(theta_o) is 1 % too large (pdf x 1/1.01)",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let control = exact_set(b, |_| {})?;
            let broken = Arc::new(ScaledPdf {
                inner: Arc::clone(&control),
                factor: 1.0 / 1.01,
            });
            Ok(shared_pair(broken, control, Domain::Hemisphere, b, wo, r))
        },
    },
    Mutant {
        name: "exact-envelope-too-low",
        description: "adaptive-exact whose bounds come from three theta intervals of 30 degrees, two bound nodes each (the ends), safety factor 1 and no splitting: too low midway between the nodes",
        brdf: "phong:n=50",
        theta_o: 45.0,
        build: |b, wo, r| {
            let broken = exact_set(b, |o| {
                o.initial_intervals = 3;
                o.bound_nodes = 2;
                o.max_trials = 1e9;
                o.normaliser_tol = 1.0;
                o.set.safety_factor = 1.0;
            })?;
            Ok(shared_pair(
                broken,
                exact_set(b, |_| {})?,
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

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use brdf::direction_from_angles;
    use stats::{QuadratureOptions, SphereBinning, integrate};

    /// `∫ pdf(ωo, ·) dω` over the sphere (or hemisphere).
    fn mass(s: &dyn DirectionSampler, wo: &Vec3, sphere: bool) -> f64 {
        let bins = if sphere {
            SphereBinning::sphere(32, 32).unwrap()
        } else {
            SphereBinning::hemisphere(16, 32).unwrap()
        };
        let f = |d: [f64; 3]| s.pdf(wo, &Vec3::new(d[0], d[1], d[2]));
        integrate(&f, &bins, 1e-8, &QuadratureOptions::default())
            .unwrap()
            .value
    }

    #[test]
    fn bases_and_pdf_preserving_mutants_are_normalised() {
        let wo = direction_from_angles(45.0, 0.0);
        let base = phong_mixture();
        assert_relative_eq!(mass(&base, &wo, true), 1.0, epsilon = 1e-6);
        assert_relative_eq!(mass(&CosineHemisphere, &wo, false), 1.0, epsilon = 1e-8);
        // These mutants keep ∫ pdf = 1: only the tests that look at the samples catch them.
        let region = RegionScaledPdf { base, factor: 1.03 };
        assert_relative_eq!(mass(&region, &wo, true), 1.0, epsilon = 1e-6);
        assert_relative_eq!(
            mass(&CosineReportedUniform, &wo, false),
            1.0,
            epsilon = 1e-8
        );
        let hole = TruncatedCosine {
            theta_max_deg: 80.0,
        };
        assert_relative_eq!(mass(&hole, &wo, false), 1.0, epsilon = 1e-6);
        // ... while the unnormalised mixture integrates to 1.2.
        let broken = LobeMixture {
            pdf_weights: [0.35, 0.85],
            ..LobeMixture::correct(0.35 / 1.2, 50.0)
        };
        assert_relative_eq!(mass(&broken, &wo, true), 1.2, epsilon = 1e-6);
    }

    #[test]
    fn samples_report_their_pdf() {
        let wo = direction_from_angles(30.0, 20.0);
        let mut rng = <rand::rngs::Xoshiro256PlusPlus as rand::SeedableRng>::seed_from_u64(4);
        let samplers: [&dyn DirectionSampler; 3] = [
            &phong_mixture(),
            &CosineHemisphere,
            &TruncatedCosine {
                theta_max_deg: 80.0,
            },
        ];
        for s in samplers {
            for _ in 0..200 {
                let x = s.sample(&wo, &mut rng);
                assert!((x.wi.norm() - 1.0).abs() < 1e-12);
                assert_relative_eq!(x.pdf, s.pdf(&wo, &x.wi), max_relative = 1e-12);
                assert!(x.pdf > 0.0);
            }
        }
    }

    #[test]
    fn every_mutant_builds() {
        for m in mutants() {
            let b: Arc<dyn Brdf> = Arc::from(brdf::parse_spec(m.brdf).unwrap());
            let wo = direction_from_angles(m.theta_o, 0.0);
            let r = crate::subject::Reference {
                value: 1.0,
                abs_error: 0.0,
                rule: String::new(),
            };
            let refs = BrdfReferences {
                albedo: r.clone(),
                lit: r,
            };
            assert!(m.build(&b, &wo, &refs).is_ok(), "{}", m.name);
        }
    }
}
