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
//! conservative). The values depend on `θo` alone (not on the interval or thread). The first
//! pieces are the spans between the build's breaks cut to at most [`FIRST_PIECE_MAX_DEG`]
//! (§29.3: the wider first pieces were all halved, their nodes dropped).

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

/// Widest first piece (degrees): a span between two `breaks` wider than this is cut into
/// `2^k` equal first pieces, the fewest that are at most this wide (issue 29,
/// docs/benchmarks.md §29.3). The pieces of the shared Cornell files' tables end at most
/// 7.5° wide (`krylon_blue`, `cayman`: a 7.5° limit leaves their tables unchanged; the
/// tolerance there is mostly the nodes' own error), so the 15° spans between the build's
/// breaks failed the 9-versus-5 test once or twice on the way down, and their nodes were
/// integrated at the full budget and dropped. Nodes integrated
/// (`set_table_first_piece_survey`): 389 / 497 / 771 with no limit, 369 / 461 / 751 at 7.5°,
/// **333 / 433 / 735 at 5°**, 343 / 409 / 693 at 3.75° (`krylon_blue`'s worst declared
/// error then rises from 3.55 to 4.09·10⁻⁴); at 5° the worst declared error of each table is
/// unchanged.
const FIRST_PIECE_MAX_DEG: f64 = 5.0;

