//! Measured spectral BRDFs of the Cornell Program of Computer Graphics in pbrt-v2's text format
//! (`.brdf`): scattered samples interpolated over the whole hemisphere.
//!
//! **Format.** Whitespace-separated numbers; `#` starts a comment to the end of the line. First
//! the wavelength count `N`, then the `N` wavelengths (nm, increasing; they may span lines and
//! end at a line end), then one sample per line: `θi φi θo φo` (radians) followed by `N` values
//! of `f_r` (1/sr). Every sample line must have exactly `4 + N` numbers, angles finite with
//! `θ ∈ [0, π/2]`, values finite; negative values are clamped to 0 and reported
//! ([`CornellBrdf::clamped`]); at least [`MIN_SAMPLES`] samples.
//!
//! **Colour.** Each sample's spectrum becomes linear sRGB with the CIE 1931 observer
//! ([`colour::SpectrumToRgb`]); [`Brdf::eval`] is its luminance.
//!
//! **kNN interpolant** (after pbrt-v2's irregular isotropic BRDF). A pair of directions maps to
//! `p(ωo, ωi) = (sin θi sin θo, Δφ/π, cos θi cos θo)` with `Δφ = |φi − φo|` folded into
//! `[0, π]`: symmetric in `ωi ↔ ωo` (reciprocity), invariant under a common rotation (isotropy)
//! and under the mirror `φ ↦ −φ`. `f` at a query is the weighted mean `Σ w_k f_k / Σ w_k` over
//! the `K` = [`NEIGHBOURS`] samples nearest to `p` (candidate lists on a grid over the remapped cube, each made on its first query; a k-d tree beside it), with Gaussian weights
//! cut at the next (`K + 1`-th) nearest sample's distance:
//! `w_k = exp(−d_k²/(2h²)) − exp(−d_{K+1}²/(2h²))`, `h` = [`BANDWIDTH`]. A
//! sample's weight thus falls to 0 as it leaves the neighbour set, so `f` is continuous in the
//! directions (with plain Gaussian weights it jumps wherever the neighbour set changes, which
//! made the validation suite's adaptive reference quadrature refine every such surface: > 70 s
//! per angle). The weights are non-negative with a positive sum (when the `K + 1` nearest are
//! equidistant the plain Gaussian mean is used), so `f` is defined, finite and non-negative on
//! the whole hemisphere (also far from every sample, where it tends to the nearest samples'
//! values). The declared symmetries hold exactly by construction.
//!
//! **Tabulated interpolant** (the default, spec `cornell:PATH` or `cornell:PATH,interp=grid`;
//! [`Interpolation::Grid`]): the kNN interpolant above at the vertices of a regular
//! [`GRID_CELLS`]³ grid of the remapped cube (made by blocks on first use), trilinear in
//! between. Its albedo is an exact sum ([`CornellBrdf::grid_albedo`]), so an `adaptive-exact`
//! sampler's normaliser is exact up to rounding and its build spends no quadrature on it, and
//! an evaluation is ≈ 3× cheaper than the kNN one. As a reconstruction of the measured samples
//! it is as faithful as the kNN interpolant: in leave-one-out cross-validation on the three
//! Cornell files of the team's data it moves the kNN prediction by a median 1–2 % of the kNN's
//! own prediction error and is the closer of the two at about half the samples; the albedos
//! differ by at most 3 % (docs/benchmarks.md §30.4). The kNN interpolant itself stays
//! available as `cornell:PATH,interp=knn` ([`Interpolation::Knn`]): continuous with kinks
//! along its neighbour regions' boundaries, so its normaliser is a quadrature estimate
//! (relative error ≈ 4·10⁻⁴ declared) and its `adaptive-exact` builds take 5–10 s.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use colour::{SpectrumToRgb, WavelengthError};
use thiserror::Error;

use crate::brdf::{Brdf, luminance};
use crate::geometry::Vec3;

/// Fewest samples a file must have.
pub const MIN_SAMPLES: usize = 16;
/// Number of nearest samples blended per query.
pub const NEIGHBOURS: usize = 8;
/// Bandwidth `h` of the Gaussian weights in the remapped space.
pub const BANDWIDTH: f64 = 0.05;

