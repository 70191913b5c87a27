//! A density evaluated on a dense grid (the papers' bottom-up "image map", seed 000 §3.7):
//! region integrals by the midpoint rule, region bounds from point values times a safety
//! factor.

use rayon::prelude::*;

use crate::density::{
    Density, DensityShape, IntegralSource, ProviderKind, RegionEstimate, RegionStats,
};
use crate::error::DensityError;
use crate::pyramid::{CellSource, Pyramid, snap};
use crate::rect::{Domain, Rect, interval_min_abs};
use crate::sampler::Point2;

/// Default multiplier applied to grid maxima to obtain the leaf bounds `M_i`.
pub const DEFAULT_SAFETY_FACTOR: f64 = 1.1;

/// Sub-samples per axis in fine cells crossed by the disc boundary.
const SUB: usize = 8;

/// Largest accepted grid resolution per axis.
const MAX_RESOLUTION: usize = 8192;

/// Any [`Density`] `f` plus an `n × n` grid of fine cells over the domain's bounding rectangle,
/// evaluated once at construction (in parallel, deterministically):
///
/// * integral of a fine cell: `f(centre) · area` (midpoint rule); cells crossed by the disc
///   boundary use an 8 × 8 sub-grid restricted to the disc; cells outside the disc are 0;
/// * maximum of a fine cell: the largest of the point values at its 4 corners and its centre
///   (plus, on the disc boundary, the sub-grid points and their radial projections onto the
///   circle); the leaf bound is `M_i = safety · max` over the fine cells touching the leaf;
/// * the relative error of the total integral is estimated by Richardson extrapolation
///   (midpoint rule at spacing `h` against `2h`, `|I_h − I_2h| / 3`, over interior 2 × 2
///   blocks) plus, for the disc, the summed signed difference between the 8 × 8 and 4 × 4
///   sub-grids of the boundary cells.
///
/// Pointwise evaluation ([`Density::eval`]) calls `f` itself (0 outside the domain), so
/// sampling is exact in shape whenever the bounds hold; the sampler audits them.
/// Use `n` a power of two so quadtree cells align with fine cells.
#[derive(Clone)]
pub struct SampledGridDensity<D> {
    f: D,
    domain: Domain,
    grid: Rect,
    n: usize,
    cells: Vec<[f64; 2]>,
    pyramid: Pyramid,
    safety: f64,
    total: f64,
    rel_err: f64,
    sx: f64,
    sy: f64,
}

/// Evaluates `f` at `p`, mapping points outside the domain to 0 and recording the first
/// invalid value.
fn eval_checked<D: Density>(f: &D, domain: &Domain, p: Point2) -> Result<f64, DensityError> {
    if !domain.contains(p) {
        return Ok(0.0);
    }
    f.eval_checked(p)
}

/// Statistics of one boundary cell: (max, integral with 8×8 sub-grid, integral with 4×4).
fn boundary_cell<D: Density>(f: &D, cell: &Rect) -> Result<(f64, f64, f64), DensityError> {
    let d = Domain::UnitDisc;
    let (w, h) = (cell.width(), cell.height());
    let mut max = 0.0f64;
    let mut s8 = 0.0;
    for b in 0..SUB {
        for a in 0..SUB {
            let p = [
                cell.x0 + (a as f64 + 0.5) / SUB as f64 * w,
                cell.y0 + (b as f64 + 0.5) / SUB as f64 * h,
            ];
            let r2 = p[0] * p[0] + p[1] * p[1];
            if r2 <= 1.0 {
                let v = eval_checked(f, &d, p)?;
                s8 += v;
                max = max.max(v);
            } else {
                // Radial projection onto the circle, kept if it lies in the cell.
                let k = (1.0 - 1e-12) / r2.sqrt();
                let q = [p[0] * k, p[1] * k];
                if cell.contains(q) {
                    max = max.max(eval_checked(f, &d, q)?);
                }
            }
        }
    }
    let mut s4 = 0.0;
    for b in 0..4 {
        for a in 0..4 {
            let p = [
                cell.x0 + (a as f64 + 0.5) / 4.0 * w,
                cell.y0 + (b as f64 + 0.5) / 4.0 * h,
            ];
            s4 += eval_checked(f, &d, p)?;
        }
    }
    let area = cell.area();
    Ok((max, s8 * area / (SUB * SUB) as f64, s4 * area / 16.0))
}

