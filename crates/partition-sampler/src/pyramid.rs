//! Max and sum pyramids (mip levels of `2^k × 2^k` cell blocks) over a `W × H` grid of cells,
//! with exact range queries over arbitrary (fractional) rectangles in grid coordinates.
//!
//! Level 0 is not stored here: it comes from a [`CellSource`], which also answers partial
//! overlaps of a single cell (so a row factor like `sin πt` can be integrated exactly over a
//! fraction of a row). A query starts at the coarsest level whose blocks are at least as large
//! as the rectangle (at most 2 × 2 blocks), takes fully covered blocks from the pyramid and
//! descends only into partially covered ones: O(1) for rectangles aligned on the block grid
//! (quadtree cells of a power-of-two grid), O(perimeter) in the worst case.

/// Level-0 access for a [`Pyramid`].
pub(crate) trait CellSource {
    /// `(max, integral)` of the full cell `(i, j)`.
    fn full(&self, i: usize, j: usize) -> (f64, f64);
    /// `(max, integral)` over the part `[xa, xb] × [ya, yb]` (grid coordinates, inside the
    /// cell `[i, i+1] × [j, j+1]`, positive area) of cell `(i, j)`.
    fn partial(&self, i: usize, j: usize, xa: f64, xb: f64, ya: f64, yb: f64) -> (f64, f64);
}

#[derive(Debug, Clone, Copy)]
struct Level {
    w: usize,
    h: usize,
    offset: usize,
}

/// Stored levels `1..=top` of `(max, sum)` pairs.
#[derive(Debug, Clone)]
pub(crate) struct Pyramid {
    w: usize,
    h: usize,
    /// `levels[k]` describes level `k` (entry 0 is level 0, whose data lives in the source).
    levels: Vec<Level>,
    data: Vec<[f64; 2]>,
}

const STACK: usize = 108;

/// A query rectangle in grid coordinates.
#[derive(Debug, Clone, Copy)]
struct Span {
    xa: f64,
    xb: f64,
    ya: f64,
    yb: f64,
}

/// Fixed-size DFS stack of `(level, block x, block y)`; its depth is bounded by
/// `4 + 3 · levels` ≤ 103 for grids below 2^32 cells per side.
struct Stack {
    items: [(u8, u32, u32); STACK],
    n: usize,
}

impl Stack {
    /// Pushes the blocks `[i0, i1) × [j0, j1)` of level `lvl` that overlap `q` with positive area.
    fn push_blocks(&mut self, lvl: usize, q: &Span, [i0, i1]: [usize; 2], [j0, j1]: [usize; 2]) {
        let size = (1u64 << lvl) as f64;
        for bj in j0..j1 {
            let by0 = bj as f64 * size;
            if !(by0 < q.yb && by0 + size > q.ya) {
                continue;
            }
            for bi in i0..i1 {
                let bx0 = bi as f64 * size;
                if !(bx0 < q.xb && bx0 + size > q.xa) {
                    continue;
                }
                if let Some(slot) = self.items.get_mut(self.n) {
                    *slot = (lvl as u8, bi as u32, bj as u32);
                    self.n += 1;
                }
            }
        }
    }

    fn pop(&mut self) -> Option<(usize, usize, usize)> {
        self.n = self.n.checked_sub(1)?;
        let (l, i, j) = self.items[self.n];
        Some((l as usize, i as usize, j as usize))
    }
}

