//! The `K + 1` nearest samples of a remapped point without a heap allocation: a small k-d tree
//! over the samples (built once per file; boxes per node, leaves of at most [`LEAF`] samples)
//! and a search that keeps the best candidates sorted in a stack array. Queries in the
//! remapped unit cube (every pair of directions) scan the candidate list of their cell of a
//! uniform grid instead ([`Tree::nearest_fast`]): the same samples in the same order.
//!
//! The result is the same set of distances as any exact nearest-neighbour search (ties
//! between equidistant samples may pick other samples at the same distance, which leaves the
//! interpolant unchanged: it depends on the distances and, for the blended samples, on their
//! values, and a sample tied with the cut one has weight 0).

/// Samples kept per query: the blended ones and the one the weights are cut at (the reader's
/// `NEIGHBOURS + 1`, checked at compile time beside it).
pub(super) const K: usize = 9;

/// Most samples in a leaf (instructions per evaluation of `cayman` under cachegrind: 5 469 at
/// 4, 5 010 at 8, 4 952 at 16; docs/benchmarks.md §19.6).
const LEAF: usize = 16;

/// One node: the bounding box of its samples and either two children or a leaf range.
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// First sample (leaf) or first child (inner node; the second is `first + 1`).
    first: u32,
    /// Samples in a leaf, 0 for an inner node.
    len: u32,
    /// Inner node: the axis it is split on and where (the second child's smallest coordinate).
    axis: u32,
    split: f64,
}

/// The k-d tree of a file's remapped samples.
pub(super) struct Tree {
    /// The samples in leaf order.
    points: Vec<[f64; 3]>,
    /// The file's index of each sample of `points`.
    index: Vec<u32>,
    nodes: Vec<Node>,
    /// Each sample's point by the file's index.
    by_index: Vec<[f64; 3]>,
    /// This tree's identity in the per-thread neighbourhood cache (unique per process).
    id: u64,
    /// Each cell's candidate samples (see [`Grid`]).
    grid: Grid,
}

/// The `len` (≤ `N`) nearest samples, by increasing `(squared distance, file index)`.
pub(super) struct Best<const N: usize> {
    /// Squared distances.
    pub(super) d2: [f64; N],
    /// The file's sample indices.
    pub(super) index: [u32; N],
    /// How many were found (`N` unless the file has fewer samples).
    pub(super) len: usize,
}

/// The [`K`] nearest samples of a query.
pub(super) type Nearest = Best<K>;

impl<const N: usize> Best<N> {
    fn empty() -> Self {
        Self {
            d2: [f64::INFINITY; N],
            index: [0; N],
            len: 0,
        }
    }

    /// Whether `(d2, i)` would be kept (before the worst kept one, or room left).
    #[inline]
    fn admits(&self, d2: f64, i: u32) -> bool {
        self.len < N || before(d2, i, self.d2[N - 1], self.index[N - 1])
    }

    /// Keeps `(d2, i)` if it is among the best `N`, the order kept.
    #[inline]
    fn offer(&mut self, d2: f64, i: u32) {
        if self.len < N {
            self.len += 1;
        } else if !before(d2, i, self.d2[N - 1], self.index[N - 1]) {
            return;
        }
        let mut j = self.len - 1;
        while j > 0 && before(d2, i, self.d2[j - 1], self.index[j - 1]) {
            self.d2[j] = self.d2[j - 1];
            self.index[j] = self.index[j - 1];
            j -= 1;
        }
        self.d2[j] = d2;
        self.index[j] = i;
    }

    /// The largest squared distance kept when full, else infinity (a box farther than this
    /// holds no sample that would be kept; one at exactly this distance may, by its index).
    #[inline]
    fn bound(&self) -> f64 {
        if self.len < N {
            f64::INFINITY
        } else {
            self.d2[N - 1]
        }
    }
}

/// The order of the search: by squared distance, ties by the file's index (so the samples
/// kept are the same whatever the order they are visited in).
#[inline]
fn before(d2: f64, i: u32, d2b: f64, ib: u32) -> bool {
    d2 < d2b || (d2 == d2b && i < ib)
}

/// Squared distance of `p` to `q` (the one formula of every path, so their bits agree).
#[inline]
fn dist2(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    let (a, b, c) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    a * a + b * b + c * c
}

