//! MERL measured BRDFs (Matusik, Pfister, Brand & McMillan 2003): reader, standard lookup and
//! writer for the binary format.
//!
//! **Format.** Three little-endian `i32` dims `(90, 90, 180)` (product 1,458,000), then
//! `3 × 1,458,000` little-endian `f64`, channel-major (all R, then G, then B); file size
//! 34,992,012 bytes. Cell `(θh_i, θd_i, φd_i)` is at `idx = φd_i + 180 θd_i + 180·90 θh_i`, channel
//! `c` at `c·1,458,000 + idx`. Stored values times the channel scales `(1, 1.15, 1.66)/1500` give
//! `f_r` in 1/sr (not `f_r cos`).
//!
//! **Lookup** (nearest bin, as in MERL's `BRDFRead.cpp` and pbrt): half vector
//! `h = (ωi+ωo)/|ωi+ωo|`, `θh = acos h_z`, `φh = atan2(h_y, h_x)`; the difference vector is `ωi`
//! rotated about z by `−φh` then about y by `−θh`; `θd = acos d_z`, `φd = atan2(d_y, d_x)`.
//! Indices: `θh_i = ⌊√(θh/(π/2))·90⌋` (non-linear; 0 for `θh ≤ 0`), `θd_i = ⌊θd/(π/2)·90⌋`,
//! `φd_i = ⌊φd'/π·180⌋` with `φd' = φd + π` when `φd < 0` (reciprocity + isotropy fold); all
//! clamped to the table. `φh` is ignored (isotropy).
//!
//! **Unmeasured cells.** Negative stored values mark cells that were not measured. Policy:
//! [`MerlBrdf::eval_rgb`](crate::Brdf::eval_rgb) clamps each channel to `max(0, v)` (pbrt's
//! choice), so every consumer sees one identical non-negative `f_r`;
//! [`MerlBrdf::is_measured`] and [`MerlBrdf::unmeasured_count`] expose the flags, and
//! [`MerlBrdf::lookup_raw_rgb`] returns the signed scaled value.

use crate::brdf::{Brdf, luminance};
use crate::geometry::{Vec3, both_above, rotate_y};
use crate::models::Properties;
use std::f64::consts::{FRAC_PI_2, PI};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

/// Number of θh bins.
pub const RES_THETA_H: usize = 90;
/// Number of θd bins.
pub const RES_THETA_D: usize = 90;
/// Number of φd bins (half range, reciprocity fold).
pub const RES_PHI_D: usize = 180;
/// Cells per channel: 90·90·180 = 1,458,000.
pub const CELLS: usize = RES_THETA_H * RES_THETA_D * RES_PHI_D;
/// Header bytes (three `i32`).
pub const HEADER_BYTES: usize = 12;
/// Exact file size: 12 + 3·1,458,000·8 = 34,992,012 bytes.
pub const FILE_BYTES: usize = HEADER_BYTES + 3 * CELLS * 8;
/// Channel scales turning stored values into `f_r` (1/sr): R 1/1500, G 1.15/1500, B 1.66/1500.
pub const CHANNEL_SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// Errors reading or writing a MERL file.
#[derive(Debug, Error)]
pub enum MerlError {
    /// Filesystem error.
    #[error("MERL file {path}: {source}")]
    Io {
        /// File involved.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The header dims do not multiply to 1,458,000 (or one is ≤ 0).
    #[error("MERL header dims {dims:?} multiply to {product}, expected {CELLS} (90·90·180)")]
    DimsProduct {
        /// Header dims.
        dims: [i32; 3],
        /// Their product.
        product: i64,
    },
    /// The dims multiply to 1,458,000 but are not `(90, 90, 180)`, the layout the lookup assumes.
    #[error("MERL header dims {dims:?} are not (90, 90, 180)")]
    WrongDims {
        /// Header dims.
        dims: [i32; 3],
    },
    /// The file ends before the header or the data are complete.
    #[error("MERL data truncated: {actual} bytes, expected {expected}")]
    Truncated {
        /// Bytes required.
        expected: usize,
        /// Bytes present.
        actual: usize,
    },
    /// The file has trailing bytes after the data.
    #[error("MERL file has the wrong size: {actual} bytes, expected {expected}")]
    WrongSize {
        /// Bytes required.
        expected: usize,
        /// Bytes present.
        actual: usize,
    },
    /// A stored value is NaN or infinite.
    #[error("MERL value at channel {channel}, cell {index} is not finite ({value})")]
    NonFinite {
        /// Channel (0 R, 1 G, 2 B).
        channel: usize,
        /// Flat cell index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A raw table handed to [`MerlBrdf::from_raw`] has the wrong length.
    #[error("raw MERL table has {actual} values, expected {expected}")]
    RawLength {
        /// Values required (3·1,458,000).
        expected: usize,
        /// Values given.
        actual: usize,
    },
}

/// Bin of the MERL table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MerlIndex {
    /// θh bin, `0..90` (non-linear).
    pub theta_h: usize,
    /// θd bin, `0..90`.
    pub theta_d: usize,
    /// φd bin, `0..180`.
    pub phi_d: usize,
}

impl MerlIndex {
    /// Flat index `φd_i + 180 θd_i + 180·90 θh_i` (within one channel).
    pub fn flat(&self) -> usize {
        self.phi_d + RES_PHI_D * self.theta_d + RES_PHI_D * RES_THETA_D * self.theta_h
    }

