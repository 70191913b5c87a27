//! [`CdfSampler`]: one tabulated (or compressed) CDF per outgoing slice of a BRDF, sampled as a
//! [`DirectionSampler`] with the nearest slice.

use std::f64::consts::TAU;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use brdf::{Brdf, Vec3};
use brdf_sampling::{
    CellCoords, DirSample, DirectionSampler, PdfCellRow, PdfCells, Progress, SamplerDiagnostics,
    SetOptions, SliceLayout, SliceLocator, layout_for,
};
use distributions::UniformSource;
use rayon::prelude::*;

use super::grid::{GridShape, slice_values};
use crate::{CdfOptions, CdfOptionsError};

/// A point of one slice's `(z, φ)` domain with its density w.r.t. `dz dφ` (= solid angle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlicePoint {
    /// `z = cos θi ∈ (0, 1)`.
    pub z: f64,
    /// `φi ∈ [0, 2π)` in the slice's frame.
    pub phi: f64,
    /// Density w.r.t. `dz dφ`, i.e. w.r.t. solid angle.
    pub pdf: f64,
}

/// The per-slice distribution of a [`CdfSampler`]: built from the slice's fine cell values,
/// sampled from two uniforms, with a pdf w.r.t. `dz dφ` (= solid angle).
pub trait SliceCdf: Send + Sync + Sized {
    /// The registry name of the sampler made of these slices.
    const NAME: &'static str;
    /// Whether the CDFs are compressed (the report then states `ε`).
    const COMPRESSED: bool;

    /// The distribution of the cell values `values` (row-major `n_z × n_φ`, all positive).
    fn build(values: &[f64], shape: GridShape, options: &CdfOptions) -> Self;

    /// Warps `u ∈ [0,1)²` (`u[0]` for `z`, `u[1]` for `φ`) to a point and its density.
    fn sample(&self, shape: GridShape, u: [f64; 2]) -> SlicePoint;

    /// Density at `(z, φ)`, `z ∈ [0, 1]`, `φ ∈ [0, 2π)`, the value `sample` reports there.
    fn pdf(&self, shape: GridShape, z: f64, phi: f64) -> f64;

    /// The azimuth edges (increasing, from 0 to 2π) between which the density of fine row `row`
    /// (`z ∈ [row/n_z, (row+1)/n_z)`) is constant.
    fn phi_edges(&self, shape: GridShape, row: usize) -> Vec<f64>;

    /// Heap and inline bytes of the slice.
    fn bytes_used(&self) -> usize;

    /// CDF points stored (the uncompressed slice stores [`GridShape::cdf_points`]).
    fn stored_points(&self) -> usize;
}

/// Build report of a [`CdfSampler`].
#[derive(Debug, Clone, PartialEq)]
pub struct CdfReport {
    /// The sampler's registry name.
    pub sampler: &'static str,
    /// Outgoing slices.
    pub layout: SliceLayout,
    /// The fine grid of every slice.
    pub shape: GridShape,
    /// Evaluations per cell and axis.
    pub supersampling: usize,
    /// The Douglas–Peucker tolerance (compressed samplers only).
    pub epsilon: Option<f64>,
    /// Wall-clock build time (evaluation, CDFs and compression).
    pub build_time: Duration,
    /// Bytes of all slices.
    pub bytes: usize,
    /// CDF points of the uncompressed tables (`slices ·` [`GridShape::cdf_points`]).
    pub fine_points: usize,
    /// CDF points stored.
    pub stored_points: usize,
    /// BRDF evaluations spent on the fine grids.
    pub grid_evaluations: u64,
}

impl CdfReport {
    /// Stored points over the uncompressed table's points (1 for `tabulated-cdf`).
    pub fn compression_ratio(&self) -> f64 {
        self.stored_points as f64 / self.fine_points as f64
    }