/// Squared distance between the boxes `[alo, ahi]` and `[blo, bhi]` (0 when they meet).
#[inline]
fn box_box_d2(alo: &[f64; 3], ahi: &[f64; 3], blo: &[f64; 3], bhi: &[f64; 3]) -> f64 {
    let mut s = 0.0;
    for d in 0..3 {
        let e = (blo[d] - ahi[d]).max(alo[d] - bhi[d]).max(0.0);
        s += e * e;
    }
    s
}

/// Squared distance from `p` to the farthest point of the box `[lo, hi]`.
#[inline]
fn farthest_d2(p: &[f64; 3], lo: &[f64; 3], hi: &[f64; 3]) -> f64 {
    let mut s = 0.0;
    for d in 0..3 {
        let e = (p[d] - lo[d]).abs().max((hi[d] - p[d]).abs());
        s += e * e;
    }
    s
}

fn bounds(points: &[([f64; 3], u32)]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (p, _) in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

impl Node {
    /// A node boxing `items`, its children or leaf range set later.
    fn boxing(items: &[([f64; 3], u32)]) -> Self {
        let (lo, hi) = bounds(items);
        Node {
            lo,
            hi,
            first: 0,
            len: 0,
            axis: 0,
            split: 0.0,
        }
    }
}

impl Tree {
    /// The tree of `points` (finite coordinates; the file's order is the index).
    pub(super) fn new(points: &[[f64; 3]]) -> Self {
        let mut items: Vec<([f64; 3], u32)> = points
            .iter()
            .enumerate()
            .map(|(i, p)| (*p, i as u32))
            .collect();
        let mut nodes = Vec::with_capacity(2 * points.len() / LEAF + 2);
        nodes.push(Node::boxing(&items));
        // Each inner node's two children are adjacent in `nodes`.
        let mut todo = vec![(0usize, 0usize, items.len())];
        while let Some((node, start, end)) = todo.pop() {
            let slice = &mut items[start..end];
            if slice.len() <= LEAF {
                nodes[node].first = start as u32;
                nodes[node].len = slice.len() as u32;
                continue;
            }
            let (lo, hi) = (nodes[node].lo, nodes[node].hi);
            let axis = (0..3)
                .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
                .unwrap_or(0);
            let mid = slice.len() / 2;
            slice.select_nth_unstable_by(mid, |a, b| {
                a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
            });
            let first = nodes.len();
            for (s, e) in [(start, start + mid), (start + mid, end)] {
                nodes.push(Node::boxing(&items[s..e]));
                todo.push((nodes.len() - 1, s, e));
            }
            nodes[node].first = first as u32;
            nodes[node].axis = axis as u32;
            nodes[node].split = items[start + mid].0[axis];
        }
        let mut tree = Self {
            points: items.iter().map(|x| x.0).collect(),
            index: items.iter().map(|x| x.1).collect(),
            nodes,
            by_index: points.to_vec(),
            id: NEXT_TREE.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            grid: Grid::default(),
        };
        tree.grid = Grid::new();
        tree
    }

    /// The samples whose distance to the box `[lo, hi]` is at most `r` (file indices).
    fn within_box(&self, lo: &[f64; 3], hi: &[f64; 3], r: f64, out: &mut Vec<u32>) {
        let r2 = r * r;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if box_box_d2(&node.lo, &node.hi, lo, hi) > r2 {
                continue;
            }
            if node.len > 0 {
                let (s, e) = (node.first as usize, (node.first + node.len) as usize);
                for (p, &i) in self.points[s..e].iter().zip(&self.index[s..e]) {
                    if box_box_d2(p, p, lo, hi) <= r2 {
                        out.push(i);
                    }
                }
            } else {
                stack.push(node.first as usize);
                stack.push(node.first as usize + 1);
            }
        }
    }

    /// The grid's candidates per cell, every cell listed: `(mean, largest)`.
    #[cfg(test)]
    pub(super) fn grid_occupancy(&self) -> (f64, usize) {
        let sizes: Vec<usize> = (0..self.grid.cells.len())
            .map(|c| self.grid.list(self, c).len())
            .collect();
        let mean = sizes.iter().sum::<usize>() as f64 / sizes.len().max(1) as f64;
        (mean, sizes.iter().copied().max().unwrap_or(0))
    }

    /// The [`K`] nearest samples of `q`, ties by the file's index, the same samples in the
    /// same order (so the same interpolated value to the bit) as [`Tree::nearest`]: from
    /// `q`'s cell of the [`Grid`] when `q` is in the remapped unit cube (every pair of
    /// directions is), else through [`Tree::nearest_cached`].
    #[inline]
    pub(super) fn nearest_fast(&self, q: &[f64; 3]) -> Nearest {
        let Some(cell) = self.grid.cell(q) else {
            return self.nearest_cached(q);
        };
        let mut best = Nearest::empty();
        for &i in self.grid.list(self, cell) {
            let d2 = dist2(&self.by_index[i as usize], q);
            if best.admits(d2, i) {
                best.offer(d2, i);
            }
        }
        best
    }

    /// The candidate list of grid cell `(ix, iy, iz)` (each index below [`GRID`]): every sample
    /// that can be among the [`K`] nearest of a point of the cell's (widened) box; `None` when
    /// the tree has no grid.
    pub(super) fn cell_candidates(&self, ix: usize, iy: usize, iz: usize) -> Option<&[u32]> {
        if self.grid.cells.is_empty() || ix >= GRID || iy >= GRID || iz >= GRID {
            return None;
        }
        Some(self.grid.list(self, ix + GRID * (iy + GRID * iz)))
    }

    /// The [`CellList`] of `q`'s grid cell when `q` is in the remapped unit cube (up to the
    /// grid's padding), else `None` (see [`Tree::nearest_fast`]).
    #[inline]
    pub(super) fn cell_list_of(&self, q: &[f64; 3]) -> Option<&CellList> {
        let cell = self.grid.cell(q)?;
        Some(self.grid.cell_list(self, cell))
    }

    /// Sample `i`'s remapped point (the file's index).
    #[inline]
    pub(super) fn point(&self, i: u32) -> [f64; 3] {
        self.by_index[i as usize]
    }

    /// Squared distance from `q` to node `n`'s box (0 inside).
    #[inline]
    fn box_d2(&self, n: usize, q: &[f64; 3]) -> f64 {
        let node = &self.nodes[n];
        let mut s = 0.0;
        for ((&q, &lo), &hi) in q.iter().zip(&node.lo).zip(&node.hi) {
            let e = if q < lo {
                lo - q
            } else if q > hi {
                q - hi
            } else {
                0.0
            };
            s += e * e;
        }
        s
    }

    /// The `K` nearest samples of `q` (all of them if fewer), ties by the file's index,
    /// without the cache.
    pub(super) fn nearest(&self, q: &[f64; 3]) -> Nearest {
        self.nearest_n::<K>(q)
    }

    /// The `N` nearest samples of `q` (all of them if fewer), ties by the file's index.
    fn nearest_n<const N: usize>(&self, q: &[f64; 3]) -> Best<N> {
        let mut best = Best::<N>::empty();
        // Depth ≤ log2(samples / LEAF) + 1 (median splits); each level leaves at most one
        // pending sibling, so 40 entries serve any u32 count of samples.
        let mut stack_node = [0u32; 40];
        let mut stack_d2 = [0.0f64; 40];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (n, bd) = (stack_node[top] as usize, stack_d2[top]);
            if bd > best.bound() {
                continue;
            }
            let node = &self.nodes[n];
            if node.len > 0 {
                let (s, e) = (node.first as usize, (node.first + node.len) as usize);
                for (p, &i) in self.points[s..e].iter().zip(&self.index[s..e]) {
                    let d2 = dist2(p, q);
                    if best.admits(d2, i) {
                        best.offer(d2, i);
                    }
                }
            } else {
                let (l, r) = (node.first as usize, node.first as usize + 1);
                // The nearer child inherits this node's bound (its box is inside this one's);
                // the farther one gets its own box's distance. The nearer is popped first.
                let (near, far) = if q[node.axis as usize] < node.split {
                    (l, r)
                } else {
                    (r, l)
                };
                if top + 2 > stack_node.len() {
                    // Deeper than any median-split tree of u32 samples: never reached.
                    continue;
                }
                let far_d2 = self.box_d2(far, q);
                if far_d2 <= best.bound() {
                    stack_node[top] = far as u32;
                    stack_d2[top] = far_d2;
                    top += 1;
                }
                stack_node[top] = near as u32;
                stack_d2[top] = bd;
                top += 1;
            }
        }
        best
    }

    /// [`Tree::nearest`] through this thread's neighbourhood cache (see [`Neighbourhood`]):
    /// the same samples in the same order, so the same interpolated value to the bit.
    pub(super) fn nearest_cached(&self, q: &[f64; 3]) -> Nearest {
        CACHE.with(|cell| {
            let mut slot = cell.borrow_mut();
            let (hood, misses) = &mut *slot;
            if let Some(near) = hood
                .as_ref()
                .filter(|h| h.tree == self.id)
                .and_then(|h| h.nearest(q))
            {
                *misses = 0;
                return near;
            }
            // Queries that do not follow one another (a renderer's) would pay the wider
            // search at every call: after a miss that followed a miss, the plain search, and
            // a new neighbourhood only every `REANCHOR`-th miss in a row.
            *misses = misses.wrapping_add(1);
            if *misses > 1 && *misses % REANCHOR != 0 {
                return self.nearest(q);
            }
            let wide = self.nearest_n::<{ CANDIDATES + 1 }>(q);
            *hood = Some(Neighbourhood::new(self, q, &wide));
            let mut near = Nearest::empty();
            for j in 0..wide.len.min(K) {
                near.offer(wide.d2[j], wide.index[j]);
            }
            near
        })
    }
}

