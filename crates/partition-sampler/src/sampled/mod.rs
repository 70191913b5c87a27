//! A density evaluated on a dense grid (the papers' bottom-up "image map", seed 000 §3.7):
//! region integrals by the midpoint rule, region bounds from point values times a safety
//! factor.

mod fill;
mod lattice;
mod refinement;

use crate::contract::Point2;
use crate::density::{
    Density, DensityShape, IntegralSource, ProviderKind, RegionEstimate, RegionStats,
};
use crate::error::DensityError;
use crate::pyramid::{CellSource, Pyramid, snap};
use crate::rect::{Domain, Rect};

pub use refinement::{DEFAULT_REFINEMENT_COARSEST, DEFAULT_REFINEMENT_TOLERANCE, Refinement};

/// Default multiplier applied to grid maxima to obtain the leaf bounds `M_i`.
pub const DEFAULT_SAFETY_FACTOR: f64 = 1.1;

/// Largest accepted grid resolution per axis.
const MAX_RESOLUTION: usize = 8192;

/// Where a [`SampledGridDensity`] evaluates `f`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GridOptions {
    /// A point where `f` may have a feature narrower than the coarse stencil (e.g. the mirror
    /// direction of a glossy BRDF): with a [`Refinement`], every block whose 3 × 3-block
    /// neighbourhood contains it is split, down to single fine cells.
    pub focus: Option<Point2>,
    /// `None` (default): every corner and centre of the grid, boundary cells on an 8 × 8
    /// sub-grid (the papers' image map). `Some`: curvature-driven [`Refinement`], boundary
    /// cells on a 4 × 4 sub-grid.
    pub refinement: Option<Refinement>,
    /// The caller declares `f(x, −y) = f(x, y)`: only points with `y ≤ 0` are evaluated and
    /// mirrored (e.g. an isotropic BRDF's slice with `ωo` in the xz-plane). Requires a domain
    /// symmetric about `y = 0` and an even resolution.
    pub mirror_y: bool,
}

/// Any [`Density`] `f` plus an `n × n` grid of fine cells over the domain's bounding rectangle,
/// evaluated once at construction (in parallel, deterministically):
///
/// * integral of a fine cell: `f(centre) · area` (midpoint rule); cells crossed by the disc
///   boundary use an 8 × 8 sub-grid restricted to the disc; cells outside the disc are 0;
///   with a [`Refinement`], smooth blocks share their Simpson integral instead (see there);
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
    evaluations: usize,
    sx: f64,
    sy: f64,
}

impl<D: Density> SampledGridDensity<D> {
    /// Evaluates `f` on an `n × n` grid of fine cells over `domain`'s bounding rectangle
    /// (`[-1, 1]²` for the disc): `(n + 1)²` corners, `n²` centres and the boundary sub-grids.
    ///
    /// Errors: `n` outside `1 ..= 8192`, an invalid domain, `f` returning NaN / negative /
    /// infinite values at a grid point (the first one in row-major order is named), or an
    /// all-zero grid.
    pub fn new(f: D, domain: Domain, n: usize) -> Result<Self, DensityError> {
        Self::with_options(f, domain, n, &GridOptions::default())
    }