impl<D: Density> SampledGridDensity<D> {
    /// Evaluates `f` on an `n × n` grid of fine cells over `domain`'s bounding rectangle
    /// (`[-1, 1]²` for the disc): `(n + 1)²` corners, `n²` centres and the boundary sub-grids.
    ///
    /// Errors: `n` outside `1 ..= 8192`, an invalid domain, `f` returning NaN / negative /
    /// infinite values at a grid point (the first one in row-major order is named), or an
    /// all-zero grid.
    pub fn new(f: D, domain: Domain, n: usize) -> Result<Self, DensityError> {
        if n == 0 || n > MAX_RESOLUTION {
            return Err(DensityError::InvalidResolution(n));
        }
        if !domain.is_valid() {
            return Err(DensityError::InvalidDomain(domain.bounding_rect()));
        }
        let grid = domain.bounding_rect();
        let (hx, hy) = (grid.width() / n as f64, grid.height() / n as f64);
        let at = |a: usize, b: usize, off: f64| {
            [
                grid.x0 + (a as f64 + off) * hx,
                grid.y0 + (b as f64 + off) * hy,
            ]
        };
        // Corner lattice (n+1)² and centres n², row by row in parallel.
        let rows = |m: usize, off: f64| -> Result<Vec<f64>, DensityError> {
            let vals: Vec<Result<Vec<f64>, DensityError>> = (0..m)
                .into_par_iter()
                .map(|b| {
                    (0..m)
                        .map(|a| eval_checked(&f, &domain, at(a, b, off)))
                        .collect()
                })
                .collect();
            let mut out = Vec::with_capacity(m * m);
            for r in vals {
                out.extend(r?);
            }
            Ok(out)
        };
        let corners = rows(n + 1, 0.0)?;
        let centres = rows(n, 0.5)?;
        let disc = matches!(domain, Domain::UnitDisc);
        let cell_area = hx * hy;
        let cell_rect = |a: usize, b: usize| {
            Rect::new(
                at(a, b, 0.0)[0],
                at(a, b, 0.0)[1],
                at(a + 1, b + 1, 0.0)[0],
                at(a + 1, b + 1, 0.0)[1],
            )
        };
        // Classification: 0 = inside, 1 = boundary, 2 = outside.
        let class = |a: usize, b: usize| -> u8 {
            if !disc {
                return 0;
            }
            let r = cell_rect(a, b);
            let far = |u: f64, v: f64| u.abs().max(v.abs());
            let fx = far(r.x0, r.x1);
            let fy = far(r.y0, r.y1);
            let (mx, my) = (interval_min_abs(r.x0, r.x1), interval_min_abs(r.y0, r.y1));
            if fx * fx + fy * fy <= 1.0 {
                0
            } else if mx * mx + my * my >= 1.0 {
                2
            } else {
                1
            }
        };
        let boundary: Vec<(usize, usize)> = (0..n)
            .flat_map(|b| (0..n).map(move |a| (a, b)))
            .filter(|&(a, b)| class(a, b) == 1)
            .collect();
        let bstats: Vec<Result<(f64, f64, f64), DensityError>> = boundary
            .par_iter()
            .map(|&(a, b)| boundary_cell(&f, &cell_rect(a, b)))
            .collect();
        let mut cells = vec![[0.0f64; 2]; n * n];
        let mut bnd_err = 0.0;
        for b in 0..n {
            for a in 0..n {
                if class(a, b) == 0 {
                    let c = [
                        corners[b * (n + 1) + a],
                        corners[b * (n + 1) + a + 1],
                        corners[(b + 1) * (n + 1) + a],
                        corners[(b + 1) * (n + 1) + a + 1],
                    ];
                    let m = c.iter().fold(centres[b * n + a], |m, &v| m.max(v));
                    cells[b * n + a] = [m, centres[b * n + a] * cell_area];
                }
            }
        }
        for (&(a, b), s) in boundary.iter().zip(bstats) {
            let (m, s8, s4) = s?;
            // Corner and centre values inside the disc also count towards the maximum.
            let mut mm = m.max(centres[b * n + a]);
            for (ca, cb) in [(a, b), (a + 1, b), (a, b + 1), (a + 1, b + 1)] {
                mm = mm.max(corners[cb * (n + 1) + ca]);
            }
            cells[b * n + a] = [mm, s8];
            bnd_err += s8 - s4;
        }
        // Richardson on 2×2 blocks of interior cells: midpoint at h vs midpoint at 2h (the
        // block centre is the lattice corner (2a+1, 2b+1)).
        let mut rich = 0.0;
        for b in (0..n.saturating_sub(1)).step_by(2) {
            for a in (0..n.saturating_sub(1)).step_by(2) {
                if [(a, b), (a + 1, b), (a, b + 1), (a + 1, b + 1)]
                    .iter()
                    .all(|&(i, j)| class(i, j) == 0)
                {
                    let fine: f64 = [(a, b), (a + 1, b), (a, b + 1), (a + 1, b + 1)]
                        .iter()
                        .map(|&(i, j)| cells[j * n + i][1])
                        .sum();
                    let coarse = corners[(b + 1) * (n + 1) + a + 1] * 4.0 * cell_area;
                    rich += fine - coarse;
                }
            }
        }
        let mut d = Self {
            f,
            domain,
            grid,
            n,
            cells,
            pyramid: Pyramid::build(0, 0, &Level0(&[], 0)),
            safety: DEFAULT_SAFETY_FACTOR,
            total: 0.0,
            rel_err: 0.0,
            sx: n as f64 / grid.width(),
            sy: n as f64 / grid.height(),
        };
        d.pyramid = Pyramid::build(n, n, &Level0(&d.cells, n));
        d.total = d
            .pyramid
            .query(&Level0(&d.cells, n), 0.0, n as f64, 0.0, n as f64)
            .1;
        if !(d.total > 0.0 && d.total.is_finite()) {
            return Err(DensityError::ZeroTotal);
        }
        d.rel_err = (rich.abs() / 3.0 + bnd_err.abs()) / d.total;
        Ok(d)
    }