/// Why a Cornell `.brdf` file could not be read.
#[derive(Debug, Error)]
pub enum CornellError {
    /// Filesystem error.
    #[error("Cornell file {path}: {source}")]
    Io {
        /// File involved.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A token that is not a number.
    #[error("line {line}: `{token}` is not a number")]
    NotANumber {
        /// 1-based line.
        line: usize,
        /// The token.
        token: String,
    },
    /// The wavelength count is missing, not a positive integer, or absurdly large.
    #[error("line {line}: the wavelength count must be an integer in 2..=10000, found `{found}`")]
    BadCount {
        /// 1-based line.
        line: usize,
        /// The text found.
        found: String,
    },
    /// The file ends before the wavelength list is complete.
    #[error("the file ends after {found} of {expected} wavelengths")]
    MissingWavelengths {
        /// Wavelengths read.
        found: usize,
        /// Wavelengths announced.
        expected: usize,
    },
    /// The wavelength list is unusable.
    #[error("bad wavelength list: {0:?} (need ≥ 2 finite, increasing, visible wavelengths)")]
    Wavelengths(WavelengthError),
    /// A sample line with the wrong number of values.
    #[error("line {line}: {found} values, expected {expected} (4 angles + {n} spectral values)", n = expected - 4)]
    ColumnCount {
        /// 1-based line.
        line: usize,
        /// Values found.
        found: usize,
        /// Values expected.
        expected: usize,
    },
    /// A NaN or infinite value.
    #[error("line {line}: non-finite value")]
    NonFinite {
        /// 1-based line.
        line: usize,
    },
    /// A polar angle outside `[0, π/2]`.
    #[error("line {line}: polar angle {value} outside [0, π/2]")]
    Angle {
        /// 1-based line.
        line: usize,
        /// The angle.
        value: f64,
    },
    /// Fewer than [`MIN_SAMPLES`] samples.
    #[error("{found} samples, at least {MIN_SAMPLES} needed")]
    TooFewSamples {
        /// Samples found.
        found: usize,
    },
}

/// Negative spectral values clamped to zero when reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NegativeValues {
    /// How many.
    pub count: usize,
    /// The most negative.
    pub min: f64,
}

#[cfg(test)]
mod fidelity;
mod grid;
mod line;
mod node;
mod search;

pub use line::{LINE_ORDER, LineIntegral, SEGMENT_REL_TOL};
pub use node::{QUADRATURE_REL_BOUND, QuadratureEval};

// The search keeps the blended samples and the one their weights are cut at.
const _: () = assert!(search::K == NEIGHBOURS + 1);

/// Cells per axis of the grid of [`Interpolation::Grid`].
pub const GRID_CELLS: usize = 64;

/// How a [`CornellBrdf`] interpolates its samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// The k nearest samples with cut Gaussian weights at every query (the module docs);
    /// spec key `interp=knn`.
    Knn,
    /// That interpolant at the vertices of a regular [`GRID_CELLS`]³ grid of the remapped cube,
    /// trilinear in between (see the module docs and [`CornellBrdf::grid_albedo`]); spec key
    /// `interp=grid`, the default.
    #[default]
    Grid,
}

/// The vertex values of [`Interpolation::Grid`], by blocks of 8³ made on first use (in
/// `grid.rs`).
struct VertexGrid {
    /// Each block's vertices: luminance and RGB.
    blocks: Vec<std::sync::OnceLock<Box<[[f64; 4]]>>>,
    /// Each vertex column's `∫₀¹ L dy`, made on first use.
    columns: Vec<std::sync::OnceLock<f64>>,
}

struct Data {
    tree: search::Tree,
    rgb: Vec<[f64; 3]>,
    /// Each sample's luminance (`eval` blends these: the luminance of the blended RGB, up to
    /// rounding, without the RGB).
    lum: Vec<f64>,
    wavelengths: Vec<f64>,
    clamped: Option<NegativeValues>,
    /// The kNN interpolant at the vertices of [`Interpolation::Grid`], made by blocks.
    vertices: VertexGrid,
}

/// A Cornell measured material (see the [module docs](self)). Cheap to clone.
#[derive(Clone)]
pub struct CornellBrdf {
    data: Arc<Data>,
    interp: Interpolation,
}

impl std::fmt::Debug for CornellBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CornellBrdf")
            .field("samples", &self.data.rgb.len())
            .field("wavelengths", &self.data.wavelengths.len())
            .field("clamped", &self.data.clamped)
            .field("interp", &self.interp)
            .finish()
    }
}

/// The remapped point `(sin θi sin θo, Δφ/π, cos θi cos θo)` of a pair given by angles.
pub fn remap(theta_i: f64, phi_i: f64, theta_o: f64, phi_o: f64) -> [f64; 3] {
    let mut d = (phi_i - phi_o).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d = std::f64::consts::TAU - d;
    }
    [
        theta_i.sin() * theta_o.sin(),
        d / std::f64::consts::PI,
        theta_i.cos() * theta_o.cos(),
    ]
}