/// Cells per axis of the [`Grid`] over the remapped unit cube (instructions per evaluation
/// and candidates per cell: docs/benchmarks.md §23.7).
pub(super) const GRID: usize = 32;

/// How far (absolute) a cell's box is widened when its candidates are chosen: a query whose
/// cell index was rounded across a cell face, or on the cube's faces up to this much outside,
/// still lies in the widened box.
const GRID_PAD: f64 = 1e-9;

/// Candidate lists on a uniform grid of [`GRID`]³ cells over the remapped unit cube
/// `[0, 1]³`, where every pair of directions maps: each cell keeps every sample that can be
/// among the [`K`] nearest of a point of its (widened) box, nearest to the cell's centre
/// first. A query scans its cell's list (~35 samples per cell on the shared files) with the
/// search's own order (squared distance, ties by the file's index), so it keeps exactly the
/// samples the tree would, in the same order.
///
/// A cell's list: with `R` the `K`-th smallest distance from a sample to the *farthest*
/// point of the box, every point of the box has `K` samples within `R`, so its `K` nearest
/// (and every sample tied with the `K`-th) are within `R` of it: every sample whose distance
/// to the box is at most `R` (with a relative margin of 10⁻⁹ for rounding) is kept. The
/// samples beyond `d_K(centre) + half diagonal` of the box are never needed for `R`, so
/// only those are visited (the tree's box search).
///
/// The lists are made when a query first needs them (a list is a function of the samples
/// and the cell alone, so whichever thread makes it, it is the same): a file read for a few
/// evaluations pays for a few cells, not for all (≈ 26 000 instructions a cell).
#[derive(Default)]
struct Grid {
    /// Each cell's candidates, once made.
    cells: Vec<std::sync::OnceLock<CellList>>,
}