    /// Inverse of [`flat`](Self::flat) (the index is reduced modulo [`CELLS`]).
    pub fn from_flat(flat: usize) -> Self {
        let flat = flat % CELLS;
        Self {
            theta_h: flat / (RES_PHI_D * RES_THETA_D),
            theta_d: (flat / RES_PHI_D) % RES_THETA_D,
            phi_d: flat % RES_PHI_D,
        }
    }
}

/// Rusinkiewicz half/difference angles `(θh, θd, φd)` of a direction pair (radians,
/// `φd ∈ (−π, π]`), computed as in MERL's reference code with `ωi` as the "in" direction.
pub fn half_diff_angles(wo: &Vec3, wi: &Vec3) -> (f64, f64, f64) {
    half_diff_angles_with(wo, wi, f64::acos, f64::atan2)
}

/// [`half_diff_angles`] with the given `acos` and `atan2`.
#[inline(always)]
fn half_diff_angles_with(
    wo: &Vec3,
    wi: &Vec3,
    acos: impl Fn(f64) -> f64,
    atan2: impl Fn(f64, f64) -> f64,
) -> (f64, f64, f64) {
    let h = (wo + wi).normalize();
    let cos_h = h.z.clamp(-1.0, 1.0);
    let theta_h = acos(cos_h);
    // d = R_y(−θh) R_z(−φh) ωi, with (cos φh, sin φh) = (h.x, h.y)/r and sin θh = r: no
    // trigonometry but the two angles returned (φh = 0 when h is the normal).
    let r = (h.x * h.x + h.y * h.y).sqrt();
    let (cos_p, sin_p) = if r > 0.0 {
        (h.x / r, h.y / r)
    } else {
        (1.0, 0.0)
    };
    let x = cos_p * wi.x + sin_p * wi.y;
    let y = cos_p * wi.y - sin_p * wi.x;
    let d = Vec3::new(cos_h * x - r * wi.z, y, r * x + cos_h * wi.z);
    (theta_h, acos(d.z.clamp(-1.0, 1.0)), atan2(d.y, d.x))
}

/// Inverse of [`half_diff_angles`] with `φh = 0`: returns `(wo, wi)`. Either may lie below the
/// horizon for some angle triples.
pub fn half_diff_to_directions(theta_h: f64, theta_d: f64, phi_d: f64) -> (Vec3, Vec3) {
    let (sd, cd) = theta_d.sin_cos();
    let (sp, cp) = phi_d.sin_cos();
    let d = Vec3::new(sd * cp, sd * sp, cd);
    let wi = rotate_y(&d, theta_h);
    let h = Vec3::new(theta_h.sin(), 0.0, theta_h.cos());
    let wo = 2.0 * h.dot(&wi) * h - wi;
    (wo, wi)
}

/// Table bin of half/difference angles (standard MERL nearest lookup, clamped).
pub fn index_from_angles(theta_h: f64, theta_d: f64, phi_d: f64) -> MerlIndex {
    let th = if theta_h > 0.0 {
        ((theta_h / FRAC_PI_2).sqrt() * RES_THETA_H as f64) as usize
    } else {
        0
    };
    let td = if theta_d > 0.0 {
        (theta_d / FRAC_PI_2 * RES_THETA_D as f64) as usize
    } else {
        0
    };
    let p = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    let pd = if p > 0.0 {
        (p / PI * RES_PHI_D as f64) as usize
    } else {
        0
    };
    MerlIndex {
        theta_h: th.min(RES_THETA_H - 1),
        theta_d: td.min(RES_THETA_D - 1),
        phi_d: pd.min(RES_PHI_D - 1),
    }
}

/// Table bin of a direction pair: [`index_from_angles`] of [`half_diff_angles`], bit for bit.
///
/// The angles are computed with the `libm` crate's `acos` and `atan2` (FreeBSD's msun, errors
/// below 1 ulp; per call `acos` 51 instructions against glibc's 78, `atan2` 104 against 142,
/// cachegrind, docs/benchmarks.md §20.8). Two
/// sub-ulp-accurate angles lie within a few 1e-16 of each other, so they fall in the same bin
/// unless one lies within [`EDGE_MARGIN`] (in bin units) of a bin edge, the fold at `φd = 0`
/// or the table's ends: there the `std` angles decide, so the bin is always the one of
/// [`half_diff_angles`].
pub fn index_of(wo: &Vec3, wi: &Vec3) -> MerlIndex {
    let (th, td, pd) = half_diff_angles_with(wo, wi, libm::acos, libm::atan2);
    let fast = [
        bin_position(th, Axis::ThetaH),
        bin_position(td, Axis::ThetaD),
        bin_position(fold_phi_d(pd), Axis::PhiD),
    ];
    if fast.iter().any(|x| !(x.is_finite() && off_edge(*x))) {
        let (th, td, pd) = half_diff_angles(wo, wi);
        return index_from_angles(th, td, pd);
    }
    MerlIndex {
        theta_h: (fast[0] as usize).min(RES_THETA_H - 1),
        theta_d: (fast[1] as usize).min(RES_THETA_D - 1),
        phi_d: (fast[2] as usize).min(RES_PHI_D - 1),
    }
}

/// Distance (in bins) from a bin edge below which [`index_of`] recomputes the angles with
/// `std`: 1e-9, far above the ~1e-13 two sub-ulp angles can differ by in bin units.
pub const EDGE_MARGIN: f64 = 1e-9;

#[derive(Clone, Copy)]
enum Axis {
    ThetaH,
    ThetaD,
    PhiD,
}

/// The unclamped, unfloored bin coordinate of [`index_from_angles`] (same operations).
#[inline]
fn bin_position(angle: f64, axis: Axis) -> f64 {
    match axis {
        Axis::ThetaH => (angle / FRAC_PI_2).sqrt() * RES_THETA_H as f64,
        Axis::ThetaD => angle / FRAC_PI_2 * RES_THETA_D as f64,
        Axis::PhiD => angle / PI * RES_PHI_D as f64,
    }
}

/// The `φd` fold of [`index_from_angles`].
#[inline]
fn fold_phi_d(phi_d: f64) -> f64 {
    if phi_d < 0.0 { phi_d + PI } else { phi_d }
}

/// `x` (≥ 0) lies at least [`EDGE_MARGIN`] from every integer (the bin edges, 0 and the
/// table's end included) and below 2^52 (so that its fraction is exact).
#[inline]
fn off_edge(x: f64) -> bool {
    if !(0.0..4.0e15).contains(&x) {
        return false;
    }
    let f = x - (x as u64) as f64;
    f > EDGE_MARGIN && f < 1.0 - EDGE_MARGIN
}

/// Centre of a bin in angle space: `θh = (π/2)((i+½)/90)²`, `θd = (j+½)(π/2)/90`,
/// `φd = (k+½)π/180`.
pub fn bin_center(index: MerlIndex) -> (f64, f64, f64) {
    let x = (index.theta_h as f64 + 0.5) / RES_THETA_H as f64;
    (
        FRAC_PI_2 * x * x,
        (index.theta_d as f64 + 0.5) * FRAC_PI_2 / RES_THETA_D as f64,
        (index.phi_d as f64 + 0.5) * PI / RES_PHI_D as f64,
    )
}

/// A MERL BRDF held in memory: per cell the scaled RGB `f_r` (negative = unmeasured).
#[derive(Clone)]
pub struct MerlBrdf {
    cells: Vec<[f64; 3]>,
    unmeasured: usize,
    source: Option<PathBuf>,
}

impl std::fmt::Debug for MerlBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MerlBrdf")
            .field("cells", &self.cells.len())
            .field("unmeasured", &self.unmeasured)
            .field("source", &self.source)
            .finish()
    }
}