/// The remapped point of a pair of unit directions.
fn remap_dirs(wo: &Vec3, wi: &Vec3) -> [f64; 3] {
    let (ri, ro) = (wi.x * wi.x + wi.y * wi.y, wo.x * wo.x + wo.y * wo.y);
    if ri > 0.0 && ro > 0.0 {
        // Δφ ∈ [0, π] from one `atan2` of |sin Δφ| and cos Δφ (scaled alike): the folded
        // difference of the two azimuths, up to rounding.
        let cross = wo.x * wi.y - wo.y * wi.x;
        let dot = wo.x * wi.x + wo.y * wi.y;
        return [
            (ri * ro).sqrt(),
            cross.abs().atan2(dot) / std::f64::consts::PI,
            wi.z * wo.z,
        ];
    }
    // A direction on the pole: its azimuth is `atan2`'s of its (signed) zeros, as always.
    let (si, so) = (wi.x.hypot(wi.y), wo.x.hypot(wo.y));
    let mut d = (wi.y.atan2(wi.x) - wo.y.atan2(wo.x)).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d = std::f64::consts::TAU - d;
    }
    [si * so, d / std::f64::consts::PI, wi.z * wo.z]
}

fn numbers(line: &str, lineno: usize) -> Result<Vec<f64>, CornellError> {
    line.split_whitespace()
        .map(|t| {
            t.parse::<f64>().map_err(|_| CornellError::NotANumber {
                line: lineno,
                token: t.to_string(),
            })
        })
        .collect()
}

impl CornellBrdf {
    /// Reads and validates a `.brdf` file.
    pub fn load(path: &Path) -> Result<Self, CornellError> {
        let text = std::fs::read(path).map_err(|source| CornellError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&String::from_utf8_lossy(&text))
    }

