//! Versioned binary persistence of a [`QuadTreeSet`].
//!
//! Layout: `b"BRQS"`, [`SET_FORMAT_VERSION`] as little-endian `u32`, then the postcard encoding
//! of the set: BRDF spec and name, 32 probe values of the BRDF, variant, options, layout, build
//! evaluation count, each slice's [`DiscMap`], normalisation factor and zero floor, and every tree in partition-sampler's own versioned format
//! ([`partition_sampler::FORMAT_VERSION`]). The BRDF itself is not stored: it is re-attached on
//! load, which checks that the spec string matches and that the BRDF reproduces the probes
//! (relative 1e-9).

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use brdf::{Brdf, direction_from_angles};
use partition_sampler::{Domain, QuadTree, QuadTreeSampler};
use serde::{Deserialize, Serialize};

use crate::disc::{DiscBrdf, DiscMap, SliceDensity};
use crate::error::SetFileError;
use crate::layout::SliceLayout;
use crate::options::SetOptions;
use crate::options::Variant;
use crate::set::{QuadTreeSet, SliceNorm, layout_for};

/// Version of the stored set format; bumped on any incompatible change.
pub const SET_FORMAT_VERSION: u32 = 5;

const MAGIC: &[u8; 4] = b"BRQS";

/// Relative tolerance of the BRDF probe check on load.
const PROBE_TOLERANCE: f64 = 1e-9;

/// The bytes of the file at `path` (a failure as [`SetFileError::Io`]), for every stored set's
/// `load`.
pub(crate) fn read_set_file(path: &Path) -> Result<Vec<u8>, SetFileError> {
    std::fs::read(path).map_err(|source| SetFileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Largest accepted estimate of a loaded slice's mean rejection trials per sample (its leaves'
/// summed envelope volume over the density at the leaf centres times the leaf areas). Built
/// sets stay in the single digits (a few hundred for slices of absurd BRDFs, e.g. a MERL
/// table with 1e38 spikes); a stored tree that does not fit the density (edited bounds, map or
/// floor) goes far beyond and would make each sample run up to
/// `partition_sampler::MAX_TRIALS_PER_SAMPLE` trials.
pub const MAX_LOADED_MEAN_TRIALS: f64 = 1e4;

#[derive(Serialize, Deserialize)]
struct Stored {
    head: StoredHead,
    variant: Variant,
    options: SetOptions,
    layout: SliceLayout,
    grid_evaluations: u64,
    maps: Vec<DiscMap>,
    norms: Vec<SliceNorm>,
    /// Zero floor of each slice's density ([`crate::SUPPORT_FLOOR`]).
    floors: Vec<f64>,
    trees: Vec<Vec<u8>>,
}

/// The fields every stored set's payload starts with: the BRDF spec it was built from, the
/// BRDF's name and its [`probes`]. Postcard writes a nested struct as its fields in order, so
/// a payload holds them exactly as if they were inline.
#[derive(Serialize, Deserialize)]
pub(crate) struct StoredHead {
    /// The BRDF spec (trimmed).
    pub(crate) spec: String,
    brdf_name: String,
    probes: Vec<f64>,
}

impl StoredHead {
    /// The head of a set of `brdf` built from `spec`.
    pub(crate) fn new(spec: String, brdf: &dyn Brdf) -> Self {
        Self {
            spec,
            brdf_name: brdf.name().to_string(),
            probes: probes(brdf),
        }
    }
}

/// `f_r` at 32 fixed direction pairs (half of them near the mirror direction).
pub(crate) fn probes(brdf: &dyn Brdf) -> Vec<f64> {
    (0..32u32)
        .map(|k| {
            let to = 3.0 + f64::from((k * 37) % 84);
            let po = f64::from((k * 101) % 360);
            let wo = direction_from_angles(to, po);
            let wi = if k % 2 == 0 {
                direction_from_angles(to + 0.7, po + 181.3)
            } else {
                direction_from_angles(2.0 + f64::from((k * 53) % 86), f64::from((k * 211) % 360))
            };
            brdf.eval(&wo, &wi)
        })
        .collect()
}

fn decode(bytes: &[u8]) -> Result<Stored, SetFileError> {
    decode_payload(payload(bytes, MAGIC, SET_FORMAT_VERSION)?)
}

/// The payload of `bytes` after the header `magic` + `version` (little-endian `u32`).
pub(crate) fn payload<'a>(
    bytes: &'a [u8],
    magic: &[u8; 4],
    version: u32,
) -> Result<&'a [u8], SetFileError> {
    let (Some(found_magic), Some(found)) = (bytes.get(0..4), bytes.get(4..8)) else {
        return Err(SetFileError::Truncated);
    };
    if found_magic != magic {
        return Err(SetFileError::BadMagic);
    }
    let found = u32::from_le_bytes([found[0], found[1], found[2], found[3]]);
    if found != version {
        return Err(SetFileError::UnsupportedVersion {
            found,
            expected: version,
        });
    }
    Ok(&bytes[8..])
}