/// One cell's candidates: their file indices and, for the quadrature evaluator's lanes, their
/// remapped points as structure of arrays (`x` of every candidate, then `y`, then `z`, each
/// padded to a multiple of [`SOA_PAD`] with [`SOA_FAR`], a point no query comes near).
pub(super) struct CellList {
    /// File indices, nearest to the cell's centre first.
    pub(super) index: Box<[u32]>,
    /// `[x…, y…, z…]`, each of [`CellList::stride`] entries.
    pub(super) xyz: Box<[f64]>,
}

/// The structure-of-arrays rows of a [`CellList`] are padded to a multiple of this.
pub(super) const SOA_PAD: usize = 4;

/// Coordinate of the padding points of a [`CellList`] (squared distance ≥ 3·(10³ − 1)² from
/// any point of the unit cube: never among the nearest).
pub(super) const SOA_FAR: f64 = 1e3;

impl CellList {
    fn new(tree: &Tree, index: Box<[u32]>) -> Self {
        let stride = index.len().div_ceil(SOA_PAD) * SOA_PAD;
        let mut xyz = vec![SOA_FAR; 3 * stride];
        for (k, &i) in index.iter().enumerate() {
            let p = tree.by_index[i as usize];
            for d in 0..3 {
                xyz[d * stride + k] = p[d];
            }
        }
        Self {
            index,
            xyz: xyz.into_boxed_slice(),
        }
    }

    /// Entries per row of [`CellList::xyz`].
    #[inline]
    pub(super) fn stride(&self) -> usize {
        self.xyz.len() / 3
    }
}

