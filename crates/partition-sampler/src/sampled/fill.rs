//! How a [`super::SampledGridDensity`] fills its fine cells `[max, integral]`: the dense image
//! map (every corner and centre) or curvature-driven refinement from a coarse grid.

use rayon::prelude::*;

use super::lattice::{GridPoint, Lattice};
use super::refinement::Refinement;
use crate::contract::Point2;
use crate::density::Density;
use crate::error::DensityError;
use crate::rect::{Domain, Rect, interval_min_abs};

/// Sub-samples per axis of a fine cell crossed by the disc boundary, and of the coarser
/// Richardson partner whose signed difference estimates the boundary integral's error.
#[derive(Debug, Clone, Copy)]
pub(super) struct Subgrid {
    pub(super) fine: usize,
    pub(super) coarse: usize,
}

/// The papers' image map: an 8 × 8 boundary sub-grid checked against 4 × 4.
pub(super) const DENSE_SUBGRID: Subgrid = Subgrid { fine: 8, coarse: 4 };

/// The refined map's boundary sub-grid (the rim band and the leaf quadrature of the BRDF sets
/// take over the fine structure near the circle).
pub(super) const REFINED_SUBGRID: Subgrid = Subgrid { fine: 4, coarse: 2 };

/// Fine cells and the error terms of the total integral.
pub(super) struct Filled {
    /// `[max, integral]` of every fine cell, row-major.
    pub(super) cells: Vec<[f64; 2]>,
    /// Σ (midpoint at h − midpoint at 2h) over interior 2 × 2 blocks (Richardson, divide by 3).
    pub(super) richardson: f64,
    /// Σ (Simpson − 5-point rule) over cells kept coarse by the refinement.
    pub(super) coarse_rule: f64,
    /// Σ (fine − coarse sub-grid integral) over boundary cells.
    pub(super) boundary: f64,
    /// Points where `f` was evaluated.
    pub(super) evaluations: usize,
}

/// Fine-grid geometry: cell rectangles and their position relative to the disc.
struct Geometry {
    grid: Rect,
    n: usize,
    disc: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    Inside,
    Boundary,
    Outside,
}

impl Geometry {
    /// The block of `s × s` fine cells with lower-left fine cell `(a, b)`.
    fn rect(&self, a: usize, b: usize, s: usize) -> Rect {
        let (hx, hy) = (
            self.grid.width() / self.n as f64,
            self.grid.height() / self.n as f64,
        );
        Rect::new(
            self.grid.x0 + a as f64 * hx,
            self.grid.y0 + b as f64 * hy,
            self.grid.x0 + (a + s) as f64 * hx,
            self.grid.y0 + (b + s) as f64 * hy,
        )
    }

    fn class(&self, a: usize, b: usize, s: usize) -> Class {
        if !self.disc {
            return Class::Inside;
        }
        let r = self.rect(a, b, s);
        let far = |u: f64, v: f64| u.abs().max(v.abs());
        let (fx, fy) = (far(r.x0, r.x1), far(r.y0, r.y1));
        let (mx, my) = (interval_min_abs(r.x0, r.x1), interval_min_abs(r.y0, r.y1));
        if fx * fx + fy * fy <= 1.0 {
            Class::Inside
        } else if mx * mx + my * my >= 1.0 {
            Class::Outside
        } else {
            Class::Boundary
        }
    }

    fn fine_area(&self) -> f64 {
        self.grid.area() / (self.n * self.n) as f64
    }
}

/// Corners and centre of fine cell `(a, b)`.
fn fine_points(a: usize, b: usize) -> [GridPoint; 5] {
    [
        GridPoint::Corner(a, b),
        GridPoint::Corner(a + 1, b),
        GridPoint::Corner(a, b + 1),
        GridPoint::Corner(a + 1, b + 1),
        GridPoint::Centre(a, b),
    ]
}