impl MerlBrdf {
    /// Read and validate a MERL binary file.
    pub fn load(path: &Path) -> Result<Self, MerlError> {
        let bytes = fs::read(path).map_err(|source| MerlError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut m = Self::from_bytes(&bytes)?;
        m.source = Some(path.to_path_buf());
        Ok(m)
    }

    /// Parse and validate the bytes of a MERL file (dims, size, finiteness).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, MerlError> {
        let Some(header) = bytes.get(..HEADER_BYTES) else {
            return Err(MerlError::Truncated {
                expected: HEADER_BYTES,
                actual: bytes.len(),
            });
        };
        let mut dims = [0i32; 3];
        for (d, chunk) in dims.iter_mut().zip(header.chunks_exact(4)) {
            *d = i32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
        }
        let product = dims.iter().map(|&d| d as i64).product::<i64>();
        if dims.iter().any(|&d| d <= 0) || product != CELLS as i64 {
            return Err(MerlError::DimsProduct { dims, product });
        }
        if dims != [RES_THETA_H as i32, RES_THETA_D as i32, RES_PHI_D as i32] {
            return Err(MerlError::WrongDims { dims });
        }
        if bytes.len() < FILE_BYTES {
            return Err(MerlError::Truncated {
                expected: FILE_BYTES,
                actual: bytes.len(),
            });
        }
        if bytes.len() > FILE_BYTES {
            return Err(MerlError::WrongSize {
                expected: FILE_BYTES,
                actual: bytes.len(),
            });
        }
        Self::from_channel_major(bytes[HEADER_BYTES..].chunks_exact(8).map(|chunk| {
            let mut b = [0u8; 8];
            b.copy_from_slice(chunk);
            f64::from_le_bytes(b)
        }))
    }

