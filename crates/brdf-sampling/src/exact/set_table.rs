//! One table of `A(θo)` for the whole set, from which the intervals take their normaliser
//! nodes (issue 27 item 4; Cornell data).
//!
//! The Cornell interpolant has kinks everywhere in `ωi`, and a node good to ~3·10⁻⁵ costs
//! ~1.5·10⁵ evaluations ([`tabulated::table_normaliser`]). Its trees need narrow intervals
//! (0.47° from ~20° up: their bounds must follow the lobe), but `A(θo)` itself is smooth on a
//! scale of degrees: integrating 9 nodes per interval (~1 250 per build) paid for that width
//! twice. Here `A` is tabulated once per build on **pieces** of θo, 9 Chebyshev–Lobatto nodes
//! each; a piece is halved while the 9-node interpolant differs from the nested 5-node one by
//! more than [`PIECE_TOL`] (relative) anywhere between the nodes, down to [`MIN_PIECE_DEG`].
//! A piece that misses by at most [`NEST_MAX_EXCESS`] × the tolerance is first refined in
//! place to the 17 Lobatto nodes that contain its 9 ([`NESTED_NODES`]: 8 new nodes instead
//! of a halving's 2 × 9, the 9 kept) and kept if its 17- and 9-node interpolants differ by at
//! most the tolerance, else halved (docs/benchmarks.md §26.4). An interval's normaliser node
//! is the table's value at the node, with the table's error: the node's own estimate plus the
//! piece's 9-versus-5 (or 17-versus-9) difference (both
//! conservative). The values depend on `θo` alone (not on the interval or thread).

use std::collections::HashMap;

use brdf::Brdf;
use rayon::prelude::*;

use super::chebyshev::{ChebyshevTable, lobatto_nodes};
use super::tabulated;

/// Nodes per piece (Lobatto; its even-numbered nodes are the 5-node rule's).
const PIECE_NODES: usize = 9;

/// Nodes of a piece refined in place (Lobatto; its even-numbered nodes are the 9 of
/// [`PIECE_NODES`], bit for bit: `cos(π·2k/16)` is `cos(π·k/8)`): a piece whose 9-versus-5
/// test asks for one halving is first refined to these, and kept if its 17- and 9-node
/// interpolants differ by at most the tolerance (the same test one level up).
const NESTED_NODES: usize = 17;

/// A piece is refined in place ([`NESTED_NODES`]) only when its 9-versus-5 difference is at
/// most this many times the tolerance (one halving would do up to 32). Nodes of the three
/// shared Cornell files' tables (`set_table_nesting_survey`, docs/benchmarks.md §26.4):
/// 1 977 without, 1 873 / 1 745 / 1 657 with this at 32 / 8 / 4: a refinement that fails
/// costs 8 nodes on top of the halving, and the larger misses fail more often.
const NEST_MAX_EXCESS: f64 = 4.0;

/// Largest relative difference between a piece's 9- and 5-node interpolants (between the
/// nodes) that stops its halving, unless its nodes' error estimate is larger.
pub(crate) const PIECE_TOL: f64 = 2e-5;

/// Narrowest piece (degrees).
pub(crate) const MIN_PIECE_DEG: f64 = 0.45;

/// Points per piece where the two interpolants are compared.
const CHECKS: usize = 32;

/// Into how many equal parts a piece is cut when its 9-versus-5 difference is `excess` times
/// the tolerance and it is `room` times the narrowest piece wide (`room ≥ 2`): `2^m` with `m`
/// the halvings a 5-node interpolation error (`∝ width⁵`) needs to get below the tolerance,
/// at least 1 and no narrower than the narrowest piece. Halving one level at a time integrated
/// every level's nodes on the way down (the pieces go down ~4 levels over most of 20–90° on
/// the shared Cornell files); a part that still misses the tolerance is cut again, so the
/// acceptance test and its guarantee are those of single halvings.
fn split_count(excess: f64, room: f64) -> usize {
    let wanted = if excess.is_finite() && excess > 1.0 {
        (excess.log2() / 5.0).ceil().max(1.0)
    } else {
        1.0
    };
    // Halvings that keep a part at least the narrowest piece wide (room ≥ 2: at least one).
    let allowed = room.log2().floor().max(1.0);
    1 << (wanted.min(allowed).min(16.0) as u32)
}