    /// Parses and validates the text of a `.brdf` file.
    pub fn parse(text: &str) -> Result<Self, CornellError> {
        let mut count: Option<usize> = None;
        let mut wavelengths: Vec<f64> = Vec::new();
        let mut samples: Vec<(Vec<f64>, usize)> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let lineno = i + 1;
            let line = raw.split('#').next().unwrap_or("");
            if line.trim().is_empty() {
                continue;
            }
            let Some(n) = count else {
                let mut tokens = line.split_whitespace();
                let first = tokens.next().unwrap_or("");
                let n = first
                    .parse::<usize>()
                    .ok()
                    .filter(|n| (2..=10_000).contains(n))
                    .ok_or_else(|| CornellError::BadCount {
                        line: lineno,
                        found: first.to_string(),
                    })?;
                count = Some(n);
                let rest: Vec<&str> = tokens.collect();
                wavelengths.extend(numbers(&rest.join(" "), lineno)?);
                continue;
            };
            if wavelengths.len() < n {
                wavelengths.extend(numbers(line, lineno)?);
                if wavelengths.len() > n {
                    return Err(CornellError::ColumnCount {
                        line: lineno,
                        found: wavelengths.len(),
                        expected: n,
                    });
                }
                continue;
            }
            samples.push((numbers(line, lineno)?, lineno));
        }
        let Some(n) = count else {
            return Err(CornellError::BadCount {
                line: 0,
                found: String::new(),
            });
        };
        if wavelengths.len() < n {
            return Err(CornellError::MissingWavelengths {
                found: wavelengths.len(),
                expected: n,
            });
        }
        let to_rgb = SpectrumToRgb::new(&wavelengths).map_err(CornellError::Wavelengths)?;
        let mut points: Vec<[f64; 3]> = Vec::with_capacity(samples.len());
        let mut rgb: Vec<[f64; 3]> = Vec::with_capacity(samples.len());
        let mut clamped: Option<NegativeValues> = None;
        for (mut values, line) in samples {
            if values.len() != 4 + n {
                return Err(CornellError::ColumnCount {
                    line,
                    found: values.len(),
                    expected: 4 + n,
                });
            }
            if !values.iter().all(|v| v.is_finite()) {
                return Err(CornellError::NonFinite { line });
            }
            for &t in [values[0], values[2]].iter() {
                if !(0.0..=std::f64::consts::FRAC_PI_2 + 1e-9).contains(&t) {
                    return Err(CornellError::Angle { line, value: t });
                }
            }
            for v in values[4..].iter_mut().filter(|v| **v < 0.0) {
                let c = clamped.get_or_insert(NegativeValues { count: 0, min: 0.0 });
                c.count += 1;
                c.min = c.min.min(*v);
                *v = 0.0;
            }
            points.push(remap(values[0], values[1], values[2], values[3]));
            rgb.push(to_rgb.rgb(&values[4..]).map(|c| c.max(0.0)));
        }
        if points.len() < MIN_SAMPLES {
            return Err(CornellError::TooFewSamples {
                found: points.len(),
            });
        }
        let tree = search::Tree::new(&points);
        let lum = rgb.iter().map(|c| luminance(*c)).collect();
        Ok(Self {
            data: Arc::new(Data {
                tree,
                rgb,
                lum,
                wavelengths,
                clamped,
                vertices: VertexGrid::new(),
            }),
            interp: Interpolation::default(),
        })
    }

    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.data.rgb.len()
    }

    /// The wavelengths (nm).
    pub fn wavelengths(&self) -> &[f64] {
        &self.data.wavelengths
    }

    /// The negative spectral values clamped to zero, if any.
    pub fn clamped(&self) -> Option<NegativeValues> {
        self.data.clamped
    }

    /// This material with another interpolation (the samples and the grid's vertices
    /// shared).
    pub fn with_interpolation(&self, interp: Interpolation) -> Self {
        Self {
            data: Arc::clone(&self.data),
            interp,
        }
    }

    /// How this material interpolates its samples.
    pub fn interpolation(&self) -> Interpolation {
        self.interp
    }

    /// The interpolated RGB at a remapped point, by this material's [`Interpolation`].
    pub fn rgb_at(&self, p: &[f64; 3]) -> [f64; 3] {
        match self.interp {
            Interpolation::Knn => self.knn_rgb_at(p),
            Interpolation::Grid => self.grid_at::<3>(p, 1),
        }
    }

    /// The luminance of [`rgb_at`](Self::rgb_at) (up to rounding).
    pub fn luminance_at(&self, p: &[f64; 3]) -> f64 {
        match self.interp {
            Interpolation::Knn => self.knn_luminance_at(p),
            Interpolation::Grid => self.grid_at::<1>(p, 0)[0],
        }
    }

    /// The kNN interpolant's RGB at a remapped point (see the module docs: the
    /// [`NEIGHBOURS`] nearest samples with Gaussian weights cut at the next sample's distance).
    pub fn knn_rgb_at(&self, p: &[f64; 3]) -> [f64; 3] {
        self.blend(p, |i| self.data.rgb[i])
    }

    /// The luminance of [`knn_rgb_at`](Self::knn_rgb_at) (up to rounding), blended from the
    /// samples' own luminances.
    pub fn knn_luminance_at(&self, p: &[f64; 3]) -> f64 {
        let [l] = self.blend(p, |i| [self.data.lum[i]]);
        l
    }

    /// The weighted mean `Σ w_k v_k / Σ w_k` of `value` over the samples blended at `p` (0
    /// where every weight is 0).
    #[inline]
    fn blend<const C: usize>(&self, p: &[f64; 3], value: impl Fn(usize) -> [f64; C]) -> [f64; C] {
        let near = self.data.tree.nearest_fast(p);
        let w = weights(&near);
        let (mut sum, mut total) = ([0.0; C], 0.0);
        for (w, &i) in w.iter().zip(&near.index[..near.len.min(NEIGHBOURS)]) {
            let v = value(i as usize);
            for ch in 0..C {
                sum[ch] += w * v[ch];
            }
            total += w;
        }
        if total > 0.0 {
            sum.map(|s| s / total)
        } else {
            [0.0; C]
        }
    }
}

/// The blending weights of the nearest samples (up to a common factor).
///
/// With a cut sample at squared distance `c`, sample `k`'s weight
/// `exp(−d_k²/2h²) − exp(−c/2h²)` is `exp(−c/2h²) · expm1((c − d_k²)/2h²)`: the common factor
/// cancels in the weighted mean, so one `expm1` per blended sample (no underflow: squared
/// distances in the remapped unit cube are at most 3, so the argument is at most 600). When
/// every blended sample is as far as the cut one, the plain Gaussian mean: equal weights.
/// Without a cut sample (fewer samples than `K + 1`), the plain Gaussian weights relative to
/// the nearest.
fn weights(near: &search::Nearest) -> [f64; NEIGHBOURS] {
    let inv = 1.0 / (2.0 * BANDWIDTH * BANDWIDTH);
    let mut w = [0.0; NEIGHBOURS];
    let blended = near.len.min(NEIGHBOURS);
    if near.len > NEIGHBOURS {
        let cut = near.d2[NEIGHBOURS];
        let mut any = false;
        for (w, &d2) in w.iter_mut().zip(&near.d2[..blended]) {
            *w = ((cut - d2) * inv).exp_m1().max(0.0);
            any |= *w > 0.0;
        }
        if !any {
            w[..blended].fill(1.0);
        }
    } else {
        for (w, &d2) in w.iter_mut().zip(&near.d2[..blended]) {
            *w = (-(d2 - near.d2[0]) * inv).exp();
        }
    }
    w
}