impl Grid {
    fn new() -> Self {
        Self {
            cells: (0..GRID * GRID * GRID)
                .map(|_| std::sync::OnceLock::new())
                .collect(),
        }
    }

    /// Cell `c`'s candidates, made on first use.
    #[inline]
    fn list<'a>(&'a self, tree: &Tree, c: usize) -> &'a [u32] {
        &self.cell_list(tree, c).index
    }

    /// Cell `c`'s [`CellList`], made on first use.
    #[inline]
    fn cell_list<'a>(&'a self, tree: &Tree, c: usize) -> &'a CellList {
        self.cells[c].get_or_init(|| CellList::new(tree, Self::candidates(tree, c)))
    }

    /// Cell `c`'s candidates (see the type's docs).
    fn candidates(tree: &Tree, c: usize) -> Box<[u32]> {
        let g = GRID;
        let h = 1.0 / g as f64;
        let ijk = [c % g, c / g % g, c / (g * g)];
        let lo = ijk.map(|i| i as f64 * h - GRID_PAD);
        let hi = ijk.map(|i| (i + 1) as f64 * h + GRID_PAD);
        let centre = [0, 1, 2].map(|d| 0.5 * (lo[d] + hi[d]));
        let half_diag = 0.5 * dist2(&lo, &hi).sqrt();
        let best = tree.nearest_n::<K>(&centre);
        let mut near = Vec::new();
        if best.len < K {
            near.extend(0..tree.by_index.len() as u32);
        } else {
            // Every point of the box has `K` samples within this (1-Lipschitz `d_K`).
            let reach = (best.d2[K - 1].sqrt() + half_diag) * (1.0 + 1e-9);
            tree.within_box(&lo, &hi, reach, &mut near);
        }
        let r2 = if near.len() < K {
            f64::INFINITY
        } else {
            let mut far: Vec<f64> = near
                .iter()
                .map(|&i| farthest_d2(&tree.by_index[i as usize], &lo, &hi))
                .collect();
            far.select_nth_unstable_by(K - 1, f64::total_cmp);
            far[K - 1] * (1.0 + 1e-9)
        };
        let mut keyed: Vec<(f64, u32)> = near
            .iter()
            .copied()
            .filter(|&i| {
                let p = &tree.by_index[i as usize];
                box_box_d2(p, p, &lo, &hi) <= r2
            })
            .map(|i| (dist2(&tree.by_index[i as usize], &centre), i))
            .collect();
        keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        keyed.into_iter().map(|(_, i)| i).collect()
    }

    /// The cell of `q` if `q` is in the unit cube (up to [`GRID_PAD`]), else `None`.
    #[inline]
    fn cell(&self, q: &[f64; 3]) -> Option<usize> {
        if self.cells.is_empty() {
            return None;
        }
        let mut c = 0;
        for d in (0..3).rev() {
            let x = q[d];
            if !(-GRID_PAD..=1.0 + GRID_PAD).contains(&x) {
                return None;
            }
            c = c * GRID + ((x * GRID as f64) as usize).min(GRID - 1);
        }
        Some(c)
    }
}

/// Source of the trees' identities.
static NEXT_TREE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Samples kept around a query by the neighbourhood cache.
pub(super) const CANDIDATES: usize = 32;

std::thread_local! {
    /// The last neighbourhood searched on this thread (of whichever tree) and the misses
    /// in a row since its last hit.
    static CACHE: std::cell::RefCell<(Option<Neighbourhood>, u32)> =
        const { std::cell::RefCell::new((None, 0)) };
}

/// A run of misses builds a new neighbourhood every this many misses.
const REANCHOR: u32 = 8;

/// The [`CANDIDATES`] samples nearest to an anchor point `a` and the distance `reach` of the
/// next one (infinite when the file has no more samples). Every other sample is at least
/// `reach − |q − a|` from a query `q`; when the [`K`]-th nearest candidate of `q` is closer
/// than that, the `K` nearest samples of `q` are candidates, and the search among the
/// candidates alone (the same order, ties by index) finds exactly what the tree would. A
/// quadrature's nodes come in small pieces, so most of them fall in the last neighbourhood.
pub(super) struct Neighbourhood {
    tree: u64,
    anchor: [f64; 3],
    points: [[f64; 3]; CANDIDATES],
    index: [u32; CANDIDATES],
    len: usize,
    reach: f64,
}

