//! One table of `A(θo)` for the whole set, from which the intervals take their normaliser
//! nodes (issue 27 item 4; Cornell data).
//!
//! The Cornell interpolant has kinks everywhere in `ωi`, and a node good to ~3·10⁻⁵ costs
//! ~1.5·10⁵ evaluations ([`tabulated::table_normaliser`]). Its trees need narrow intervals
//! (0.47° from ~20° up: their bounds must follow the lobe), but `A(θo)` itself is smooth on a
//! scale of degrees: integrating 9 nodes per interval (~1 250 per build) paid for that width
//! twice. Here `A` is tabulated once per build on **pieces** of θo, 9 Chebyshev–Lobatto nodes
//! each; a piece is halved while the 9-node interpolant differs from the nested 5-node one by
//! more than [`PIECE_TOL`] (relative) anywhere between the nodes, down to
//! [`MIN_PIECE_DEG`]. An interval's normaliser node is the table's value at the node, with
//! the table's error: the node's own estimate plus the piece's 9-versus-5 difference (both
//! conservative). The values depend on `θo` alone (not on the interval or thread).

use std::collections::HashMap;

use brdf::Brdf;
use rayon::prelude::*;

use super::chebyshev::{ChebyshevTable, lobatto_nodes};
use super::tabulated;

/// Nodes per piece (Lobatto; its even-numbered nodes are the 5-node rule's).
const PIECE_NODES: usize = 9;

/// Largest relative difference between a piece's 9- and 5-node interpolants (between the
/// nodes) that stops its halving, unless its nodes' error estimate is larger.
pub(crate) const PIECE_TOL: f64 = 2e-5;

/// Narrowest piece (degrees).
pub(crate) const MIN_PIECE_DEG: f64 = 0.45;

/// Points per piece where the two interpolants are compared.
const CHECKS: usize = 32;

/// One piece `[lo, hi]` of θo (radians) and its 9-node table of `A` (over θo).
struct Piece {
    lo: f64,
    hi: f64,
    table: ChebyshevTable,
    /// The largest relative error estimate of its nodes, plus its 9-versus-5 difference.
    rel_err: f64,
}

/// `A(θo)` on pieces of `[0, top]`, see the module docs.
pub(crate) struct SetTable {
    pieces: Vec<Piece>,
}

impl SetTable {
    /// The table of `brdf` over `[lo, top]` (radians), the first pieces cut at `breaks`
    /// (increasing, inside `(lo, top)`); `None` unless [`tabulated::table_normaliser`] serves
    /// `brdf`.
    pub(crate) fn build(brdf: &dyn Brdf, lo: f64, top: f64, breaks: &[f64]) -> Option<Self> {
        let value = |t: f64| tabulated::table_normaliser(brdf, t);
        if !tabulated::table_normaliser_exists(brdf) {
            return None;
        }
        let mut edges = vec![lo];
        edges.extend(breaks.iter().copied().filter(|&b| b > lo && b < top));
        edges.push(top);
        let mut todo: Vec<(f64, f64)> = edges.windows(2).map(|w| (w[0], w[1])).collect();
        let mut known: HashMap<u64, (f64, f64)> = HashMap::new();
        let mut pieces = Vec::new();
        let min_width = MIN_PIECE_DEG.to_radians();
        while !todo.is_empty() {
            // Every node of this round at once (in parallel; each depends on θo alone).
            let mut wanted: Vec<f64> = todo
                .iter()
                .flat_map(|&(a, b)| lobatto_nodes(a, b, PIECE_NODES))
                .filter(|t| !known.contains_key(&t.to_bits()))
                .collect();
            wanted.sort_by(f64::total_cmp);
            wanted.dedup_by(|a, b| a.to_bits() == b.to_bits());
            let values: Vec<(f64, (f64, f64))> = wanted
                .par_iter()
                .map(|&t| (t, value(t).unwrap_or((f64::NAN, f64::INFINITY))))
                .collect();
            known.extend(values.into_iter().map(|(t, v)| (t.to_bits(), v)));
            let mut next = Vec::new();
            for (a, b) in todo {
                let nodes = lobatto_nodes(a, b, PIECE_NODES);
                let got: Vec<(f64, f64)> = nodes.iter().map(|t| known[&t.to_bits()]).collect();
                let values: Vec<f64> = got.iter().map(|v| v.0).collect();
                let node_err = got.iter().map(|v| v.1).fold(0.0, f64::max);
                let fine = ChebyshevTable::new(nodes.clone(), vec![0.0], values.clone());
                let coarse = ChebyshevTable::new(
                    nodes.iter().step_by(2).copied().collect(),
                    vec![0.0],
                    values.iter().step_by(2).copied().collect(),
                );
                let diff = (0..CHECKS)
                    .map(|k| {
                        let t = a + (b - a) * (k as f64 + 0.5) / CHECKS as f64;
                        let f = fine.eval(t, 0.0);
                        (f - coarse.eval(t, 0.0)).abs() / f.abs()
                    })
                    .fold(0.0, f64::max);
                // Below the nodes' own error the difference is their noise, not the
                // interpolant's: halving would not lower it (measured: every piece went down
                // to the narrowest with the tolerance alone).
                if !(diff <= PIECE_TOL.max(node_err)) && 0.5 * (b - a) >= min_width {
                    let m = 0.5 * (a + b);
                    next.push((a, m));
                    next.push((m, b));
                } else {
                    pieces.push(Piece {
                        lo: a,
                        hi: b,
                        table: fine,
                        rel_err: node_err + diff,
                    });
                }
            }
            todo = next;
        }
        pieces.sort_by(|p, q| p.lo.total_cmp(&q.lo));
        Some(Self { pieces })
    }

    /// `(A, relative error estimate)` at `theta` (radians; clamped to the table).
    pub(crate) fn at(&self, theta: f64) -> (f64, f64) {
        let i = self
            .pieces
            .partition_point(|p| p.hi < theta)
            .min(self.pieces.len() - 1);
        let p = &self.pieces[i];
        (p.table.eval(theta.clamp(p.lo, p.hi), 0.0), p.rel_err)
    }

    /// The pieces' edges (radians).
    #[cfg(test)]
    pub(crate) fn edges(&self) -> Vec<f64> {
        let mut e: Vec<f64> = self.pieces.iter().map(|p| p.lo).collect();
        e.extend(self.pieces.last().map(|p| p.hi));
        e
    }
}
