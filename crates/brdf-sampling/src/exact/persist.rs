//! Versioned binary persistence of an [`ExactSet`] (`brdf-lab build --out`, `--set FILE`), so
//! that a costly build is paid once.
//!
//! Layout: `b"BRQE"`, [`EXACT_FORMAT_VERSION`] as little-endian `u32`, then the postcard encoding
//! of: the BRDF spec and name, 32 probe values of the BRDF (as the quadtree sets,
//! `crate::persist`), the options, the build's time, and per azimuth cell its intervals: θ and δ
//! numerators (see `Grid`), normaliser table (nodes and values of `A · cos θo`), the
//! quadrature's error estimate, the build's evaluation count, the tree in partition-sampler's
//! own versioned format ([`partition_sampler::FORMAT_VERSION`]) and the leaves' thinning bounds
//! (16 codes per leaf in the tree's leaf order, per θo layer, and the layers' inner edges; or none;
//! version 2, §30.1; version 3: the layers, §30.6; version 4: the options' `thinning_growth` and
//! `thinning_rigorous`, §31.3 — a version-3 file would otherwise fail to decode its options;
//! version 5: the one-layer codes' served bounds per leaf, an `f32` each or none, §32.1).
//!
//! The BRDF is not stored: it is re-attached on load, which checks that the spec matches and
//! that the BRDF reproduces the probes. The set's grid, cells, table variable and azimuth
//! period are derived again from the BRDF and the options, each interval's disc map and bound
//! nodes from its numerators, and the cells' search tables from the numerators (which must tile
//! every cell), all by the build's own code: a loaded set draws the same samples per seed as the
//! one that was saved.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use brdf::Brdf;
use partition_sampler::{AuditCounters, Domain, QuadTree, QuadTreeSampler};
use serde::{Deserialize, Serialize};

use crate::disc::SliceDensity;
use crate::error::SetFileError;
use crate::persist::{
    MAX_LOADED_MEAN_TRIALS, StoredHead, check_stored, decode_payload, encode,
    estimated_mean_trials, payload, read_set_file,
};

use super::build::Plan;
use super::build_interval::{stored_density, worst_trials};
use super::chebyshev::ChebyshevTable;
use super::grid::EDGE_BITS;
use super::interval::Interval;
use super::jobs::{Inheritance, Job};
use super::layout::{Cell, Placed};
use super::options::{ExactOptions, THETA_TOP_DEG};
use super::set::ExactSet;
use super::table::{SUB_CELLS, SubBounds};

/// Version of the stored `adaptive-exact` format; bumped on any incompatible change.
pub const EXACT_FORMAT_VERSION: u32 = 5;

const MAGIC: &[u8; 4] = b"BRQE";

/// Most Chebyshev nodes a stored table may have along one axis (the options allow 32 θ
/// nodes; δ doubles up to 17).
const MAX_TABLE_NODES: usize = 64;

#[derive(Serialize, Deserialize)]
struct StoredExact {
    head: StoredHead,
    options: ExactOptions,
    build_seconds: f64,
    cells: Vec<Vec<StoredInterval>>,
}

#[derive(Serialize, Deserialize)]
struct StoredInterval {
    num: [u64; 2],
    dnum: [u64; 2],
    table_theta: Vec<f64>,
    table_delta: Vec<f64>,
    table_values: Vec<f64>,
    quad_err: f64,
    evaluations: u64,
    tree: Vec<u8>,
    /// The thinning bounds' codes, [`SUB_CELLS`] per leaf, layer after layer (empty: none).
    sub_bounds: Vec<u8>,
    /// The thinning layers' inner θo edges (radians; empty: one layer).
    sub_edges: Vec<f64>,
    /// The served bounds of one layer's codes, one per leaf (empty: none; [`SubBounds::tops`]).
    sub_tops: Vec<f32>,
}

impl StoredInterval {
    fn of(iv: &Interval) -> Self {
        Self {
            num: iv.num,
            dnum: iv.dnum,
            table_theta: iv.table.theta.clone(),
            table_delta: iv.table.delta.clone(),
            table_values: iv.table.values.clone(),
            quad_err: iv.quad_err,
            evaluations: iv.evaluations,
            tree: iv.tree.tree().to_bytes(),
            sub_bounds: iv
                .sub_bounds
                .as_ref()
                .map_or_else(Vec::new, |s| s.codes.as_flattened().to_vec()),
            sub_edges: iv
                .sub_bounds
                .as_ref()
                .map_or_else(Vec::new, |s| s.edges.to_vec()),
            sub_tops: iv
                .sub_bounds
                .as_ref()
                .map_or_else(Vec::new, |s| s.tops.to_vec()),
        }
    }
}