    /// [`SampledGridDensity::new`] with a choice of evaluation points ([`GridOptions`]).
    ///
    /// Errors as for `new`, plus an invalid [`Refinement`] (coarsest not a power of two `≥ 2`,
    /// `n` not a power of two, tolerance not finite and `≥ 0`) and a mirror request
    /// on a domain not symmetric about `y = 0` or with odd `n`.
    pub fn with_options(
        f: D,
        domain: Domain,
        n: usize,
        options: &GridOptions,
    ) -> Result<Self, DensityError> {
        if n == 0 || n > MAX_RESOLUTION {
            return Err(DensityError::InvalidResolution(n));
        }
        if !domain.is_valid() {
            return Err(DensityError::InvalidDomain(domain.bounding_rect()));
        }
        let grid = domain.bounding_rect();
        if options.mirror_y && (!n.is_multiple_of(2) || grid.y0 != -grid.y1) {
            return Err(DensityError::InvalidMirror { n, domain: grid });
        }
        let filled = match options.refinement {
            None => fill::dense(&f, domain, n, options.mirror_y, fill::DENSE_SUBGRID)?,
            Some(r) => {
                let ok = n.is_power_of_two()
                    && r.coarsest.is_power_of_two()
                    && r.coarsest >= 2
                    && r.tolerance.is_finite()
                    && r.tolerance >= 0.0;
                if !ok {
                    return Err(DensityError::InvalidRefinement {
                        n,
                        coarsest: r.coarsest,
                        tolerance: r.tolerance,
                    });
                }
                fill::refined(&f, domain, n, options.mirror_y, r, options.focus)?
            }
        };
        let mut d = Self {
            f,
            domain,
            grid,
            n,
            cells: filled.cells,
            pyramid: Pyramid::build(0, 0, &Level0(&[], 0)),
            safety: DEFAULT_SAFETY_FACTOR,
            total: 0.0,
            rel_err: 0.0,
            evaluations: filled.evaluations,
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
        d.rel_err =
            (filled.richardson.abs() / 3.0 + filled.coarse_rule.abs() + filled.boundary.abs())
                / d.total;
        Ok(d)
    }

    /// Points of the domain where `f` was evaluated at construction.
    pub fn evaluations(&self) -> usize {
        self.evaluations
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

impl<D> SampledGridDensity<D> {
    /// `region(cell).max_bound` bit for bit, without the integral: `safety ·` the largest
    /// fine-cell maximum over the cells meeting `cell` with positive area (grid coordinates
    /// snapped as `region` snaps them); `+∞` once compacted. For callers that need the bound
    /// only (a bound over a grown rectangle), at a fraction of `region`'s cost on rectangles
    /// not aligned on the pyramid's blocks (docs/benchmarks.md §32.2).
    pub fn max_bound(&self, cell: &Rect) -> f64 {
        if self.cells.is_empty() {
            return f64::INFINITY;
        }
        let nf = self.n as f64;
        let xa = snap((cell.x0 - self.grid.x0) * self.sx, nf);
        let xb = snap((cell.x1 - self.grid.x0) * self.sx, nf);
        let ya = snap((cell.y0 - self.grid.y0) * self.sy, nf);
        let yb = snap((cell.y1 - self.grid.y0) * self.sy, nf);
        self.pyramid
            .query_max(&Level0(&self.cells, self.n), xa, xb, ya, yb)
            * self.safety
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
        self.domain.restrict(p, |p| self.f.eval(p))
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

    /// [`SampledGridDensity::max_bound`] is `region(..).max_bound` bit for bit on a refined
    /// disc grid (kept blocks, boundary cells), for random rectangles inside and across the
    /// disc, tiny to whole, and on the compacted density.
    #[test]
    fn max_bound_is_the_region_bound() {
        let f = |p: Point2| (-30.0 * ((p[0] - 0.3).powi(2) + (p[1] + 0.2).powi(2))).exp() + 0.1;
        let options = GridOptions {
            refinement: Some(Refinement::default()),
            ..GridOptions::default()
        };
        let d = SampledGridDensity::with_options(f, Domain::UnitDisc, 128, &options)
            .unwrap()
            .with_safety_factor(1.1)
            .unwrap();
        let mut state = 9u64;
        let mut u = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as f64 / 2f64.powi(64)
        };
        for _ in 0..5_000 {
            let size = 2.2 * u().powi(4) + 1e-4;
            let (x, y) = (2.4 * u() - 1.2, 2.4 * u() - 1.2);
            let r = Rect::new(x, y, x + size, y + size * (0.3 + u()));
            assert_eq!(
                d.max_bound(&r).to_bits(),
                d.region(&r).max_bound.to_bits(),
                "{r:?}"
            );
        }
        let c = d.compact();
        let r = Rect::new(0.0, 0.0, 0.1, 0.1);
        assert_eq!(c.max_bound(&r), c.region(&r).max_bound);
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