/// The postcard decoding of a payload (a short one is [`SetFileError::Truncated`]).
pub(crate) fn decode_payload<T: serde::de::DeserializeOwned>(
    payload: &[u8],
) -> Result<T, SetFileError> {
    postcard::from_bytes(payload).map_err(|e| match e {
        postcard::Error::DeserializeUnexpectedEnd => SetFileError::Truncated,
        other => SetFileError::Decode(other.to_string()),
    })
}

/// `magic`, `version` and the postcard encoding of `stored`.
pub(crate) fn encode<T: Serialize>(magic: &[u8; 4], version: u32, stored: &T) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    // Serialising plain data into a Vec cannot fail.
    if let Ok(payload) = postcard::to_allocvec(stored) {
        out.extend_from_slice(&payload);
    }
    out
}

/// The checks every stored set's `from_bytes` starts with, in this order: the given `spec`
/// (trimmed) is the one in the stored `head` ([`SetFileError::SpecMismatch`]), `brdf` reproduces the stored
/// probe values ([`check_probes`]) and the stored options validate (`options`, the result of
/// their `validate()`; [`SetFileError::Corrupt`]). Shared by [`QuadTreeSet::from_bytes`] and
/// [`crate::ExactSet::from_bytes`].
pub(crate) fn check_stored<E: std::fmt::Display>(
    head: &StoredHead,
    spec: &str,
    brdf: &dyn Brdf,
    options: Result<(), E>,
) -> Result<(), SetFileError> {
    if head.spec != spec.trim() {
        return Err(SetFileError::SpecMismatch {
            stored: head.spec.clone(),
            given: spec.trim().to_string(),
        });
    }
    check_probes(&head.probes, brdf)?;
    options.map_err(|e| SetFileError::Corrupt(format!("options: {e}")))
}

/// Checks that `brdf` reproduces the `stored` probe values ([`probes`], relative
/// [`PROBE_TOLERANCE`]).
pub(crate) fn check_probes(stored: &[f64], brdf: &dyn Brdf) -> Result<(), SetFileError> {
    let found = probes(brdf);
    for (probe, (&a, &b)) in stored.iter().zip(&found).enumerate() {
        let ok = a == b || (a - b).abs() <= PROBE_TOLERANCE * a.abs().max(b.abs());
        if !ok {
            return Err(SetFileError::BrdfMismatch {
                name: brdf.name().to_string(),
                probe,
                stored: a,
                found: b,
            });
        }
    }
    if stored.len() != found.len() {
        return Err(SetFileError::Corrupt(format!(
            "{} probes, expected {}",
            stored.len(),
            found.len()
        )));
    }
    Ok(())
}

/// `Σ volume / Σ f(centre) · area` over the leaves: the mean trials per sample if the density
/// were its value at each leaf's centre (infinite when it vanishes at every centre).
pub(crate) fn estimated_mean_trials(s: &QuadTreeSampler<SliceDensity>) -> f64 {
    use partition_sampler::Density;
    let (mut volume, mut mass) = (0.0, 0.0);
    for leaf in s.tree().leaves() {
        volume += leaf.volume;
        mass += s.density().eval(leaf.rect.center()).max(0.0) * leaf.rect.area();
    }
    if mass > 0.0 {
        volume / mass
    } else {
        f64::INFINITY
    }
}