fn corrupt(what: String) -> SetFileError {
    SetFileError::Corrupt(what)
}

impl ExactSet {
    /// Encodes the set for `spec`, the BRDF spec it was built from (recorded, and checked on
    /// load): header (magic `BRQE`, [`EXACT_FORMAT_VERSION`]) + postcard payload (see the
    /// module docs).
    pub fn to_bytes(&self, spec: &str) -> Vec<u8> {
        let stored = StoredExact {
            head: StoredHead::new(spec.trim().to_string(), self.brdf.as_ref()),
            options: self.options,
            build_seconds: self.build_time.as_secs_f64(),
            cells: self
                .cells
                .iter()
                .map(|c| c.intervals.iter().map(StoredInterval::of).collect())
                .collect(),
        };
        encode(MAGIC, EXACT_FORMAT_VERSION, &stored)
    }

    /// Whether `bytes` start like a stored exact set (magic `BRQE`; the version and payload
    /// are checked by [`ExactSet::from_bytes`]).
    pub fn is_stored(bytes: &[u8]) -> bool {
        bytes.get(0..4) == Some(&MAGIC[..])
    }

    /// The BRDF spec recorded in stored bytes (to parse the BRDF before
    /// [`ExactSet::from_bytes`]).
    pub fn stored_spec(bytes: &[u8]) -> Result<String, SetFileError> {
        decode(bytes).map(|s| s.head.spec)
    }

    /// Decodes a set written by [`ExactSet::to_bytes`] and re-attaches `brdf`.
    ///
    /// Errors: [`SetFileError::Truncated`], [`SetFileError::BadMagic`] (e.g. a quadtree set's
    /// file), [`SetFileError::UnsupportedVersion`], [`SetFileError::Decode`],
    /// [`SetFileError::SpecMismatch`], [`SetFileError::BrdfMismatch`] (another BRDF),
    /// [`SetFileError::Corrupt`] (options, cells, tables or trees inconsistent with each other
    /// or with the BRDF), [`SetFileError::Tree`] / [`SetFileError::Attach`] for a bad tree (the
    /// slice number counts the intervals over all cells).
    pub fn from_bytes(bytes: &[u8], brdf: Arc<dyn Brdf>, spec: &str) -> Result<Self, SetFileError> {
        let s = decode(bytes)?;
        check_stored(&s.head, spec, brdf.as_ref(), s.options.validate())?;
        // The build's own plan (no timing: the node cache does not matter here).
        let plan = Plan::new(brdf.as_ref(), &s.options, Some(false), true);
        if s.cells.len() != plan.phis.len() {
            return Err(corrupt(format!(
                "{} azimuth cells, the options and the BRDF give {}",
                s.cells.len(),
                plan.phis.len()
            )));
        }
        let mut cells = Vec::with_capacity(s.cells.len());
        let mut slice = 0;
        for (k, stored) in s.cells.into_iter().enumerate() {
            check_tiling(&plan, k, &stored)?;
            let mut members: Vec<Placed> = Vec::with_capacity(stored.len());
            for iv in stored {
                let (num, dnum) = (iv.num, iv.dnum);
                members.push((
                    num,
                    dnum,
                    load_interval(&brdf, &s.options, &plan, k, slice, iv)?,
                ));
                slice += 1;
            }
            members.sort_by_key(|(num, dnum, _)| (num[0], dnum[0]));
            cells.push(Cell::new(plan.phis[k], members, &plan.grid, plan.var));
        }
        let build_time = Duration::try_from_secs_f64(s.build_seconds).unwrap_or_default();
        Ok(Self {
            brdf,
            options: s.options,
            isotropic: plan.isotropic,
            period: plan.period,
            cells,
            var: plan.var,
            top_cos: THETA_TOP_DEG.to_radians().cos(),
            build_time,
            counters: AuditCounters::new(),
        })
    }

