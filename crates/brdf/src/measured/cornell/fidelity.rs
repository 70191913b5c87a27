//! Test-only survey (issue 29, docs/benchmarks.md §30.4): how faithful to the measured samples
//! are the kNN interpolant and the tabulated (grid) interpolant?
//!
//! For each measured sample `i` (remapped point `p_i`, measured value `v_i`) the survey compares
//! `v_i` with
//! - **in-sample**: the kNN interpolant `kNN(p_i)` of every sample (the reader's rule:
//!   [`NEIGHBOURS`] nearest, Gaussian weights cut at the next sample's distance, [`weights`]),
//!   and the grid interpolant `grid_N(p_i)`: trilinear, on `p_i`'s cell of the regular `N³`
//!   grid of the remapped cube, of the kNN interpolant at the cell's 8 vertices `(i, j, k)/N`
//!   (for `N` = [`GRID_CELLS`] this is [`super::Interpolation::Grid`], checked bit for bit);
//! - **leave-one-out**: the same rules with sample `i` removed from the data: `kNN₋ᵢ(p_i)`,
//!   and `grid₋ᵢ,N(p_i)` = trilinear of `kNN₋ᵢ` at the 8 vertices of `p_i`'s cell; and for
//!   context pbrt-v2's rule (`IrregIsotropicBRDF::f`): every other sample within squared
//!   distance `r² = 0.001` of `p_i`, `r²` doubled until more than 2 are found (or past 1.5),
//!   weights `exp(−100 d²)` (evaluated here in f64, pbrt in f32).
//!
//! Errors `e_i = estimate − v_i` are summarised relative (`|e_i| / v_i`, over the samples with
//! `v_i` above 1 % of the file's largest measured value) and absolute over the file's largest
//! value (`|e_i| / peak`, every sample): median, 90th and 99th percentile (nearest rank),
//! max, RMS. Neighbour lists are brute force over the samples (by squared distance, ties by
//! the file's index: the order of [`search`]), so `kNN₋ᵢ` is exactly the reader's interpolant
//! of the file without sample `i` (the non-ignored test checks that against a re-read file).
//!
//! The survey also prints the albedo of the kNN interpolant (`2π ∫ sin θi cos θi J(θi) dθi`,
//! `J` by [`CornellBrdf::luminance_line_integral`], an adaptive Gauss rule in `θi` as
//! `brdf-sampling`'s `cornell_albedo`) beside [`CornellBrdf::grid_albedo`].
//!
//! `cargo test --release -p brdf --lib fidelity_survey -- --ignored --nocapture`, knobs
//! `FIDELITY_FILES=krylon_blue,cayman,acryl_blue`, `FIDELITY_CELLS=64,128`,
//! `FIDELITY_ANGLES=0,15,30,45,60,75,85` (empty: no albedo), `FIDELITY_ALBEDO_TOL=1e-5`,
//! `FIDELITY_PBRT_M=256,512` (the albedo of pbrt's rule and, as a check, of the kNN one by
//! a midpoint rule of `m²` points; none by default).

use std::collections::HashMap;

use super::{CornellBrdf, GRID_CELLS, NEIGHBOURS, search, weights};

/// Neighbours kept per query: the blended ones, the cut one, and one more so that any one
/// sample can be left out.
const KEEP: usize = NEIGHBOURS + 2;

/// The [`KEEP`] samples nearest to `q`, by increasing `(squared distance, index)` (brute
/// force).
fn nearest_list(points: &[[f64; 3]], q: &[f64; 3]) -> Vec<(f64, u32)> {
    let mut best: Vec<(f64, u32)> = Vec::with_capacity(KEEP + 1);
    for (j, p) in points.iter().enumerate() {
        let (a, b, c) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
        let d2 = a * a + b * b + c * c;
        let key = (d2, j as u32);
        if best.len() == KEEP && !before(key, best[KEEP - 1]) {
            continue;
        }
        let at = best.partition_point(|&e| before(e, key));
        best.insert(at, key);
        best.truncate(KEEP);
    }
    best
}

