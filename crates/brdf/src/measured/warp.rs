//! Bilinear tables on the unit square, conditioned on one parameter, and the exact
//! inverse-CDF warp of their normalised interpolant (the sampling structure of the RGL format).
//!
//! A table holds `slices` grids of `nx × ny` values `v[s][y][x]` at the grid points
//! `(x/(nx−1), y/(ny−1))` of `[0,1]²`. Between grid points a slice is the bilinear interpolant;
//! between two parameter values (a [`ParamAxis`]) it is the linear blend of the two
//! neighbouring slices.
//!
//! [`Warp2D`] normalises every slice so that its interpolant is a probability density on
//! `[0,1]²` (w.r.t. area). The blend of two normalised slices is again a density, and its
//! marginal CDF in `y` and conditional CDF in `x` are the blends of the slices' CDFs. The warp
//! is `sample(u) = p` with `F_Y(p.y) = u.y` and `F_{X|Y}(p.x | p.y) = u.x` (rows first, then the
//! column, each inverted exactly on the linear pieces); [`Warp2D::invert`] is its inverse
//! `p ↦ (F_{X|Y}(p.x | p.y), F_Y(p.y))` and [`Warp2D::eval`] the density. These are the
//! definitions the RGL format relies on (Dupuy & Jakob 2018; Mitsuba's continuous
//! `Marginal2D`), computed here in `f64`.

/// Parameter values at which the slices of a table are given (strictly increasing).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamAxis {
    values: Vec<f64>,
}

impl ParamAxis {
    /// An axis; the caller has checked that `values` is non-empty, finite and increasing.
    pub(crate) fn new(values: Vec<f64>) -> Self {
        Self { values }
    }

    /// The parameter values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// `(i, w)`: the value `p` blends slice `i` with weight `1 − w` and slice `i + 1` with weight
    /// `w ∈ [0, 1]` (clamped outside the axis; `(0, 0)` for a one-value axis).
    pub fn locate(&self, p: f64) -> (usize, f64) {
        let n = self.values.len();
        if n < 2 {
            return (0, 0.0);
        }
        // Largest i in [0, n−2] with values[i] < p (0 when none).
        let i = self.values[1..n - 1].partition_point(|&v| v < p);
        let (p0, p1) = (self.values[i], self.values[i + 1]);
        let w = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
        // NaN parameters blend nothing beyond the first slice.
        (i, if w.is_nan() { 0.0 } else { w })
    }
}

/// `slices` grids of `nx × ny` values (row-major, `x` fastest), bilinearly interpolated.
#[derive(Debug, Clone, PartialEq)]
pub struct BilinearTable {
    nx: usize,
    ny: usize,
    data: Vec<f64>,
}

impl BilinearTable {
    /// A table; the caller has checked `nx, ny ≥ 2` and `data.len() = slices·nx·ny`.
    pub(crate) fn new(nx: usize, ny: usize, data: Vec<f64>) -> Self {
        Self { nx, ny, data }
    }

    /// The values, slice after slice (row-major, `x` fastest).
    pub fn values(&self) -> &[f64] {
        &self.data
    }

    /// Number of slices.
    pub fn slices(&self) -> usize {
        self.data.len() / (self.nx * self.ny)
    }