impl Pyramid {
    /// Builds levels `1..` from `src` in O(W·H).
    pub(crate) fn build<S: CellSource>(w: usize, h: usize, src: &S) -> Self {
        let mut levels = vec![Level { w, h, offset: 0 }];
        let (mut lw, mut lh) = (w, h);
        let mut total = 0usize;
        while lw > 1 || lh > 1 {
            lw = lw.div_ceil(2);
            lh = lh.div_ceil(2);
            levels.push(Level {
                w: lw,
                h: lh,
                offset: total,
            });
            total += lw * lh;
        }
        let mut data = vec![[0.0f64; 2]; total];
        if levels.len() > 1 {
            let l1 = levels[1];
            for bj in 0..l1.h {
                for bi in 0..l1.w {
                    let mut m = 0.0f64;
                    let mut s = 0.0f64;
                    for j in 2 * bj..(2 * bj + 2).min(h) {
                        for i in 2 * bi..(2 * bi + 2).min(w) {
                            let (cm, cs) = src.full(i, j);
                            m = m.max(cm);
                            s += cs;
                        }
                    }
                    data[l1.offset + bj * l1.w + bi] = [m, s];
                }
            }
            for k in 2..levels.len() {
                let (lo, hi) = (levels[k - 1], levels[k]);
                for bj in 0..hi.h {
                    for bi in 0..hi.w {
                        let mut m = 0.0f64;
                        let mut s = 0.0f64;
                        for j in 2 * bj..(2 * bj + 2).min(lo.h) {
                            for i in 2 * bi..(2 * bi + 2).min(lo.w) {
                                let [cm, cs] = data[lo.offset + j * lo.w + i];
                                m = m.max(cm);
                                s += cs;
                            }
                        }
                        data[hi.offset + bj * hi.w + bi] = [m, s];
                    }
                }
            }
        }
        Self { w, h, levels, data }
    }

    /// Bytes held.
    pub(crate) fn bytes_used(&self) -> usize {
        self.data.capacity() * std::mem::size_of::<[f64; 2]>()
            + self.levels.capacity() * std::mem::size_of::<Level>()
    }

    /// The start of a descent over the clamped, non-empty `[xa, xb] × [ya, yb]`: the query's
    /// span and a stack holding the blocks that cover it on the coarsest level whose block side
    /// is at least the rectangle's larger extent (shared by [`Pyramid::query`] and
    /// [`Pyramid::query_max`]).
    #[inline(always)]
    fn descent(&self, xa: f64, xb: f64, ya: f64, yb: f64) -> (Span, Stack) {
        let top = self.levels.len() - 1;
        let ext = (xb - xa).max(yb - ya);
        let mut k = 0usize;
        while k < top && ((1u64 << k) as f64) < ext {
            k += 1;
        }
        let q = Span { xa, xb, ya, yb };
        let mut stack = Stack {
            items: [(0u8, 0u32, 0u32); STACK],
            n: 0,
        };
        {
            let lv = self.levels[k];
            let size = (1u64 << k) as f64;
            let i0 = (xa / size) as usize;
            let i1 = ((xb / size).ceil() as usize).min(lv.w);
            let j0 = (ya / size) as usize;
            let j1 = ((yb / size).ceil() as usize).min(lv.h);
            stack.push_blocks(k, &q, [i0, i1], [j0, j1]);
        }
        (q, stack)
    }

    /// `(max, integral)` over `[xa, xb] × [ya, yb]` in grid coordinates (clamped to the grid).
    /// `(0, 0)` for an empty rectangle.
    pub(crate) fn query<S: CellSource>(
        &self,
        src: &S,
        xa: f64,
        xb: f64,
        ya: f64,
        yb: f64,
    ) -> (f64, f64) {
        let (wf, hf) = (self.w as f64, self.h as f64);
        let xa = xa.max(0.0);
        let ya = ya.max(0.0);
        let xb = xb.min(wf);
        let yb = yb.min(hf);
        if !(xa < xb && ya < yb) {
            return (0.0, 0.0);
        }
        let (q, mut stack) = self.descent(xa, xb, ya, yb);
        let mut max = 0.0f64;
        let mut sum = 0.0f64;
        while let Some((lvl, bi, bj)) = stack.pop() {
            let size = (1u64 << lvl) as f64;
            let bx0 = bi as f64 * size;
            let by0 = bj as f64 * size;
            let bx1 = (bx0 + size).min(wf);
            let by1 = (by0 + size).min(hf);
            let covered = xa <= bx0 && bx1 <= xb && ya <= by0 && by1 <= yb;
            if lvl == 0 {
                let (m, s) = if covered {
                    src.full(bi, bj)
                } else {
                    src.partial(bi, bj, xa.max(bx0), xb.min(bx1), ya.max(by0), yb.min(by1))
                };
                max = max.max(m);
                sum += s;
            } else if covered {
                let lv = self.levels[lvl];
                let [m, s] = self.data[lv.offset + bj * lv.w + bi];
                max = max.max(m);
                sum += s;
            } else {
                let lo = self.levels[lvl - 1];
                let i0 = 2 * bi;
                let j0 = 2 * bj;
                stack.push_blocks(
                    lvl - 1,
                    &q,
                    [i0, (i0 + 2).min(lo.w)],
                    [j0, (j0 + 2).min(lo.h)],
                );
            }
        }
        (max, sum)
    }
}