    /// Build from the raw stored table: `3 × 1,458,000` unscaled values, channel-major.
    pub fn from_raw(raw: &[f64]) -> Result<Self, MerlError> {
        if raw.len() != 3 * CELLS {
            return Err(MerlError::RawLength {
                expected: 3 * CELLS,
                actual: raw.len(),
            });
        }
        Self::from_channel_major(raw.iter().copied())
    }

    /// The `3 × 1,458,000` unscaled stored values, channel-major (each one finite), scaled by
    /// channel into cells.
    fn from_channel_major(values: impl Iterator<Item = f64>) -> Result<Self, MerlError> {
        let mut cells = vec![[0.0f64; 3]; CELLS];
        for (k, v) in values.enumerate() {
            let (channel, index) = (k / CELLS, k % CELLS);
            if !v.is_finite() {
                return Err(MerlError::NonFinite {
                    channel,
                    index,
                    value: v,
                });
            }
            cells[index][channel] = v * CHANNEL_SCALE[channel];
        }
        Ok(Self::from_cells(cells))
    }

    /// Tabulate `f(θh, θd, φd) → RGB f_r` (1/sr) at every bin centre ([`bin_center`]).
    /// Negative channel values mark the cell unmeasured; non-finite values are stored as −1.
    pub fn from_fn(f: impl Fn(f64, f64, f64) -> [f64; 3]) -> Self {
        let mut cells = vec![[0.0f64; 3]; CELLS];
        for (flat, cell) in cells.iter_mut().enumerate() {
            let (th, td, pd) = bin_center(MerlIndex::from_flat(flat));
            let v = f(th, td, pd);
            for c in 0..3 {
                cell[c] = if v[c].is_finite() { v[c] } else { -1.0 };
            }
        }
        Self::from_cells(cells)
    }