/// How far above the final test's thresholds a piece's coarse 9-versus-5 difference, less its
/// possible change, must be for the piece to be cut on coarse values ([`early_split`]).
const EARLY_MARGIN: f64 = 2.0;

/// The nodes of a table, integrated in two stages (issue 29, docs/benchmarks.md §29.3): a
/// coarse stage first, for every node a round asks for, then the final stage only for the
/// nodes of pieces that may be accepted. The final value must not depend on whether or when
/// the coarse stage was run (a resumed rule, or one run to the full budget).
pub(crate) trait TableNodes: Sync {
    /// The state kept between the stages.
    type Run: Send;
    /// Whether the coarse values differ from the final ones (`false`: the coarse stage is
    /// final, and no piece is cut on it).
    const EARLY: bool;
    /// `(A, relative error estimate)` at `θo` at the coarse stage (`None`: not finite) and
    /// the state to finish from.
    fn coarse(&self, theta: f64) -> (Option<(f64, f64)>, Self::Run);
    /// The final `(A, relative error estimate)` at `θo` from its coarse state.
    fn finish(&self, theta: f64, run: Self::Run) -> Option<(f64, f64)>;
}

/// A node at the coarse stage: its value (`None`: not finite) and the run to finish.
type Coarse<R> = (Option<(f64, f64)>, R);

/// Nodes of one stage: the coarse value is the final one.
struct OneStage<'a>(&'a (dyn Fn(f64) -> Option<(f64, f64)> + Sync));

impl TableNodes for OneStage<'_> {
    type Run = Option<(f64, f64)>;
    const EARLY: bool = false;
    fn coarse(&self, theta: f64) -> (Option<(f64, f64)>, Self::Run) {
        let v = (self.0)(theta);
        (v, v)
    }
    fn finish(&self, _theta: f64, run: Self::Run) -> Option<(f64, f64)> {
        run
    }
}

/// Nodes a table build integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct NodeCounts {
    /// Nodes integrated to the final stage (the full budget).
    pub(crate) finished: usize,
    /// Nodes left at the coarse stage (their pieces were cut on coarse values).
    pub(crate) coarse_only: usize,
}