impl Brdf for CornellBrdf {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return 0.0;
        }
        self.luminance_at(&remap_dirs(wo, wi))
    }

    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return [0.0; 3];
        }
        self.rgb_at(&remap_dirs(wo, wi))
    }

    fn is_isotropic(&self) -> bool {
        true
    }
    fn is_mirror_symmetric(&self) -> bool {
        true
    }
    fn is_half_turn_symmetric(&self) -> bool {
        true
    }
    fn is_reciprocal(&self) -> bool {
        true
    }
    fn name(&self) -> &str {
        "cornell"
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// A Cornell-format text (a fixture for tests and examples): `f = 0.05 + 3 exp(−(Δθ² + (π −
/// Δφ)²)/0.08)`, a lobe at the mirror direction, at every `θi, θo ∈ {5°, 15°, …, 85°}` and
/// `Δφ ∈ {0°, 30°, …, 180°}` (567 samples on a regular grid, so many are equidistant from a
/// query), over three wavelengths (450, 550, 650 nm) whose values are `spectrum(f)`.
pub fn lobe_grid_text(spectrum: impl Fn(f64) -> [f64; 3]) -> String {
    let mut text = String::from("3\n450 550 650\n");
    for ti in (0..9).map(|k| (5.0 + 10.0 * k as f64).to_radians()) {
        for to in (0..9).map(|k| (5.0 + 10.0 * k as f64).to_radians()) {
            for dp in (0..7).map(|k| (30.0 * k as f64).to_radians()) {
                let lobe = ((ti - to).powi(2) + (std::f64::consts::PI - dp).powi(2)) / 0.08;
                let [a, b, c] = spectrum(0.05 + 3.0 * (-lobe).exp());
                text.push_str(&format!("{ti} 0 {to} {dp} {a} {b} {c}\n"));
            }
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    use std::num::NonZero;

    /// The interpolant as it was computed before issue 29 (kiddo's `nearest_n` into a `Vec`,
    /// sorted; weights relative to the nearest sample; RGB, then luminance): the judge of
    /// the allocation-free search and weights.
    struct Before {
        tree: ImmutableKdTree<f64, 3>,
        rgb: Vec<[f64; 3]>,
    }

    impl Before {
        fn new(text: &str) -> Self {
            let b = CornellBrdf::parse(text).unwrap();
            // The remapped points again, from the parser's own rule.
            let mut points = Vec::new();
            let mut count = None;
            let mut wl = 0;
            for line in text.lines() {
                let line = line.split('#').next().unwrap_or("");
                let v: Vec<f64> = line
                    .split_whitespace()
                    .filter_map(|t| t.parse().ok())
                    .collect();
                if v.is_empty() {
                    continue;
                }
                match count {
                    None => {
                        count = Some(v[0] as usize);
                        wl += v.len() - 1;
                    }
                    Some(n) if wl < n => wl += v.len(),
                    Some(_) => points.push(remap(v[0], v[1], v[2], v[3])),
                }
            }
            Self {
                tree: ImmutableKdTree::new_from_slice(&points).unwrap(),
                rgb: b.data.rgb.clone(),
            }
        }

        fn rgb_at(&self, p: &[f64; 3]) -> [f64; 3] {
            let k = NonZero::new((NEIGHBOURS + 1).min(self.rgb.len())).unwrap();
            let mut found = self
                .tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(k)
                .execute();
            found.sort_by(|a, b| a.distance.total_cmp(&b.distance));
            let nearest = found.first().map_or(0.0, |r| r.distance);
            let kernel = |d2: f64| (-(d2 - nearest) / (2.0 * BANDWIDTH * BANDWIDTH)).exp();
            let (blend, cut) = if found.len() > NEIGHBOURS {
                (&found[..NEIGHBOURS], kernel(found[NEIGHBOURS].distance))
            } else {
                (&found[..], 0.0)
            };
            let mean = |weight: &dyn Fn(f64) -> f64| {
                let (mut sum, mut total) = ([0.0; 3], 0.0);
                for r in blend {
                    let w = weight(r.distance);
                    let c = self.rgb[r.item as usize];
                    for ch in 0..3 {
                        sum[ch] += w * c[ch];
                    }
                    total += w;
                }
                (total > 0.0).then(|| sum.map(|s| s / total))
            };
            mean(&|d2| (kernel(d2) - cut).max(0.0))
                .or_else(|| mean(&kernel))
                .unwrap_or([0.0; 3])
        }

        /// The old `eval` with the old `remap_dirs` (two `atan2`, two `hypot`).
        fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
            if !(wo.z > 0.0 && wi.z > 0.0) {
                return [0.0; 3];
            }
            let (si, so) = (wi.x.hypot(wi.y), wo.x.hypot(wo.y));
            let mut d = (wi.y.atan2(wi.x) - wo.y.atan2(wo.x)).rem_euclid(std::f64::consts::TAU);
            if d > std::f64::consts::PI {
                d = std::f64::consts::TAU - d;
            }
            self.rgb_at(&[si * so, d / std::f64::consts::PI, wi.z * wo.z])
        }
    }

    /// A file of 567 samples of a glossy lobe on a regular grid (many equidistant samples).
    fn synthetic() -> String {
        super::lobe_grid_text(|f| [0.7 * f, f, 0.2 + f])
    }

    /// The team's Cornell files when the data repository sits beside this one.
    fn shared_files() -> Vec<(String, String)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/measured/cornell");
        let mut out = Vec::new();
        for name in ["acryl_blue", "cayman", "krylon_blue"] {
            match std::fs::read_to_string(dir.join(format!("{name}.brdf"))) {
                Ok(t) => out.push((name.to_string(), t)),
                Err(_) => eprintln!("skipped {name}: {} is absent", dir.display()),
            }
        }
        out
    }

    /// Random direction pairs (xorshift, fixed seed), uniform on the hemisphere, with the
    /// poles and a shared azimuth now and then.
    fn pairs(n: usize, mut state: u64) -> Vec<(Vec3, Vec3)> {
        let mut u = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut dir = |k: usize| {
            if k.is_multiple_of(997) {
                return Vec3::new(0.0, 0.0, 1.0);
            }
            let (z, phi) = (u(), std::f64::consts::TAU * u());
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        (0..n).map(|k| (dir(k), dir(k + 500))).collect()
    }

    /// Largest relative difference of the new `eval` and `eval_rgb` to the old interpolant
    /// (each RGB channel relative to itself or, if smaller, to the largest channel).
    fn worst_difference(text: &str, n: usize) -> f64 {
        let new = CornellBrdf::parse(text)
            .unwrap()
            .with_interpolation(Interpolation::Knn);
        let old = Before::new(text);
        let mut worst = 0.0f64;
        for (wo, wi) in pairs(n, 0x2545_f491_4f6c_dd1d) {
            let o = old.eval_rgb(&wo, &wi);
            let rgb = new.eval_rgb(&wo, &wi);
            let rel = |a: f64, b: f64| if a == b { 0.0 } else { (a - b).abs() / b.abs() };
            // A channel far below the others (10⁻¹⁰ of them: the colour matching's
            // cancellation) is compared to the largest channel.
            let scale = o.iter().fold(0.0f64, |m, c| m.max(c.abs()));
            for ch in 0..3 {
                worst = worst.max(rel(rgb[ch], o[ch]).min((rgb[ch] - o[ch]).abs() / scale));
            }
            worst = worst.max(rel(new.eval(&wo, &wi), luminance(o)));
        }
        worst
    }

    /// Issue 29: the allocation-free search, the `expm1` weights, the one-`atan2` remap and the
    /// luminance blended from the samples' luminances change `f` by rounding only: on 20 000
    /// random pairs per file (and the poles) within 1e-10 relative of the old computation
    /// (measured 10⁶ pairs per shared file: docs/benchmarks.md §19.6).
    /// Every file's worst relative difference from the old interpolant over `pairs` random
    /// direction pairs is at most 1e-10 (rounding).
    fn assert_same_interpolant(files: Vec<(String, String)>, pairs: usize) {
        for (name, text) in files {
            let (mean, largest) = CornellBrdf::parse(&text)
                .unwrap()
                .data
                .tree
                .grid_occupancy();
            eprintln!("{name}: {mean:.1} candidates per grid cell, at most {largest}");
            let worst = worst_difference(&text, pairs);
            eprintln!("{name}: max relative difference on {pairs} pairs {worst:.2e}");
            assert!(worst <= 1e-10, "{name}: {worst:e}");
        }
    }

    #[test]
    fn fast_eval_is_the_old_interpolant() {
        let mut files = vec![("synthetic".to_string(), synthetic())];
        files.extend(shared_files());
        assert_same_interpolant(files, 20_000);
    }

    /// The figure of §19.6: 10⁶ random pairs per file (`cargo test --release -p brdf --lib
    /// fast_eval_on_a_million_pairs -- --ignored --nocapture`).
    #[test]
    #[ignore = "10⁶ pairs per file, about a minute"]
    fn fast_eval_on_a_million_pairs() {
        assert_same_interpolant(shared_files(), 1_000_000);
    }

    /// Instructions per evaluation, for cachegrind (docs/benchmarks.md §19.6):
    /// `CORNELL_EVALS=N CORNELL_IMPL=old|new|grid|loop valgrind --tool=cachegrind TEST_BINARY
    /// eval_cost_probe --ignored --exact`, at two N, the difference divided by the difference of N.
    #[test]
    #[ignore = "a cachegrind probe"]
    fn eval_cost_probe() {
        let n: usize = std::env::var("CORNELL_EVALS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(10_000);
        let which = std::env::var("CORNELL_IMPL").unwrap_or_default();
        let Some((_, text)) = shared_files().into_iter().nth(1) else {
            return;
        };
        let new_b = CornellBrdf::parse(&text)
            .unwrap()
            .with_interpolation(Interpolation::Knn);
        let grid_b = new_b.with_interpolation(Interpolation::Grid);
        let old_b = Before::new(&text);
        let ps = pairs(n, 7);
        let mut sum = 0.0;
        for (wo, wi) in &ps {
            sum += match which.as_str() {
                "old" => luminance(old_b.eval_rgb(wo, wi)),
                "new" => new_b.eval(wo, wi),
                "grid" => grid_b.eval(wo, wi),
                // The loop alone (pairs and sum), to subtract.
                _ => wo.z * wi.z,
            };
        }
        eprintln!("sum {sum}");
    }

    /// Issue 29, the tabulated interpolant: at the grid's vertices it is the kNN interpolant
    /// (bit for bit, every block's indexing), in between trilinear, and its albedo
    /// ([`CornellBrdf::grid_albedo`]) is the integral of its own `eval`: within 10⁻⁶ relative
    /// of a brute-force iterated rule (θi: 4 Gauss points on 1 000 panels; Δφ: 2 Gauss points
    /// on each grid cell, exact for the piecewise linear interpolant) and within its estimate
    /// plus that rule's error. Fails with the column sums as plain sums (no trapezoid ends).
    #[test]
    fn grid_interpolant_and_its_albedo() {
        let b = CornellBrdf::parse(&synthetic()).unwrap();
        assert_eq!(b.interpolation(), Interpolation::Grid, "the default");
        let knn = b.with_interpolation(Interpolation::Knn);
        let n = GRID_CELLS;
        for (i, j, k) in [(0, 0, 0), (n, n, n), (7, 8, 9), (63, 1, 32), (17, 40, 64)] {
            let p = [i, j, k].map(|v| v as f64 / n as f64);
            assert_eq!(b.luminance_at(&p), knn.knn_luminance_at(&p), "{p:?}");
            assert_eq!(b.rgb_at(&p), knn.knn_rgb_at(&p), "{p:?}");
        }
        // Midway along an edge: the mean of its two vertices.
        let (p, q) = ([10.0 / 64.0, 0.5, 0.25], [11.0 / 64.0, 0.5, 0.25]);
        let mid = [10.5 / 64.0, 0.5, 0.25];
        let want = 0.5 * (knn.knn_luminance_at(&p) + knn.knn_luminance_at(&q));
        assert!((b.luminance_at(&mid) - want).abs() <= 1e-14 * want.abs());
        let gl4 = crate::quadrature::GaussLegendre::new(4);
        let gl2 = crate::quadrature::GaussLegendre::new(2);
        for deg in [0.0f64, 23.0, 61.3, 88.0] {
            let to = deg.to_radians();
            let (value, err) = b.grid_albedo(to).unwrap();
            let wo = crate::direction_from_radians(to, 0.0);
            let panels = 1_000;
            let h = std::f64::consts::FRAC_PI_2 / panels as f64;
            let brute: f64 = (0..panels)
                .map(|m| {
                    gl4.integrate(m as f64 * h, (m + 1) as f64 * h, |ti| {
                        let (si, ci) = ti.sin_cos();
                        let ring: f64 = (0..n)
                            .map(|c| {
                                let (a, z) = (c as f64 / n as f64, (c + 1) as f64 / n as f64);
                                gl2.integrate(a, z, |t| {
                                    let phi = std::f64::consts::PI * t;
                                    let wi = Vec3::new(si * phi.cos(), si * phi.sin(), ci);
                                    b.eval(&wo, &wi)
                                })
                            })
                            .sum();
                        std::f64::consts::TAU * si * ci * ring
                    })
                })
                .sum();
            let gap = (value - brute).abs();
            eprintln!("θo {deg}°: grid albedo {value} ± {err:.1e}, brute force {brute}: {gap:.1e}");
            assert!(gap <= 1e-6 * brute, "θo {deg}°: {value} vs {brute}");
            assert!(err <= 1e-9 * value, "θo {deg}°: estimate {err:e}");
        }
        assert!(b.grid_albedo(f64::NAN).is_none() && b.grid_albedo(2.0).is_none());
    }

    /// The tabulated interpolant against the kNN one, for the record (docs/benchmarks.md
    /// §24.6): at every measured sample's remapped point and at 10⁵ random direction pairs
    /// per shared file, the relative difference of the luminance (largest, mean, 99th
    /// percentile, and relative to the file's largest value), and the CPU time of making every
    /// vertex. `cargo test --release -p brdf --lib grid_against_knn -- --ignored --nocapture`
    #[test]
    #[ignore = "a survey for the record"]
    fn grid_against_knn_survey() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/measured/cornell");
        for (name, text) in shared_files() {
            let knn = CornellBrdf::parse(&text).unwrap();
            let grid = knn.with_interpolation(Interpolation::Grid);
            let t = std::time::Instant::now();
            let n = GRID_CELLS + 1;
            let mut peak = 0.0f64;
            for k in 0..n {
                for j in 0..n {
                    for i in 0..n {
                        let p = [i, j, k].map(|v| v as f64 / GRID_CELLS as f64);
                        peak = peak.max(grid.luminance_at(&p));
                    }
                }
            }
            let fill = t.elapsed().as_secs_f64();
            let stats = |pts: &[[f64; 3]]| {
                let mut rel: Vec<f64> = Vec::with_capacity(pts.len());
                let mut worst_abs = 0.0f64;
                for p in pts {
                    let (g, k) = (grid.luminance_at(p), knn.knn_luminance_at(p));
                    rel.push(if k > 0.0 {
                        (g - k).abs() / k
                    } else {
                        (g - k).abs()
                    });
                    worst_abs = worst_abs.max((g - k).abs());
                }
                rel.sort_by(f64::total_cmp);
                let mean = rel.iter().sum::<f64>() / rel.len() as f64;
                format!(
                    "relative difference mean {:.2e}, median {:.2e}, 99th percentile {:.2e}, max {:.2e}; max absolute / file peak {:.2e}",
                    mean,
                    rel[rel.len() / 2],
                    rel[rel.len() * 99 / 100],
                    rel[rel.len() - 1],
                    worst_abs / peak
                )
            };
            let samples: Vec<[f64; 3]> = (0..knn.samples() as u32)
                .map(|i| knn.data.tree.point(i))
                .collect();
            let random: Vec<[f64; 3]> = pairs(100_000, 0x9e37_79b9_7f4a_7c15)
                .iter()
                .filter(|(o, i)| o.z > 0.0 && i.z > 0.0)
                .map(|(o, i)| remap_dirs(o, i))
                .collect();
            eprintln!(
                "{name} ({}): every vertex made in {fill:.2} s (one thread)",
                dir.display()
            );
            eprintln!(
                "{name}: at the {} measured samples: {}",
                samples.len(),
                stats(&samples)
            );
            eprintln!(
                "{name}: at {} random pairs: {}",
                random.len(),
                stats(&random)
            );
        }
    }

    /// `cornell:PATH,interp=knn|grid` picks the interpolation (kNN without the key); any other
    /// value is a typed error.
    #[test]
    fn spec_key_picks_the_interpolation() {
        let path = std::env::temp_dir().join(format!("cornell-spec-{}.brdf", std::process::id()));
        std::fs::write(&path, synthetic()).unwrap();
        let interp = |suffix: &str| {
            let b = crate::parse_spec(&format!("cornell:{}{suffix}", path.display()))?;
            let c = b
                .as_any()
                .and_then(|a| a.downcast_ref::<CornellBrdf>())
                .map(|c| c.interpolation());
            Ok::<_, crate::SpecError>(c)
        };
        assert_eq!(interp("").unwrap(), Some(Interpolation::Grid));
        assert_eq!(interp(",interp=knn").unwrap(), Some(Interpolation::Knn));
        assert_eq!(interp(",interp=grid").unwrap(), Some(Interpolation::Grid));
        assert!(interp(",interp=cubic").is_err());
        let _ = std::fs::remove_file(&path);
    }
}