    /// Tabulate an analytic model: each bin centre is converted to `(ωo, ωi)` with
    /// [`half_diff_to_directions`]; configurations with a direction at or below the horizon are
    /// stored as unmeasured (−1), like the grazing gaps of real MERL data.
    pub fn tabulate(brdf: &(impl Brdf + ?Sized)) -> Self {
        Self::from_fn(|th, td, pd| {
            let (wo, wi) = half_diff_to_directions(th, td, pd);
            if both_above(&wo, &wi) {
                brdf.eval_rgb(&wo, &wi)
            } else {
                [-1.0; 3]
            }
        })
    }

    fn from_cells(cells: Vec<[f64; 3]>) -> Self {
        let unmeasured = cells.iter().filter(|c| c.iter().any(|&v| v < 0.0)).count();
        Self {
            cells,
            unmeasured,
            source: None,
        }
    }

    /// File this table was loaded from, if any.
    pub fn source(&self) -> Option<&Path> {
        self.source.as_deref()
    }

    /// Scaled signed RGB of one cell (negative = unmeasured).
    pub fn cell(&self, index: MerlIndex) -> [f64; 3] {
        self.cells.get(index.flat()).copied().unwrap_or([0.0; 3])
    }

    /// Scaled signed RGB looked up for a direction pair (no clamping). `[0; 3]` when either
    /// direction is at or below the horizon.
    pub fn lookup_raw_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        if !both_above(wo, wi) {
            return [0.0; 3];
        }
        self.cell(index_of(wo, wi))
    }

    /// True when all three channels of the looked-up cell were measured (are ≥ 0).
    pub fn is_measured(&self, wo: &Vec3, wi: &Vec3) -> bool {
        both_above(wo, wi) && self.cell(index_of(wo, wi)).iter().all(|&v| v >= 0.0)
    }

    /// Number of cells with at least one negative (unmeasured) channel.
    pub fn unmeasured_count(&self) -> usize {
        self.unmeasured
    }

    /// The file bytes of this table (header + channel-major raw values).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(FILE_BYTES);
        for d in [RES_THETA_H, RES_THETA_D, RES_PHI_D] {
            out.extend_from_slice(&(d as i32).to_le_bytes());
        }
        for c in 0..3 {
            for cell in &self.cells {
                out.extend_from_slice(&(cell[c] / CHANNEL_SCALE[c]).to_le_bytes());
            }
        }
        out
    }

    /// Write the table as a MERL file, atomically (temporary file in the same directory, then
    /// rename).
    pub fn write(&self, path: &Path) -> Result<(), MerlError> {
        write_atomic(path, &self.to_bytes())
    }
}

/// Tabulate `f(θh, θd, φd) → RGB f_r` at the bin centres and write it as a MERL file
/// (atomically). See [`MerlBrdf::from_fn`].
pub fn write_merl(path: &Path, f: &dyn Fn(f64, f64, f64) -> [f64; 3]) -> Result<(), MerlError> {
    MerlBrdf::from_fn(f).write(path)
}

static TMP_COUNTER: AtomicUsize = AtomicUsize::new(0);

/// Write `bytes` to `path` via a temporary sibling file and a rename.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), MerlError> {
    let io = |source| MerlError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let file = fs::File::create(&tmp)?;
        let mut w = BufWriter::new(file);
        w.write_all(bytes)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io)
}