/// The search's order: squared distance, ties by index.
fn before(a: (f64, u32), b: (f64, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// The reader's kNN blend of `values` over `list` with sample `exclude` left out (the same
/// weights and summation order as `CornellBrdf::blend`).
fn knn_from(list: &[(f64, u32)], exclude: Option<u32>, values: &[f64]) -> f64 {
    let mut near = search::Nearest {
        d2: [f64::INFINITY; search::K],
        index: [0; search::K],
        len: 0,
    };
    for &(d2, j) in list {
        if Some(j) == exclude {
            continue;
        }
        if near.len == search::K {
            break;
        }
        near.d2[near.len] = d2;
        near.index[near.len] = j;
        near.len += 1;
    }
    let w = weights(&near);
    let (mut sum, mut total) = (0.0, 0.0);
    for (w, &j) in w.iter().zip(&near.index[..near.len.min(NEIGHBOURS)]) {
        sum += w * values[j as usize];
        total += w;
    }
    if total > 0.0 { sum / total } else { 0.0 }
}

/// The kNN neighbour lists of the vertices of a regular `n³` grid, made on demand.
struct GridLists {
    n: usize,
    lists: HashMap<[usize; 3], Vec<(f64, u32)>>,
}

impl GridLists {
    fn new(n: usize) -> Self {
        Self {
            n,
            lists: HashMap::new(),
        }
    }

    /// The trilinear interpolant at `p` of the kNN blend (sample `exclude` left out) at the
    /// vertices of `p`'s cell (the formula of `CornellBrdf::grid_at`).
    fn value(
        &mut self,
        points: &[[f64; 3]],
        p: &[f64; 3],
        exclude: Option<u32>,
        values: &[f64],
    ) -> f64 {
        let n = self.n as f64;
        let mut idx = [0usize; 3];
        let mut frac = [0.0; 3];
        for d in 0..3 {
            let s = p[d].clamp(0.0, 1.0) * n;
            let i = (s as usize).min(self.n - 1);
            idx[d] = i;
            frac[d] = s - i as f64;
        }
        let h = 1.0 / n;
        let mut out = 0.0;
        for corner in 0..8 {
            let (a, b, c) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if a == 1 { frac[0] } else { 1.0 - frac[0] })
                * (if b == 1 { frac[1] } else { 1.0 - frac[1] })
                * (if c == 1 { frac[2] } else { 1.0 - frac[2] });
            let v = [idx[0] + a, idx[1] + b, idx[2] + c];
            let list = self.lists.entry(v).or_insert_with(|| {
                let q = v.map(|k| k as f64 * h);
                nearest_list(points, &q)
            });
            out += w * knn_from(list, exclude, values);
        }
        out
    }
}

/// pbrt-v2's irregular isotropic rule at `q` over every sample but `exclude`: the samples
/// with `d² < r²`, `r²` from 0.001 doubled until more than 2 are found or `r² > 1.5`, mean
/// weighted by `exp(−100 d²)` (0 if none is found).
fn pbrt_rule(points: &[[f64; 3]], q: &[f64; 3], exclude: Option<u32>, values: &[f64]) -> f64 {
    let mut r2 = 0.001;
    loop {
        let (mut sum, mut total, mut found) = (0.0, 0.0, 0usize);
        for (j, p) in points.iter().enumerate() {
            if Some(j as u32) == exclude {
                continue;
            }
            let (a, b, c) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
            let d2 = a * a + b * b + c * c;
            if d2 < r2 {
                let w = (-100.0 * d2).exp();
                sum += w * values[j];
                total += w;
                found += 1;
            }
        }
        if found > 2 || r2 > 1.5 {
            return if total > 0.0 { sum / total } else { 0.0 };
        }
        r2 *= 2.0;
    }
}

/// Error summary of estimates against measured values.
#[derive(Debug, Clone, Copy)]
struct Summary {
    /// Samples in the relative statistics (`v_i` > 1 % of the peak).
    rel_count: usize,
    /// Relative error: median, 90th, 99th percentile, max, RMS.
    rel: [f64; 5],
    /// Absolute error over the peak: median, 90th, 99th percentile, max, RMS.
    abs: [f64; 5],
    /// Relative error over every sample with `v_i > 0`: median, 90th, 99th percentile, max,
    /// RMS.
    rel_all: [f64; 5],
    /// Mean signed error over the peak (bias).
    bias: f64,
}

/// Median, 90th and 99th percentile (nearest rank), max and RMS of non-negative values
/// (zeros when empty).
fn five(mut e: Vec<f64>) -> [f64; 5] {
    if e.is_empty() {
        return [0.0; 5];
    }
    e.sort_by(f64::total_cmp);
    let rank = |q: f64| e[((q * e.len() as f64).ceil() as usize).clamp(1, e.len()) - 1];
    let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
    [rank(0.5), rank(0.9), rank(0.99), e[e.len() - 1], rms]
}

/// The summary of `estimates` against `measured` (peak: the largest measured value).
fn summarise(estimates: &[f64], measured: &[f64]) -> Summary {
    let peak = measured.iter().fold(0.0f64, |m, &v| m.max(v));
    let mut rel = Vec::new();
    let mut abs = Vec::with_capacity(measured.len());
    let mut rel_all = Vec::with_capacity(measured.len());
    let mut bias = 0.0;
    for (&e, &v) in estimates.iter().zip(measured) {
        if v > 0.01 * peak {
            rel.push((e - v).abs() / v);
        }
        if v > 0.0 {
            rel_all.push((e - v).abs() / v);
        }
        abs.push((e - v).abs() / peak);
        bias += (e - v) / peak;
    }
    Summary {
        rel_count: rel.len(),
        rel: five(rel),
        abs: five(abs),
        rel_all: five(rel_all),
        bias: bias / measured.len().max(1) as f64,
    }
}

/// Every estimate of the survey for one channel's `values`.
struct Estimates {
    knn_in: Vec<f64>,
    knn_loo: Vec<f64>,
    /// Per grid size: in-sample and leave-one-out.
    grid: Vec<(usize, Vec<f64>, Vec<f64>)>,
    pbrt_loo: Vec<f64>,
}

/// Neighbour lists of the samples and of the grids' vertices (shared by the channels).
struct Lists {
    points: Vec<[f64; 3]>,
    own: Vec<Vec<(f64, u32)>>,
    grids: Vec<GridLists>,
}

impl Lists {
    fn new(b: &CornellBrdf, cells: &[usize]) -> Self {
        let points: Vec<[f64; 3]> = (0..b.samples() as u32)
            .map(|i| b.data.tree.point(i))
            .collect();
        let own = points.iter().map(|p| nearest_list(&points, p)).collect();
        Self {
            points,
            own,
            grids: cells.iter().map(|&n| GridLists::new(n)).collect(),
        }
    }

    fn estimates(&mut self, values: &[f64], pbrt: bool) -> Estimates {
        let n = self.points.len();
        let knn_in = (0..n)
            .map(|i| knn_from(&self.own[i], None, values))
            .collect();
        let knn_loo = (0..n)
            .map(|i| knn_from(&self.own[i], Some(i as u32), values))
            .collect();
        let points = &self.points;
        let grid = self
            .grids
            .iter_mut()
            .map(|g| {
                let inside = (0..n)
                    .map(|i| g.value(points, &points[i], None, values))
                    .collect();
                let loo = (0..n)
                    .map(|i| g.value(points, &points[i], Some(i as u32), values))
                    .collect();
                (g.n, inside, loo)
            })
            .collect();
        let pbrt_loo = if pbrt {
            (0..n)
                .map(|i| pbrt_rule(points, &points[i], Some(i as u32), values))
                .collect()
        } else {
            Vec::new()
        };
        Estimates {
            knn_in,
            knn_loo,
            grid,
            pbrt_loo,
        }
    }
}

/// The kNN interpolant's albedo at `theta_o`: `2π ∫ sin θi cos θi J(θi) dθi`, `J` by
/// [`CornellBrdf::luminance_line_integral`], an adaptive Gauss rule in `θi` (6 points per
/// half of a piece against 6 on the whole, the piece of the largest difference halved until
/// the summed differences and inner estimates are at most `rel_tol` of the value or 40 000
/// lines were integrated): `(value, estimate)`.
fn knn_albedo(b: &CornellBrdf, theta_o: f64, rel_tol: f64) -> (f64, f64) {
    use std::f64::consts::{FRAC_PI_2, TAU};
    let gl = crate::quadrature::GaussLegendre::new(6);
    let (so, co) = theta_o.sin_cos();
    let rule = |a: f64, c: f64| {
        let (mid, half) = (0.5 * (a + c), 0.5 * (c - a));
        let (mut v, mut e) = (0.0, 0.0);
        for (x, w) in gl.nodes().iter().zip(gl.weights()) {
            let (si, ci) = (mid + half * x).sin_cos();
            let (lv, le) = b
                .luminance_line_integral((si * so).clamp(0.0, 1.0), (ci * co).clamp(0.0, 1.0))
                .map_or((f64::NAN, f64::NAN), |l| (l.value, l.abs_err));
            let jac = TAU * si * ci * w * half;
            v += jac * lv;
            e += jac.abs() * le;
        }
        (v, e)
    };
    // (a, b, whole, left, right)
    type Piece = (f64, f64, (f64, f64), (f64, f64), (f64, f64));
    let piece = |a: f64, c: f64, whole: (f64, f64)| -> Piece {
        let m = 0.5 * (a + c);
        (a, c, whole, rule(a, m), rule(m, c))
    };
    let diff = |p: &Piece| (p.2.0 - p.3.0 - p.4.0).abs();
    let mut pieces: Vec<Piece> = (0..8)
        .map(|k| {
            let (a, c) = (FRAC_PI_2 * k as f64 / 8.0, FRAC_PI_2 * (k + 1) as f64 / 8.0);
            piece(a, c, rule(a, c))
        })
        .collect();
    let mut lines = 8 * 18;
    loop {
        pieces.sort_by(|x, y| x.0.total_cmp(&y.0));
        let value: f64 = pieces.iter().map(|p| p.3.0 + p.4.0).sum();
        let err: f64 = pieces.iter().map(|p| diff(p) + p.3.1 + p.4.1).sum();
        if err <= rel_tol * value.abs() || lines >= 40_000 {
            return (value, err);
        }
        let worst = (0..pieces.len()).fold(0, |w, i| {
            if diff(&pieces[i]) > diff(&pieces[w]) {
                i
            } else {
                w
            }
        });
        let p = pieces.swap_remove(worst);
        let m = 0.5 * (p.0 + p.1);
        pieces.push(piece(p.0, m, p.3));
        pieces.push(piece(m, p.1, p.4));
        lines += 24;
    }
}

/// [`CornellBrdf::grid_albedo`]'s exact sum for a regular `n³` grid of the kNN interpolant
/// (any `n`, vertex columns made on demand): `2π ∫ sin θi cos θi J(θi) dθi` with `J` the
/// bilinear interpolant of the columns' trapezoid sums over `y`, 8 Gauss–Legendre points
/// between the angles where `sin θi sin θo` or `cos θi cos θo` crosses a grid plane.
fn grid_albedo_n(b: &CornellBrdf, n: usize, theta_o: f64) -> f64 {
    use std::f64::consts::TAU;
    let (so, co) = theta_o.sin_cos();
    let nf = n as f64;
    let breaks = super::grid::grid_break_angles(n, so, co);
    let h = 1.0 / nf;
    let columns = std::cell::RefCell::new(HashMap::<(usize, usize), f64>::new());
    let column = |i: usize, k: usize| {
        if let Some(&c) = columns.borrow().get(&(i, k)) {
            return c;
        }
        let at = |j: usize| b.knn_luminance_at(&[i as f64 * h, j as f64 * h, k as f64 * h]);
        let inner: f64 = (1..n).map(at).sum();
        let c = (inner + 0.5 * (at(0) + at(n))) / nf;
        columns.borrow_mut().insert((i, k), c);
        c
    };
    let j_at = |t: f64| {
        let (si, ci) = t.sin_cos();
        let (x, z) = (
            (si * so).clamp(0.0, 1.0) * nf,
            (ci * co).clamp(0.0, 1.0) * nf,
        );
        let (i, k) = ((x as usize).min(n - 1), (z as usize).min(n - 1));
        let (fx, fz) = (x - i as f64, z - k as f64);
        let j = (1.0 - fx) * ((1.0 - fz) * column(i, k) + fz * column(i, k + 1))
            + fx * ((1.0 - fz) * column(i + 1, k) + fz * column(i + 1, k + 1));
        TAU * si * ci * j
    };
    let g8 = crate::quadrature::GaussLegendre::new(8);
    breaks
        .windows(2)
        .map(|w| g8.integrate(w[0], w[1], j_at))
        .sum()
}

/// The albedo at `theta_o` of an interpolant `f` of the remapped point (pbrt-v2's rule,
/// [`pbrt_rule`], or the kNN one as a check): the midpoint rule with `m` points in
/// `θi ∈ [0, π/2]` and `m` in `t = Δφ/π ∈ [0, 1]` of
/// `2π ∫ sin θi cos θi ∫₀¹ f(sin θi sin θo, t, cos θi cos θo) dt dθi` (pbrt's rule jumps where
/// its sample set changes, so this converges slowly: compare two `m`).
fn midpoint_albedo(f: impl Fn(&[f64; 3]) -> f64, theta_o: f64, m: usize) -> f64 {
    use std::f64::consts::{FRAC_PI_2, TAU};
    let (so, co) = theta_o.sin_cos();
    let (ht, hy) = (FRAC_PI_2 / m as f64, 1.0 / m as f64);
    let mut total = 0.0;
    for a in 0..m {
        let (si, ci) = ((a as f64 + 0.5) * ht).sin_cos();
        let line: f64 = (0..m)
            .map(|c| f(&[si * so, (c as f64 + 0.5) * hy, ci * co]))
            .sum();
        total += TAU * si * ci * line * hy * ht;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measured::cornell::Interpolation;

    /// The lobe fixture (567 samples on a regular grid: ties, and each `(θi, θo)` pair also
    /// as `(θo, θi)`, an exact duplicate of its remapped point and value).
    fn fixture() -> String {
        crate::measured::cornell::lobe_grid_text(|f| [0.7 * f, f, 0.2 + f])
    }

    /// The fixture without sample `i` (its line after the two header lines).
    fn without(text: &str, i: usize) -> String {
        text.lines()
            .enumerate()
            .filter(|&(k, _)| k != i + 2)
            .map(|(_, l)| format!("{l}\n"))
            .collect()
    }

    /// The survey's rules are the reader's: in-sample, the brute-force kNN blend and the grid
    /// helper at `GRID_CELLS` equal `knn_luminance_at` and `Interpolation::Grid` bit for bit at
    /// every sample; left out, `kNN₋ᵢ(p_i)` and `grid₋ᵢ(p_i)` equal the reader's interpolants
    /// of the file re-read without line `i`, and so does pbrt's rule; and on a fixture whose
    /// samples all have one value every estimate is that value (and the midpoint albedo `π c`);
    /// the grid albedo for any `n` is `grid_albedo` at `GRID_CELLS`. Fails when the exclusion
    /// is forgotten in `knn_from` or in `pbrt_rule` (`Some(j) == exclude` never skipping).
    #[test]
    fn survey_rules_are_the_readers_with_sample_left_out() {
        let text = fixture();
        let b = CornellBrdf::parse(&text).unwrap();
        let grid = b.with_interpolation(Interpolation::Grid);
        let mut lists = Lists::new(&b, &[GRID_CELLS]);
        let lum = b.data.lum.clone();
        let est = lists.estimates(&lum, true);
        for (i, p) in lists.points.iter().enumerate() {
            assert_eq!(est.knn_in[i], b.knn_luminance_at(p), "sample {i}");
            assert_eq!(est.grid[0].1[i], grid.luminance_at(p), "sample {i}");
        }
        for i in [0, 1, 40, 123, 300, 566] {
            let rest = CornellBrdf::parse(&without(&text, i)).unwrap();
            let p = lists.points[i];
            assert_eq!(est.knn_loo[i], rest.knn_luminance_at(&p), "sample {i}");
            let rest_grid = rest.with_interpolation(Interpolation::Grid);
            let g = rest_grid.luminance_at(&p);
            assert!(
                (est.grid[0].2[i] - g).abs() <= 1e-15 * g.abs(),
                "sample {i}: {} vs {g}",
                est.grid[0].2[i]
            );
            let rest_points: Vec<[f64; 3]> = (0..rest.samples() as u32)
                .map(|k| rest.data.tree.point(k))
                .collect();
            let want = pbrt_rule(&rest_points, &p, None, &rest.data.lum);
            assert_eq!(est.pbrt_loo[i], want, "sample {i}");
        }
        // The left-out estimate does not see the sample's own value (with it, the duplicate
        // pair's blend moves).
        let mut changed = lum.clone();
        changed[123] = 1e6;
        let moved = lists.estimates(&changed, true);
        assert_eq!(moved.knn_loo[123], est.knn_loo[123]);
        assert_eq!(moved.pbrt_loo[123], est.pbrt_loo[123]);
        assert_ne!(moved.knn_in[123], est.knn_in[123]);
        // One value everywhere: every rule reproduces it (errors 0, up to rounding).
        let flat = vec![0.25; lum.len()];
        let e = lists.estimates(&flat, true);
        let s = summarise(&e.knn_loo, &flat);
        assert!(s.abs[3] <= 1e-15 && s.rel_count == flat.len(), "{s:?}");
        for v in e.grid[0].1.iter().chain(&e.grid[0].2).chain(&e.pbrt_loo) {
            assert!((v - 0.25).abs() <= 1e-15, "{v}");
        }
        // The survey's grid albedo for any `n` is the reader's at `GRID_CELLS`.
        for deg in [0.0f64, 37.0, 80.0] {
            let (want, _) = grid.grid_albedo(deg.to_radians()).unwrap();
            let got = grid_albedo_n(&b, GRID_CELLS, deg.to_radians());
            assert!(
                (got - want).abs() <= 1e-12 * want,
                "{deg}°: {got} vs {want}"
            );
        }
        // The midpoint albedo of a constant `c` is `π c` (up to the rule's O(h²) error).
        let pb = |p: &[f64; 3]| pbrt_rule(&lists.points, p, None, &flat);
        let a = midpoint_albedo(pb, 0.7, 64);
        let want = std::f64::consts::PI * 0.25;
        assert!((a - want).abs() <= 1e-3 * want, "{a} vs {want}");
        // The percentiles by nearest rank.
        let f = five((1..=100).map(f64::from).collect());
        assert_eq!(&f[..4], &[50.0, 90.0, 99.0, 100.0]);
    }

    fn env_list<T: std::str::FromStr>(key: &str, default: &str) -> Vec<T> {
        std::env::var(key)
            .unwrap_or_else(|_| default.to_string())
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect()
    }

    fn row(label: &str, s: &Summary) -> String {
        let f = |v: &[f64; 5]| {
            v.iter()
                .map(|x| format!("{x:.2e}"))
                .collect::<Vec<_>>()
                .join(" | ")
        };
        format!(
            "| {label} | {} | {} | {} | {:+.1e} |",
            f(&s.rel_all),
            f(&s.rel),
            f(&s.abs),
            s.bias
        )
    }

    /// The survey of docs/benchmarks.md §30.4 (see the module docs for the command and knobs).
    #[test]
    #[ignore = "a survey for the record (≈ 6 s per file; ≈ 17 s with FIDELITY_PBRT_M=256,512)"]
    fn fidelity_survey() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/measured/cornell");
        let files: Vec<String> = env_list("FIDELITY_FILES", "krylon_blue,cayman,acryl_blue");
        let cells: Vec<usize> = env_list("FIDELITY_CELLS", "64,128");
        let angles: Vec<f64> = env_list("FIDELITY_ANGLES", "0,15,30,45,60,75,85");
        let pbrt_m: Vec<usize> = env_list("FIDELITY_PBRT_M", "");
        let tol: f64 = std::env::var("FIDELITY_ALBEDO_TOL")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1e-5);
        for name in files {
            let path = dir.join(format!("{name}.brdf"));
            let Ok(b) = CornellBrdf::load(&path) else {
                eprintln!("skipped {name}: {} unreadable", path.display());
                continue;
            };
            let t = std::time::Instant::now();
            let mut lists = Lists::new(&b, &cells);
            let lum = b.data.lum.clone();
            let est = lists.estimates(&lum, true);
            let n = lum.len();
            let peak = lum.iter().fold(0.0f64, |m, &v| m.max(v));
            let dup = (0..n).filter(|&i| lists.own[i][1].0 == 0.0).count();
            let mut sorted = lum.clone();
            sorted.sort_by(f64::total_cmp);
            let q = |f: f64| sorted[((f * n as f64) as usize).min(n - 1)];
            eprintln!(
                "{name}: measured luminance min {:.3e}, p10 {:.3e}, median {:.3e}, p90 {:.3e}, p99 {:.3e}, max {:.3e}; nearest other sample's distance: median {:.3e}",
                sorted[0],
                q(0.1),
                q(0.5),
                q(0.9),
                q(0.99),
                sorted[n - 1],
                {
                    let mut d: Vec<f64> = lists.own.iter().map(|l| l[1].0.sqrt()).collect();
                    d.sort_by(f64::total_cmp);
                    d[n / 2]
                }
            );
            eprintln!(
                "\n#### {name}: {n} samples, peak luminance {peak:.4}, {dup} with another sample at distance 0, {} above 1 % of the peak ({:.1} s)",
                summarise(&lum, &lum).rel_count,
                t.elapsed().as_secs_f64()
            );
            eprintln!(
                "| rule | rel (v>0) median | p90 | p99 | max | RMS | rel (v>1 % peak) median | p90 | p99 | max | RMS | abs÷peak median | p90 | p99 | max | RMS | bias÷peak |"
            );
            eprintln!("|---|{}", "---:|".repeat(16));
            eprintln!("{}", row("in-sample kNN", &summarise(&est.knn_in, &lum)));
            for (c, inside, _) in &est.grid {
                eprintln!(
                    "{}",
                    row(&format!("in-sample grid {c}³"), &summarise(inside, &lum))
                );
            }
            let knn_loo = summarise(&est.knn_loo, &lum);
            eprintln!("{}", row("LOO kNN", &knn_loo));
            for (c, _, loo) in &est.grid {
                eprintln!("{}", row(&format!("LOO grid {c}³"), &summarise(loo, &lum)));
            }
            eprintln!("{}", row("LOO pbrt-v2", &summarise(&est.pbrt_loo, &lum)));
            // Paired: how far each grid's left-out estimate is from the kNN one, in units of the
            // kNN one's own left-out error, and how often the grid is the closer to `v_i`.
            for (c, _, loo) in &est.grid {
                let (mut ratio, mut closer, mut ties) = (Vec::new(), 0usize, 0usize);
                for i in 0..n {
                    let (g, k) = ((loo[i] - lum[i]).abs(), (est.knn_loo[i] - lum[i]).abs());
                    if k > 0.0 {
                        ratio.push((loo[i] - est.knn_loo[i]).abs() / k);
                    }
                    if g < k {
                        closer += 1;
                    } else if g == k {
                        ties += 1;
                    }
                }
                let r = five(ratio);
                eprintln!(
                    "paired {c}³: |grid₋ᵢ − kNN₋ᵢ| / |kNN₋ᵢ − v| median {:.2e}, p90 {:.2e}, p99 {:.2e}, max {:.2e}; grid closer to v at {closer} of {n} samples ({ties} ties)",
                    r[0], r[1], r[2], r[3]
                );
            }
            // The reader's grid interpolant at the samples, as a check of the helper.
            if let Some((_, inside, _)) = est.grid.iter().find(|g| g.0 == GRID_CELLS) {
                let g = b.with_interpolation(Interpolation::Grid);
                let worst = (0..n)
                    .map(|i| (inside[i] - g.luminance_at(&lists.points[i])).abs())
                    .fold(0.0f64, f64::max);
                eprintln!(
                    "check: grid helper vs Interpolation::Grid at the samples: max |Δ| {worst:e}"
                );
            }
            // The CPU time of the kNN luminance at every vertex of each grid (one thread; the
            // reader makes luminance and RGB per vertex, by blocks, with one search).
            for &c in &cells {
                let t = std::time::Instant::now();
                let h = 1.0 / c as f64;
                let mut sum = 0.0;
                for k in 0..=c {
                    for j in 0..=c {
                        for i in 0..=c {
                            sum += b.knn_luminance_at(&[i as f64 * h, j as f64 * h, k as f64 * h]);
                        }
                    }
                }
                let secs = t.elapsed().as_secs_f64();
                let count = (c + 1).pow(3);
                eprintln!(
                    "vertices {c}³: {count} kNN evaluations in {secs:.2} s ({:.0} ns each; sum {sum:.3e})",
                    1e9 * secs / count as f64
                );
            }
            // RGB channels: relative median / p99 (values above 1 % of the channel's peak).
            for ch in 0..3 {
                let v: Vec<f64> = b.data.rgb.iter().map(|c| c[ch]).collect();
                let e = lists.estimates(&v, false);
                let s = summarise(&e.knn_loo, &v);
                let mut line = format!(
                    "channel {}: rel (v>0) median / p90 / p99: LOO kNN {:.2e} / {:.2e} / {:.2e}",
                    ["R", "G", "B"][ch],
                    s.rel_all[0],
                    s.rel_all[1],
                    s.rel_all[2]
                );
                for (c, _, loo) in &e.grid {
                    let s = summarise(loo, &v);
                    line += &format!(
                        "; LOO grid {c}³ {:.2e} / {:.2e} / {:.2e}",
                        s.rel_all[0], s.rel_all[1], s.rel_all[2]
                    );
                }
                eprintln!("{line}");
            }
            if angles.is_empty() {
                continue;
            }
            eprintln!(
                "| θo | A_knn (± est.) | A_grid {GRID_CELLS}³ | (A_grid − A_knn)/A_knn | ÷ LOO kNN rel (v>0) median | s (kNN) | {} |",
                cells
                    .iter()
                    .map(|c| format!("(A_grid {c}³ − A_knn)/A_knn"))
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
            eprintln!(
                "|---:|---:|---:|---:|---:|---:|{}",
                "---:|".repeat(cells.len())
            );
            for deg in &angles {
                let to = deg.to_radians();
                let t = std::time::Instant::now();
                let (ak, ek) = knn_albedo(&b, to, tol);
                let secs = t.elapsed().as_secs_f64();
                let (ag, _) = b.grid_albedo(to).unwrap_or((f64::NAN, 0.0));
                let d = (ag - ak) / ak;
                let pbrt: Vec<String> = pbrt_m
                    .iter()
                    .map(|&m| {
                        let pb = |p: &[f64; 3]| pbrt_rule(&lists.points, p, None, &lum);
                        let a = midpoint_albedo(pb, to, m);
                        let k = midpoint_albedo(|p: &[f64; 3]| b.knn_luminance_at(p), to, m);
                        format!(
                            "m {m}: {:+.2e} (the same rule on kNN: {:+.2e})",
                            (a - ak) / ak,
                            (k - ak) / ak
                        )
                    })
                    .collect();
                eprintln!(
                    "pbrt-v2 rule albedo at {deg}°, midpoint rule of m² points, (A_pbrt − A_knn)/A_knn: {}",
                    pbrt.join(", ")
                );
                let finer: Vec<String> = cells
                    .iter()
                    .map(|&c| format!("{:+.2e}", (grid_albedo_n(&b, c, to) - ak) / ak))
                    .collect();
                eprintln!(
                    "| {deg}° | {ak:.6} (± {:.1e}) | {ag:.6} | {d:+.2e} | {:.2} | {secs:.1} | {} |",
                    ek / ak,
                    d.abs() / knn_loo.rel_all[0],
                    finer.join(" | ")
                );
            }
        }
    }
}