/// Into how many equal first pieces a span of `width` is cut: the least power of two whose
/// parts are at most `max` wide (1 for a non-finite or non-positive `max`; at most 2¹⁶).
fn first_parts(width: f64, max: f64) -> usize {
    let mut parts = 1usize;
    while max > 0.0 && width / parts as f64 > max && parts < 1 << 16 {
        parts *= 2;
    }
    parts
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
    /// excess (`None`: none), and the number of nodes integrated.
    pub(crate) fn build_with(
        brdf: &dyn Brdf,
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
    ) -> Option<(Self, usize)> {
        if !tabulated::table_normaliser_exists(brdf) {
            return None;
        }
        let value = |t: f64| tabulated::table_normaliser(brdf, t);
        Some(Self::build_from(&value, lo, top, breaks, nested))
    }

    /// The table of the nodes `value(θo) = Some((A, relative error estimate))` (`None`: not
    /// finite) over `[lo, top]`, cut first at `breaks`; and the number of nodes integrated.
    pub(crate) fn build_from(
        value: &(dyn Fn(f64) -> Option<(f64, f64)> + Sync),
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
    ) -> (Self, usize) {
        Self::build_tuned(
            value,
            lo,
            top,
            breaks,
            nested,
            FIRST_PIECE_MAX_DEG.to_radians(),
        )
    }

    /// [`SetTable::build_from`] with the first pieces at most `first_max` wide (radians; the
    /// build's is [`FIRST_PIECE_MAX_DEG`]).
    pub(crate) fn build_tuned(
        value: &(dyn Fn(f64) -> Option<(f64, f64)> + Sync),
        lo: f64,
        top: f64,
        breaks: &[f64],
        nested: Option<f64>,
        first_max: f64,
    ) -> (Self, usize) {
        let mut edges = vec![lo];
        edges.extend(breaks.iter().copied().filter(|&b| b > lo && b < top));
        edges.push(top);
        // `(a, b, nodes, excess)`: a piece and its node count; `excess` is its 9-node test's
        // difference over the tolerance when it is refined to `NESTED_NODES` (else 0).
        let mut todo: Vec<(f64, f64, usize, f64)> = Vec::new();
        for w in edges.windows(2) {
            push_parts(&mut todo, w[0], w[1], first_parts(w[1] - w[0], first_max));
        }
        let mut known: HashMap<u64, (f64, f64)> = HashMap::new();
        let mut pieces = Vec::new();
        let min_width = MIN_PIECE_DEG.to_radians();
        while !todo.is_empty() {
            // Every node of this round at once (in parallel; each depends on θo alone).
            let mut wanted: Vec<f64> = todo
                .iter()
                .flat_map(|&(a, b, n, _)| lobatto_nodes(a, b, n))
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
            for (a, b, n, excess_before) in todo {
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
        (Self { pieces }, known.len())
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
    use super::{NESTED_NODES, PIECE_NODES, SetTable, first_parts, lobatto_nodes, split_count};

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
            // First pieces as wide as the breaks allow (the build's 5° limit would cut this
            // 1.5-radian range into pieces that need no nesting).
            let (table, nodes) = SetTable::build_tuned(
                &value,
                lo,
                top,
                &[0.5, 1.0],
                nested.then_some(super::NEST_MAX_EXCESS),
                f64::INFINITY,
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

    /// The Cornell set table with its first pieces at most `FIRST_MAX_DEG` wide (a list,
    /// `inf`: as cut by the build's breaks only), for the record (docs/benchmarks.md §29.3):
    /// nodes integrated and used by the final pieces, pieces, the worst declared error, and
    /// each table against the first of the list at 601 angles (`|A/A₀ − 1|`, and its largest
    /// share of the two declared errors). Node values are cached across the variants (they
    /// depend on θo alone). `CORNELL_FILES` (default the three shared files);
    /// `cargo test --release -p brdf-sampling --lib set_table_first_piece_survey -- --ignored --nocapture`
    #[test]
    #[ignore = "a survey for the record (minutes)"]
    fn set_table_first_piece_survey() {
        use crate::exact::tabulated::table_normaliser;
        use std::collections::HashMap;
        use std::sync::Mutex;
        let widths: Vec<f64> = std::env::var("FIRST_MAX_DEG")
            .unwrap_or_else(|_| "inf,7.5,3.75".into())
            .split(',')
            .filter_map(|s| s.parse().ok())
            .collect();
        for (name, b, breaks, top) in crate::exact::tests::cornell_survey_inputs() {
            let cache: Mutex<HashMap<u64, Option<(f64, f64)>>> = Mutex::new(HashMap::new());
            let value = |t: f64| {
                if let Some(v) = cache.lock().unwrap().get(&t.to_bits()) {
                    return *v;
                }
                let v = table_normaliser(&b, t);
                cache.lock().unwrap().insert(t.to_bits(), v);
                v
            };
            let mut first: Option<SetTable> = None;
            for &w in &widths {
                let (t, n) = SetTable::build_tuned(
                    &value,
                    0.0,
                    top,
                    &breaks,
                    Some(super::NEST_MAX_EXCESS),
                    w.to_radians(),
                );
                let e = t.edges();
                let worst = (0..e.len() - 1)
                    .map(|i| t.at(0.5 * (e[i] + e[i + 1])).1)
                    .fold(0.0, f64::max);
                let mut line = format!(
                    "{name} first pieces ≤ {w}°: {n} nodes ({} used), {} pieces, worst declared {worst:.3e}",
                    t.used_nodes(),
                    e.len() - 1
                );
                if let Some(r) = &first {
                    let (mut gap, mut share) = (0.0f64, 0.0f64);
                    for k in 0..=600 {
                        let th = top * k as f64 / 600.0;
                        let ((a1, e1), (a0, e0)) = (t.at(th), r.at(th));
                        let g = (a1 / a0 - 1.0).abs();
                        gap = gap.max(g);
                        share = share.max(g / (e0 + e1));
                    }
                    line += &format!(
                        "; max |A/A₀ − 1| {gap:.2e}, at most {share:.2} of the declared sum"
                    );
                }
                eprintln!("{line}");
                if first.is_none() {
                    first = Some(t);
                }
            }
        }
    }

    /// The first pieces are the spans between the breaks cut into the least power of two of
    /// equal parts at most `first_max` wide (issue 29, docs/benchmarks.md §29.3): a table of a
    /// smooth function (`1 + 0.3 sin t`, exact nodes declared at 10⁻¹³), whose pieces the
    /// 9-versus-5 test accepts at the breaks' width (0.5), has every piece at most 0.2 wide
    /// with `first_max` = 0.2 (4 parts of 0.125 per span; 0.25 would be the next power of two
    /// down, too wide) and stays within its declared error at 3 000 points. Fails when
    /// `first_parts` stops one halving short (pieces 0.25 wide: checked, docs §29.3).
    #[test]
    fn first_pieces_are_at_most_the_widest_first_piece() {
        assert_eq!(first_parts(0.5, 0.2), 4);
        assert_eq!(first_parts(0.5, 0.25), 2);
        assert_eq!(first_parts(0.5, f64::INFINITY), 1);
        assert_eq!(first_parts(0.5, 0.0), 1);
        assert_eq!(first_parts(0.5, f64::NAN), 1);
        for (w, m) in [(0.26f64, 0.1f64), (1.0, 0.3), (15.0, 5.0), (14.99, 3.75)] {
            let n = first_parts(w, m);
            assert!(n.is_power_of_two() && w / n as f64 <= m, "{w} {m}: {n}");
            assert!(
                n == 1 || w / (n / 2) as f64 > m,
                "{w} {m}: {n} is not the least"
            );
        }
        let g = |t: f64| 1.0 + 0.3 * t.sin();
        let value = |t: f64| Some((g(t), 1e-13));
        let (lo, top) = (0.0, 1.5);
        for (first_max, widest) in [(f64::INFINITY, 0.5), (0.2, 0.125)] {
            let (table, nodes) = SetTable::build_tuned(
                &value,
                lo,
                top,
                &[0.5, 1.0],
                Some(super::NEST_MAX_EXCESS),
                first_max,
            );
            let edges = table.edges();
            let w = edges.windows(2).map(|e| e[1] - e[0]).fold(0.0, f64::max);
            eprintln!("first pieces ≤ {first_max}: {nodes} nodes, widest piece {w}");
            assert!(
                (w - widest).abs() <= 1e-12,
                "first_max {first_max}: widest {w}"
            );
            for k in 0..3000 {
                let t = lo + (top - lo) * (k as f64 + 0.5) / 3000.0;
                let (a, declared) = table.at(t);
                let gap = (a / g(t) - 1.0).abs();
                assert!(gap <= declared, "θ {t}: gap {gap:e} above {declared:e}");
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
