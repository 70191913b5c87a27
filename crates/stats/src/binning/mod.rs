//! Binned domains: a uniform grid in a 2D parameter plane `(u, v)` mapped onto the domain.
//!
//! Every binning describes its domain by a parameterisation `(u, v) ↦ point` and the density
//! `J(u, v)` of the domain's measure with respect to `du dv`; bins are the cells of a uniform
//! `n_u × n_v` grid in the parameter plane, clipped to the domain. A pdf given with respect to
//! the domain's measure (area for planar domains, solid angle for directions) integrates over a
//! bin as `∫∫ pdf(point(u, v)) J(u, v) du dv`.

mod disc;
mod grid;
mod rect;
mod sphere;

pub use disc::DiscBinning;
pub use grid::Grid;
pub use rect::RectBinning;
pub use sphere::SphereBinning;

/// A point of a planar domain, `[x, y]`.
pub type Point2 = [f64; 2];

/// A direction (unit vector) `[x, y, z]`; `z` is the polar axis (`cos θ = z`).
pub type Direction = [f64; 3];

/// A coordinate axis of the parameter plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Axis {
    /// The first parameter `u` (x for planar domains, `cos θ` for directions).
    U,
    /// The second parameter `v` (y for planar domains, `φ` for directions).
    V,
}

/// A lower or upper boundary `v = edge(u)` of a [`Patch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Edge {
    /// `v = c`.
    Const(f64),
    /// `v = +√(1 − u²)`, the upper half of the unit circle.
    CircleUpper,
    /// `v = −√(1 − u²)`, the lower half of the unit circle.
    CircleLower,
}

impl Edge {
    /// The boundary value `v` at `u` (the circle uses `√max(0, 1 − u²)`).
    pub fn at(&self, u: f64) -> f64 {
        match *self {
            Edge::Const(c) => c,
            Edge::CircleUpper => (1.0 - u * u).max(0.0).sqrt(),
            Edge::CircleLower => -(1.0 - u * u).max(0.0).sqrt(),
        }
    }

    /// Whether the edge is an arc of the unit circle.
    pub fn is_circle(&self) -> bool {
        !matches!(self, Edge::Const(_))
    }
}

/// A piece of a bin in the parameter plane: `{(u, v) : u₀ ≤ u ≤ u₁, lo(u) ≤ v ≤ hi(u)}`.
///
/// The edges are smooth on `[u₀, u₁]`, so tensor Gauss–Legendre rules converge fast on a patch.
/// Patches whose edges are circle arcs are integrated with `u = sin s` so that the square-root
/// behaviour of `√(1 − u²)` at `u = ±1` disappears.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patch {
    /// `[u₀, u₁]` with `u₀ < u₁`.
    pub u: [f64; 2],
    /// Lower boundary `v = lo(u)`.
    pub lo: Edge,
    /// Upper boundary `v = hi(u)`.
    pub hi: Edge,
}

impl Patch {
    /// The axis-aligned rectangle `[u₀, u₁] × [v₀, v₁]`.
    pub fn rect(u: [f64; 2], v: [f64; 2]) -> Self {
        Self {
            u,
            lo: Edge::Const(v[0]),
            hi: Edge::Const(v[1]),
        }
    }
}

/// A binned domain with points of type [`Binning::Point`].
///
/// Bin `b` is the grid cell `(i_u, i_v)` with `b = i_v · n_u + i_u` (rows of constant `v`; for an
/// image, `u = x` and `v = y`, so bins are in row-major order) intersected with the domain.
pub trait Binning: Sync {
    /// The domain's point type (`[f64; 2]` for planar domains, `[f64; 3]` for directions).
    type Point: Copy + Send + Sync;

    /// The uniform grid of the parameter plane.
    fn grid(&self) -> &Grid;

    /// Parameters `(u, v)` of a point, or `None` when the point is outside the domain or not finite.
    fn param_of(&self, p: &Self::Point) -> Option<[f64; 2]>;

    /// The point with parameters `(u, v)`.
    fn point_at(&self, uv: [f64; 2]) -> Self::Point;

    /// Density of the domain's measure with respect to `du dv` at `(u, v)`.
    fn jacobian(&self, uv: [f64; 2]) -> f64;

    /// The part of the domain inside the parameter rectangle `u × v`, as smooth patches
    /// (empty when they do not meet).
    fn clip(&self, u: [f64; 2], v: [f64; 2]) -> Vec<Patch>;

    /// The section of the domain on the line `axis = t`: the intervals of the *other*
    /// parameter covered by the domain (empty outside it). Used for marginal densities.
    fn section(&self, axis: Axis, t: f64) -> Vec<[f64; 2]>;

    /// Number of bins `n_u · n_v` (bins entirely outside the domain included; they have zero mass).
    fn n_bins(&self) -> usize {
        self.grid().n_cells()
    }

    /// The bin containing a point, or `None` outside the domain.
    fn bin_of(&self, p: &Self::Point) -> Option<usize> {
        self.param_of(p).and_then(|uv| self.grid().index_of(uv))
    }

    /// The patches of bin `bin` (empty for an out-of-range index or a bin outside the domain).
    fn bin_patches(&self, bin: usize) -> Vec<Patch> {
        match self.grid().cell(bin) {
            Some((u, v)) => self.clip(u, v),
            None => Vec::new(),
        }
    }
}

/// Observed counts per bin, plus the samples that fell outside the binned domain.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Histogram {
    /// `counts[b]` samples landed in bin `b`.
    pub counts: Vec<u64>,
    /// Samples outside the domain or not finite.
    pub outside: u64,
}

impl Histogram {
    /// Total number of samples, inside and outside.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum::<u64>() + self.outside
    }
}

/// Counts the points per bin of `binning`.
pub fn histogram<B: Binning + ?Sized>(binning: &B, points: &[B::Point]) -> Histogram {
    let mut counts = vec![0u64; binning.n_bins()];
    let mut outside = 0u64;
    for p in points {
        match binning.bin_of(p).and_then(|b| counts.get_mut(b)) {
            Some(c) => *c += 1,
            None => outside += 1,
        }
    }
    Histogram { counts, outside }
}