/// Largest of the values at the corners and the centre of fine cell `(a, b)`.
fn fine_max<D: Density>(lat: &Lattice<'_, D>, a: usize, b: usize) -> f64 {
    fine_points(a, b)
        .iter()
        .fold(0.0f64, |m, &p| m.max(lat.get(p)))
}

/// The dense rule on single fine cells: interior cells get the largest of their corner and
/// centre values and the midpoint integral; the cells crossing the disc boundary are returned
/// (for [`fill_boundary`]); cells outside stay 0.
fn fill_fine_cells<D: Density>(
    lat: &Lattice<'_, D>,
    geo: &Geometry,
    cells: &mut [[f64; 2]],
    fine: impl Iterator<Item = (usize, usize)>,
) -> Vec<(usize, usize)> {
    let (n, area) = (geo.n, geo.fine_area());
    let mut boundary = Vec::new();
    for (a, b) in fine {
        match geo.class(a, b, 1) {
            Class::Inside => {
                cells[b * n + a] = [fine_max(lat, a, b), lat.get(GridPoint::Centre(a, b)) * area];
            }
            Class::Boundary => boundary.push((a, b)),
            Class::Outside => {}
        }
    }
    boundary
}

/// Statistics of one boundary cell: (max, integral on the fine sub-grid, on the coarse one).
///
/// The cell's points (the fine sub-grid's inside the disc, the radial projections onto the
/// circle of those outside that fall in the cell, the coarse sub-grid's inside the disc) are
/// gathered and evaluated in one [`Density::eval_block`] call, then checked and summed in the
/// order a point-by-point evaluation takes them: the same statistics and the same first
/// invalid value, bit for bit.
fn boundary_cell<D: Density>(
    f: &D,
    cell: &Rect,
    sub: Subgrid,
) -> Result<(f64, f64, f64), DensityError> {
    let disc = Domain::UnitDisc;
    let (w, h) = (cell.width(), cell.height());
    let at = |a: usize, b: usize, k: usize| {
        [
            cell.x0 + (a as f64 + 0.5) / k as f64 * w,
            cell.y0 + (b as f64 + 0.5) / k as f64 * h,
        ]
    };
    // Per point of the rule, in order: what it adds (`Fine`: the fine sum and the max;
    // `Edge`: the max; `Coarse`: the coarse sum) and whether `f` is evaluated there.
    #[derive(Clone, Copy)]
    enum Role {
        Fine,
        Edge,
        Coarse,
    }
    let mut roles: Vec<(Role, bool)> =
        Vec::with_capacity(2 * sub.fine * sub.fine + sub.coarse * sub.coarse);
    let mut points: Vec<Point2> = Vec::with_capacity(roles.capacity());
    for b in 0..sub.fine {
        for a in 0..sub.fine {
            let p = at(a, b, sub.fine);
            let r2 = p[0] * p[0] + p[1] * p[1];
            if r2 <= 1.0 {
                let inside = disc.contains(p);
                roles.push((Role::Fine, inside));
                if inside {
                    points.push(p);
                }
            } else {
                // Radial projection onto the circle, kept if it lies in the cell.
                let k = (1.0 - 1e-12) / r2.sqrt();
                let q = [p[0] * k, p[1] * k];
                if cell.contains(q) {
                    let inside = disc.contains(q);
                    roles.push((Role::Edge, inside));
                    if inside {
                        points.push(q);
                    }
                }
            }
        }
    }
    for b in 0..sub.coarse {
        for a in 0..sub.coarse {
            let p = at(a, b, sub.coarse);
            let inside = disc.contains(p);
            roles.push((Role::Coarse, inside));
            if inside {
                points.push(p);
            }
        }
    }
    let mut values = vec![0.0f64; points.len()];
    f.eval_block(&points, &mut values);
    let mut max = 0.0f64;
    let mut fine = 0.0;
    let mut coarse = 0.0;
    let mut next = 0;
    for &(role, inside) in &roles {
        let v = if inside {
            let (p, v) = (points[next], values[next]);
            next += 1;
            if !(v.is_finite() && v >= 0.0) {
                return Err(DensityError::InvalidSample {
                    x: p[0],
                    y: p[1],
                    value: v,
                });
            }
            v
        } else {
            0.0
        };
        match role {
            Role::Fine => {
                fine += v;
                max = max.max(v);
            }
            Role::Edge => max = max.max(v),
            Role::Coarse => coarse += v,
        }
    }
    let area = cell.area();
    Ok((
        max,
        fine * area / (sub.fine * sub.fine) as f64,
        coarse * area / (sub.coarse * sub.coarse) as f64,
    ))
}