    /// Writes [`ExactSet::to_bytes`] to `path` atomically (a temporary file in the same
    /// directory, renamed over `path`: a reader never sees a partial file).
    pub fn save(&self, path: &Path, spec: &str) -> Result<(), SetFileError> {
        let io = |source| SetFileError::Io {
            path: path.to_path_buf(),
            source,
        };
        let name = path
            .file_name()
            .ok_or_else(|| io(std::io::Error::other("not a file path")))?;
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.tmp", std::process::id()));
        let tmp = path.with_file_name(tmp_name);
        let written =
            std::fs::write(&tmp, self.to_bytes(spec)).and_then(|()| std::fs::rename(&tmp, path));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            return Err(io(e));
        }
        Ok(())
    }

    /// Reads a set from `path` and re-attaches `brdf` (see [`ExactSet::from_bytes`]).
    pub fn load(path: &Path, brdf: Arc<dyn Brdf>, spec: &str) -> Result<Self, SetFileError> {
        Self::from_bytes(&read_set_file(path)?, brdf, spec)
    }
}

fn decode(bytes: &[u8]) -> Result<StoredExact, SetFileError> {
    decode_payload(payload(bytes, MAGIC, EXACT_FORMAT_VERSION)?)
}

/// The stored intervals of cell `k` must tile it: numerators inside the cell, no two
/// overlapping, and their areas summing to the cell's (`Cell::new` relies on it).
fn check_tiling(plan: &Plan, k: usize, stored: &[StoredInterval]) -> Result<(), SetFileError> {
    let (theta_end, delta_end) = (plan.n0 << EDGE_BITS, 1u64 << EDGE_BITS);
    let bad = |why: &str| Err(corrupt(format!("cell {k}: {why}")));
    if stored.is_empty() {
        return bad("no intervals");
    }
    let mut area = 0u128;
    for iv in stored {
        let ([a, b], [c, d]) = (iv.num, iv.dnum);
        if !(a < b && b <= theta_end && c < d && d <= delta_end) {
            return bad("interval numerators out of range");
        }
        if plan.isotropic && (c, d) != (0, delta_end) {
            return bad("azimuth split of an isotropic set");
        }
        area += u128::from(b - a) * u128::from(d - c);
    }
    if area != u128::from(theta_end) * u128::from(delta_end) {
        return bad("the intervals do not tile the cell");
    }
    for (i, p) in stored.iter().enumerate() {
        for q in &stored[i + 1..] {
            let apart = p.num[1] <= q.num[0]
                || q.num[1] <= p.num[0]
                || p.dnum[1] <= q.dnum[0]
                || q.dnum[1] <= p.dnum[0];
            if !apart {
                return bad("overlapping intervals");
            }
        }
    }
    Ok(())
}

