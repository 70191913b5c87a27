//! Isotropic RGB materials of the RGL database (Dupuy & Jakob 2018, "An Adaptive
//! Parameterization for Efficient Material Acquisition and Rendering", ACM TOG 37(6)), the
//! `.bsdf` tensor files read by Mitsuba's `measured` plugin.
//!
//! **Fields** (see [`tensor`](super::tensor) for the container): `theta_i[T]` and `phi_i[1]`
//! (the incident angles of the slices, radians; one `φ` value = isotropic), `ndf[Py, Px]` and
//! `sigma[Py, Px]` (the microfacet distribution `D` and the projected area `σ`, on the
//! `u`-square of a direction), `vndf[1, T, Ny, Nx]` (the visible-normal distribution, a
//! sampling density of the half vector on the `u`-square), `luminance[1, T, M, M]` and
//! `rgb[1, T, 3, M, M]` (reflectance tables over the **warped** square, the VNDF warp's
//! uniform domain), `jacobian[1]` (`u8`, whether the `D/(4σ)` factor is to be applied) and
//! `description`. Every table must be finite, `ndf`, `vndf`, `luminance` non-negative, `sigma`
//! positive, `theta_i` increasing in `[0, π/2]`, and the shapes consistent.
//!
//! **Coordinates.** A direction of elevation `θ` and azimuth `φ` has `u = (√(2θ/π),
//! (φ + π)/(2π))`. For `ωo` (the format's "incident" direction: the one the tables are sliced
//! by) and `ωi`, the half vector `m = (ωo + ωi)/|ωo + ωi|` has `u_m = (√(2θm/π),
//! frac((φm − φo + π)/(2π)))` (isotropy: the azimuth is taken relative to `ωo`).
//!
//! **Value.** With `s = vndf⁻¹(u_m; θo)` (the inverse of the VNDF warp at the slice of `θo`,
//! [`Warp2D::invert`]), the file defines each channel of `f_r · cos θi` (the quantity Mitsuba's
//! `BSDF::eval` returns: the BRDF times the foreshortening of the sampled direction) as
//! `rgb_c(s; θo) · D(u_m) / (4 σ(u_o))` (the factor only when `jacobian = 1`; `D/(4σ)` is the
//! VNDF's density of `ωi`, so the table holds `f·cos / p_vndf`). `rgb_c`, `D`, `σ` are bilinear
//! in their squares and linear in `θo` between slices. The BRDF is that value divided by
//! `cos θi`; [`Brdf::eval`] is its luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
//!
//! **Negative entries.** Real files hold slightly negative `rgb` entries (fitting noise, down
//! to about −0.01 in `cc_ibiza_sunset`, −0.1 reported elsewhere). They are clamped to 0 when
//! read; [`RglBrdf::clamped`] reports how many and the most negative one.
//!
//! **Reciprocity** is not guaranteed by the format (the tables are sliced by `ωo` only), so
//! [`Brdf::is_reciprocal`] is `false`.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;
use std::sync::{Arc, Weak};

use super::tensor::TensorFile;
use super::warp::{BilinearTable, ParamAxis, Warp2D, Warp2DSlice};
use crate::brdf::{Brdf, Outgoing, luminance};
use crate::geometry::Vec3;

pub use super::rgl_error::RglError;

mod angles;
mod bound;
mod lanes;

use angles::fast;
pub use angles::{elevation, phi_to_u, theta_to_u, u_to_phi, u_to_theta};
pub use bound::{
    DirectionBox, MARGIN as BOUND_MARGIN, PAD as BOUND_PAD, ThetaPiece,
    abs_range as bound_abs_range,
};

/// How many negative `rgb` entries were clamped to zero when reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NegativeClamp {
    /// Number of clamped entries.
    pub count: usize,
    /// The most negative value.
    pub min: f64,
}

/// The tables of one material (shared by clones).
#[derive(Debug)]
struct Tables {
    description: String,
    theta: ParamAxis,
    ndf: BilinearTable,
    sigma: BilinearTable,
    vndf: Warp2D,
    luminance: Warp2D,
    /// Slices `[θ][channel]`.
    rgb: BilinearTable,
    /// Luminance `0.2126 R + 0.7152 G + 0.0722 B` of the (clamped) `rgb` table, slices `[θ]`:
    /// interpolation is linear, so this is the luminance of the interpolated RGB.
    rgb_luminance: BilinearTable,
    jacobian: bool,
    clamped: Option<NegativeClamp>,
    /// `ndf` and `sigma` do not depend on the azimuth.
    isotropic: bool,
    /// Every row of `sigma` equals row 0 bit for bit (then `σ(u_o)` is read at `φo = 0`).
    sigma_y_constant: bool,
    /// Every table is even in the relative azimuth (`u.y ↦ 1 − u.y`).
    mirror_symmetric: bool,
}

/// The `vndf` and luminance tables of one θo, blended once from the two slices around it
/// ([`RglBrdf::prepare_slice`]): an evaluation at that θo then inverts and reads one plain
/// slice instead of blending two at every table read. [`RglBrdf::eval_in_slice`] returns
/// [`Brdf::eval_prepared`]'s value bit for bit (each blended entry is the one the two-slice
/// path computes at each read, by the same expression).
#[derive(Debug, Clone)]
pub struct PreparedSlice {
    /// Address of the material's tables (a slice of another material is not used).
    owner: usize,
    /// The slice `i` and weight `w` of θo on the `theta_i` axis.
    slice: usize,
    weight: f64,
    vndf: Warp2DSlice,
    rgb_luminance: BilinearTable,
}

impl PreparedSlice {
    /// Heap bytes of the slice.
    pub fn bytes_used(&self) -> usize {
        let (nx, ny) = self.rgb_luminance.size();
        self.vndf.bytes_used() + 8 * nx * ny
    }

    fn matches(&self, owner: usize, slice: usize, weight: f64) -> bool {
        self.owner == owner && self.slice == slice && self.weight.to_bits() == weight.to_bits()
    }
}

/// Accepted range of the NDF's normalisation `∫ D(m) cos θm dm` (1 for a microfacet
/// distribution; 1.008 in the four RGL files of `../shared`, whose tables are bilinear
/// resamplings).
pub const NDF_NORMALISATION_RANGE: (f64, f64) = (0.5, 2.0);

/// Largest accepted directional albedo of an `rgb` slice (its mean over the warped square when
/// `jacobian = 1`): 10 times the energy received is no measurement (the four RGL files of
/// `../shared` stay below 1.61, reached at grazing angles).
pub const MAX_SLICE_ALBEDO: f64 = 10.0;

/// Relative tolerance of the symmetry checks made when a file is read.
pub const SYMMETRY_TOLERANCE: f64 = 1e-6;

/// An isotropic RGL material (see the [module docs](self)). Cheap to clone.
#[derive(Debug, Clone)]
pub struct RglBrdf {
    tables: Arc<Tables>,
}

/// The half-vector coordinates of a pair `(ωo, ωi)` in the format's parametrisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfCoords {
    /// Elevation of `ωo` (the slice parameter).
    pub theta_o: f64,
    /// `u` of `ωo`.
    pub u_o: [f64; 2],
    /// `u_m` of the half vector (azimuth relative to `ωo`).
    pub u_m: [f64; 2],
    /// The unit half vector.
    pub m: Vec3,
}

/// Grid sizes `(nx, ny)` of an [`RglBrdf`]'s bilinear tables ([`RglBrdf::grids`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RglGrids {
    /// `ndf` (`D`) on the `u_m`-square.
    pub ndf: (usize, usize),
    /// `vndf` (the warp's density) on the `u_m`-square.
    pub vndf: (usize, usize),
    /// `rgb` (and `luminance`) on the warped square.
    pub rgb: (usize, usize),
}