impl Pyramid {
    /// The first value of [`Pyramid::query`] alone, `max(0, the largest level-0 maximum of
    /// the cells overlapping `[xa, xb] × [ya, yb]` with positive area)` (clamped to the grid;
    /// 0 for an empty rectangle), for a source whose partial maximum is its full one
    /// (`src.partial(..).0 == src.full(i, j).0`). The maximum does not depend on the order it
    /// is taken in, so small rectangles (at most [`DIRECT_MAX_CELLS`] cells a side) read their
    /// cells directly, larger ones descend the pyramid as `query` does, without the integrals.
    pub(crate) fn query_max<S: CellSource>(
        &self,
        src: &S,
        xa: f64,
        xb: f64,
        ya: f64,
        yb: f64,
    ) -> f64 {
        let (wf, hf) = (self.w as f64, self.h as f64);
        let xa = xa.max(0.0);
        let ya = ya.max(0.0);
        let xb = xb.min(wf);
        let yb = yb.min(hf);
        if !(xa < xb && ya < yb) {
            return 0.0;
        }
        // The cells `i` with `i < xb` and `i + 1 > xa`: `⌊xa⌋ ≤ i < ⌈xb⌉`.
        let (i0, i1) = (xa.floor() as usize, (xb.ceil() as usize).min(self.w));
        let (j0, j1) = (ya.floor() as usize, (yb.ceil() as usize).min(self.h));
        let mut max = 0.0f64;
        if i1 - i0 <= DIRECT_MAX_CELLS && j1 - j0 <= DIRECT_MAX_CELLS {
            for j in j0..j1 {
                for i in i0..i1 {
                    max = max.max(src.full(i, j).0);
                }
            }
            return max;
        }
        let (q, mut stack) = self.descent(xa, xb, ya, yb);
        while let Some((lvl, bi, bj)) = stack.pop() {
            if lvl == 0 {
                max = max.max(src.full(bi, bj).0);
                continue;
            }
            let size = (1u64 << lvl) as f64;
            let bx0 = bi as f64 * size;
            let by0 = bj as f64 * size;
            let bx1 = (bx0 + size).min(wf);
            let by1 = (by0 + size).min(hf);
            if xa <= bx0 && bx1 <= xb && ya <= by0 && by1 <= yb {
                let lv = self.levels[lvl];
                max = max.max(self.data[lv.offset + bj * lv.w + bi][0]);
            } else {
                let lo = self.levels[lvl - 1];
                let (i0, j0) = (2 * bi, 2 * bj);
                stack.push_blocks(
                    lvl - 1,
                    &q,
                    [i0, (i0 + 2).min(lo.w)],
                    [j0, (j0 + 2).min(lo.h)],
                );
            }
        }
        max
    }
}

/// Largest rectangle side (in cells) whose maximum [`Pyramid::query_max`] reads cell by cell.
const DIRECT_MAX_CELLS: usize = 12;