/// `max_t Σ_i |ℓ⁹_i(t) − ℓ⁵_i(t)|` over the test points of a piece (`ℓ⁹`, `ℓ⁵`: the Lagrange
/// bases of the piece's 9 and nested 5 Lobatto nodes, `ℓ⁵_i = 0` at odd `i`): node values
/// that move by at most `δ` move the 9-versus-5 difference by at most this times `δ`.
fn difference_spread() -> f64 {
    let nodes = lobatto_nodes(0.0, 1.0, PIECE_NODES);
    let even: Vec<f64> = nodes.iter().step_by(2).copied().collect();
    (0..CHECKS)
        .map(|k| {
            let t = (k as f64 + 0.5) / CHECKS as f64;
            (0..PIECE_NODES)
                .map(|i| {
                    let unit: Vec<f64> = (0..PIECE_NODES)
                        .map(|j| f64::from(u8::from(i == j)))
                        .collect();
                    let five: Vec<f64> = unit.iter().step_by(2).copied().collect();
                    (interpolate(&nodes, &unit, t) - interpolate(&even, &five, t)).abs()
                })
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// Into how many parts a 9-node piece with nodes `ts` and values `got` (some coarse;
/// `(A, relative error estimate)`) is cut without finishing its nodes, or `None` (finish
/// them; the final test decides). With `e` the largest relative estimate among the nodes,
/// `d` the 9-versus-5 difference of the given values and `s` the [`difference_spread`], the
/// final values are taken within `2e` of these (each node's coarse estimate, plus a final one
/// no larger), so the final difference is at least `d_lo = d − 2 s e · max|A_i| / min|A|`,
/// and the final tolerance `max(PIECE_TOL, e_final)` at most `t_hi = max(PIECE_TOL, e)`.
/// The piece is cut when `d_lo > EARLY_MARGIN · m · t_hi` (`m` the nesting threshold, 1
/// without nesting): the final test would neither accept nor refine it in place; into
/// [`split_count`]`(d_lo / t_hi, room)` parts (at most as many as the final test would
/// choose; a part that still misses is cut again).
fn early_split(
    ts: &[f64],
    got: &[(f64, f64)],
    spread: f64,
    nested: Option<f64>,
    room: f64,
) -> Option<usize> {
    if room < 2.0 {
        return None;
    }
    let values: Vec<f64> = got.iter().map(|v| v.0).collect();
    let e = got.iter().map(|v| v.1).fold(0.0, f64::max);
    if !(e.is_finite() && values.iter().all(|v| v.is_finite())) {
        return None;
    }
    let (a, b) = (ts[0], ts[ts.len() - 1]);
    let even: Vec<f64> = ts.iter().step_by(2).copied().collect();
    let five: Vec<f64> = values.iter().step_by(2).copied().collect();
    let fine = ChebyshevTable::new(ts.to_vec(), vec![0.0], values.clone());
    let coarse = ChebyshevTable::new(even, vec![0.0], five);
    let (mut diff, mut f_min) = (0.0f64, f64::INFINITY);
    for k in 0..CHECKS {
        let t = a + (b - a) * (k as f64 + 0.5) / CHECKS as f64;
        let f = fine.eval(t, 0.0);
        diff = diff.max((f - coarse.eval(t, 0.0)).abs() / f.abs());
        f_min = f_min.min(f.abs());
    }
    let v_max = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d_lo = diff - 2.0 * spread * e * v_max / f_min;
    let t_hi = PIECE_TOL.max(e);
    (d_lo > EARLY_MARGIN * nested.unwrap_or(1.0) * t_hi).then(|| split_count(d_lo / t_hi, room))
}

/// The polynomial through `values` at the Lobatto `nodes`, at `t` (the tables' own evaluation).
fn interpolate(nodes: &[f64], values: &[f64], t: f64) -> f64 {
    ChebyshevTable::new(nodes.to_vec(), vec![0.0], values.to_vec()).eval(t, 0.0)
}

/// `[a, b]` cut into `parts` equal pieces of [`PIECE_NODES`] nodes, pushed to `next`.
fn push_parts(next: &mut Vec<(f64, f64, usize, f64)>, a: f64, b: f64, parts: usize) {
    let step = (b - a) / parts as f64;
    for k in 0..parts {
        let lo = if k == 0 { a } else { a + step * k as f64 };
        let hi = if k + 1 == parts {
            b
        } else {
            a + step * (k + 1) as f64
        };
        next.push((lo, hi, PIECE_NODES, 0.0));
    }
}

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
        Self::build_with(brdf, lo, top, breaks, Some(NEST_MAX_EXCESS)).map(|(t, _)| t)
    }

    /// [`SetTable::build`] with the nested refinement ([`NESTED_NODES`]) up to the given
    /// excess (`None`: none), and the nodes integrated.
    pub(crate) fn build_with(
        brdf: &dyn Brdf,
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
    ) -> Option<(Self, NodeCounts)> {
        if !tabulated::table_normaliser_exists(brdf) {
            return None;
        }
        if let Some(nodes) = tabulated::ProgressiveCornellNodes::new(brdf) {
            return Some(Self::build_progressive(&nodes, lo, top, breaks, nested));
        }
        let value = |t: f64| tabulated::table_normaliser(brdf, t);
        let (table, n) = Self::build_from(&value, lo, top, breaks, nested);
        Some((
            table,
            NodeCounts {
                finished: n,
                coarse_only: 0,
            },
        ))
    }

    /// The table of the nodes `value(θo) = Some((A, relative error estimate))` (`None`: not
    /// finite) over `[lo, top]`, cut first at `breaks`; and the number of nodes integrated.
    /// Every node is integrated in one stage (no early decisions).
    pub(crate) fn build_from(
        value: &(dyn Fn(f64) -> Option<(f64, f64)> + Sync),
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
    ) -> (Self, usize) {
        let (table, counts) = Self::build_progressive(&OneStage(value), lo, top, breaks, nested);
        (table, counts.finished)
    }

    /// The table of `nodes` over `[lo, top]`, cut first at `breaks` (see the module docs and
    /// [`TableNodes`]), and the nodes integrated.
    ///
    /// Each round integrates the new nodes of its pieces to the coarse stage first. A piece of
    /// 9 nodes some of which are coarse is halved (cut) at once, its coarse nodes left
    /// unfinished, when its 9-versus-5 difference is far above what the final test could
    /// accept ([`early_split`]); every other piece has its nodes finished, and is decided by
    /// the one-stage test on finished values only. So every accepted piece, its table and its
    /// declared error are what that test gives at the full budget; only which pieces are
    /// tried changes (a piece cut early is one the final test would have cut, unless the
    /// coarse estimates are short by a factor of more than [`EARLY_MARGIN`]: then the table is
    /// finer than needed, never less accurate).
    pub(crate) fn build_progressive<N: TableNodes>(
        nodes: &N,
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
    ) -> (Self, NodeCounts) {
        let mut edges = vec![lo];
        edges.extend(breaks.iter().copied().filter(|&b| b > lo && b < top));
        edges.push(top);
        // `(a, b, nodes, excess)`: a piece and its node count; `excess` is its 9-node test's
        // difference over the tolerance when it is refined to `NESTED_NODES` (else 0).
        let mut todo: Vec<(f64, f64, usize, f64)> = edges
            .windows(2)
            .map(|w| (w[0], w[1], PIECE_NODES, 0.0))
            .collect();
        let mut known: HashMap<u64, (f64, f64)> = HashMap::new();
        // Nodes at the coarse stage: the value (`None`: not finite) and the run to finish.
        let mut coarse: HashMap<u64, Coarse<N::Run>> = HashMap::new();
        let mut pieces = Vec::new();
        let min_width = MIN_PIECE_DEG.to_radians();
        let spread = difference_spread();
        let not_finite = (f64::NAN, f64::INFINITY);
        while !todo.is_empty() {
            // Every new node of this round to the coarse stage at once (in parallel; each
            // depends on θo alone).
            let mut wanted: Vec<f64> = todo
                .iter()
                .flat_map(|&(a, b, n, _)| lobatto_nodes(a, b, n))
                .filter(|t| !known.contains_key(&t.to_bits()) && !coarse.contains_key(&t.to_bits()))
                .collect();
            wanted.sort_by(f64::total_cmp);
            wanted.dedup_by(|a, b| a.to_bits() == b.to_bits());
            let started: Vec<(f64, Coarse<N::Run>)> =
                wanted.par_iter().map(|&t| (t, nodes.coarse(t))).collect();
            coarse.extend(started.into_iter().map(|(t, c)| (t.to_bits(), c)));
            // Pieces cut on coarse values; the others wait for their nodes to be finished.
            let mut next = Vec::new();
            let mut ready = Vec::new();
            let mut finish: Vec<f64> = Vec::new();
            for (a, b, n, excess_before) in todo {
                let ts = lobatto_nodes(a, b, n);
                let unfinished: Vec<f64> = ts
                    .iter()
                    .copied()
                    .filter(|t| !known.contains_key(&t.to_bits()))
                    .collect();
                if !unfinished.is_empty() && N::EARLY && n == PIECE_NODES {
                    let got: Option<Vec<(f64, f64)>> = ts
                        .iter()
                        .map(|t| {
                            known
                                .get(&t.to_bits())
                                .copied()
                                .or_else(|| coarse[&t.to_bits()].0)
                        })
                        .collect();
                    #[cfg(test)]
                    if let (Ok(_), Some(g)) = (std::env::var("SET_TABLE_TRACE"), &got) {
                        {
                            let e = g.iter().map(|v| v.1).fold(0.0, f64::max);
                            let es: Vec<String> =
                                g.iter().map(|v| format!("{:.1e}", v.1)).collect();
                            eprintln!(
                                "TRACE coarse {:.4}-{:.4}°: early {:?} e_c {e:.3e} [{}]",
                                a.to_degrees(),
                                b.to_degrees(),
                                early_split(&ts, g, spread, nested, (b - a) / min_width),
                                es.join(" ")
                            );
                        }
                    }
                    if let Some(parts) = got
                        .and_then(|got| early_split(&ts, &got, spread, nested, (b - a) / min_width))
                    {
                        push_parts(&mut next, a, b, parts);
                        continue;
                    }
                }
                finish.extend(unfinished);
                ready.push((a, b, n, excess_before));
            }
            finish.sort_by(f64::total_cmp);
            finish.dedup_by(|a, b| a.to_bits() == b.to_bits());
            let runs: Vec<(f64, N::Run)> = finish
                .iter()
                .map(|t| (*t, coarse.remove(&t.to_bits()).expect("a coarse node").1))
                .collect();
            let done: Vec<(f64, (f64, f64))> = runs
                .into_par_iter()
                .map(|(t, run)| (t, nodes.finish(t, run).unwrap_or(not_finite)))
                .collect();
            known.extend(done.into_iter().map(|(t, v)| (t.to_bits(), v)));
            for (a, b, n, excess_before) in ready {
                let nodes = lobatto_nodes(a, b, n);
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
                let tol = PIECE_TOL.max(node_err);
                let room = (b - a) / min_width;
                #[cfg(test)]
                if std::env::var("SET_TABLE_TRACE").is_ok() {
                    eprintln!(
                        "TRACE piece {:.4}-{:.4}° n {n}: diff {diff:.3e} node_err {node_err:.3e} excess {:.2}",
                        a.to_degrees(),
                        b.to_degrees(),
                        diff / tol
                    );
                }
                if !(diff <= tol) && 0.5 * (b - a) >= min_width {
                    if nested.is_some_and(|m| diff <= m * tol)
                        && n == PIECE_NODES
                        && split_count(diff / tol, room) == 2
                    {
                        // A halving would integrate 2 × 9 fresh nodes and drop these 9; the
                        // 17 nodes that nest them cost 8.
                        next.push((a, b, NESTED_NODES, diff / tol));
                        continue;
                    }
                    let excess = if n == PIECE_NODES {
                        diff / tol
                    } else {
                        excess_before
                    };
                    push_parts(&mut next, a, b, split_count(excess, room));
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
        let counts = NodeCounts {
            finished: known.len(),
            coarse_only: coarse.len(),
        };
        (Self { pieces }, counts)
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

    /// The distinct nodes the pieces' tables use.
    #[cfg(test)]
    pub(crate) fn used_nodes(&self) -> usize {
        let mut bits: Vec<u64> = self
            .pieces
            .iter()
            .flat_map(|p| p.table.theta.iter().map(|t| t.to_bits()))
            .collect();
        bits.sort_unstable();
        bits.dedup();
        bits.len()
    }

    /// The pieces' edges (radians).
    #[cfg(test)]
    pub(crate) fn edges(&self) -> Vec<f64> {
        let mut e: Vec<f64> = self.pieces.iter().map(|p| p.lo).collect();
        e.extend(self.pieces.last().map(|p| p.hi));
        e
    }
}

#[cfg(test)]
mod tests {
    use super::{NESTED_NODES, PIECE_NODES, SetTable, lobatto_nodes, split_count};

    /// The refined piece's even-numbered nodes are the 9 nodes of the piece, bit for bit, so
    /// the table's node map (keyed by the bits of `θo`) hands their values over.
    #[test]
    fn nested_nodes_contain_the_piece_nodes_bit_for_bit() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let a = 1.5 * next();
            let b = a + (1.5 - a) * next() + 1e-9;
            let coarse = lobatto_nodes(a, b, PIECE_NODES);
            let fine = lobatto_nodes(a, b, NESTED_NODES);
            let even: Vec<u64> = fine.iter().step_by(2).map(|t| t.to_bits()).collect();
            let bits: Vec<u64> = coarse.iter().map(|t| t.to_bits()).collect();
            assert_eq!(even, bits, "[{a}, {b}]");
        }
    }

    /// A table of a function with a weak singularity (`|t − 0.77|^3.5`, so that interpolants
    /// converge slowly; exact node values, declared error 10⁻¹³): with
    /// and without the nested refinement, the table is within its declared error of the
    /// function at 3 000 points, and the nested one integrates fewer nodes.
    #[test]
    fn nested_refinement_keeps_its_declared_error_with_fewer_nodes() {
        let g = |t: f64| 1.0 + 0.5 * (t - 0.77).abs().powf(3.5) + 0.3 * t.sin();
        let value = |t: f64| Some((g(t), 1e-13));
        let (lo, top) = (0.0, 1.5);
        let mut counts = Vec::new();
        for nested in [false, true] {
            let (table, nodes) = SetTable::build_from(
                &value,
                lo,
                top,
                &[0.5, 1.0],
                nested.then_some(super::NEST_MAX_EXCESS),
            );
            for k in 0..3000 {
                let t = lo + (top - lo) * (k as f64 + 0.5) / 3000.0;
                let (a, declared) = table.at(t);
                let gap = (a / g(t) - 1.0).abs();
                assert!(
                    gap <= declared,
                    "nested {nested}, θ {t}: gap {gap:e} above the declared {declared:e}"
                );
            }
            eprintln!(
                "nested {nested}: {nodes} nodes, {} pieces",
                table.edges().len() - 1
            );
            counts.push(nodes);
        }
        assert!(counts[1] < counts[0], "nodes {counts:?}");
    }

    /// The Cornell set table built in two stages (coarse nodes, then finished ones:
    /// [`SetTable::build_progressive`]) against the one-stage build (every node at the full
    /// budget), for the record (docs/benchmarks.md §29.3): nodes finished and left coarse,
    /// pieces, whether the pieces' edges are the same, the largest `|A₂/A₁ − 1|` at 601 angles
    /// and the worst declared error. `CORNELL_FILES` (default the three shared files),
    /// `COARSE_BUDGETS` (default 50000), `ONE_STAGE=0` skips the one-stage build.
    /// `cargo test --release -p brdf-sampling --lib set_table_progressive_survey -- --ignored --nocapture`
    #[test]
    #[ignore = "a survey for the record (minutes)"]
    fn set_table_progressive_survey() {
        use crate::exact::tabulated::{ProgressiveCornellNodes, table_normaliser};
        let files = std::env::var("CORNELL_FILES")
            .unwrap_or_else(|_| "krylon_blue,cayman,acryl_blue".into());
        let budgets: Vec<u64> = std::env::var("COARSE_BUDGETS")
            .unwrap_or_else(|_| "50000".into())
            .split(',')
            .filter_map(|s| s.parse().ok())
            .collect();
        let one_stage = std::env::var("ONE_STAGE").map_or(true, |v| v != "0");
        for name in files.split(',') {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("../../../shared/data/measured/cornell/{name}.brdf"));
            let Ok(b) = brdf::CornellBrdf::load(&path) else {
                eprintln!("skipped {name}");
                continue;
            };
            let b = b.with_interpolation(brdf::measured::cornell::Interpolation::Knn);
            let options = crate::ExactOptions::default();
            let plan = crate::exact::build::Plan::new(&b, &options, None, true);
            let breaks: Vec<f64> = (1..plan.n0)
                .map(|i| plan.grid.edge(i << crate::exact::grid::EDGE_BITS))
                .collect();
            let top = crate::exact::options::THETA_TOP_DEG.to_radians();
            let nest = Some(super::NEST_MAX_EXCESS);
            let worst = |t: &SetTable| {
                let e = t.edges();
                (0..e.len() - 1)
                    .map(|i| t.at(0.5 * (e[i] + e[i + 1])).1)
                    .fold(0.0, f64::max)
            };
            let reference = one_stage.then(|| {
                let start = std::time::Instant::now();
                let value = |t: f64| table_normaliser(&b, t);
                let (t, n) = SetTable::build_from(&value, 0.0, top, &breaks, nest);
                eprintln!(
                    "{name} one stage: {n} nodes ({} used), {} pieces, worst declared {:.3e}, {:.1} s",
                    t.used_nodes(),
                    t.edges().len() - 1,
                    worst(&t),
                    start.elapsed().as_secs_f64()
                );
                t
            });
            for &budget in &budgets {
                let start = std::time::Instant::now();
                let nodes = ProgressiveCornellNodes::new(&b)
                    .unwrap()
                    .with_coarse_budget(budget);
                let (t, counts) = SetTable::build_progressive(&nodes, 0.0, top, &breaks, nest);
                let full_price = counts.finished as f64
                    + counts.coarse_only as f64 * budget as f64
                        / crate::exact::tabulated::CORNELL_NODE_BUDGET as f64;
                let mut line = format!(
                    "{name} coarse {budget}: {counts:?} (≈ {full_price:.0} full-price, {} used), {} pieces, worst declared {:.3e}, {:.1} s",
                    t.used_nodes(),
                    t.edges().len() - 1,
                    worst(&t),
                    start.elapsed().as_secs_f64()
                );
                if let Some(r) = &reference {
                    let same = r.edges() == t.edges();
                    let mut gap = 0.0f64;
                    for k in 0..=600 {
                        let th = top * k as f64 / 600.0;
                        gap = gap.max((t.at(th).0 / r.at(th).0 - 1.0).abs());
                    }
                    line += &format!("; same edges {same}, max |A₂/A₁ − 1| {gap:.2e}");
                }
                eprintln!("{line}");
            }
        }
    }

    /// A piece is cut into a power of two of parts, at least 2, never narrower than the
    /// narrowest piece, and into more parts the further its difference is above the tolerance
    /// (5 halvings per factor 32: a 5-node error ∝ width⁵).
    #[test]
    fn split_counts() {
        assert_eq!(split_count(1.5, 100.0), 2);
        assert_eq!(split_count(32.0, 100.0), 2);
        assert_eq!(split_count(33.0, 100.0), 4);
        assert_eq!(split_count(1e6, 100.0), 16);
        assert_eq!(split_count(1e6, 5.0), 4);
        assert_eq!(split_count(1e6, 2.0), 2);
        assert_eq!(split_count(f64::NAN, 100.0), 2);
        assert_eq!(split_count(f64::INFINITY, 100.0), 2);
        for excess in [1.01, 7.0, 1e3, 1e9, 1e300] {
            for room in [2.0, 3.9, 4.0, 17.0, 1e4] {
                let n = split_count(excess, room);
                assert!(n.is_power_of_two() && n >= 2, "{excess} {room}: {n}");
                assert!(n as f64 <= room, "{excess} {room}: {n}");
            }
        }
    }
}