impl RglBrdf {
    /// Reads and validates an RGL `.bsdf` file.
    pub fn load(path: &Path) -> Result<Self, RglError> {
        let bytes = std::fs::read(path).map_err(|source| RglError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes)
    }

    /// Reads and validates an RGL `.bsdf` file's bytes.
    ///
    /// Besides the per-value rules of the [module docs](self), the tables must obey the
    /// physics the format encodes (each a typed [`RglError::Implausible`]): the NDF's
    /// normalisation `∫ D cos θm dm` lies in [`NDF_NORMALISATION_RANGE`]; `sigma`, the
    /// projected area `∫ D ⟨ω·m⟩ dm`, lies between `cos θ / 2` and twice `∫ D dm`; with the
    /// Jacobian factor, each `rgb` slice's mean (the directional albedo) is at most
    /// [`MAX_SLICE_ALBEDO`]; the largest value `rgb · D / (4σ)` can take and each sampling
    /// slice's sum are finite in `f32` (the precision Mitsuba evaluates the format in). These
    /// reject absurd-but-finite files (e.g. words set to 1e38) whose dynamic range would make a
    /// sampler's build run for minutes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, RglError> {
        let tf = TensorFile::parse(bytes)?;
        let description = String::from_utf8_lossy(tf.u8_data("description")?).into_owned();
        let phi = tf.f32_data("phi_i")?;
        let phi_shape = &tf.field("phi_i")?.shape;
        if phi_shape.len() != 1 {
            return Err(shape_error("phi_i", phi_shape, "rank 1"));
        }
        if phi.len() != 1 {
            return Err(RglError::Anisotropic { n_phi: phi.len() });
        }
        let theta = tf.f32_data("theta_i")?;
        let theta_shape = &tf.field("theta_i")?.shape;
        if theta_shape.len() != 1 || theta.is_empty() {
            return Err(shape_error("theta_i", theta_shape, "[T] with T ≥ 1"));
        }
        for (index, &t) in theta.iter().enumerate() {
            if !(0.0..=FRAC_PI_2 + 1e-6).contains(&t) {
                return Err(RglError::OutOfRange {
                    field: "theta_i".into(),
                    index,
                    value: t,
                    rule: "must lie in [0, π/2]",
                });
            }
            if index > 0 && !(t > theta[index - 1]) {
                return Err(RglError::OutOfRange {
                    field: "theta_i".into(),
                    index,
                    value: t,
                    rule: "must be strictly increasing",
                });
            }
        }
        let n_theta = theta.len();
        let axis = ParamAxis::new(theta);

        let (ndf, _) = plain_table(&tf, "ndf", 0.0, false)?;
        let (sigma, _) = plain_table(&tf, "sigma", 0.0, true)?;

        let vndf = sampling_table(&tf, "vndf", n_theta, &axis)?;
        let lum = sampling_table(&tf, "luminance", n_theta, &axis)?;

        let rgb_field = tf.field("rgb")?;
        let lum_shape = &tf.field("luminance")?.shape;
        let expected_rgb = [1, n_theta, 3, lum_shape[2], lum_shape[3]];
        if rgb_field.shape != expected_rgb {
            return Err(shape_error(
                "rgb",
                &rgb_field.shape,
                &format!("{expected_rgb:?} (phi_i, theta_i, channel, luminance's grid)"),
            ));
        }
        let mut rgb = tf.f32_data("rgb")?;
        let mut clamped: Option<NegativeClamp> = None;
        for v in rgb.iter_mut().filter(|v| **v < 0.0) {
            let c = clamped.get_or_insert(NegativeClamp { count: 0, min: 0.0 });
            c.count += 1;
            c.min = c.min.min(*v);
            *v = 0.0;
        }
        let jac_field = tf.field("jacobian")?;
        if jac_field.shape != [1] {
            return Err(shape_error("jacobian", &jac_field.shape, "[1]"));
        }
        let jacobian = tf.u8_data("jacobian")?[0] != 0;
        check_physics(&ndf, &sigma, &rgb, (lum_shape[3], lum_shape[2]), jacobian)?;

        let cell = lum_shape[2] * lum_shape[3];
        let mut y = Vec::with_capacity(n_theta * cell);
        for t in 0..n_theta {
            let at = |ch: usize, k: usize| rgb[(3 * t + ch) * cell + k];
            y.extend((0..cell).map(|k| luminance([at(0, k), at(1, k), at(2, k)])));
        }
        let rgb_luminance = BilinearTable::new(lum_shape[3], lum_shape[2], y);
        let rgb = BilinearTable::new(lum_shape[3], lum_shape[2], rgb);