    /// Sets the safety factor `s ≥ 1` (bounds are `s ·` grid maxima).
    pub fn with_safety_factor(mut self, s: f64) -> Result<Self, DensityError> {
        if !(s.is_finite() && s >= 1.0) {
            return Err(DensityError::InvalidSafetyFactor(s));
        }
        self.safety = s;
        Ok(self)
    }

    /// The safety factor.
    pub fn safety_factor(&self) -> f64 {
        self.safety
    }

    /// Fine cells per axis.
    pub fn resolution(&self) -> usize {
        self.n
    }

    /// Grid estimate of `∫_D f dA`.
    pub fn total_integral(&self) -> f64 {
        self.total
    }

    /// Estimated relative error of [`SampledGridDensity::total_integral`].
    pub fn estimated_rel_err(&self) -> f64 {
        self.rel_err
    }

    /// The wrapped density.
    pub fn inner(&self) -> &D {
        &self.f
    }

    /// Frees the grid (about `21 n²` bytes) once a tree has been built: pointwise evaluation
    /// and the shape fingerprint are kept, but region queries then return an infinite bound,
    /// so building another tree from the compacted density fails with a typed error.
    pub fn compact(mut self) -> Self {
        self.cells = Vec::new();
        self.pyramid = Pyramid::build(0, 0, &Level0(&[], 0));
        self
    }
}

impl<D> std::fmt::Debug for SampledGridDensity<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SampledGridDensity")
            .field("domain", &self.domain)
            .field("resolution", &self.n)
            .field("safety", &self.safety)
            .field("total", &self.total)
            .field("rel_err", &self.rel_err)
            .finish_non_exhaustive()
    }
}

/// Level-0 view of the fine cells.
struct Level0<'a>(&'a [[f64; 2]], usize);

impl CellSource for Level0<'_> {
    #[inline]
    fn full(&self, i: usize, j: usize) -> (f64, f64) {
        let [m, s] = self.0[j * self.1 + i];
        (m, s)
    }
    fn partial(&self, i: usize, j: usize, xa: f64, xb: f64, ya: f64, yb: f64) -> (f64, f64) {
        let [m, s] = self.0[j * self.1 + i];
        (m, s * (xb - xa) * (yb - ya))
    }
}