    /// Grid size `(nx, ny)`.
    pub fn size(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Whether every slice is even under `y ↦ 1 − y` (row `r` equals row `ny − 1 − r` within a
    /// relative `tol`).
    pub fn is_y_symmetric(&self, tol: f64) -> bool {
        self.rows_match(tol, |ny, r| ny - 1 - r)
    }

    /// Whether every slice is constant along `y` (every row equals row 0 within a relative
    /// `tol`).
    pub fn is_y_constant(&self, tol: f64) -> bool {
        self.rows_match(tol, |_, _| 0)
    }

    fn rows_match(&self, tol: f64, other: impl Fn(usize, usize) -> usize) -> bool {
        let (nx, ny) = (self.nx, self.ny);
        self.data.chunks_exact(nx * ny).all(|slice| {
            (0..ny).all(|r| {
                let o = other(ny, r);
                (0..nx).all(|x| {
                    let (a, b) = (slice[r * nx + x], slice[o * nx + x]);
                    (a - b).abs() <= tol * a.abs().max(b.abs())
                })
            })
        })
    }

    fn slice_len(&self) -> usize {
        self.nx * self.ny
    }

    /// Value at grid index `k` of the blend of slices `s` and `s + stride` with weight `w`.
    #[inline]
    fn blend(&self, s: usize, stride: usize, w: f64, k: usize) -> f64 {
        let n = self.slice_len();
        let v0 = self.data[s * n + k];
        if w == 0.0 {
            v0
        } else {
            (1.0 - w) * v0 + w * self.data[(s + stride) * n + k]
        }
    }

    /// The four corners `(v00, v10, v01, v11)` of cell `(cx, cy)` of the blended slice.
    #[inline]
    fn corners(&self, s: usize, stride: usize, w: f64, cx: usize, cy: usize) -> [f64; 4] {
        let k = cy * self.nx + cx;
        [
            self.blend(s, stride, w, k),
            self.blend(s, stride, w, k + 1),
            self.blend(s, stride, w, k + self.nx),
            self.blend(s, stride, w, k + self.nx + 1),
        ]
    }

    /// The bilinear interpolant at `pos` of the blend of slice `s` (weight `1 − w`) and slice
    /// `s + stride` (weight `w`).
    pub fn eval(&self, pos: [f64; 2], s: usize, stride: usize, w: f64) -> f64 {
        let (cx, cy, fx, fy) = grid_cell(pos, self.nx, self.ny);
        let [v00, v10, v01, v11] = self.corners(s, stride, w, cx, cy);
        (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
    }
}

impl BilinearTable {
    /// The blend of slice `s` (weight `1 − w`) and slice `s + stride` (weight `w`) as a
    /// one-slice table: each grid value is the one [`eval`](Self::eval) blends at every read,
    /// so `blended.eval(pos, 0, 0, 0.0)` equals `eval(pos, s, stride, w)` bit for bit. The
    /// caller passes slices that exist.
    pub(crate) fn blend_slice(&self, s: usize, stride: usize, w: f64) -> BilinearTable {
        let n = self.slice_len();
        let a = &self.data[s * n..(s + 1) * n];
        let data = if w == 0.0 {
            a.to_vec()
        } else {
            let b = &self.data[(s + stride) * n..(s + stride + 1) * n];
            // `blend`'s expression over whole slices (no per-entry index checks: vectorised).
            a.iter()
                .zip(b)
                .map(|(a, b)| (1.0 - w) * a + w * b)
                .collect()
        };
        BilinearTable::new(self.nx, self.ny, data)
    }

    /// `(nx, ny, values)`: the grid and its values, slice after slice, for the block
    /// evaluation of `measured::rgl` (slice 0 read as [`eval_single`](Self::eval_single)).
    #[inline]
    pub(crate) fn parts(&self) -> (usize, usize, &[f64]) {
        (self.nx, self.ny, &self.data)
    }

    /// [`eval`](Self::eval) of a one-slice table (slice 0, no blend).
    #[inline]
    pub(crate) fn eval_single(&self, pos: [f64; 2]) -> f64 {
        let (cx, cy, fx, fy) = grid_cell(pos, self.nx, self.ny);
        let k = cy * self.nx + cx;
        let d = &self.data;
        let [v00, v10, v01, v11] = [d[k], d[k + 1], d[k + self.nx], d[k + self.nx + 1]];
        (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
    }

    /// [`eval`](Self::eval) of `N` consecutive slices `s, s + 1, …` (e.g. the channels of an
    /// RGB table), each blended with the slice `stride` further on: the cell of `pos` is found
    /// once.
    pub fn eval_consecutive<const N: usize>(
        &self,
        pos: [f64; 2],
        s: usize,
        stride: usize,
        w: f64,
    ) -> [f64; N] {
        let (cx, cy, fx, fy) = grid_cell(pos, self.nx, self.ny);
        std::array::from_fn(|c| {
            let [v00, v10, v01, v11] = self.corners(s + c, stride, w, cx, cy);
            (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
        })
    }
}

/// Why a table cannot be a sampling density.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ZeroSlice(pub usize);

/// The normalised density of a [`BilinearTable`] conditioned on a [`ParamAxis`], with its
/// marginal (rows) and conditional (columns) CDFs: eval, exact sampling and inversion.
///
/// Layout: what one evaluation reads sits together. Every grid point holds its normalised
/// value beside the row's CDF there, every row its marginal CDF beside the row's total, so an
/// inversion reads two lines of grid points and one of rows per slice.
#[derive(Debug, Clone, PartialEq)]
pub struct Warp2D {
    axis: ParamAxis,
    nx: usize,
    ny: usize,
    /// Per slice and grid point (row-major, `x` fastest): the normalised value, and the
    /// integral along its row so far in `x` (cell units).
    cells: Vec<[f64; 2]>,
    /// Per slice and row: the integral of the rows so far in `y` (cell units, ending at 1),
    /// and the row's total along `x`.
    rows: Vec<[f64; 2]>,
}

impl Warp2D {
    /// Normalises every slice of `table` (values `≥ 0`, checked by the caller) and builds the
    /// CDFs. Error: a slice whose interpolant integrates to zero.
    pub(crate) fn new(axis: ParamAxis, table: BilinearTable) -> Result<Self, ZeroSlice> {
        let (nx, ny) = (table.nx, table.ny);
        let n = nx * ny;
        let slices = table.slices();
        let data = table.data;
        let mut cells = vec![[0.0; 2]; slices * n];
        let mut rows = vec![[0.0; 2]; slices * ny];
        for s in 0..slices {
            let d = &data[s * n..(s + 1) * n];
            let c = &mut cells[s * n..(s + 1) * n];
            for y in 0..ny {
                let mut sum = 0.0;
                for x in 0..nx - 1 {
                    sum += 0.5 * (d[y * nx + x] + d[y * nx + x + 1]);
                    c[y * nx + x + 1][1] = sum;
                }
            }
            let r = &mut rows[s * ny..(s + 1) * ny];
            let mut sum = 0.0;
            for y in 0..ny - 1 {
                sum += 0.5 * (c[y * nx + nx - 1][1] + c[(y + 1) * nx + nx - 1][1]);
                r[y + 1][0] = sum;
            }
            if !(sum > 0.0 && sum.is_finite()) {
                return Err(ZeroSlice(s));
            }
            let scale = 1.0 / sum;
            for (cell, &v) in c.iter_mut().zip(d) {
                *cell = [v * scale, cell[1] * scale];
            }
            for (y, row) in r.iter_mut().enumerate() {
                *row = [row[0] * scale, c[y * nx + nx - 1][1]];
            }
        }
        Ok(Self {
            axis,
            nx,
            ny,
            cells,
            rows,
        })
    }

    /// The normalised table (a copy).
    pub fn table(&self) -> BilinearTable {
        BilinearTable::new(self.nx, self.ny, self.cells.iter().map(|c| c[0]).collect())
    }

    /// The parameter axis.
    pub fn axis(&self) -> &ParamAxis {
        &self.axis
    }

    /// Heap bytes of the structure.
    pub fn bytes_used(&self) -> usize {
        16 * (self.cells.len() + self.rows.len()) + 8 * self.axis.values.len()
    }

    /// Number of rows `ny` of the grid (grid points along `y`).
    pub(crate) fn rows(&self) -> usize {
        self.ny
    }

    /// Whether the blend of slices `s` and `s + 1` at some weight of `[w0, w1]` has a row
    /// whose total `T(y_r) = ∫ ρ(x, y_r) dx` is not positive (the blended total is affine in
    /// the weight: checked at both ends with [`invert_located`](Self::invert_located)'s
    /// expression). There the conditional CDF `C(x, y)/T(y)` is set to 0 instead of its limit,
    /// so it is not monotone in `y` near that row (the RGL leaf bound, `measured/rgl/bound.rs`,
    /// then takes the whole `[0, 1]` range of `x`). `s` is clamped to the last pair.
    pub(crate) fn has_empty_row(&self, s: usize, w: [f64; 2]) -> bool {
        let ny = self.ny;
        let slices = self.rows.len() / ny;
        let (s, w) = if slices < 2 {
            (0, [0.0, 0.0])
        } else {
            (s.min(slices - 2), w)
        };
        (0..ny).any(|y| w.iter().any(|&wk| !(self.row_at(s, wk, y)[1] > 0.0)))
    }

    fn area_scale(&self) -> f64 {
        ((self.nx - 1) * (self.ny - 1)) as f64
    }

    /// Grid point `k` (value, row CDF) of the blend of slices `s` and `s + 1` with weight `w`.
    #[inline]
    fn cell_at(&self, s: usize, w: f64, k: usize) -> [f64; 2] {
        blend_pair(&self.cells, self.nx * self.ny, s, w, k)
    }

    /// Row `y` (marginal CDF, row total) of the blend of slices `s` and `s + 1`.
    #[inline]
    fn row_at(&self, s: usize, w: f64, y: usize) -> [f64; 2] {
        blend_pair(&self.rows, self.ny, s, w, y)
    }

    /// The four corner values `(v00, v10, v01, v11)` and the row CDFs at `(cx, cy)` and
    /// `(cx, cy + 1)` of the blended slice.
    #[inline]
    fn corners(&self, s: usize, w: f64, cx: usize, cy: usize) -> ([f64; 4], [f64; 2]) {
        let k = cy * self.nx + cx;
        let [v00, c0] = self.cell_at(s, w, k);
        let [v10, _] = self.cell_at(s, w, k + 1);
        let [v01, c1] = self.cell_at(s, w, k + self.nx);
        let [v11, _] = self.cell_at(s, w, k + self.nx + 1);
        ([v00, v10, v01, v11], [c0, c1])
    }

    /// Density at `pos ∈ [0,1]²` (w.r.t. area) for parameter `param`.
    pub fn eval(&self, pos: [f64; 2], param: f64) -> f64 {
        let (s, w) = self.axis.locate(param);
        let (cx, cy, fx, fy) = grid_cell(pos, self.nx, self.ny);
        let ([v00, v10, v01, v11], _) = self.corners(s, w, cx, cy);
        let v = (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11);
        v * self.area_scale()
    }

    /// The warp: a uniform `u ∈ [0,1]²` to a point with this density; returns the point and its
    /// density.
    pub fn sample(&self, u: [f64; 2], param: f64) -> ([f64; 2], f64) {
        let (s, w) = self.axis.locate(param);
        let (nx, ny) = (self.nx, self.ny);
        let uy = u[1].clamp(0.0, 1.0);
        let ux = u[0].clamp(0.0, 1.0);
        // Row: largest r in [0, ny−2] with F(r) < uy.
        let row = {
            let (mut lo, mut hi) = (0usize, ny - 1);
            while hi - lo > 1 {
                let mid = (lo + hi) / 2;
                if self.row_at(s, w, mid)[0] < uy {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let [m0, r0] = self.row_at(s, w, row);
        let [_, r1] = self.row_at(s, w, row + 1);
        let ty = solve_linear_density(r0, r1, uy - m0);
        // Column, on the row blended at ty.
        let cond = |x: usize| {
            (1.0 - ty) * self.cell_at(s, w, row * nx + x)[1]
                + ty * self.cell_at(s, w, (row + 1) * nx + x)[1]
        };
        let target = ux * ((1.0 - ty) * r0 + ty * r1);
        let col = {
            let (mut lo, mut hi) = (0usize, nx - 1);
            while hi - lo > 1 {
                let mid = (lo + hi) / 2;
                if cond(mid) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let ([v00, v10, v01, v11], [c0_row, c1_row]) = self.corners(s, w, col, row);
        let rest = target - ((1.0 - ty) * c0_row + ty * c1_row);
        let c0 = (1.0 - ty) * v00 + ty * v01;
        let c1 = (1.0 - ty) * v10 + ty * v11;
        let tx = solve_linear_density(c0, c1, rest);
        let pdf = ((1.0 - tx) * c0 + tx * c1) * self.area_scale();
        (
            [
                (col as f64 + tx) / (nx - 1) as f64,
                (row as f64 + ty) / (ny - 1) as f64,
            ],
            pdf,
        )
    }

    /// The inverse of [`sample`](Self::sample): `pos ↦ (F_{X|Y}(x | y), F_Y(y))`, with the
    /// density at `pos`.
    pub fn invert(&self, pos: [f64; 2], param: f64) -> ([f64; 2], f64) {
        let (s, w) = self.axis.locate(param);
        self.invert_located(pos, s, w)
    }

    /// [`invert`](Self::invert) for a parameter already located on the axis (`(s, w)` from
    /// [`ParamAxis::locate`] of this warp's axis).
    pub(crate) fn invert_located(&self, pos: [f64; 2], s: usize, w: f64) -> ([f64; 2], f64) {
        // Main's code, not `invert_on`: the shared closure form measured ≈ 10 % slower on
        // random-ωo evaluations (docs/benchmarks.md §24.3); the same arithmetic.
        let (cx, cy, fx, fy) = grid_cell(pos, self.nx, self.ny);
        let ([v00, v10, v01, v11], [along0, along1]) = self.corners(s, w, cx, cy);
        let [m0, r0] = self.row_at(s, w, cy);
        let [_, r1] = self.row_at(s, w, cy + 1);
        let c0 = (1.0 - fy) * v00 + fy * v01;
        let c1 = (1.0 - fy) * v10 + fy * v11;
        let pdf = ((1.0 - fx) * c0 + fx * c1) * self.area_scale();
        let row_total = (1.0 - fy) * r0 + fy * r1;
        let along = fx * (c0 + 0.5 * fx * (c1 - c0)) + (1.0 - fy) * along0 + fy * along1;
        let ux = if row_total > 0.0 {
            along / row_total
        } else {
            0.0
        };
        let uy = fy * (r0 + 0.5 * fy * (r1 - r0)) + m0;
        ([ux, uy], pdf)
    }

    /// The blend of slices `s` and `s + 1` with weight `w` (`(s, w)` from [`ParamAxis::locate`]
    /// of this warp's axis, `s` clamped to the last pair) as one plain slice: every grid
    /// point's value and row CDF, every row's marginal CDF and total, blended once by the very
    /// expression [`invert_located`](Self::invert_located) evaluates at each read, so
    /// [`Warp2DSlice::invert`] returns its values bit for bit.
    pub(crate) fn blend_slice(&self, s: usize, w: f64) -> Warp2DSlice {
        let (n, ny) = (self.nx * self.ny, self.ny);
        let slices = self.cells.len() / n;
        let (s, w) = if slices < 2 {
            (0, 0.0)
        } else {
            (s.min(slices - 2), w)
        };
        Warp2DSlice {
            nx: self.nx,
            ny,
            area_scale: self.area_scale(),
            cells: blend_slices(&self.cells, n, s, w),
            rows: blend_slices(&self.rows, ny, s, w),
        }
    }
}

/// `(nx, ny, area_scale, cells, rows)` of a [`Warp2DSlice`] ([`Warp2DSlice::parts`]).
pub(crate) type SliceParts<'a> = (usize, usize, f64, &'a [[f64; 2]], &'a [[f64; 2]]);

/// One slice of a [`Warp2D`] blended at a fixed parameter ([`Warp2D::blend_slice`]): its
/// inversion reads one plain slice instead of blending two at every read.
#[derive(Debug, Clone, PartialEq)]
pub struct Warp2DSlice {
    nx: usize,
    ny: usize,
    area_scale: f64,
    cells: Vec<[f64; 2]>,
    rows: Vec<[f64; 2]>,
}

impl Warp2DSlice {
    /// [`Warp2D::invert_located`] at the slice's parameter, bit for bit.
    #[inline]
    pub(crate) fn invert(&self, pos: [f64; 2]) -> ([f64; 2], f64) {
        invert_on(
            pos,
            self.nx,
            self.ny,
            self.area_scale,
            |k| self.cells[k],
            |y| self.rows[y],
        )
    }

    /// Heap bytes of the slice.
    pub fn bytes_used(&self) -> usize {
        16 * (self.cells.len() + self.rows.len())
    }

    /// `(nx, ny, area_scale, cells, rows)`: what [`invert`](Self::invert) reads, for the
    /// block evaluation of `measured::rgl` (the same arithmetic over many points in lanes).
    #[inline]
    pub(crate) fn parts(&self) -> SliceParts<'_> {
        (self.nx, self.ny, self.area_scale, &self.cells, &self.rows)
    }
}

/// The inversion `pos ↦ (F_{X|Y}(x | y), F_Y(y))` and the density at `pos`, on a slice whose
/// grid point `k` is `cell(k)` (value, row CDF) and row `y` is `row(y)` (marginal CDF, row
/// total): one arithmetic for the blended and the prepared slices.
#[inline(always)]
fn invert_on(
    pos: [f64; 2],
    nx: usize,
    ny: usize,
    area_scale: f64,
    cell: impl Fn(usize) -> [f64; 2],
    row: impl Fn(usize) -> [f64; 2],
) -> ([f64; 2], f64) {
    let (cx, cy, fx, fy) = grid_cell(pos, nx, ny);
    let k = cy * nx + cx;
    let [v00, along0] = cell(k);
    let [v10, _] = cell(k + 1);
    let [v01, along1] = cell(k + nx);
    let [v11, _] = cell(k + nx + 1);
    let [m0, r0] = row(cy);
    let [_, r1] = row(cy + 1);
    let c0 = (1.0 - fy) * v00 + fy * v01;
    let c1 = (1.0 - fy) * v10 + fy * v11;
    let pdf = ((1.0 - fx) * c0 + fx * c1) * area_scale;
    let row_total = (1.0 - fy) * r0 + fy * r1;
    let along = fx * (c0 + 0.5 * fx * (c1 - c0)) + (1.0 - fy) * along0 + fy * along1;
    let ux = if row_total > 0.0 {
        along / row_total
    } else {
        0.0
    };
    let uy = fy * (r0 + 0.5 * fy * (r1 - r0)) + m0;
    ([ux, uy], pdf)
}

/// Every entry of the blend of slices `s` (weight `1 − w`) and `s + 1` (weight `w`) of `data`,
/// slices of `n` entries: [`blend_pair`]'s values over whole slices (no per-entry index
/// checks, so the loop is vectorised).
fn blend_slices(data: &[[f64; 2]], n: usize, s: usize, w: f64) -> Vec<[f64; 2]> {
    let a = &data[s * n..(s + 1) * n];
    if w == 0.0 {
        return a.to_vec();
    }
    let b = &data[(s + 1) * n..(s + 2) * n];
    a.iter()
        .zip(b)
        .map(|(a, b)| [(1.0 - w) * a[0] + w * b[0], (1.0 - w) * a[1] + w * b[1]])
        .collect()
}

/// Entry `k` of the blend of slices `s` (weight `1 − w`) and `s + 1` (weight `w`) of `data`,
/// slices of `n` entries.
#[inline]
fn blend_pair(data: &[[f64; 2]], n: usize, s: usize, w: f64, k: usize) -> [f64; 2] {
    let a = data[s * n + k];
    if w == 0.0 {
        a
    } else {
        let b = data[(s + 1) * n + k];
        [(1.0 - w) * a[0] + w * b[0], (1.0 - w) * a[1] + w * b[1]]
    }
}

/// Cell `(cx, cy)` and fractions `(fx, fy)` of `pos` (clamped to `[0,1]²`, NaN to 0) on a grid
/// of `nx × ny` points.
#[inline]
fn grid_cell(pos: [f64; 2], nx: usize, ny: usize) -> (usize, usize, f64, f64) {
    let sx = pos[0].clamp(0.0, 1.0) * (nx - 1) as f64;
    let sy = pos[1].clamp(0.0, 1.0) * (ny - 1) as f64;
    let (sx, sy) = (
        if sx.is_nan() { 0.0 } else { sx },
        if sy.is_nan() { 0.0 } else { sy },
    );
    let cx = (sx as usize).min(nx - 2);
    let cy = (sy as usize).min(ny - 2);
    (cx, cy, sx - cx as f64, sy - cy as f64)
}

/// The `t ∈ [0,1]` with `∫₀ᵗ ((1−τ)a + τb) dτ = rest` (a linear density on one cell), or the
/// constant-density answer when `a ≈ b`.
#[inline]
fn solve_linear_density(a: f64, b: f64, rest: f64) -> f64 {
    let t = if (a - b).abs() <= 1e-9 * (a + b) {
        if a + b > 0.0 {
            2.0 * rest / (a + b)
        } else {
            0.0
        }
    } else {
        // a t + (b − a) t²/2 = rest, the root in [0, 1], in the cancellation-free form.
        let disc = (a * a + 2.0 * rest * (b - a)).max(0.0);
        2.0 * rest / (a + disc.sqrt())
    };
    if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warp() -> Warp2D {
        // Two slices of a 4 × 3 grid with very different shapes.
        let mut data = Vec::new();
        for s in 0..2 {
            for y in 0..3 {
                for x in 0..4 {
                    let v = if s == 0 {
                        1.0 + x as f64 * 2.0 + y as f64
                    } else {
                        0.1 + ((x * 3 + y * 5) % 7) as f64
                    };
                    data.push(v);
                }
            }
        }
        Warp2D::new(
            ParamAxis::new(vec![0.0, 1.0]),
            BilinearTable::new(4, 3, data),
        )
        .expect("positive")
    }

    #[test]
    fn density_integrates_to_one_for_blended_parameters() {
        let w = warp();
        for p in [0.0, 0.3, 1.0] {
            let n = 400;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let pos = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                    sum += w.eval(pos, p);
                }
            }
            let mean = sum / (n * n) as f64;
            approx::assert_abs_diff_eq!(mean, 1.0, epsilon = 1e-4);
        }
    }

    #[test]
    fn invert_undoes_sample_and_pdfs_agree() {
        let w = warp();
        for p in [0.0, 0.45, 1.0] {
            for i in 0..23 {
                for j in 0..19 {
                    let u = [(i as f64 + 0.37) / 23.0, (j as f64 + 0.61) / 19.0];
                    let (pos, pdf) = w.sample(u, p);
                    let (back, pdf2) = w.invert(pos, p);
                    approx::assert_abs_diff_eq!(back[0], u[0], epsilon = 1e-9);
                    approx::assert_abs_diff_eq!(back[1], u[1], epsilon = 1e-9);
                    approx::assert_relative_eq!(pdf, pdf2, max_relative = 1e-9);
                    approx::assert_relative_eq!(pdf, w.eval(pos, p), max_relative = 1e-9);
                }
            }
        }
    }

    #[test]
    fn the_inverse_is_the_cdf() {
        // invert(x, y).1 = ∫₀^y marginal, checked by brute-force quadrature.
        let w = warp();
        let (x, y) = (0.7, 0.62);
        let n = 2000;
        let mut below = 0.0;
        let mut row = 0.0;
        let mut left = 0.0;
        for j in 0..n {
            let yy = (j as f64 + 0.5) / n as f64 * y;
            for i in 0..n {
                let xx = (i as f64 + 0.5) / n as f64;
                below += w.eval([xx, yy], 0.3);
            }
        }
        below *= y / (n * n) as f64;
        for i in 0..n {
            let xx = (i as f64 + 0.5) / n as f64;
            row += w.eval([xx, y], 0.3);
            if xx < x {
                left += w.eval([xx, y], 0.3);
            }
        }
        let (u, _) = w.invert([x, y], 0.3);
        approx::assert_abs_diff_eq!(u[1], below, epsilon = 1e-4);
        approx::assert_abs_diff_eq!(u[0], left / row, epsilon = 1e-3);
    }

    #[test]
    fn axis_locates_and_clamps() {
        let a = ParamAxis::new(vec![0.0, 1.0, 3.0]);
        assert_eq!(a.locate(-1.0), (0, 0.0));
        assert_eq!(a.locate(0.5), (0, 0.5));
        assert_eq!(a.locate(2.0), (1, 0.5));
        assert_eq!(a.locate(9.0), (1, 1.0));
        assert_eq!(ParamAxis::new(vec![2.0]).locate(5.0), (0, 0.0));
    }

    #[test]
    fn zero_slice_is_refused() {
        let t = BilinearTable::new(2, 2, vec![0.0; 4]);
        assert_eq!(
            Warp2D::new(ParamAxis::new(vec![0.0]), t).err(),
            Some(ZeroSlice(0))
        );
    }
}