        let tol = SYMMETRY_TOLERANCE;
        let isotropic = ndf.is_y_constant(tol) && sigma.is_y_constant(tol);
        let sigma_y_constant = sigma.is_y_constant(0.0);
        let mirror_symmetric = isotropic
            && vndf.table().is_y_symmetric(tol)
            && lum.table().is_y_symmetric(tol)
            && rgb.is_y_symmetric(tol);
        Ok(Self {
            tables: Arc::new(Tables {
                isotropic,
                sigma_y_constant,
                mirror_symmetric,
                description,
                theta: axis,
                ndf,
                sigma,
                vndf,
                luminance: lum,
                rgb,
                rgb_luminance,
                jacobian,
                clamped,
            }),
        })
    }

    /// The file's description string.
    pub fn description(&self) -> &str {
        &self.tables.description
    }

    /// The negative `rgb` entries clamped to zero, if there were any.
    pub fn clamped(&self) -> Option<NegativeClamp> {
        self.tables.clamped
    }

    /// The slice angles `theta_i` (radians).
    pub fn theta_slices(&self) -> &[f64] {
        self.tables.theta.values()
    }

    /// The outgoing polar angles (radians, increasing, inside `(0, π/2)`) where the albedo
    /// `A(θo) = ∫ f_r cos θi dσ` has its kinks: the interior slice angles (the tables are
    /// blended linearly in θo between them), and, above the last interior slice, the θ of
    /// `σ`'s grid nodes when the file applies the `D/(4σ)` factor. `σ` is bilinear in
    /// `u = √(2θ/π)`, so `A ∝ 1/σ(θo)` has a kink at each of its nodes; below the last slice
    /// they are 0.7–1.4° apart and their kinks small beside the slices', above it (no slice up
    /// to 90°) they are the only kinks, ~1.4° apart: the normaliser table of a set interpolated
    /// across them was 1–3·10⁻⁴ off (issue 27, docs/benchmarks.md §13.10).
    pub fn theta_kinks(&self) -> Vec<f64> {
        let eps = 1e-6;
        let top = FRAC_PI_2 - eps;
        let mut k: Vec<f64> = self
            .theta_slices()
            .iter()
            .copied()
            .filter(|t| t.is_finite() && *t > eps && *t < top)
            .collect();
        let last = k.iter().copied().fold(0.0, f64::max);
        if self.tables.jacobian {
            let nx = self.tables.sigma.size().0;
            k.extend(
                (1..nx.saturating_sub(1))
                    .map(|i| u_to_theta(i as f64 / (nx - 1) as f64))
                    .filter(|&t| t > last + eps && t < top),
            );
        }
        k.sort_by(f64::total_cmp);
        k.dedup_by(|a, b| (*a - *b).abs() <= eps);
        k
    }

    /// Grid sizes `(nx, ny)` of the bilinear tables `f` is made of: its interpolant is smooth
    /// inside their cells and has kinks on their edges (`ndf` and `vndf` on the `u_m`-square,
    /// `rgb` on the warped square). For integrators that follow the kinks.
    pub fn grids(&self) -> RglGrids {
        let t = &self.tables;
        RglGrids {
            ndf: t.ndf.size(),
            vndf: t.vndf.table().size(),
            rgb: t.rgb.size(),
        }
    }

    /// The VNDF warp (half-vector `u_m` from the warped square, conditioned on `θo`).
    pub fn vndf(&self) -> &Warp2D {
        &self.tables.vndf
    }

    /// The luminance sampling density on the warped square, conditioned on `θo`.
    pub fn luminance_warp(&self) -> &Warp2D {
        &self.tables.luminance
    }

    /// Heap bytes of the tables.
    pub fn bytes_used(&self) -> usize {
        let t = &self.tables;
        t.vndf.bytes_used()
            + t.luminance.bytes_used()
            + 8 * (t.rgb.slices() * t.rgb.size().0 * t.rgb.size().1)
            + 8 * 2 * (t.ndf.size().0 * t.ndf.size().1)
    }

    /// The format's coordinates of `(ωo, ωi)`; `None` when either is at or below the horizon,
    /// not finite, or `ωi = −ωo`.
    pub fn half_coords(wo: &Vec3, wi: &Vec3) -> Option<HalfCoords> {
        if !(wo.z > 0.0 && wi.z > 0.0) {
            return None;
        }
        Self::half_coords_any(wo, wi)
    }

    /// [`half_coords`](Self::half_coords) for any `ωi` (the native sampler's pdf on the whole
    /// sphere): the half vector is flipped into the upper hemisphere when needed.
    pub fn half_coords_any(wo: &Vec3, wi: &Vec3) -> Option<HalfCoords> {
        let sum = wo + wi;
        let norm = sum.norm();
        if !(norm > 1e-12) || !(wo.z > 0.0) {
            return None;
        }
        let mut m = sum / norm;
        if m.z < 0.0 {
            m = -m;
        }
        let theta_o = elevation(wo);
        let phi_o = wo.y.atan2(wo.x);
        let theta_m = elevation(&m);
        let phi_m = m.y.atan2(m.x);
        let mut um_y = phi_to_u(phi_m - phi_o);
        um_y -= um_y.floor();
        Some(HalfCoords {
            theta_o,
            u_o: [theta_to_u(theta_o), phi_to_u(phi_o)],
            u_m: [theta_to_u(theta_m), um_y],
            m,
        })
    }

    /// Linear RGB value of `f_r · cos θi` at given coordinates (the format's definition, see
    /// the module docs).
    pub fn rgb_cos_at(&self, c: &HalfCoords) -> [f64; 3] {
        let (s, i, w, factor) = self.lookup(c);
        let t = &self.tables;
        let mut out = [0.0; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            *o = (t.rgb.eval(s, 3 * i + ch, 3, w) * factor).max(0.0);
        }
        out
    }

    /// Luminance of [`rgb_cos_at`](Self::rgb_cos_at) (one table lookup instead of three).
    pub fn luminance_cos_at(&self, c: &HalfCoords) -> f64 {
        let (s, i, w, factor) = self.lookup(c);
        (self.tables.rgb_luminance.eval(s, i, 1, w) * factor).max(0.0)
    }

    /// The warped-square position, the slice blend and the `D/(4σ)` factor of `c`.
    fn lookup(&self, c: &HalfCoords) -> ([f64; 2], usize, f64, f64) {
        let t = &self.tables;
        let (s, _) = t.vndf.invert(c.u_m, c.theta_o);
        let (i, w) = t.theta.locate(c.theta_o);
        let factor = if t.jacobian {
            let sigma = t.sigma.eval(c.u_o, 0, 0, 0.0);
            t.ndf.eval(c.u_m, 0, 0, 0.0) / (4.0 * sigma)
        } else {
            1.0
        };
        (s, i, w, factor)
    }
}

fn shape_error(field: &str, shape: &[usize], expected: &str) -> RglError {
    RglError::WrongShape {
        field: field.to_string(),
        shape: shape.to_vec(),
        expected: expected.to_string(),
    }
}

/// A rank-2 table `[Py, Px]` (both ≥ 2) with values `≥ min` (`> min` when `strict`).
fn plain_table(
    tf: &TensorFile<'_>,
    name: &str,
    min: f64,
    strict: bool,
) -> Result<(BilinearTable, ()), RglError> {
    let shape = tf.field(name)?.shape.clone();
    if shape.len() != 2 || shape[0] < 2 || shape[1] < 2 {
        return Err(shape_error(name, &shape, "[Py, Px] with Py, Px ≥ 2"));
    }
    let data = tf.f32_data(name)?;
    check_min(name, &data, min, strict)?;
    Ok((BilinearTable::new(shape[1], shape[0], data), ()))
}

fn check_min(name: &str, data: &[f64], min: f64, strict: bool) -> Result<(), RglError> {
    for (index, &value) in data.iter().enumerate() {
        let ok = if strict { value > min } else { value >= min };
        if !ok {
            return Err(RglError::OutOfRange {
                field: name.to_string(),
                index,
                value,
                rule: if strict {
                    "must be positive"
                } else {
                    "must be non-negative"
                },
            });
        }
    }
    Ok(())
}

/// Trapezoid weights of the mean over `[0, 1]` of the linear interpolant on `n ≥ 2` equally
/// spaced nodes.
fn trapezoid_weight(k: usize, n: usize) -> f64 {
    let h = 1.0 / (n - 1) as f64;
    if k == 0 || k == n - 1 { 0.5 * h } else { h }
}

/// `∫₀¹ p(u) g(u) du` for the linear interpolant `p` of `profile` (nodes `k/(n−1)`), with 8
/// midpoints per cell.
fn integrate_profile(profile: &[f64], g: impl Fn(f64) -> f64) -> f64 {
    const SUB: usize = 8;
    let cells = profile.len() - 1;
    let h = 1.0 / (cells * SUB) as f64;
    let mut sum = 0.0;
    for c in 0..cells {
        for k in 0..SUB {
            let t = (k as f64 + 0.5) / SUB as f64;
            let u = (c as f64 + t) / cells as f64;
            sum += ((1.0 - t) * profile[c] + t * profile[c + 1]) * g(u) * h;
        }
    }
    sum
}

fn implausible(field: &str, detail: String) -> RglError {
    RglError::Implausible {
        field: field.to_string(),
        detail,
    }
}