impl QuadTreeSet {
    /// Encodes the set: header (magic, version) + postcard payload (see the module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let stored = Stored {
            head: StoredHead::new(self.spec.clone(), self.brdf.as_ref()),
            variant: self.variant,
            options: self.options,
            layout: self.locator.layout(),
            grid_evaluations: self.grid_evaluations,
            maps: self.trees.iter().map(|t| t.density().map()).collect(),
            norms: self.norms.clone(),
            floors: self
                .trees
                .iter()
                .map(|t| t.density().disc_brdf().zero_floor())
                .collect(),
            trees: self.trees.iter().map(|t| t.tree().to_bytes()).collect(),
        };
        encode(MAGIC, SET_FORMAT_VERSION, &stored)
    }

    /// The BRDF spec recorded in stored bytes (to parse the BRDF before
    /// [`QuadTreeSet::from_bytes`]).
    pub fn stored_spec(bytes: &[u8]) -> Result<String, SetFileError> {
        decode(bytes).map(|s| s.head.spec)
    }

    /// Decodes a set written by [`QuadTreeSet::to_bytes`] and re-attaches `brdf`.
    ///
    /// Errors: [`SetFileError::Truncated`], [`SetFileError::BadMagic`],
    /// [`SetFileError::UnsupportedVersion`], [`SetFileError::Decode`],
    /// [`SetFileError::Corrupt`] (inconsistent layout or options),
    /// [`SetFileError::SpecMismatch`] (`spec` differs from the stored one after trimming),
    /// [`SetFileError::BrdfMismatch`] (the BRDF does not reproduce the stored probe values),
    /// [`SetFileError::Tree`] / [`SetFileError::Attach`] for a bad tree.
    pub fn from_bytes(bytes: &[u8], brdf: Arc<dyn Brdf>, spec: &str) -> Result<Self, SetFileError> {
        let s = decode(bytes)?;
        check_stored(&s.head, spec, brdf.as_ref(), s.options.validate())?;
        if layout_for(brdf.as_ref(), &s.options) != s.layout
            || s.layout.len() != s.trees.len()
            || s.maps.len() != s.trees.len()
            || s.norms.len() != s.trees.len()
            || s.floors.len() != s.trees.len()
        {
            return Err(SetFileError::Corrupt(format!(
                "layout {} × {} with {} trees and {} maps does not fit the options and the BRDF's isotropy",
                s.layout.theta,
                s.layout.phi,
                s.trees.len(),
                s.maps.len()
            )));
        }
        if let Some(slice) = s
            .norms
            .iter()
            .position(|n| !(n.factor.is_finite() && n.factor > 0.0))
        {
            return Err(SetFileError::Corrupt(format!(
                "slice {slice}: invalid normalisation factor"
            )));
        }
        let mut trees = Vec::with_capacity(s.trees.len());
        for (slice, raw) in s.trees.iter().enumerate() {
            let tree =
                QuadTree::from_bytes(raw).map_err(|source| SetFileError::Tree { slice, source })?;
            if tree.domain() != Domain::UnitDisc || tree.params().scheme != s.variant_scheme() {
                return Err(SetFileError::Corrupt(format!(
                    "slice {slice}: wrong domain or scheme"
                )));
            }
            let shape = *tree.shape();
            let map = s.maps.get(slice).copied().unwrap_or_default();
            let floor = s.floors[slice];
            if !(floor.is_finite() && floor >= 0.0) {
                return Err(SetFileError::Corrupt(format!(
                    "slice {slice}: invalid zero floor"
                )));
            }
            let f = DiscBrdf::with_map(Arc::clone(&brdf), s.layout.direction_of(slice), map)
                .with_zero_floor(floor);
            let sampler = QuadTreeSampler::from_parts(tree, SliceDensity { f, shape })
                .map_err(|source| SetFileError::Attach { slice, source })?;
            let trials = estimated_mean_trials(&sampler);
            if !(trials <= MAX_LOADED_MEAN_TRIALS) {
                return Err(SetFileError::Corrupt(format!(
                    "slice {slice}: the stored bounds are {trials:.3e} times the density at the \
                     leaf centres (more than {MAX_LOADED_MEAN_TRIALS:e}): the tree does not fit \
                     the BRDF, its disc map or its floor"
                )));
            }
            trees.push(sampler);
        }
        Ok(QuadTreeSet {
            brdf,
            spec: s.head.spec,
            variant: s.variant,
            options: s.options,
            locator: crate::layout::SliceLocator::new(s.layout),
            trees,
            norms: s.norms,
            build_time: Duration::ZERO,
            grid_evaluations: s.grid_evaluations,
            counters: partition_sampler::AuditCounters::new(),
        })
    }

    /// Writes [`QuadTreeSet::to_bytes`] to `path`.
    pub fn save(&self, path: &Path) -> Result<(), SetFileError> {
        std::fs::write(path, self.to_bytes()).map_err(|source| SetFileError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads a set from `path` and re-attaches `brdf` (see [`QuadTreeSet::from_bytes`]).
    pub fn load(path: &Path, brdf: Arc<dyn Brdf>, spec: &str) -> Result<Self, SetFileError> {
        Self::from_bytes(&read_set_file(path)?, brdf, spec)
    }
}

impl Stored {
    fn variant_scheme(&self) -> partition_sampler::Scheme {
        match self.variant {
            Variant::Adaptive => partition_sampler::Scheme::Envelope,
            Variant::Paper => partition_sampler::Scheme::Paper,
        }
    }
}