    /// One line for logs and the CLI.
    pub fn summary(&self) -> String {
        let eps = self
            .epsilon
            .map_or(String::new(), |e| format!(", ε = {e:e}"));
        format!(
            "{}: {} slices ({} θ × {} φ{}) of {} × {} cells (z × φ, {}² evaluations each){eps}; built in {:.3} s; {:.1} KiB; {} of {} CDF points stored (ratio {:.4})",
            self.sampler,
            self.layout.len(),
            self.layout.theta,
            self.layout.phi,
            if self.layout.half_turn {
                " over [0°, 180°)"
            } else {
                ""
            },
            self.shape.n_z,
            self.shape.n_phi,
            self.supersampling,
            self.build_time.as_secs_f64(),
            self.bytes as f64 / 1024.0,
            self.stored_points,
            self.fine_points,
            self.compression_ratio()
        )
    }
}

/// The slice layout of `brdf` under `options`: `slices` θ slices for an isotropic BRDF (φ
/// rotation serves every azimuth), else the `[θ, φ]` grid of `anisotropic_slices`, over
/// `[0, π)` for a half-turn-symmetric BRDF with an even φ count (see [`SliceLayout`]).
pub fn cdf_layout(brdf: &dyn Brdf, options: &CdfOptions) -> SliceLayout {
    // The quadtree set's own rule with every declared symmetry in use: the CDF tables slice
    // the outgoing directions exactly as the sets do.
    let set = SetOptions {
        slices: options.slices,
        anisotropic_slices: options.anisotropic_slices,
        symmetries: true,
        ..SetOptions::default()
    };
    layout_for(brdf, &set)
}

/// A tabulated CDF per outgoing slice of one BRDF, as a [`DirectionSampler`]
/// (baselines.md §B).
///
/// Slice `(θ_j, φ_k)` of [`cdf_layout`] tabulates `g(ωi) = f_r(ωo_jk, ωi) cos θi` (luminance
/// for RGB BRDFs) on the fine `(z, φ)` grid of [`CdfOptions`] and holds the distribution `S`
/// of it. For an outgoing direction `ωo` the **nearest** slice `c` is used in both `sample` and
/// `pdf` ([`SliceLayout::nearest`]), its sample turned about the normal by `Δ = φo − φ_k`, so
///
/// `p(ωi | ωo) = p_c(cos θi, φi − Δ)` w.r.t. **solid angle** (`dz dφ = dω`), 0 below the
/// horizon.
///
/// Every cell of every slice has positive mass (the defensive floor), so `p > 0` on the whole
/// upper hemisphere and `(1/N) Σ f cos / p` is unbiased for any BRDF, however coarse the slices.
pub struct CdfSampler<S> {
    /// The layout and the nearest-slice rule without trigonometry ([`SliceLocator::nearest`]);
    /// `sample` and `pdf` both use it, so a direction's pdf is always evaluated with the slice
    /// that sampled it.
    locator: SliceLocator,
    shape: GridShape,
    slices: Vec<S>,
    report: CdfReport,
}

impl<S> std::fmt::Debug for CdfSampler<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CdfSampler")
            .field("report", &self.report)
            .finish_non_exhaustive()
    }
}

impl<S: SliceCdf> CdfSampler<S> {
    /// Builds the slices of `brdf` (in parallel with rayon; the result does not depend on the
    /// thread count).
    ///
    /// Errors: an invalid option, or a table larger than [`CdfOptions::MAX_TOTAL_CELLS`].
    pub fn build(brdf: &dyn Brdf, options: &CdfOptions) -> Result<Self, CdfOptionsError> {
        Self::build_with_progress(brdf, options, None)
    }