/// The rules between `ndf`, `sigma` and `rgb` listed in [`RglBrdf::from_bytes`]. `rgb` is
/// clamped (non-negative); `rgb_grid` is its `(nx, ny)`.
fn check_physics(
    ndf: &BilinearTable,
    sigma: &BilinearTable,
    rgb: &[f64],
    rgb_grid: (usize, usize),
    jacobian: bool,
) -> Result<(), RglError> {
    let (nx, ny) = ndf.size();
    let d = ndf.values();
    // Mean of D over the azimuth (exact for the bilinear interpolant), per θ node.
    let profile: Vec<f64> = (0..nx)
        .map(|i| {
            (0..ny)
                .map(|j| trapezoid_weight(j, ny) * d[j * nx + i])
                .sum()
        })
        .collect();
    // dω = sin θ dθ dφ with θ = u₀²π/2, φ = 2πu₁ − π: sin θ · πu₀ du₀ · 2π du₁.
    let jac = |u: f64| 2.0 * PI * PI * u;
    let theta = u_to_theta;
    let norm = integrate_profile(&profile, |u| theta(u).cos() * theta(u).sin() * jac(u));
    let (lo, hi) = NDF_NORMALISATION_RANGE;
    if !(lo..=hi).contains(&norm) {
        return Err(implausible(
            "ndf",
            format!(
                "∫ D cos θm dm = {norm:.4e}, outside [{lo}, {hi}] (a microfacet distribution has 1)"
            ),
        ));
    }
    let total = integrate_profile(&profile, |u| theta(u).sin() * jac(u));
    let (sx, sy) = sigma.size();
    let s = sigma.values();
    for j in 0..sy {
        for i in 0..sx {
            let v = s[j * sx + i];
            let cos = theta(i as f64 / (sx - 1) as f64).cos();
            if !(v >= 0.5 * cos && v <= 2.0 * total) {
                return Err(implausible(
                    "sigma",
                    format!(
                        "value {v:e} at index {} is outside [cos θ / 2, 2 ∫ D dm] = [{:.4e}, {:.4e}] (the projected area ∫ D ⟨ω·m⟩ dm)",
                        j * sx + i,
                        0.5 * cos,
                        2.0 * total
                    ),
                ));
            }
        }
    }
    let (mx, my) = rgb_grid;
    let cell = mx * my;
    if jacobian {
        for (k, slice) in rgb.chunks_exact(cell).enumerate() {
            let mean: f64 = (0..my)
                .map(|j| {
                    let row: f64 = (0..mx)
                        .map(|i| trapezoid_weight(i, mx) * slice[j * mx + i])
                        .sum();
                    trapezoid_weight(j, my) * row
                })
                .sum();
            if !(mean <= MAX_SLICE_ALBEDO) {
                return Err(implausible(
                    "rgb",
                    format!(
                        "slice {} channel {} has albedo {mean:.4e} > {MAX_SLICE_ALBEDO}",
                        k / 3,
                        k % 3
                    ),
                ));
            }
        }
    }
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let min_sigma = s.iter().copied().fold(f64::INFINITY, f64::min);
    let peak = if jacobian {
        max(rgb) * max(d) / (4.0 * min_sigma)
    } else {
        max(rgb)
    };
    if !(peak <= f64::from(f32::MAX)) {
        return Err(implausible(
            "rgb",
            format!("max rgb · max D / (4 min σ) = {peak:e} overflows f32"),
        ));
    }
    Ok(())
}

/// Each slice of a sampling table sums to a finite `f32` (Mitsuba builds its CDFs in `f32`).
fn check_f32_sums(name: &str, values: &[f64], slice_len: usize) -> Result<(), RglError> {
    for (k, slice) in values.chunks_exact(slice_len).enumerate() {
        let sum: f64 = slice.iter().sum();
        if !(sum <= f64::from(f32::MAX)) {
            return Err(implausible(
                name,
                format!("slice {k} sums to {sum:e}, which overflows f32"),
            ));
        }
    }
    Ok(())
}

/// A rank-4 sampling table `[1, T, Ny, Nx]` (non-negative, every slice positive).
fn sampling_table(
    tf: &TensorFile<'_>,
    name: &str,
    n_theta: usize,
    axis: &ParamAxis,
) -> Result<Warp2D, RglError> {
    let shape = tf.field(name)?.shape.clone();
    if shape.len() != 4 || shape[0] != 1 || shape[1] != n_theta || shape[2] < 2 || shape[3] < 2 {
        return Err(shape_error(
            name,
            &shape,
            &format!("[1, {n_theta}, Ny, Nx] with Ny, Nx ≥ 2"),
        ));
    }
    let data = tf.f32_data(name)?;
    check_min(name, &data, 0.0, false)?;
    check_f32_sums(name, &data, shape[2] * shape[3])?;
    Warp2D::new(axis.clone(), BilinearTable::new(shape[3], shape[2], data)).map_err(|z| {
        RglError::ZeroSlice {
            field: name.to_string(),
            slice: z.0,
        }
    })
}

/// What [`RglBrdf::prepare`](Brdf::prepare) keeps of `ωo` (indices into [`Outgoing::cache`]).
mod prepared {
    /// 1 when `ωo` is above the horizon, else 0.
    pub(super) const VALID: usize = 0;
    /// `(cos φo, sin φo)`: the turn that brings the half vector's azimuth relative to `ωo`.
    pub(super) const COS_PHI: usize = 1;
    /// See [`COS_PHI`].
    pub(super) const SIN_PHI: usize = 2;
    /// The slice `i` and weight `w` of `θo` on the `theta_i` axis.
    pub(super) const SLICE: usize = 3;
    /// See [`SLICE`].
    pub(super) const WEIGHT: usize = 4;
    /// `4 σ(u_o)` (1 when the file has no Jacobian factor).
    pub(super) const FOUR_SIGMA: usize = 5;
}

impl RglBrdf {
    /// The slice and weight stored in `q`, made safe to index with whatever `q` holds.
    fn prepared_slice(&self, q: &Outgoing) -> (usize, f64) {
        let n = self.tables.theta.values().len();
        if n < 2 {
            return (0, 0.0);
        }
        let (i, w) = (q.cache()[prepared::SLICE], q.cache()[prepared::WEIGHT]);
        let w = if (0.0..=1.0).contains(&w) { w } else { 0.0 };
        ((i.max(0.0) as usize).min(n - 2), w)
    }

    /// The warped-square position `s`, the slice blend `(i, w)` and the `D/(4σ)` factor of
    /// `(ωo, ωi)` for a prepared `ωo`; `None` below the horizon or for `ωi = −ωo`.
    #[inline]
    fn lookup_prepared(&self, q: &Outgoing, wi: &Vec3) -> Option<([f64; 2], usize, f64, f64)> {
        // Main's code, not through `half_prepared`: that form measured ≈ 10 % slower on
        // random-ωo evaluations (docs/benchmarks.md §24.3); the same arithmetic.
        let c = q.cache();
        // A cache from another BRDF may hold anything: only positive 4σ is taken.
        if !(c[prepared::VALID] == 1.0 && wi.z > 0.0 && c[prepared::FOUR_SIGMA] > 0.0) {
            return None;
        }
        let sum = q.wo() + wi;
        let norm = sum.norm();
        if !(norm > 1e-12) {
            return None;
        }
        let m = sum / norm;
        let (cos_o, sin_o) = (c[prepared::COS_PHI], c[prepared::SIN_PHI]);
        // Azimuth of m relative to ωo: m turned by −φo (`atan2` is scale-free: the unnormalised
        // sum serves).
        let rel = fast::atan2(cos_o * sum.y - sin_o * sum.x, cos_o * sum.x + sin_o * sum.y);
        let u_m = [theta_to_u(fast::elevation(&m)), fast::unit_azimuth(rel)];
        let t = &self.tables;
        let (i, w) = self.prepared_slice(q);
        let (s, _) = t.vndf.invert_located(u_m, i, w);
        let factor = if t.jacobian {
            t.ndf.eval(u_m, 0, 0, 0.0) / c[prepared::FOUR_SIGMA]
        } else {
            1.0
        };
        Some((s, i, w, factor))
    }

    /// The half vector's `u_m` and the `D/(4σ)` factor of `(ωo, ωi)` for a prepared `ωo`;
    /// `None` below the horizon or for `ωi = −ωo`.
    #[inline]
    fn half_prepared(&self, q: &Outgoing, wi: &Vec3) -> Option<([f64; 2], f64)> {
        let c = q.cache();
        // A cache from another BRDF may hold anything: only positive 4σ is taken.
        if !(c[prepared::VALID] == 1.0 && wi.z > 0.0 && c[prepared::FOUR_SIGMA] > 0.0) {
            return None;
        }
        let sum = q.wo() + wi;
        let norm = sum.norm();
        if !(norm > 1e-12) {
            return None;
        }
        let m = sum / norm;
        let (cos_o, sin_o) = (c[prepared::COS_PHI], c[prepared::SIN_PHI]);
        // Azimuth of m relative to ωo: m turned by −φo (`atan2` is scale-free: the unnormalised
        // sum serves).
        let rel = fast::atan2(cos_o * sum.y - sin_o * sum.x, cos_o * sum.x + sin_o * sum.y);
        let u_m = [theta_to_u(fast::elevation(&m)), fast::unit_azimuth(rel)];
        let t = &self.tables;
        let factor = if t.jacobian {
            t.ndf.eval(u_m, 0, 0, 0.0) / c[prepared::FOUR_SIGMA]
        } else {
            1.0
        };
        Some((u_m, factor))
    }