/// Fills the boundary fine cells (mirror images share one computation).
fn fill_boundary<D: Density>(
    lat: &Lattice<'_, D>,
    f: &D,
    geo: &Geometry,
    mirror: bool,
    cells: &mut [[f64; 2]],
    list: &[(usize, usize)],
    sub: Subgrid,
) -> Result<f64, DensityError> {
    let n = geo.n;
    let canon = |(a, b): (usize, usize)| {
        if mirror && b > n - 1 - b {
            (a, n - 1 - b)
        } else {
            (a, b)
        }
    };
    let mut unique: Vec<(usize, usize)> = list.iter().map(|&c| canon(c)).collect();
    unique.sort_unstable_by_key(|&(a, b)| (b, a));
    unique.dedup();
    let stats: Vec<Result<(f64, f64, f64), DensityError>> = unique
        .par_iter()
        .map(|&(a, b)| boundary_cell(f, &geo.rect(a, b, 1), sub))
        .collect();
    let mut by_cell = std::collections::HashMap::with_capacity(unique.len());
    for (&c, s) in unique.iter().zip(stats) {
        by_cell.insert(c, s?);
    }
    let mut err = 0.0;
    for &(a, b) in list {
        let (m, fine, coarse) = by_cell[&canon((a, b))];
        // Corner and centre values inside the disc also count towards the maximum.
        cells[b * n + a] = [m.max(fine_max(lat, a, b)), fine];
        err += fine - coarse;
    }
    Ok(err)
}

/// Every corner and centre of the `n × n` grid, boundary cells on `sub`.
pub(super) fn dense<D: Density>(
    f: &D,
    domain: Domain,
    n: usize,
    mirror: bool,
    sub: Subgrid,
) -> Result<Filled, DensityError> {
    let geo = Geometry {
        grid: domain.bounding_rect(),
        n,
        disc: matches!(domain, Domain::UnitDisc),
    };
    let mut lat = Lattice::new(f, domain, n, mirror);
    let mut points: Vec<GridPoint> = Vec::with_capacity((n + 1) * (n + 1) + n * n);
    points.extend((0..=n).flat_map(|b| (0..=n).map(move |a| GridPoint::Corner(a, b))));
    points.extend((0..n).flat_map(|b| (0..n).map(move |a| GridPoint::Centre(a, b))));
    lat.ensure(&points)?;
    let area = geo.fine_area();
    let mut cells = vec![[0.0f64; 2]; n * n];
    let all = (0..n).flat_map(|b| (0..n).map(move |a| (a, b)));
    let boundary = fill_fine_cells(&lat, &geo, &mut cells, all);
    let bnd = fill_boundary(&lat, f, &geo, mirror, &mut cells, &boundary, sub)?;
    // Richardson on 2×2 blocks of interior cells: midpoint at h vs midpoint at 2h (the block
    // centre is the lattice corner (a + 1, b + 1)).
    let mut rich = 0.0;
    for b in (0..n.saturating_sub(1)).step_by(2) {
        for a in (0..n.saturating_sub(1)).step_by(2) {
            if geo.class(a, b, 2) == Class::Inside {
                rich += block_richardson(&lat, &cells, n, a, b, area);
            }
        }
    }
    Ok(Filled {
        cells,
        richardson: rich,
        coarse_rule: 0.0,
        boundary: bnd,
        evaluations: lat.evaluations(),
    })
}