impl Neighbourhood {
    fn new(tree: &Tree, anchor: &[f64; 3], wide: &Best<{ CANDIDATES + 1 }>) -> Self {
        let len = wide.len.min(CANDIDATES);
        let mut points = [[0.0; 3]; CANDIDATES];
        let mut index = [0u32; CANDIDATES];
        for j in 0..len {
            index[j] = wide.index[j];
            points[j] = tree.by_index[wide.index[j] as usize];
        }
        let reach = if wide.len > CANDIDATES {
            wide.d2[CANDIDATES].sqrt()
        } else {
            f64::INFINITY
        };
        Self {
            tree: tree.id,
            anchor: *anchor,
            points,
            index,
            len,
            reach,
        }
    }

    /// The `K` nearest samples of `q` if they are provably among the candidates.
    #[inline]
    fn nearest(&self, q: &[f64; 3]) -> Option<Nearest> {
        let shift = dist2(q, &self.anchor).sqrt();
        if !(shift < self.reach) {
            return None;
        }
        let mut near = Nearest::empty();
        for (p, &i) in self.points[..self.len].iter().zip(&self.index[..self.len]) {
            let d2 = dist2(p, q);
            if near.admits(d2, i) {
                near.offer(d2, i);
            }
        }
        // Every sample outside is at least `reach − shift` away: strictly farther than the
        // last one kept (with a relative margin far above the rounding of the distances).
        let kept = near.bound().sqrt();
        (self.reach.is_infinite() || (kept + shift) * (1.0 + 1e-9) < self.reach).then_some(near)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A xorshift64 stream of uniforms in [0, 1) (53 bits) from `state`.
    pub(crate) fn xorshift(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The 8 × 8 × 8 grid on the unit cube: every query has many equidistant samples.
    fn tie_grid() -> Vec<[f64; 3]> {
        (0..512)
            .map(|i| {
                [
                    (i % 8) as f64 / 7.0,
                    (i / 8 % 8) as f64 / 7.0,
                    (i / 64) as f64 / 7.0,
                ]
            })
            .collect()
    }

    /// Against a brute-force scan: the same sorted distances (ties may pick other samples at
    /// the same distance), on random points and on a grid full of ties.
    #[test]
    fn nearest_matches_a_scan() {
        let mut uniform = xorshift(0x9e37_79b9_7f4a_7c15);
        let random: Vec<[f64; 3]> = (0..700)
            .map(|_| [uniform(), uniform(), uniform()])
            .collect();
        let grid = tie_grid();
        for points in [random, grid, (0..5).map(|i| [i as f64, 0.0, 0.0]).collect()] {
            let tree = Tree::new(&points);
            for k in 0..3000 {
                let q = if k % 3 == 0 {
                    // On the grid's own coordinates: many equidistant samples.
                    [(k % 8) as f64 / 7.0, (k / 8 % 8) as f64 / 7.0, 0.5]
                } else {
                    [1.4 * uniform() - 0.2, uniform(), 1.4 * uniform() - 0.2]
                };
                let got = tree.nearest(&q);
                let mut all: Vec<f64> = points
                    .iter()
                    .map(|p| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2))
                    .collect();
                all.sort_by(f64::total_cmp);
                let n = K.min(points.len());
                assert_eq!(got.len, n);
                for j in 0..n {
                    let p = points[got.index[j] as usize];
                    let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                    assert!((got.d2[j] - d2).abs() <= 1e-15, "{q:?}: {j}");
                    assert!(
                        (got.d2[j] - all[j]).abs() <= 1e-15,
                        "{q:?}: {j}: {} vs {}",
                        got.d2[j],
                        all[j]
                    );
                }
                let mut seen = got.index[..n].to_vec();
                seen.sort_unstable();
                seen.dedup();
                assert_eq!(seen.len(), n, "a sample found twice");
            }
        }
    }

    /// The grid's search finds the same samples in the same order (bit for bit) as the tree's
    /// on random points, on the tie grid (the queries on its planes and on the cells' faces),
    /// on a file smaller than `K + 1` samples and on points clustered in a corner (cells far
    /// from every sample); on the cube's faces and corners; and queries outside the cube take
    /// the tree.
    #[test]
    fn grid_search_is_the_tree_search() {
        let mut uniform = xorshift(0x6a09_e667_f3bc_c908);
        let random: Vec<[f64; 3]> = (0..1500)
            .map(|_| [uniform(), uniform(), uniform()])
            .collect();
        let corner: Vec<[f64; 3]> = (0..300)
            .map(|_| [0.1 * uniform(), 0.1 * uniform(), 0.1 * uniform()])
            .collect();
        let small: Vec<[f64; 3]> = (0..7).map(|i| [i as f64 / 6.0, 0.5, 0.25]).collect();
        let g = GRID as f64;
        for (name, points) in [
            ("random", random),
            ("grid", tie_grid()),
            ("corner", corner),
            ("small", small),
        ] {
            let tree = Tree::new(&points);
            let (mean, largest) = tree.grid_occupancy();
            eprintln!("{name}: {mean:.1} candidates per cell, at most {largest}");
            for k in 0..30_000 {
                let mut q = [uniform(), uniform(), uniform()];
                match k % 5 {
                    // On the tie grid's planes.
                    0 => q = [(k % 8) as f64 / 7.0, q[1], (k / 8 % 8) as f64 / 7.0],
                    // On a cell's face, or a rounding step beside it.
                    1 => {
                        let face = ((q[0] * g).floor() / g + [-1e-16, 0.0, 1e-16][k % 3]).max(0.0);
                        q[0] = face;
                    }
                    // On the cube's faces and corners.
                    2 => {
                        q = q.map(|x| {
                            if x < 0.3 {
                                0.0
                            } else if x > 0.7 {
                                1.0
                            } else {
                                x
                            }
                        })
                    }
                    _ => {}
                }
                let (a, b) = (tree.nearest_fast(&q), tree.nearest(&q));
                assert!(tree.grid.cell(&q).is_some(), "{q:?}");
                assert_eq!(a.len, b.len, "{name} {q:?}");
                for j in 0..a.len {
                    assert_eq!(a.index[j], b.index[j], "{name} {q:?}: {j}");
                    assert_eq!(a.d2[j].to_bits(), b.d2[j].to_bits(), "{name} {q:?}: {j}");
                }
            }
            for q in [[1.5, 0.5, 0.5], [-0.1, 0.0, 0.0], [0.5, f64::NAN, 0.5]] {
                assert!(tree.grid.cell(&q).is_none(), "{q:?}");
                let (a, b) = (tree.nearest_fast(&q), tree.nearest(&q));
                assert_eq!(a.index[..a.len], b.index[..b.len], "{name} {q:?}");
            }
        }
    }

    /// The cached search finds the same samples in the same order (bit for bit) as the
    /// tree's, on walks of small steps (a quadrature's nodes: mostly hits) with jumps (misses),
    /// on random points, on a grid full of equidistant samples and on a file smaller than the
    /// neighbourhood; it answers most of the small steps from the cache.
    #[test]
    fn cached_search_is_the_tree_search() {
        let mut uniform = xorshift(0x2545_f491_4f6c_dd1d);
        let random: Vec<[f64; 3]> = (0..1500)
            .map(|_| [uniform(), uniform(), uniform()])
            .collect();
        let grid = tie_grid();
        let small: Vec<[f64; 3]> = (0..20).map(|i| [i as f64 / 19.0, 0.5, 0.5]).collect();
        for (name, points) in [("random", random), ("grid", grid), ("small", small)] {
            let tree = Tree::new(&points);
            let mut q = [0.5, 0.5, 0.5];
            let (mut hits, mut steps) = (0usize, 0usize);
            for k in 0..20_000 {
                if k % 200 == 0 {
                    q = [uniform(), uniform(), uniform()];
                } else if k % 3 == 0 {
                    // On the grid's planes: ties.
                    q = [(k % 8) as f64 / 7.0, q[1], (k / 8 % 8) as f64 / 7.0];
                } else {
                    for c in &mut q {
                        *c += 0.004 * (uniform() - 0.5);
                    }
                    steps += 1;
                    hits += CACHE
                        .with(|c| c.borrow().0.as_ref().and_then(|h| h.nearest(&q)))
                        .is_some() as usize;
                }
                let (a, b) = (tree.nearest_cached(&q), tree.nearest(&q));
                assert_eq!(a.len, b.len, "{name} {q:?}");
                for j in 0..a.len {
                    assert_eq!(a.index[j], b.index[j], "{name} {q:?}: {j}");
                    assert_eq!(a.d2[j].to_bits(), b.d2[j].to_bits(), "{name} {q:?}: {j}");
                }
            }
            eprintln!("{name}: {hits} of {steps} small steps from the cache");
            assert!(hits * 2 > steps, "{name}: {hits} of {steps}");
        }
    }
}