    /// [`eval_prepared`](Brdf::eval_prepared) through the two-slice tables.
    #[inline]
    fn eval_blended(&self, q: &Outgoing, wi: &Vec3) -> f64 {
        match self.lookup_prepared(q, wi) {
            Some((s, i, w, factor)) => {
                (self.tables.rgb_luminance.eval(s, i, 1, w) * factor).max(0.0) / wi.z
            }
            None => 0.0,
        }
    }

    /// Address of the tables: the identity of the material (shared by clones).
    fn owner(&self) -> usize {
        Arc::as_ptr(&self.tables) as usize
    }

    /// The `vndf` and luminance tables blended once at the elevation of `ωo`, for many
    /// evaluations at outgoing directions of that elevation (any azimuth) through
    /// [`eval_in_slice`](Self::eval_in_slice). Costs about as much as 10³ evaluations save
    /// (the `vndf` grid is read whole); [`Brdf::prepare_run`] holds one for a run of
    /// evaluations at one `ωo`.
    pub fn prepare_slice(&self, wo: &Vec3) -> PreparedSlice {
        let (i, w) = self.tables.theta.locate(fast::elevation(wo));
        self.blend_prepared(i, w)
    }

    /// The [`PreparedSlice`] of the blend `(i, w)` (as [`prepared_slice`] sanitises it).
    ///
    /// [`prepared_slice`]: Self::prepared_slice
    fn blend_prepared(&self, i: usize, w: f64) -> PreparedSlice {
        let t = &self.tables;
        let q = Outgoing::with_cache(Vec3::new(0.0, 0.0, 1.0), {
            let mut c = [0.0; Outgoing::CACHE_LEN];
            c[prepared::SLICE] = i as f64;
            c[prepared::WEIGHT] = w;
            c
        });
        let (i, w) = self.prepared_slice(&q);
        let one = t.theta.values().len() < 2;
        PreparedSlice {
            owner: self.owner(),
            slice: i,
            weight: w,
            vndf: t.vndf.blend_slice(i, w),
            rgb_luminance: if one {
                t.rgb_luminance.blend_slice(0, 0, 0.0)
            } else {
                t.rgb_luminance.blend_slice(i, 1, w)
            },
        }
    }

    /// [`Brdf::eval_prepared`] for `q` from this BRDF's [`prepare`](Brdf::prepare) through a
    /// slice from [`prepare_slice`](Self::prepare_slice): the same value bit for bit, read
    /// from the one blended slice when `q`'s θo has `p`'s blend, else through the two-slice
    /// tables.
    #[inline]
    pub fn eval_in_slice(&self, p: &PreparedSlice, q: &Outgoing, wi: &Vec3) -> f64 {
        let (i, w) = self.prepared_slice(q);
        if !p.matches(self.owner(), i, w) {
            return self.eval_blended(q, wi);
        }
        self.eval_on_slice(p, q, wi)
    }

    /// `out[k] =` [`eval_in_slice`](Self::eval_in_slice)`(p, q, wi[k])` for
    /// `k < min(wi.len(), out.len())`, bit for bit: in vector lanes (`measured/rgl/lanes.rs`,
    /// as a run's [`PreparedRun::eval_block`](crate::brdf::PreparedRun::eval_block)) when `p`
    /// holds `q`'s blend, else one direction at a time through the two-slice tables.
    pub fn eval_block_in_slice(
        &self,
        p: &PreparedSlice,
        q: &Outgoing,
        wi: &[Vec3],
        out: &mut [f64],
    ) {
        let (i, w) = self.prepared_slice(q);
        if !p.matches(self.owner(), i, w) {
            for (o, wi) in out.iter_mut().zip(wi) {
                *o = self.eval_blended(q, wi);
            }
            return;
        }
        lanes::eval_block(&block_run(self, q, p), wi, out);
    }

    /// [`eval_in_slice`](Self::eval_in_slice) for a slice known to hold `q`'s blend.
    #[inline]
    fn eval_on_slice(&self, p: &PreparedSlice, q: &Outgoing, wi: &Vec3) -> f64 {
        match self.half_prepared(q, wi) {
            Some((u_m, factor)) => {
                let (s, _) = p.vndf.invert(u_m);
                (p.rgb_luminance.eval_single(s) * factor).max(0.0) / wi.z
            }
            None => 0.0,
        }
    }
}

/// A run of evaluations at one `ωo` ([`Brdf::prepare_run`]): `ωo` prepared and its θo blend's
/// [`PreparedSlice`], held by the caller.
struct RglRun<'a> {
    brdf: &'a RglBrdf,
    q: Outgoing,
    slice: Arc<PreparedSlice>,
}

std::thread_local! {
    /// This thread's last slice made by [`Brdf::prepare_run`], with the material it belongs
    /// to (a `Weak` of its tables: the tables' allocation outlives the entry, so no other
    /// material can take its address while the entry names it). A run at a θo of the same
    /// blend `(i, w)` — the same bits — of the same material takes it instead of blending
    /// again (≈ 2·10⁵ instructions, docs/benchmarks.md §29.1): consecutive batches at one `ωo`
    /// (a fixed-ωo benchmark's chunks, a pixel's samples called in pieces). Holds one slice
    /// (≈ 3.4·10⁴ `f64`) per thread until the thread ends or another blend replaces it.
    static LAST_SLICE: std::cell::RefCell<Option<(Weak<Tables>, Arc<PreparedSlice>)>> =
        const { std::cell::RefCell::new(None) };
}

impl RglBrdf {
    /// The [`PreparedSlice`] of `wo`, `(i, w)` the θo blend its prepared form locates
    /// ([`prepared_slice`](Self::prepared_slice)): this thread's last one when it is this
    /// material's at the same blend bits, else
    /// [`prepare_slice`](Self::prepare_slice)`(wo)`, kept as the thread's last when it holds
    /// `(i, w)`. `None` when the made slice does not hold `(i, w)` (as before the cache).
    fn run_slice(&self, wo: &Vec3, i: usize, w: f64) -> Option<Arc<PreparedSlice>> {
        let owner = self.owner();
        let hit = LAST_SLICE
            .try_with(|c| {
                c.borrow().as_ref().and_then(|(m, p)| {
                    (Weak::as_ptr(m) as usize == owner && p.matches(owner, i, w))
                        .then(|| Arc::clone(p))
                })
            })
            .ok()
            .flatten();
        if hit.is_some() {
            return hit;
        }
        let slice = self.prepare_slice(wo);
        if !slice.matches(owner, i, w) {
            return None;
        }
        let slice = Arc::new(slice);
        let _ = LAST_SLICE.try_with(|c| {
            if let Ok(mut c) = c.try_borrow_mut() {
                *c = Some((Arc::downgrade(&self.tables), Arc::clone(&slice)));
            }
        });
        Some(slice)
    }
}

impl RglRun<'_> {
    /// The run as the block evaluation reads it.
    fn block_run(&self) -> lanes::BlockRun<'_> {
        block_run(self.brdf, &self.q, &self.slice)
    }
}