    /// [`CdfSampler::build`] reporting `(slices done, total)` after each slice.
    pub fn build_with_progress(
        brdf: &dyn Brdf,
        options: &CdfOptions,
        progress: Option<Progress<'_>>,
    ) -> Result<Self, CdfOptionsError> {
        options.validate()?;
        let layout = cdf_layout(brdf, options);
        options.validate_size(layout.len())?;
        let start = Instant::now();
        let shape = GridShape {
            n_z: options.n_z,
            n_phi: options.n_phi,
        };
        let done = AtomicUsize::new(0);
        let built: Vec<(S, u64)> = (0..layout.len())
            .into_par_iter()
            .map(|i| {
                let wo = layout.direction_of(i);
                let (values, evaluations) =
                    slice_values(brdf, &wo, shape, options.supersampling, options.floor);
                let slice = S::build(&values, shape, options);
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                if let Some(p) = progress {
                    p(d, layout.len());
                }
                (slice, evaluations)
            })
            .collect();
        let grid_evaluations = built.iter().map(|b| b.1).sum();
        let slices: Vec<S> = built.into_iter().map(|b| b.0).collect();
        let report = CdfReport {
            sampler: S::NAME,
            layout,
            shape,
            supersampling: options.supersampling,
            epsilon: S::COMPRESSED.then_some(options.epsilon),
            build_time: start.elapsed(),
            bytes: std::mem::size_of::<Self>() + slices.iter().map(S::bytes_used).sum::<usize>(),
            fine_points: layout.len() * shape.cdf_points(),
            stored_points: slices.iter().map(S::stored_points).sum(),
            grid_evaluations,
        };
        Ok(Self {
            locator: SliceLocator::new(layout),
            shape,
            slices,
            report,
        })
    }

    /// The build report (time, memory, compression).
    pub fn report(&self) -> &CdfReport {
        &self.report
    }

    /// The slice layout.
    pub fn layout(&self) -> SliceLayout {
        self.locator.layout()
    }

    /// The fine grid of every slice.
    pub fn shape(&self) -> GridShape {
        self.shape
    }

    /// Slice `index` of the layout.
    pub fn slice(&self, index: usize) -> Option<&S> {
        self.slices.get(index)
    }
}

impl<S: SliceCdf> DirectionSampler for CdfSampler<S> {
    fn sample(&self, wo: &Vec3, u: &mut dyn UniformSource) -> DirSample {
        let u0 = u.next_uniform();
        let u1 = u.next_uniform();
        let Some(f) = self.locator.nearest(wo) else {
            return DirSample {
                wi: Vec3::new(0.0, 0.0, 1.0),
                pdf: 0.0,
            };
        };
        let p = self.slices[f.index].sample(self.shape, [u0, u1]);
        let r = (1.0 - p.z * p.z).max(0.0).sqrt();
        let (s, c) = p.phi.sin_cos();
        let (x, y) = (r * c, r * s);
        DirSample {
            wi: f.rotation.apply(&Vec3::new(x, y, p.z)),
            pdf: p.pdf,
        }
    }

    fn pdf(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let Some(f) = self.locator.nearest(wo) else {
            return 0.0;
        };
        let v = f.rotation.undo(wi);
        let mut phi = v.y.atan2(v.x);
        if phi < 0.0 {
            phi += TAU;
        }
        self.slices[f.index].pdf(self.shape, wi.z.min(1.0), phi)
    }

    fn bytes_used(&self) -> usize {
        self.report.bytes
    }
}

impl<S: SliceCdf> SamplerDiagnostics for CdfSampler<S> {
    /// The pdf at `wo` is constant on the cells of the serving slice's fine rows
    /// (`z ∈ [a/n_z, (a+1)/n_z)`), cut at [`SliceCdf::phi_edges`] and turned by the slice's
    /// rotation `Δ`; zero below the horizon (the rows tile the upper hemisphere).
    fn pdf_cells(&self, wo: &Vec3) -> Option<PdfCells> {
        let f = self.locator.nearest(wo)?;
        let slice = &self.slices[f.index];
        let turn = f.rotation.angle();
        let n_z = self.shape.n_z;
        let rows = (0..n_z)
            .map(|a| {
                let z = [
                    a as f64 / n_z as f64,
                    if a + 1 == n_z {
                        1.0
                    } else {
                        (a + 1) as f64 / n_z as f64
                    },
                ];
                PdfCellRow::turned(z, &slice.phi_edges(self.shape, a), turn)
            })
            .collect();
        Some(PdfCells {
            coords: CellCoords::Incident,
            rows,
            cosine_weight: 0.0,
        })
    }

    /// [`CdfReport::summary`]: layout, grid, build time, memory and compression.
    fn build_report(&self) -> Option<String> {
        Some(self.report.summary())
    }
}