/// Snaps a grid coordinate to the nearest integer when it is within rounding distance of it
/// (so quadtree cells mapped into grid coordinates stay aligned on cell boundaries).
#[inline]
pub(crate) fn snap(v: f64, scale: f64) -> f64 {
    let r = v.round();
    if (v - r).abs() <= 64.0 * f64::EPSILON * scale.max(1.0) {
        r
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Grid {
        w: usize,
        v: Vec<f64>,
    }
    impl CellSource for Grid {
        fn full(&self, i: usize, j: usize) -> (f64, f64) {
            let v = self.v[j * self.w + i];
            (v, v)
        }
        fn partial(&self, i: usize, j: usize, xa: f64, xb: f64, ya: f64, yb: f64) -> (f64, f64) {
            let v = self.v[j * self.w + i];
            (v, v * (xb - xa) * (yb - ya))
        }
    }

    fn brute(g: &Grid, h: usize, xa: f64, xb: f64, ya: f64, yb: f64) -> (f64, f64) {
        let mut m = 0.0f64;
        let mut s = 0.0;
        for j in 0..h {
            for i in 0..g.w {
                let ox = (xb.min(i as f64 + 1.0) - xa.max(i as f64)).max(0.0);
                let oy = (yb.min(j as f64 + 1.0) - ya.max(j as f64)).max(0.0);
                if ox > 0.0 && oy > 0.0 {
                    let v = g.v[j * g.w + i];
                    m = m.max(v);
                    s += v * ox * oy;
                }
            }
        }
        (m, s)
    }

    /// `query_max` is `query`'s maximum bit for bit (docs/benchmarks.md §32.2): random
    /// rectangles from a hundredth of a cell to the whole grid, integer and fractional edges,
    /// partly outside the grid and empty, on an odd grid with ties and zeros. Fails when the
    /// direct path also reads the cell at `⌈xb⌉` (tried: a rectangle of 0.2 cells differs).
    #[test]
    fn query_max_is_the_query_maximum() {
        let (w, h) = (53usize, 37usize);
        let v: Vec<f64> = (0..w * h)
            .map(|k| match k % 7 {
                0 => 0.0,
                _ => ((k * 7919) % 101) as f64,
            })
            .collect();
        let g = Grid { w, v };
        let p = Pyramid::build(w, h, &g);
        let mut state = 3u64;
        let mut u = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as f64 / 2f64.powi(64)
        };
        for k in 0..20_000 {
            let size = 60.0 * u().powi(3) + 0.01;
            let (x, y) = (70.0 * u() - 8.0, 50.0 * u() - 6.0);
            let (mut xa, mut xb, mut ya, mut yb) = (x, x + size, y, y + size * (0.2 + u()));
            if k % 3 == 0 {
                (xa, xb, ya, yb) = (xa.round(), xb.round(), ya.round(), yb.round());
            }
            if k % 11 == 0 {
                std::mem::swap(&mut xa, &mut xb);
            }
            let m = p.query_max(&g, xa, xb, ya, yb);
            let (qm, _) = p.query(&g, xa, xb, ya, yb);
            assert_eq!(m.to_bits(), qm.to_bits(), "{xa} {xb} {ya} {yb}");
        }
    }

    #[test]
    fn matches_brute_force_on_odd_grid() {
        let (w, h) = (13usize, 7usize);
        let v: Vec<f64> = (0..w * h).map(|k| ((k * 7919) % 31) as f64).collect();
        let g = Grid { w, v };
        let p = Pyramid::build(w, h, &g);
        let rects = [
            (0.0, 13.0, 0.0, 7.0),
            (0.5, 12.25, 1.75, 6.5),
            (3.0, 4.0, 2.0, 3.0),
            (2.2, 2.3, 5.1, 5.9),
            (8.0, 12.0, 0.0, 4.0),
            (-1.0, 20.0, -3.0, 3.5),
        ];
        for (xa, xb, ya, yb) in rects {
            let (m, s) = p.query(&g, xa, xb, ya, yb);
            let (bm, bs) = brute(&g, h, xa, xb, ya, yb);
            assert_eq!(m, bm, "max on {xa} {xb} {ya} {yb}");
            assert!((s - bs).abs() <= 1e-9 * bs.max(1.0), "sum {s} vs {bs}");
        }
    }
}