/// `brdf` at `q` (prepared by it) on the slice `slice` holding `q`'s blend, as the block
/// evaluation reads it.
fn block_run<'a>(brdf: &'a RglBrdf, q: &Outgoing, slice: &'a PreparedSlice) -> lanes::BlockRun<'a> {
    let c = q.cache();
    lanes::BlockRun {
        wo: *q.wo(),
        cos_o: c[prepared::COS_PHI],
        sin_o: c[prepared::SIN_PHI],
        four_sigma: c[prepared::FOUR_SIGMA],
        jacobian: brdf.tables.jacobian,
        valid: c[prepared::VALID] == 1.0 && c[prepared::FOUR_SIGMA] > 0.0,
        vndf: &slice.vndf,
        ndf: &brdf.tables.ndf,
        lum: &slice.rgb_luminance,
    }
}

impl crate::brdf::PreparedRun for RglRun<'_> {
    #[inline]
    fn eval(&self, wi: &Vec3) -> f64 {
        self.brdf.eval_on_slice(&self.slice, &self.q, wi)
    }

    /// The block in vector lanes (`measured/rgl/lanes.rs`): structure-of-arrays passes over
    /// 16 directions at a time, dispatched at run time to AVX-512 or AVX2 code; each value
    /// is [`eval`](crate::brdf::PreparedRun::eval)'s bit for bit.
    fn eval_block(&self, wi: &[Vec3], out: &mut [f64]) {
        lanes::eval_block(&self.block_run(), wi, out);
    }

    /// `true`: the block's lanes cost ≈ 0.6 of the scalar slice path per direction
    /// (docs/benchmarks.md §25.3).
    fn prefers_blocks(&self) -> bool {
        true
    }
}

impl Brdf for RglBrdf {
    fn eval(&self, wo: &Vec3, wi: &Vec3) -> f64 {
        self.eval_prepared(&self.prepare(wo), wi)
    }

    fn eval_rgb(&self, wo: &Vec3, wi: &Vec3) -> [f64; 3] {
        let q = self.prepare(wo);
        match self.lookup_prepared(&q, wi) {
            Some((s, i, w, factor)) => {
                let rgb: [f64; 3] = self.tables.rgb.eval_consecutive(s, 3 * i, 3, w);
                rgb.map(|v| (v * factor).max(0.0) / wi.z)
            }
            None => [0.0; 3],
        }
    }

    /// Keeps `θo`'s slice blend, `(cos φo, sin φo)` and `4σ(u_o)`: an evaluation at a prepared
    /// `ωo` needs one `atan2` and one `asin` (the half vector's angles) instead of two each.
    fn prepare(&self, wo: &Vec3) -> Outgoing {
        let mut c = [0.0; Outgoing::CACHE_LEN];
        if wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite() {
            let t = &self.tables;
            let theta_o = fast::elevation(wo);
            let r = fast::hypot(wo.x, wo.y);
            let (cos_o, sin_o) = if r > 0.0 {
                (wo.x / r, wo.y / r)
            } else {
                (1.0, 0.0)
            };
            let (i, w) = t.theta.locate(theta_o);
            let four_sigma = if t.jacobian {
                // φo enters σ only when σ depends on the azimuth (not in an isotropic file,
                // whose rows are then equal bit for bit: any φo gives the same value).
                let phi_o = if t.sigma_y_constant {
                    0.0
                } else if r > 0.0 {
                    fast::atan2(wo.y, wo.x)
                } else {
                    0.0
                };
                4.0 * t
                    .sigma
                    .eval([theta_to_u(theta_o), phi_to_u(phi_o)], 0, 0, 0.0)
            } else {
                1.0
            };
            c[prepared::VALID] = 1.0;
            c[prepared::COS_PHI] = cos_o;
            c[prepared::SIN_PHI] = sin_o;
            c[prepared::SLICE] = i as f64;
            c[prepared::WEIGHT] = w;
            c[prepared::FOUR_SIGMA] = four_sigma;
        }
        Outgoing::with_cache(*wo, c)
    }

    fn eval_prepared(&self, q: &Outgoing, wi: &Vec3) -> f64 {
        match self.lookup_prepared(q, wi) {
            Some((s, i, w, factor)) => {
                (self.tables.rgb_luminance.eval(s, i, 1, w) * factor).max(0.0) / wi.z
            }
            None => 0.0,
        }
    }