/// Midpoint rule on the four fine cells of the block at `(a, b)` minus the block's own
/// midpoint rule.
fn block_richardson<D: Density>(
    lat: &Lattice<'_, D>,
    cells: &[[f64; 2]],
    n: usize,
    a: usize,
    b: usize,
    area: f64,
) -> f64 {
    let fine: f64 = [(a, b), (a + 1, b), (a, b + 1), (a + 1, b + 1)]
        .iter()
        .map(|&(i, j)| cells[j * n + i][1])
        .sum();
    fine - lat.get(GridPoint::Corner(a + 1, b + 1)) * 4.0 * area
}

/// The 3 × 3 stencil of an `s × s` block (`s ≥ 2` even): lattice corners at spacing `s/2`,
/// `v[l][k]` at `(a + k s/2, b + l s/2)`.
fn stencil_points(a: usize, b: usize, s: usize) -> impl Iterator<Item = GridPoint> {
    let d = s / 2;
    (0..3).flat_map(move |l| (0..3).map(move |k| GridPoint::Corner(a + k * d, b + l * d)))
}

/// Curvature-driven refinement: blocks of `s × s` fine cells, from `s = n / coarsest` down to
/// single fine cells, are judged on their 3 × 3 stencil (spacing `d = s/2`). With the largest
/// second differences `Δx` (along rows) and `Δy` (along columns), a quadratic exceeds its
/// bilinear interpolant on a stencil sub-square by at most `e = (|Δx| + |Δy|)/8`. A block
/// inside the domain with `e ≤ tolerance · max(v)` is kept: its fine cells get the bilinear
/// interpolant's maximum over the cell plus `e` as maximum, and its 2-D Simpson integral shared
/// in proportion to the interpolant at their centres. Other blocks (and every block meeting
/// the disc boundary, and every block near `focus`) are split in four; single fine cells use
/// the dense rule.
pub(super) fn refined<D: Density>(
    f: &D,
    domain: Domain,
    n: usize,
    mirror: bool,
    refinement: Refinement,
    focus: Option<Point2>,
) -> Result<Filled, DensityError> {
    let geo = Geometry {
        grid: domain.bounding_rect(),
        n,
        disc: matches!(domain, Domain::UnitDisc),
    };
    let mut lat = Lattice::new(f, domain, n, mirror);
    let area = geo.fine_area();
    let mut cells = vec![[0.0f64; 2]; n * n];
    let mut s = n / refinement.coarsest.min(n);
    let mut level: Vec<(usize, usize)> = (0..n)
        .step_by(s)
        .flat_map(|b| (0..n).step_by(s).map(move |a| (a, b)))
        .filter(|&(a, b)| geo.class(a, b, s) != Class::Outside)
        .collect();
    let mut coarse_rule = 0.0;
    let mut refined_pairs = Vec::new();
    while s > 1 {
        let points: Vec<GridPoint> = level
            .iter()
            .flat_map(|&(a, b)| stencil_points(a, b, s))
            .collect();
        lat.ensure(&points)?;
        let d = s / 2;
        let mut next = Vec::with_capacity(level.len());
        for &(a, b) in &level {
            let class = geo.class(a, b, s);
            let mut v = [[0.0f64; 3]; 3];
            for (i, p) in stencil_points(a, b, s).enumerate() {
                v[i / 3][i % 3] = lat.get(p);
            }
            let dx = (0..3)
                .map(|l| (v[l][0] - 2.0 * v[l][1] + v[l][2]).abs())
                .fold(0.0, f64::max);
            let dy = (0..3)
                .map(|k| (v[0][k] - 2.0 * v[1][k] + v[2][k]).abs())
                .fold(0.0, f64::max);
            let vmax = v.iter().flatten().fold(0.0f64, |m, &x| m.max(x));
            let excess = (dx + dy) / 8.0;
            let focused = focus.is_some_and(|p| {
                let r = geo.rect(a, b, s);
                let (w, h) = (r.width(), r.height());
                p[0] >= r.x0 - w && p[0] <= r.x1 + w && p[1] >= r.y0 - h && p[1] <= r.y1 + h
            });
            if class == Class::Inside && !focused && excess <= refinement.tolerance * vmax {
                coarse_rule += keep_block(&mut cells, n, a, b, s, &v, excess, area);
                continue;
            }
            if s == 2 && class == Class::Inside {
                refined_pairs.push((a, b));
            }
            for (ca, cb) in [(a, b), (a + d, b), (a, b + d), (a + d, b + d)] {
                if geo.class(ca, cb, d) != Class::Outside {
                    next.push((ca, cb));
                }
            }
        }
        level = next;
        s = d;
    }
    // Single fine cells: the dense rule.
    let points: Vec<GridPoint> = level.iter().flat_map(|&(a, b)| fine_points(a, b)).collect();
    lat.ensure(&points)?;
    let boundary = fill_fine_cells(&lat, &geo, &mut cells, level.iter().copied());
    let bnd = fill_boundary(
        &lat,
        f,
        &geo,
        mirror,
        &mut cells,
        &boundary,
        REFINED_SUBGRID,
    )?;
    let rich = refined_pairs
        .iter()
        .map(|&(a, b)| block_richardson(&lat, &cells, n, a, b, area))
        .sum();
    Ok(Filled {
        cells,
        richardson: rich,
        coarse_rule,
        boundary: bnd,
        evaluations: lat.evaluations(),
    })
}

