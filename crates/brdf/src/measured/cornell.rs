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
//! **Interpolation** (after pbrt-v2's irregular isotropic BRDF). A pair of directions maps to
//! `p(ωo, ωi) = (sin θi sin θo, Δφ/π, cos θi cos θo)` with `Δφ = |φi − φo|` folded into
//! `[0, π]`: symmetric in `ωi ↔ ωo` (reciprocity), invariant under a common rotation (isotropy)
//! and under the mirror `φ ↦ −φ`. `f` at a query is the weighted mean `Σ w_k f_k / Σ w_k` over
//! the `K` = [`NEIGHBOURS`] samples nearest to `p` (a k-d tree, `kiddo`), with Gaussian weights
//! cut at the next (`K + 1`-th) nearest sample's distance:
//! `w_k = exp(−d_k²/(2h²)) − exp(−d_{K+1}²/(2h²))`, `h` = [`BANDWIDTH`]. A
//! sample's weight thus falls to 0 as it leaves the neighbour set, so `f` is continuous in the
//! directions (with plain Gaussian weights it jumps wherever the neighbour set changes, which
//! made the validation suite's adaptive reference quadrature refine every such surface: > 70 s
//! per angle). The weights are non-negative with a positive sum (when the `K + 1` nearest are
//! equidistant the plain Gaussian mean is used), so `f` is defined, finite and non-negative on
//! the whole hemisphere (also far from every sample, where it tends to the nearest samples'
//! values). The declared symmetries hold exactly by construction.

use std::num::NonZero;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use colour::{SpectrumToRgb, WavelengthError};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
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

struct Data {
    tree: ImmutableKdTree<f64, 3>,
    rgb: Vec<[f64; 3]>,
    wavelengths: Vec<f64>,
    clamped: Option<NegativeValues>,
}

/// A Cornell measured material (see the [module docs](self)). Cheap to clone.
#[derive(Clone)]
pub struct CornellBrdf {
    data: Arc<Data>,
}

impl std::fmt::Debug for CornellBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CornellBrdf")
            .field("samples", &self.data.rgb.len())
            .field("wavelengths", &self.data.wavelengths.len())
            .field("clamped", &self.data.clamped)
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
        let tree =
            ImmutableKdTree::new_from_slice(&points).map_err(|_| CornellError::TooFewSamples {
                found: points.len(),
            })?;
        Ok(Self {
            data: Arc::new(Data {
                tree,
                rgb,
                wavelengths,
                clamped,
            }),
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

    /// The interpolated RGB at a remapped point (see the module docs: the [`NEIGHBOURS`]
    /// nearest samples with Gaussian weights cut at the next sample's distance).
    pub fn rgb_at(&self, p: &[f64; 3]) -> [f64; 3] {
        let n = self.data.rgb.len();
        let k = NonZero::new((NEIGHBOURS + 1).min(n)).unwrap_or(NonZero::<usize>::MIN);
        let mut found = self
            .data
            .tree
            .query(p)
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute();
        found.sort_by(|a, b| a.distance.total_cmp(&b.distance));
        let nearest = found.first().map_or(0.0, |r| r.distance);
        // Weights relative to the nearest sample's, so far queries do not underflow.
        let kernel = |d2: f64| (-(d2 - nearest) / (2.0 * BANDWIDTH * BANDWIDTH)).exp();
        // With a (k+1)-th sample, its kernel value is subtracted: a sample's weight falls to 0
        // as it leaves the neighbour set, so the interpolant is continuous.
        let (blend, cut) = if found.len() > NEIGHBOURS {
            (&found[..NEIGHBOURS], kernel(found[NEIGHBOURS].distance))
        } else {
            (&found[..], 0.0)
        };
        let mean = |weight: &dyn Fn(f64) -> f64| {
            let (mut sum, mut total) = ([0.0; 3], 0.0);
            for r in blend {
                let w = weight(r.distance);
                let c = self.data.rgb[r.item as usize];
                for ch in 0..3 {
                    sum[ch] += w * c[ch];
                }
                total += w;
            }
            (total > 0.0).then(|| sum.map(|s| s / total))
        };
        mean(&|d2| (kernel(d2) - cut).max(0.0))
            // Every blended sample as far as the cut one (ties): the plain Gaussian mean.
            .or_else(|| mean(&kernel))
            .unwrap_or([0.0; 3])
    }
}

impl Brdf for CornellBrdf {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        luminance(self.eval_rgb(wo, wi))
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
