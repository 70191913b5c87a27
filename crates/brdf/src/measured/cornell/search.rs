//! The `K + 1` nearest samples of a remapped point without a heap allocation: a small k-d tree
//! over the samples (built once per file; boxes per node, leaves of at most [`LEAF`] samples)
//! and a search that keeps the best candidates sorted in a stack array.
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
}

/// The `len` (≤ [`K`]) nearest samples, by increasing squared distance.
pub(super) struct Nearest {
    /// Squared distances.
    pub(super) d2: [f64; K],
    /// The file's sample indices.
    pub(super) index: [u32; K],
    /// How many were found (`K` unless the file has fewer samples).
    pub(super) len: usize,
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
        Self {
            points: items.iter().map(|x| x.0).collect(),
            index: items.iter().map(|x| x.1).collect(),
            nodes,
        }
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

    /// The `K` nearest samples of `q` (all of them if fewer).
    pub(super) fn nearest(&self, q: &[f64; 3]) -> Nearest {
        let mut best = Nearest {
            d2: [f64::INFINITY; K],
            index: [0; K],
            len: 0,
        };
        // Depth ≤ log2(samples / LEAF) + 1 (median splits); each level leaves at most one
        // pending sibling, so 40 entries serve any u32 count of samples.
        let mut stack_node = [0u32; 40];
        let mut stack_d2 = [0.0f64; 40];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (n, bd) = (stack_node[top] as usize, stack_d2[top]);
            if best.len == K && bd >= best.d2[K - 1] {
                continue;
            }
            let node = &self.nodes[n];
            if node.len > 0 {
                let (s, e) = (node.first as usize, (node.first + node.len) as usize);
                for (p, &i) in self.points[s..e].iter().zip(&self.index[s..e]) {
                    let (a, b, c) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
                    let d2 = a * a + b * b + c * c;
                    if best.len < K {
                        best.len += 1;
                    } else if d2 >= best.d2[K - 1] {
                        continue;
                    }
                    // Insert, keeping d2 increasing.
                    let mut j = best.len - 1;
                    while j > 0 && best.d2[j - 1] > d2 {
                        best.d2[j] = best.d2[j - 1];
                        best.index[j] = best.index[j - 1];
                        j -= 1;
                    }
                    best.d2[j] = d2;
                    best.index[j] = i;
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
                if best.len < K || far_d2 < best.d2[K - 1] {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against a brute-force scan: the same sorted distances (ties may pick other samples at
    /// the same distance), on random points and on a grid full of ties.
    #[test]
    fn nearest_matches_a_scan() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let random: Vec<[f64; 3]> = (0..700)
            .map(|_| [uniform(), uniform(), uniform()])
            .collect();
        let grid: Vec<[f64; 3]> = (0..512)
            .map(|i| {
                [
                    (i % 8) as f64 / 7.0,
                    (i / 8 % 8) as f64 / 7.0,
                    (i / 64) as f64 / 7.0,
                ]
            })
            .collect();
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
}