/// Interval `iv` of cell `k` (number `slice` over all cells) with `brdf` re-attached.
fn load_interval(
    brdf: &Arc<dyn Brdf>,
    options: &ExactOptions,
    plan: &Plan,
    k: usize,
    slice: usize,
    iv: StoredInterval,
) -> Result<Interval, SetFileError> {
    let bad = |why: String| corrupt(format!("interval {slice}: {why}"));
    let (nt, nd) = (iv.table_theta.len(), iv.table_delta.len());
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    // Chebyshev–Lobatto nodes run from the upper end down (the normaliser clamps to them).
    let non_increasing = |v: &[f64]| v.windows(2).all(|w| w[0] >= w[1]);
    if !((2..=MAX_TABLE_NODES).contains(&nt)
        && (1..=MAX_TABLE_NODES).contains(&nd)
        && (plan.isotropic == (nd == 1))
        && iv.table_values.len() == nt * nd
        && finite(&iv.table_theta)
        && finite(&iv.table_delta)
        && non_increasing(&iv.table_theta)
        && non_increasing(&iv.table_delta)
        && iv.table_values.iter().all(|v| v.is_finite() && *v > 0.0))
    {
        return Err(bad(format!(
            "normaliser table of {nt} × {nd} nodes and {} values",
            iv.table_values.len()
        )));
    }
    if !(iv.quad_err.is_finite() && iv.quad_err >= 0.0) {
        return Err(bad("invalid quadrature error".into()));
    }
    let tree =
        QuadTree::from_bytes(&iv.tree).map_err(|source| SetFileError::Tree { slice, source })?;
    if tree.domain() != Domain::UnitDisc
        || tree.params().scheme != partition_sampler::Scheme::Envelope
    {
        return Err(bad("wrong domain or scheme".into()));
    }
    let leaves = tree.leaves().len();
    let layers = iv.sub_edges.len() + 1;
    if !iv.sub_edges.is_sorted_by(|a, b| a < b) || iv.sub_edges.iter().any(|e| !e.is_finite()) {
        return Err(bad("thinning layer edges not finite and increasing".into()));
    }
    if !(iv.sub_tops.is_empty() || iv.sub_tops.len() == leaves && layers == 1)
        || iv.sub_tops.iter().any(|t| !(t.is_finite() && *t >= 0.0))
    {
        return Err(bad(
            "thinning served bounds: not one finite value per leaf".into()
        ));
    }
    let sub_bounds: Option<SubBounds> = match iv.sub_bounds.len() {
        0 => None,
        n if n == layers * leaves * SUB_CELLS => Some(SubBounds {
            codes: iv
                .sub_bounds
                .chunks_exact(SUB_CELLS)
                .map(|c| {
                    let mut a = [0u8; SUB_CELLS];
                    a.copy_from_slice(c);
                    a
                })
                .collect(),
            edges: iv.sub_edges.clone().into_boxed_slice(),
            tops: iv.sub_tops.clone().into_boxed_slice(),
        }),
        n => {
            return Err(bad(format!(
                "{n} thinning bound codes for {layers} layers of {leaves} leaves (want {})",
                layers * leaves * SUB_CELLS
            )));
        }
    };
    let job = Job {
        cell: k,
        num: iv.num,
        dnum: iv.dnum,
        inherited: Arc::new(Inheritance::default()),
    };
    let ctx = plan.context(&job);
    let (map, f) = stored_density(brdf, options, &job, &ctx);
    let shape = *tree.shape();
    let volume = tree.volume();
    let sampler = QuadTreeSampler::from_parts(tree, SliceDensity { f, shape })
        .map_err(|source| SetFileError::Attach { slice, source })?;
    let trials = estimated_mean_trials(&sampler);
    if !(trials <= MAX_LOADED_MEAN_TRIALS) {
        return Err(bad(format!(
            "the stored bounds are {trials:.3e} times the envelope at the leaf centres: the \
             tree does not fit the BRDF or its disc map"
        )));
    }
    let table = ChebyshevTable::new(iv.table_theta, iv.table_delta, iv.table_values);
    let worst = worst_trials(&table, volume, plan.var);
    if !(worst <= MAX_LOADED_MEAN_TRIALS) {
        return Err(bad(format!(
            "mean trials {worst:.3e} at a normaliser node: the table does not fit the tree"
        )));
    }
    let grid = &plan.grid;
    Ok(Interval {
        num: iv.num,
        dnum: iv.dnum,
        theta: [grid.edge(iv.num[0]), grid.edge(iv.num[1])],
        delta: ctx.delta,
        tree: sampler,
        map,
        norm_err: iv.quad_err + table.rel_tail(),
        table,
        worst_trials: worst,
        quad_err: iv.quad_err,
        evaluations: iv.evaluations,
        sub_bounds,
    })
}

#[cfg(test)]
mod compare {
    use super::*;

    /// A probe, not a check (ignored): the saved sets `SET_A` and `SET_B` (files written by
    /// `brdf-lab build --out`) are equal apart from their diagnostics — the build time and the
    /// per-interval build evaluation counts (zeroed in both, then re-encoded and compared byte
    /// for byte: options, intervals, tables, trees and thinning codes). Used to show that a
    /// change of the build's schedule or counting leaves the set as it was (docs/benchmarks.md
    /// §32.2).
    #[test]
    #[ignore = "a probe of two saved sets named by SET_A and SET_B"]
    fn saved_sets_equal_apart_from_diagnostics() {
        let read = |var: &str| {
            let path = std::env::var(var).expect("SET_A and SET_B name two saved sets");
            let mut s = decode(&std::fs::read(&path).unwrap()).unwrap();
            let evaluations: u64 = s.cells.iter().flatten().map(|iv| iv.evaluations).sum();
            s.build_seconds = 0.0;
            for iv in s.cells.iter_mut().flatten() {
                iv.evaluations = 0;
            }
            let intervals = s.cells.iter().map(Vec::len).sum::<usize>();
            (postcard::to_allocvec(&s).unwrap(), evaluations, intervals)
        };
        let ((a, ea, na), (b, eb, nb)) = (read("SET_A"), read("SET_B"));
        println!(
            "A: {na} intervals, {} bytes, {ea} evaluations; B: {nb} intervals, {} bytes, {eb} evaluations",
            a.len(),
            b.len()
        );
        assert!(a == b, "the sets differ beyond their diagnostics");
    }
}
