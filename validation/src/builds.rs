//! How the suite builds each kind of registered sampler, and what the planar ones are tested
//! on. Samplers have names only in the `samplers` registry; this module maps each
//! [`Constructor`] kind to a subject under test:
//! * direction samplers (adaptive sets and the others) — built once per BRDF with the default
//!   [`SetOptions`], tested per `ωo` on the hemisphere or the sphere (their [`Support`]);
//! * disc samplers — built per (BRDF, `ωo`), tested on the disc;
//! * environment-map samplers — tested on [`test_maps`];
//! * grid samplers — tested on a synthetic 16 × 8 grid.

use std::sync::Arc;

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, SetOptions};
use envmap::{AdaptiveOptions, EnvMap};
use partition_sampler::Rect;
use samplers::{Constructor, DirectionRequest, DiscSampler, RegistryError, SamplerEntry, Support};

use crate::adapters::{EnvMapPlanar, PlainPlanar, QuadTreePlanar};
use crate::domain::Domain;
use crate::subject::{Point2, SamplerUnderTest, Subject};
use crate::targets::{envmap_subject, grid_subject, synthetic_map, synthetic_values};

/// A standalone case: a target label and the subject.
pub struct StandaloneCase {
    /// What is sampled (e.g. `map:procedural-sky-128x64`).
    pub target: String,
    /// The subject.
    pub subject: Subject<Point2>,
}

/// Whether the entry is tested per (BRDF, `θo`) (direction and disc samplers).
pub fn uses_brdf(entry: &SamplerEntry) -> bool {
    entry.is_direction() || matches!(entry.constructor, Constructor::Disc(_))
}

/// The test domain of a direction sampler: the hemisphere, or the sphere when its samples may
/// land below the horizon.
pub fn direction_domain(entry: &SamplerEntry) -> Option<Domain> {
    entry.constructor.support().map(|s| match s {
        Support::Hemisphere => Domain::Hemisphere,
        Support::Sphere => Domain::Sphere,
    })
}

/// The entry's direction sampler for `brdf`, with the default [`SetOptions`].
pub fn build_direction(
    entry: &SamplerEntry,
    brdf: &Arc<dyn Brdf>,
) -> Result<Arc<dyn DirectionSampler>, RegistryError> {
    let options = SetOptions::default();
    Ok(entry
        .build_direction(&DirectionRequest::new(Arc::clone(brdf), &options))?
        .sampler)
}

/// The entry's disc sampler of `f_r(ωo, h⁻¹(x))`, as a subject (one-sample draws, its
/// stratified batch mode and its bound audit).
pub fn build_disc(
    entry: &SamplerEntry,
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
) -> Result<Arc<dyn SamplerUnderTest<Point2>>, RegistryError> {
    Ok(Arc::new(QuadTreePlanar(entry.build_disc(brdf, wo)?)))
}

/// The registry's `quadtree-disc` sampler (the base of the disc mutants).
pub fn quadtree_disc_sampler(
    brdf: &Arc<dyn Brdf>,
    wo: &Vec3,
) -> Result<DiscSampler, RegistryError> {
    samplers::find("quadtree-disc")?.build_disc(brdf, wo)
}

/// The cases of a standalone (environment-map or grid) entry; `None` for BRDF samplers.
pub fn standalone_cases(
    entry: &SamplerEntry,
) -> Option<Result<Vec<StandaloneCase>, RegistryError>> {
    match entry.constructor {
        Constructor::EnvMap(_) => Some(envmap_cases(entry)),
        Constructor::Grid(_) => Some(grid_cases(entry)),
        _ => None,
    }
}

/// The maps the environment-map samplers are tested on.
pub fn test_maps() -> Result<Vec<(String, EnvMap)>, RegistryError> {
    Ok(vec![
        (
            "map:procedural-sky-128x64".into(),
            envmap::procedural_sky(128, 64)?,
        ),
        ("map:synthetic-16x8".into(), synthetic_map()?),
    ])
}

fn envmap_cases(entry: &SamplerEntry) -> Result<Vec<StandaloneCase>, RegistryError> {
    test_maps()?
        .into_iter()
        .map(|(target, map)| {
            let s = entry.build_envmap(&map, &AdaptiveOptions::default())?;
            Ok(StandaloneCase {
                target,
                subject: envmap_subject(Arc::new(EnvMapPlanar(s)), &map),
            })
        })
        .collect()
}

fn grid_cases(entry: &SamplerEntry) -> Result<Vec<StandaloneCase>, RegistryError> {
    let (w, h) = (16, 8);
    let values = synthetic_values(w, h, 2);
    let table = entry.build_grid(w, h, values.clone(), Rect::UNIT)?;
    Ok(vec![StandaloneCase {
        target: "grid:synthetic-16x8".into(),
        subject: grid_subject(Arc::new(PlainPlanar(table)), w, h, values),
    }])
}