    /// `ωo` prepared and its θo blend's [`PreparedSlice`] (≈ 3.4·10⁴ table entries blended
    /// once: worth it for runs of many hundred evaluations); evaluations then read one slice,
    /// bit for bit `eval`'s values. `None` at and below the horizon.
    fn prepare_run(&self, wo: &Vec3) -> Option<Box<dyn crate::brdf::PreparedRun + '_>> {
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite()) {
            return None;
        }
        let q = self.prepare(wo);
        let (i, w) = self.prepared_slice(&q);
        let slice = self.run_slice(wo, i, w)?;
        Some(Box::new(RglRun {
            brdf: self,
            q,
            slice,
        }) as Box<dyn crate::brdf::PreparedRun + '_>)
    }

    /// True when the file's `ndf` and `sigma` do not depend on the azimuth (checked when read):
    /// the rest of the format depends on azimuths only through `φm − φo`.
    fn is_isotropic(&self) -> bool {
        self.tables.isotropic
    }

    /// Isotropic and every table even in the relative azimuth (checked when read, relative
    /// tolerance [`SYMMETRY_TOLERANCE`]): then `φm − φo ↦ φo − φm` leaves `f` unchanged.
    fn is_mirror_symmetric(&self) -> bool {
        self.tables.mirror_symmetric
    }

    fn is_half_turn_symmetric(&self) -> bool {
        self.tables.isotropic
    }

    /// `false`: tabulated `f·cos θi` does not vanish at grazing `ωi` (bilinear interpolation
    /// of measured data), so `f = (f·cos)/cos θi` grows like `1/cos θi` there.
    fn bounded_at_horizon(&self) -> bool {
        false
    }

    fn name(&self) -> &str {
        "rgl"
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// The repository's fixture (`data/measured/rgl/paper_white_rgb.bsdf`).
    fn fixture() -> RglBrdf {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        RglBrdf::load(&path).expect("the RGL fixture is in the repository")
    }

    /// The evaluation before the `libm` angles (session 8), kept as the reference: `std`'s
    /// `asin`, `hypot`, `atan2` and `floor`, `σ` read at `φo`, the normalised half vector's
    /// azimuth. Returns the luminance and the RGB of `f_r`.
    fn old_eval(b: &RglBrdf, wo: &Vec3, wi: &Vec3) -> (f64, [f64; 3]) {
        let t = &b.tables;
        if !(wo.z > 0.0 && wo.x.is_finite() && wo.y.is_finite() && wi.z > 0.0) {
            return (0.0, [0.0; 3]);
        }
        let theta_o = elevation(wo);
        let r = wo.x.hypot(wo.y);
        let (phi_o, cos_o, sin_o) = if r > 0.0 {
            (wo.y.atan2(wo.x), wo.x / r, wo.y / r)
        } else {
            (0.0, 1.0, 0.0)
        };
        let (i, w) = t.theta.locate(theta_o);
        let four_sigma = if t.jacobian {
            4.0 * t
                .sigma
                .eval([theta_to_u(theta_o), phi_to_u(phi_o)], 0, 0, 0.0)
        } else {
            1.0
        };
        let sum = wo + wi;
        let norm = sum.norm();
        if !(norm > 1e-12) {
            return (0.0, [0.0; 3]);
        }
        let m = sum / norm;
        let rel = (cos_o * m.y - sin_o * m.x).atan2(cos_o * m.x + sin_o * m.y);
        let mut um_y = phi_to_u(rel);
        um_y -= um_y.floor();
        let u_m = [theta_to_u(elevation(&m)), um_y];
        let (s, _) = t.vndf.invert_located(u_m, i, w);
        let factor = if t.jacobian {
            t.ndf.eval(u_m, 0, 0, 0.0) / four_sigma
        } else {
            1.0
        };
        let y = (t.rgb_luminance.eval(s, i, 1, w) * factor).max(0.0) / wi.z;
        let rgb: [f64; 3] = t.rgb.eval_consecutive(s, 3 * i, 3, w);
        (y, rgb.map(|v| (v * factor).max(0.0) / wi.z))
    }

    /// The fixture, then every `.bsdf` file of the team's data set beside the repository (as
    /// CI has it; sorted by path), or the fixture alone when that directory is absent.
    fn fixture_and_shared_files() -> Vec<RglBrdf> {
        let mut files = vec![fixture()];
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/measured/rgl");
        match std::fs::read_dir(&dir) {
            Ok(entries) => {
                let mut paths: Vec<_> = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == "bsdf"))
                    .collect();
                paths.sort();
                files.extend(paths.iter().map(|p| RglBrdf::load(p).unwrap()));
            }
            Err(_) => println!("skipping the shared RGL files: {} is absent", dir.display()),
        }
        files
    }

    /// A direction of the upper hemisphere from two uniforms, cosine-weighted towards the
    /// horizon as often as the normal (`z = u`), with 1 in 64 within 1e-9 of the normal.
    fn direction(u: f64, v: f64, near_normal: bool) -> Vec3 {
        let z = if near_normal {
            1.0 - 1e-9 * u
        } else {
            u.max(1e-6)
        };
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * v;
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }

    /// The evaluation path (`prepare` + `eval_prepared`, and `eval_rgb`) is the same
    /// interpolant as before its `libm` angles and dropped `floor`/`hypot`/`φo` (session 8):
    /// 10⁵ random pairs (fixed seed) within 1e-12 relative of [`old_eval`] (values below
    /// 1e-12 of the largest compared absolutely).
    #[test]
    fn evaluation_matches_the_std_angles_on_random_pairs() {
        let b = fixture();
        let mut uniform = crate::test_support::splitmix_uniforms(0x9e37_79b9_7f4a_7c15_u64);
        let mut pairs = Vec::with_capacity(100_000);
        for k in 0..100_000 {
            let wo = direction(uniform(), uniform(), k % 64 == 0);
            let wi = direction(uniform(), uniform(), k % 64 == 1);
            pairs.push((wo, wi));
        }
        let values: Vec<_> = pairs
            .iter()
            .map(|(wo, wi)| {
                let q = b.prepare(wo);
                (
                    b.eval_prepared(&q, wi),
                    b.eval_rgb(wo, wi),
                    old_eval(&b, wo, wi),
                )
            })
            .collect();
        let peak = values.iter().map(|v| v.2.0).fold(0.0, f64::max);
        assert!(peak > 0.0);
        // Worst relative difference: both directions up to 85° from the normal, and any.
        let (mut worst, mut worst_grazing, mut positive) = (0.0_f64, 0.0_f64, 0);
        // The old path's own change when `ωi.x` moves by one ulp, at the grazing pairs: the
        // conditioning that bounds any change of rounding there.
        let mut ulp_change = 0.0_f64;
        let grazing = |d: &Vec3| d.z < 85f64.to_radians().cos();
        for ((y, rgb, (y0, rgb0)), (wo, wi)) in values.iter().zip(&pairs) {
            positive += usize::from(*y0 > 0.0);
            let mut e = 0.0_f64;
            for (a, r) in std::iter::once((*y, *y0)).chain(rgb.iter().copied().zip(*rgb0)) {
                assert!(a.is_finite() && a >= 0.0);
                e = e.max((a - r).abs() / r.max(1e-12 * peak));
            }
            if grazing(wo) || grazing(wi) {
                worst_grazing = worst_grazing.max(e);
                let nudged = Vec3::new(f64::from_bits(wi.x.to_bits() + 1), wi.y, wi.z);
                let y1 = old_eval(&b, wo, &nudged).0;
                ulp_change = ulp_change.max((y1 - y0).abs() / y0.max(1e-12 * peak));
            } else {
                worst = worst.max(e);
            }
        }
        println!(
            "relative difference to the std path: {worst:e} (both ≤ 85°), {worst_grazing:e} \
             (one beyond 85°); the std path's own change for a 1-ulp move of ωi.x there: \
             {ulp_change:e}"
        );
        assert!(positive > 90_000, "{positive} positive values");
        assert!(worst <= 1e-12, "worst relative difference {worst:e}");
        // Near the horizon the interpolant is ill-conditioned (a 1-ulp move of an angle moves
        // f by up to ~1e-10): the difference must stay below that order.
        assert!(
            worst_grazing <= 1e-9,
            "worst relative difference beyond 85° {worst_grazing:e}"
        );
    }

    /// The block evaluation in lanes (`lanes.rs`) returns [`PreparedRun::eval`]'s value (itself
    /// `eval`'s) **bit for bit**, at every instruction-set level the host has, on the fixture
    /// and every shared RGL file: random pairs (`ωi` cosine-spread, near the normal, at the
    /// mirror direction — `atan2(0, 0)`, msun's special case —, below the horizon, `−ωo`),
    /// blocks of every length 0–40 (partial lanes), `ωo` at the normal, on slices and random;
    /// the direct msun copies against `libm` on arguments spanning each of their ranges.
    ///
    /// [`PreparedRun::eval`]: crate::brdf::PreparedRun::eval
    #[test]
    fn block_evaluation_in_lanes_is_bit_identical() {
        let mut uniform = crate::test_support::splitmix_uniforms(0x001a_9e5b_10c4_u64);
        // The msun copies, each range of `asin` on [0, 1) and of `atan2` (both signs).
        for k in 0..200_000 {
            let e = -30.0 * uniform();
            let x = if k % 2 == 0 { uniform() } else { 2f64.powf(e) };
            let (a, bad) = lanes::asin_lane(x);
            assert!(!bad);
            assert_eq!(a.to_bits(), libm::asin(x).to_bits(), "asin({x:e})");
            let (y, x) = (
                (uniform() - 0.5) * 2f64.powf(40.0 * uniform() - 20.0),
                (uniform() - 0.5) * 2f64.powf(40.0 * uniform() - 20.0),
            );
            let (a, bad) = lanes::atan2_lane(y, x);
            if !bad {
                assert_eq!(
                    a.to_bits(),
                    libm::atan2(y, x).to_bits(),
                    "atan2({y:e}, {x:e})"
                );
            }
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (-0.0, -1.0),
            (1.0, 1.0),
            (1e-300, -1.0),
        ] {
            assert!(lanes::atan2_lane(y, x).1, "({y}, {x}) is flagged");
        }
        let files = fixture_and_shared_files();
        let levels = lanes::levels();
        println!("levels {levels:?}");
        let (mut compared, mut positive) = (0usize, 0usize);
        for b in &files {
            let slices: Vec<f64> = b.theta_slices().to_vec();
            for k in 0..24 {
                let wo = match k % 6 {
                    0 => Vec3::new(0.0, 0.0, 1.0),
                    1 | 2 => {
                        let t = slices[k % slices.len()].min(FRAC_PI_2 - 1e-6);
                        Vec3::new(t.sin(), 0.0, t.cos())
                    }
                    _ => direction(uniform(), uniform(), false),
                };
                let run = b.prepare_run(&wo).expect("a run above the horizon");
                let rgl = RglRun {
                    brdf: b,
                    q: b.prepare(&wo),
                    slice: Arc::new(b.prepare_slice(&wo)),
                };
                let wis: Vec<Vec3> = (0..820)
                    .map(|j| match j % 41 {
                        0 => crate::mirror(&wo),
                        1 => -wo,
                        2 => Vec3::new(0.3, 0.2, -0.5).normalize(),
                        3 => Vec3::new(0.0, 0.0, 1.0),
                        4 => direction(uniform(), uniform(), true),
                        _ => direction(uniform(), uniform(), false),
                    })
                    .collect();
                let want: Vec<f64> = wis.iter().map(|w| b.eval(&wo, w)).collect();
                for (w, v) in wis.iter().zip(&want) {
                    assert_eq!(run.eval(w).to_bits(), v.to_bits());
                }
                for &level in &levels {
                    // Blocks of every length 0..=40 over the list.
                    let mut start = 0;
                    let mut len = 0;
                    while start < wis.len() {
                        let end = (start + len).min(wis.len());
                        let mut out = vec![f64::NAN; end - start + 1];
                        lanes::eval_block_at(level, &rgl.block_run(), &wis[start..end], &mut out);
                        for (o, v) in out.iter().zip(&want[start..end]) {
                            assert_eq!(o.to_bits(), v.to_bits(), "{level:?} ωo {wo:?}");
                        }
                        assert!(
                            out[end - start].is_nan(),
                            "entries past the block untouched"
                        );
                        start = end;
                        len = (len + 1) % 41;
                    }
                }
                let mut out = vec![0.0; wis.len()];
                run.eval_block(&wis, &mut out);
                for (o, v) in out.iter().zip(&want) {
                    assert_eq!(o.to_bits(), v.to_bits());
                    positive += usize::from(*v > 0.0);
                }
                compared += wis.len();
            }
        }
        assert!(
            10 * positive > 8 * compared,
            "{positive} of {compared} positive"
        );
    }

    /// The prepared-slice path (one blended slice, [`RglBrdf::eval_in_slice`], and the
    /// caller-held run of [`Brdf::prepare_run`]) returns the
    /// two-slice path's value bit for bit: 10⁵ pairs (fixed seed) on the fixture, 400 `ωo`
    /// (random θo, the normal, every slice angle exactly) × 250 random `ωi`, and 10⁴ on each
    /// file of the team's data set that is present (100 × 100).
    #[test]
    fn prepared_slice_evaluation_is_bit_identical_on_random_pairs() {
        let files = fixture_and_shared_files();
        let mut uniform = crate::test_support::splitmix_uniforms(0x05ee_d0f5_11ce_u64);
        for (f, b) in files.iter().enumerate() {
            let (n_wo, n_wi) = if f == 0 { (400, 250) } else { (100, 100) };
            let slices: Vec<f64> = b.theta_slices().to_vec();
            let (mut compared, mut positive, mut on_slice) = (0usize, 0usize, 0usize);
            for k in 0..n_wo {
                let wo = match k % 25 {
                    0 => Vec3::new(0.0, 0.0, 1.0),
                    1..=8 => {
                        let t = slices[(k % 25 - 1) % slices.len()].min(FRAC_PI_2 - 1e-6);
                        let phi = TAU * uniform();
                        Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
                    }
                    _ => direction(uniform(), uniform(), false),
                };
                let q = b.prepare(&wo);
                let p = b.prepare_slice(&wo);
                // The slice is the blend `prepare` located.
                assert!(p.matches(b.owner(), b.prepared_slice(&q).0, b.prepared_slice(&q).1));
                on_slice += usize::from(p.weight == 0.0);
                let run = b.prepare_run(&wo).expect("a run above the horizon");
                for _ in 0..n_wi {
                    let wi = direction(uniform(), uniform(), false);
                    let two = b.eval_blended(&q, &wi);
                    let one = b.eval_in_slice(&p, &q, &wi);
                    assert_eq!(one.to_bits(), two.to_bits(), "ωo {wo:?} ωi {wi:?}");
                    assert_eq!(b.eval_prepared(&q, &wi).to_bits(), two.to_bits());
                    // The caller-held run: `eval` bit for bit.
                    assert_eq!(run.eval(&wi).to_bits(), b.eval(&wo, &wi).to_bits());
                    compared += 1;
                    positive += usize::from(two > 0.0);
                }
            }
            assert_eq!(compared, n_wo * n_wi);
            assert!(10 * positive > 9 * compared, "{positive} positive values");
            assert!(on_slice * 20 >= n_wo, "{on_slice} ωo on a slice");
        }
    }

    /// [`Brdf::prepare_run`]'s per-thread slice ([`RglBrdf::run_slice`]): a run at another `ωo`
    /// of the same blend bits of the same material takes the thread's last slice (the same
    /// allocation); another weight of the same slice `i`, or another material at the same `ωo`,
    /// gets its own; every run's values are `eval`'s bit for bit, in any order of runs.
    #[test]
    fn runs_share_the_threads_last_slice_only_at_the_same_material_and_blend() {
        let b = fixture();
        let c = fixture();
        assert_ne!(b.owner(), c.owner());
        let at = |deg: f64, phi: f64| {
            let t = deg.to_radians();
            Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
        };
        let blend = |m: &RglBrdf, wo: &Vec3| m.prepared_slice(&m.prepare(wo));
        let (w1, w2) = (at(30.0, 0.3), at(30.0, 2.1));
        // Another weight of the same slice `i`: a θo 0.4° away.
        let w3 = at(30.4, 0.3);
        let (b1, b3) = (blend(&b, &w1), blend(&b, &w3));
        assert_eq!(b1, blend(&b, &w2));
        assert_eq!(b1.0, b3.0, "the test needs one slice i");
        assert_ne!(b1.1.to_bits(), b3.1.to_bits());
        let s1 = b.run_slice(&w1, b1.0, b1.1).expect("a slice");
        let s2 = b.run_slice(&w2, b1.0, b1.1).expect("a slice");
        assert!(Arc::ptr_eq(&s1, &s2), "the same blend takes the kept slice");
        let s3 = b.run_slice(&w3, b3.0, b3.1).expect("a slice");
        assert!(s3.matches(b.owner(), b3.0, b3.1));
        let s4 = c.run_slice(&w3, b3.0, b3.1).expect("a slice");
        assert!(!Arc::ptr_eq(&s3, &s4), "another material makes its own");
        assert!(s4.matches(c.owner(), b3.0, b3.1));
        // Runs' values in an order that alternates blends and materials.
        let mut uniform = crate::test_support::splitmix_uniforms(0x51ce_cace);
        let wis: Vec<Vec3> = (0..400)
            .map(|_| direction(uniform(), uniform(), false))
            .collect();
        let mut positive = 0;
        for (m, wo) in [
            (&b, w1),
            (&b, w3),
            (&c, w3),
            (&b, w1),
            (&c, w2),
            (&b, w2),
            (&b, w3),
        ] {
            let run = m.prepare_run(&wo).expect("a run above the horizon");
            let mut block = vec![0.0; wis.len()];
            run.eval_block(&wis, &mut block);
            for (wi, v) in wis.iter().zip(&block) {
                let want = m.eval(&wo, wi);
                assert_eq!(
                    run.eval(wi).to_bits(),
                    want.to_bits(),
                    "ωo {wo:?} ωi {wi:?}"
                );
                assert_eq!(v.to_bits(), want.to_bits(), "block, ωo {wo:?} ωi {wi:?}");
                positive += usize::from(want > 0.0);
            }
        }
        assert!(positive > 7 * 300, "{positive} positive values");
    }
}