impl MerlBrdf {
    /// Isotropic, half-turn symmetric and reciprocal: the lookup depends on `(θh, θd, φd)` only,
    /// which a common rotation about the normal leaves unchanged, and the `φd` fold maps
    /// `(ωo, ωi)` and `(ωi, ωo)` to the same bin (up to rounding at bin edges). Not
    /// mirror-symmetric: the fold identifies `φd` with `φd + π`, not with `−φd`.
    pub fn properties(&self) -> Properties {
        Properties::ISOTROPIC | Properties::HALF_TURN_SYMMETRIC | Properties::RECIPROCAL
    }
}

impl Brdf for MerlBrdf {
    /// Luminance of [`eval_rgb`](Brdf::eval_rgb).
    #[inline]
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        luminance(self.eval_rgb(wo, wi))
    }
    /// Nearest-bin RGB with each channel clamped to `max(0, v)` (unmeasured cells read as 0).
    #[inline]
    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        let c = self.lookup_raw_rgb(wo, wi);
        [c[0].max(0.0), c[1].max(0.0), c[2].max(0.0)]
    }
    crate::models::brdf_properties!("merl");
    /// For [`MerlBrdf::albedo_in_bins`] (the exact sampler's normaliser, issue 27).
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(wo: &Vec3, wi: &Vec3) -> MerlIndex {
        let (th, td, pd) = half_diff_angles(wo, wi);
        index_from_angles(th, td, pd)
    }

    /// `index_of` (the `libm` angles with the `std` fallback near bin edges) is the bin of the
    /// `std` angles on 10⁵ random pairs (fixed seed) and on pairs built at every bin edge of
    /// each axis, a few ulps either side.
    #[test]
    fn index_of_is_the_std_bin_at_random_and_at_edges() {
        let mut uniform = crate::test_support::splitmix_uniforms(0x2545_f491_4f6c_dd1d_u64);
        let dir = |u: f64, v: f64| {
            let z = u.max(1e-9);
            let s = (1.0 - z * z).sqrt();
            let p = std::f64::consts::TAU * v;
            Vec3::new(s * p.cos(), s * p.sin(), z)
        };
        let mut pairs = Vec::new();
        for _ in 0..100_000 {
            let (a, b, c, d) = (uniform(), uniform(), uniform(), uniform());
            pairs.push((dir(a, b), dir(c, d)));
        }
        // Bin edges of each axis (and the fold at φd = 0, ±π), nudged by −3..=3 ulps, the other
        // two angles at bin centres.
        let nudge = |x: f64, k: i64| f64::from_bits((x.to_bits() as i64 + k).max(0) as u64);
        let mid = bin_center(MerlIndex {
            theta_h: 20,
            theta_d: 30,
            phi_d: 50,
        });
        for k in 0..=RES_THETA_D {
            let th_edge = FRAC_PI_2 * (k as f64 / 90.0).powi(2);
            let td_edge = k as f64 * FRAC_PI_2 / 90.0;
            for n in -3..=3 {
                for (th, td, pd) in [
                    (nudge(th_edge, n), mid.1, mid.2),
                    (mid.0, nudge(td_edge, n), mid.2),
                ] {
                    let (wo, wi) = half_diff_to_directions(th, td, pd);
                    pairs.push((wo, wi));
                }
            }
        }
        for k in 0..=2 * RES_PHI_D {
            let pd_edge = k as f64 * PI / 180.0 - PI;
            for n in -3..=3 {
                let (wo, wi) = half_diff_to_directions(mid.0, mid.1, pd_edge + n as f64 * 1e-16);
                pairs.push((wo, wi));
            }
        }
        let mut mismatches = 0;
        for (wo, wi) in &pairs {
            if index_of(wo, wi) != reference(wo, wi) {
                mismatches += 1;
            }
        }
        assert_eq!(mismatches, 0, "{mismatches} of {} bins differ", pairs.len());
    }
}