/// Fills the fine cells of a block kept coarse (see [`refined`]); returns Simpson minus the
/// 5-point rule `(mean of corners)/3 + (2/3) centre` (both exact for quadratics).
#[allow(clippy::too_many_arguments)]
fn keep_block(
    cells: &mut [[f64; 2]],
    n: usize,
    a: usize,
    b: usize,
    s: usize,
    v: &[[f64; 3]; 3],
    excess: f64,
    fine_area: f64,
) -> f64 {
    const W: [f64; 3] = [1.0, 4.0, 1.0];
    let block_area = fine_area * (s * s) as f64;
    let simpson: f64 = (0..3)
        .flat_map(|l| (0..3).map(move |k| W[l] * W[k] * v[l][k]))
        .sum::<f64>()
        * block_area
        / 36.0;
    let five = ((v[0][0] + v[0][2] + v[2][0] + v[2][2]) / 12.0 + v[1][1] * 2.0 / 3.0) * block_area;
    let d = (s / 2) as f64;
    // Bilinear interpolant of the stencil sub-square containing block-local point (x, y)
    // (fine units, 0 ≤ x, y ≤ s); `hint` picks the sub-square of the fine cell (p, q).
    let bilinear = |x: f64, y: f64, kx: usize, ky: usize| {
        let u = x / d - kx as f64;
        let w = y / d - ky as f64;
        (1.0 - u) * (1.0 - w) * v[ky][kx]
            + u * (1.0 - w) * v[ky][kx + 1]
            + (1.0 - u) * w * v[ky + 1][kx]
            + u * w * v[ky + 1][kx + 1]
    };
    let half = s / 2;
    let mut shares = 0.0;
    for q in 0..s {
        for p in 0..s {
            let (kx, ky) = (usize::from(p >= half), usize::from(q >= half));
            let (x, y) = (p as f64, q as f64);
            let corner_max = [(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)]
                .iter()
                .fold(0.0f64, |m, &(cx, cy)| m.max(bilinear(cx, cy, kx, ky)));
            let centre = bilinear(x + 0.5, y + 0.5, kx, ky).max(0.0);
            cells[(b + q) * n + a + p] = [corner_max + excess, centre];
            shares += centre;
        }
    }
    for q in 0..s {
        for p in 0..s {
            let c = &mut cells[(b + q) * n + a + p];
            c[1] = if shares > 0.0 {
                simpson * c[1] / shares
            } else {
                simpson / (s * s) as f64
            };
        }
    }
    simpson - five
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boundary cell's statistics as they were computed before the gathered block: one
    /// `eval_checked` per point.
    fn boundary_cell_pointwise<D: Density>(
        f: &D,
        cell: &Rect,
        sub: Subgrid,
    ) -> Result<(f64, f64, f64), DensityError> {
        let disc = Domain::UnitDisc;
        let eval = |p| {
            if disc.contains(p) {
                f.eval_checked(p)
            } else {
                Ok(0.0)
            }
        };
        let (w, h) = (cell.width(), cell.height());
        let at = |a: usize, b: usize, k: usize| {
            [
                cell.x0 + (a as f64 + 0.5) / k as f64 * w,
                cell.y0 + (b as f64 + 0.5) / k as f64 * h,
            ]
        };
        let mut max = 0.0f64;
        let mut fine = 0.0;
        for b in 0..sub.fine {
            for a in 0..sub.fine {
                let p = at(a, b, sub.fine);
                let r2 = p[0] * p[0] + p[1] * p[1];
                if r2 <= 1.0 {
                    let v = eval(p)?;
                    fine += v;
                    max = max.max(v);
                } else {
                    // Radial projection onto the circle, kept if it lies in the cell.
                    let k = (1.0 - 1e-12) / r2.sqrt();
                    let q = [p[0] * k, p[1] * k];
                    if cell.contains(q) {
                        max = max.max(eval(q)?);
                    }
                }
            }
        }
        let mut coarse = 0.0;
        for b in 0..sub.coarse {
            for a in 0..sub.coarse {
                coarse += eval(at(a, b, sub.coarse))?;
            }
        }
        let area = cell.area();
        Ok((
            max,
            fine * area / (sub.fine * sub.fine) as f64,
            coarse * area / (sub.coarse * sub.coarse) as f64,
        ))
    }

    /// Issue 29 (docs/benchmarks.md §27.4): a boundary cell's points gathered into one
    /// `eval_block` call give the point-by-point statistics bit for bit (max, fine and coarse
    /// integrals) on every cell of a 64² grid crossing the circle, for both sub-grids, and the
    /// same error (the first invalid value in the rule's order).
    #[test]
    fn gathered_boundary_cells_are_the_pointwise_rule() {
        let f = |p: Point2| (1.0 + 3.0 * p[0] - p[1] * p[1]).abs() + (7.0 * p[1]).sin().abs();
        let geo = Geometry {
            grid: Domain::UnitDisc.bounding_rect(),
            n: 64,
            disc: true,
        };
        let mut cells = 0;
        let mut picked = None;
        for sub in [DENSE_SUBGRID, REFINED_SUBGRID] {
            for b in 0..geo.n {
                for a in 0..geo.n {
                    if geo.class(a, b, 1) != Class::Boundary {
                        continue;
                    }
                    cells += 1;
                    let r = geo.rect(a, b, 1);
                    if cells == 40 {
                        picked = Some(r);
                    }
                    let (m, fi, co) = boundary_cell(&f, &r, sub).unwrap();
                    let (m2, fi2, co2) = boundary_cell_pointwise(&f, &r, sub).unwrap();
                    assert_eq!(
                        [m.to_bits(), fi.to_bits(), co.to_bits()],
                        [m2.to_bits(), fi2.to_bits(), co2.to_bits()],
                        "cell ({a}, {b})"
                    );
                }
            }
        }
        assert!(cells > 300, "{cells}");
        // Invalid values at two of a cell's points: the error names the first in rule order.
        let r = picked.unwrap();
        let bad = |p: Point2| {
            if p[0] > r.x0 + 0.4 * r.width() {
                -1.0 - p[1]
            } else {
                1.0
            }
        };
        for sub in [DENSE_SUBGRID, REFINED_SUBGRID] {
            let e = format!("{:?}", boundary_cell(&bad, &r, sub).unwrap_err());
            let e2 = format!("{:?}", boundary_cell_pointwise(&bad, &r, sub).unwrap_err());
            assert_eq!(e, e2);
        }
    }
}