impl<D: Density> Density for SampledGridDensity<D> {
    #[inline]
    fn eval(&self, p: Point2) -> f64 {
        if self.domain.contains(p) {
            self.f.eval(p)
        } else {
            0.0
        }
    }
}

impl<D: Density> RegionStats for SampledGridDensity<D> {
    fn domain(&self) -> Domain {
        self.domain
    }

    fn region(&self, cell: &Rect) -> RegionEstimate {
        if self.cells.is_empty() {
            return RegionEstimate {
                max_bound: f64::INFINITY,
                integral: 0.0,
                integral_rel_err: None,
            };
        }
        let nf = self.n as f64;
        let xa = snap((cell.x0 - self.grid.x0) * self.sx, nf);
        let xb = snap((cell.x1 - self.grid.x0) * self.sx, nf);
        let ya = snap((cell.y0 - self.grid.y0) * self.sy, nf);
        let yb = snap((cell.y1 - self.grid.y0) * self.sy, nf);
        let (m, s) = self
            .pyramid
            .query(&Level0(&self.cells, self.n), xa, xb, ya, yb);
        RegionEstimate {
            max_bound: m * self.safety,
            integral: s,
            integral_rel_err: None,
        }
    }

    fn integral_source(&self) -> IntegralSource {
        IntegralSource::GridEstimate
    }

    fn total_rel_err(&self) -> Option<f64> {
        Some(self.rel_err)
    }

    fn min_cell_size(&self) -> Option<[f64; 2]> {
        Some([
            self.grid.width() / self.n as f64,
            self.grid.height() / self.n as f64,
        ])
    }

    fn shape(&self) -> DensityShape {
        DensityShape {
            kind: ProviderKind::SampledGrid,
            domain: self.domain,
            dims: [self.n as u64, self.n as u64],
            fingerprint: self.total.to_bits() ^ self.safety.to_bits().rotate_left(17),
        }
    }

    fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.cells.capacity() * 16 + self.pyramid.bytes_used()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_integrals_and_error_estimate() {
        // ∫_D 1 = π, ∫_D x² = π/4.
        let one = SampledGridDensity::new(|_: Point2| 1.0, Domain::UnitDisc, 64).unwrap();
        assert!(
            (one.total_integral() - std::f64::consts::PI).abs() < 2e-3,
            "{}",
            one.total_integral()
        );
        let x2 = SampledGridDensity::new(|p: Point2| p[0] * p[0], Domain::UnitDisc, 128).unwrap();
        let err =
            (x2.total_integral() - std::f64::consts::FRAC_PI_4).abs() / std::f64::consts::FRAC_PI_4;
        assert!(err < 1e-3, "{err}");
        // The estimate has the right order of magnitude (within a factor of 30 either way).
        let est = x2.estimated_rel_err();
        assert!(
            est > err / 30.0 && est < err * 30.0 + 1e-6,
            "estimate {est} vs actual {err}"
        );
        // Regions: the four quadrants sum to the total; bounds include the safety factor.
        let q = [
            Rect::new(-1.0, -1.0, 0.0, 0.0),
            Rect::new(0.0, -1.0, 1.0, 0.0),
            Rect::new(-1.0, 0.0, 0.0, 1.0),
            Rect::new(0.0, 0.0, 1.0, 1.0),
        ];
        let s: f64 = q.iter().map(|r| x2.region(r).integral).sum();
        assert!((s - x2.total_integral()).abs() < 1e-12);
        assert!(x2.region(&q[3]).max_bound >= DEFAULT_SAFETY_FACTOR * (1.0 - 1e-3));
    }

    #[test]
    fn rectangle_integral_is_second_order() {
        let f = |p: Point2| (p[0] * 3.0).sin().abs() + p[1];
        let r = Rect::new(0.0, 0.0, 1.0, 2.0);
        let exact = (1.0 - 3f64.cos()) / 3.0 * 2.0 + 2.0;
        let e32 = (SampledGridDensity::new(f, Domain::Rect(r), 32)
            .unwrap()
            .total_integral()
            - exact)
            .abs();
        let e64 = (SampledGridDensity::new(f, Domain::Rect(r), 64)
            .unwrap()
            .total_integral()
            - exact)
            .abs();
        assert!(e64 < e32 / 3.0, "{e32} {e64}");
    }
}
