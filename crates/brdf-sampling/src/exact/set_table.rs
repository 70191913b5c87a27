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
//!
//! **Control variate over θo** (kNN Cornell materials, docs/benchmarks.md §25.5). The tabulated
//! interpolant's albedo `A_grid(θo)` ([`brdf::CornellBrdf::grid_albedo`]) is exact and costs
//! no evaluation; the table then holds `D(θo) = A(θo) − A_grid(θo)` at its nodes (the same
//! nodes, the same rule) and a query is `A_grid(θo) + D̂(θo)`. The pieces are halved while
//! `D`'s 9- and 5-node interpolants differ by more than the tolerance relative to `A`: the
//! structure the two interpolants share is no longer interpolated over θo, so fewer pieces
//! pass the test. The declared error is the nodes' plus `D`'s 9-versus-5 difference (relative
//! to `A`) plus the grid albedo's own estimate (≤ 10⁻¹³).

use std::collections::HashMap;

use brdf::measured::cornell::Interpolation;
use brdf::{Brdf, CornellBrdf};
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
    /// The control variate: the tables hold `A − A_grid` of this material (module docs).
    base: Option<CornellBrdf>,
    /// Distinct θo integrated.
    nodes: usize,
}

/// The control variate of `brdf` (module docs): its tabulated interpolant, for a Cornell
/// material interpolated by its k nearest samples.
fn control_variate(brdf: &dyn Brdf) -> Option<CornellBrdf> {
    brdf.as_any()
        .and_then(|a| a.downcast_ref::<CornellBrdf>())
        .filter(|c| c.interpolation() == Interpolation::Knn)
        .map(|c| c.with_interpolation(Interpolation::Grid))
}

/// `(A_grid(θo), its absolute error estimate)` of `base`, `(0, 0)` without one.
fn base_at(base: Option<&CornellBrdf>, theta: f64) -> (f64, f64) {
    base.and_then(|g| g.grid_albedo(theta))
        .unwrap_or((0.0, 0.0))
}

impl SetTable {
    /// The table of `brdf` over `[lo, top]` (radians), the first pieces cut at `breaks`
    /// (increasing, inside `(lo, top)`); `None` unless [`tabulated::table_normaliser`] serves
    /// `brdf`.
    pub(crate) fn build(brdf: &dyn Brdf, lo: f64, top: f64, breaks: &[f64]) -> Option<Self> {
        Self::build_with(brdf, lo, top, breaks, true)
    }

    /// [`SetTable::build`], with the control variate (module docs) where it applies when
    /// `use_base`, without it otherwise.
    pub(crate) fn build_with(
        brdf: &dyn Brdf,
        lo: f64,
        top: f64,
        breaks: &[f64],
        use_base: bool,
    ) -> Option<Self> {
        if !tabulated::table_normaliser_exists(brdf) {
            return None;
        }
        let base = if use_base {
            control_variate(brdf)
        } else {
            None
        };
        // (A, relative error, A_grid) at a node.
        let value = |t: f64| {
            let (a, rel) =
                tabulated::table_normaliser(brdf, t).unwrap_or((f64::NAN, f64::INFINITY));
            let (g, g_err) = base_at(base.as_ref(), t);
            let rel = if a > 0.0 { rel + g_err / a } else { rel };
            (a, rel, g)
        };
        let mut edges = vec![lo];
        edges.extend(breaks.iter().copied().filter(|&b| b > lo && b < top));
        edges.push(top);
        let mut todo: Vec<(f64, f64)> = edges.windows(2).map(|w| (w[0], w[1])).collect();
        let mut known: HashMap<u64, (f64, f64, f64)> = HashMap::new();
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
            let values: Vec<(f64, (f64, f64, f64))> =
                wanted.par_iter().map(|&t| (t, value(t))).collect();
            known.extend(values.into_iter().map(|(t, v)| (t.to_bits(), v)));
            let mut next = Vec::new();
            for (a, b) in todo {
                let nodes = lobatto_nodes(a, b, PIECE_NODES);
                let got: Vec<(f64, f64, f64)> = nodes.iter().map(|t| known[&t.to_bits()]).collect();
                // The tabulated quantity: A, or A − A_grid with the control variate.
                let values: Vec<f64> = got.iter().map(|v| v.0 - v.2).collect();
                let node_err = got.iter().map(|v| v.1).fold(0.0, f64::max);
                let fine = ChebyshevTable::new(nodes.clone(), vec![0.0], values.clone());
                let coarse = ChebyshevTable::new(
                    nodes.iter().step_by(2).copied().collect(),
                    vec![0.0],
                    values.iter().step_by(2).copied().collect(),
                );
                // A between the nodes (for the relative difference): the fine table plus
                // the control variate's 9-node interpolant.
                let base_fine = base.as_ref().map(|_| {
                    ChebyshevTable::new(nodes.clone(), vec![0.0], got.iter().map(|v| v.2).collect())
                });
                let diff = (0..CHECKS)
                    .map(|k| {
                        let t = a + (b - a) * (k as f64 + 0.5) / CHECKS as f64;
                        let f = fine.eval(t, 0.0);
                        let scale = match &base_fine {
                            Some(g) => f + g.eval(t, 0.0),
                            None => f,
                        };
                        (f - coarse.eval(t, 0.0)).abs() / scale.abs()
                    })
                    .fold(0.0, f64::max);
                // Below the nodes' own error the difference is their noise, not the
                // interpolant's: halving would not lower it (measured: every piece went down
                // to the narrowest with the tolerance alone).
                let tol = PIECE_TOL.max(node_err);
                if !(diff <= tol) && 0.5 * (b - a) >= min_width {
                    let parts = split_count(diff / tol, (b - a) / min_width);
                    let step = (b - a) / parts as f64;
                    for k in 0..parts {
                        let lo = if k == 0 { a } else { a + step * k as f64 };
                        let hi = if k + 1 == parts {
                            b
                        } else {
                            a + step * (k + 1) as f64
                        };
                        next.push((lo, hi));
                    }
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
        Some(Self {
            pieces,
            base,
            nodes: known.len(),
        })
    }

    /// `(A, relative error estimate)` at `theta` (radians; clamped to the table).
    pub(crate) fn at(&self, theta: f64) -> (f64, f64) {
        let i = self
            .pieces
            .partition_point(|p| p.hi < theta)
            .min(self.pieces.len() - 1);
        let p = &self.pieces[i];
        let t = theta.clamp(p.lo, p.hi);
        let tabulated = p.table.eval(t, 0.0);
        if self.base.is_none() {
            return (tabulated, p.rel_err);
        }
        let (g, g_err) = base_at(self.base.as_ref(), t);
        let a = g + tabulated;
        let rel = if a > 0.0 {
            p.rel_err + g_err / a
        } else {
            f64::INFINITY
        };
        (a, rel)
    }

    /// How many distinct θo the table integrated (its nodes).
    #[cfg(test)]
    pub(crate) fn nodes(&self) -> usize {
        self.nodes
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
    use super::{SetTable, split_count};
    use brdf::CornellBrdf;
    use brdf::measured::cornell::{Interpolation, lobe_grid_text};

    /// The synthetic Cornell file (a mirror lobe on a 9 × 9 grid of angles), kNN.
    fn synthetic() -> CornellBrdf {
        CornellBrdf::parse(&lobe_grid_text(|f| [f, f, f]))
            .unwrap()
            .with_interpolation(Interpolation::Knn)
    }

    /// Issue 29 (docs/benchmarks.md §25.5): the table with the control variate
    /// (`A_grid + D̂`) equals the plain table of `A` within their declared errors, on one
    /// piece (40°–41.5°) of the synthetic file, at the nodes and between them, and both are
    /// within their declared errors of the reference rule at 10⁶ evaluations. Fails when the
    /// grid albedo is left out of `at` or scaled by 1 + 10⁻³ (checked, §25.5).
    #[test]
    fn control_variate_table_is_the_plain_table() {
        let brdf = synthetic();
        let (lo, hi) = (40f64.to_radians(), 41.5f64.to_radians());
        let cv = SetTable::build_with(&brdf, lo, hi, &[], true).unwrap();
        let plain = SetTable::build_with(&brdf, lo, hi, &[], false).unwrap();
        assert!(cv.base.is_some() && plain.base.is_none());
        for t in [40.0f64, 40.23, 40.75, 41.07, 41.5] {
            let (a_cv, e_cv) = cv.at(t.to_radians());
            let (a_plain, e_plain) = plain.at(t.to_radians());
            let gap = (a_cv / a_plain - 1.0).abs();
            let wo = brdf::direction_from_angles(t, 0.0);
            let r = crate::reference_albedo_with_budget(&brdf, &wo, 1_000_000).unwrap();
            let (g_cv, g_plain) = (
                (a_cv / r.value - 1.0).abs(),
                (a_plain / r.value - 1.0).abs(),
            );
            let r_rel = r.abs_err / r.value;
            eprintln!(
                "θo {t}: cv {a_cv:.9} ± {e_cv:.1e}, plain {a_plain:.9} ± {e_plain:.1e}, gap \
                 {gap:.1e}; against the reference (± {r_rel:.1e}): {g_cv:.1e}, {g_plain:.1e}"
            );
            assert!(gap <= e_cv + e_plain, "θo {t}: gap {gap:e}");
            assert!(
                g_cv <= e_cv + r_rel,
                "θo {t}: cv off the reference by {g_cv:e}"
            );
            assert!(
                g_plain <= e_plain + r_rel,
                "θo {t}: plain off the reference by {g_plain:e}"
            );
        }
    }

    /// The set tables of the shared files with and without the control variate: nodes,
    /// pieces, declared errors and the gap between the two (docs/benchmarks.md §25.5).
    /// `CORNELL_FILES` (default the three), `CV_MODES` (default `plain,cv`).
    /// `cargo test --release -p brdf-sampling --lib set_table_cv_survey -- --ignored --nocapture`
    #[test]
    #[ignore = "a survey for the record"]
    fn set_table_cv_survey() {
        let env = |k: &str| std::env::var(k).ok();
        let files = env("CORNELL_FILES").unwrap_or("krylon_blue,cayman,acryl_blue".into());
        let modes = env("CV_MODES").unwrap_or("plain,cv".into());
        for name in files.split(',') {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("../../../shared/data/measured/cornell/{name}.brdf"));
            let Ok(b) = CornellBrdf::load(&path) else {
                eprintln!("skipped {name}");
                continue;
            };
            let top = super::super::options::THETA_TOP_DEG.to_radians();
            let mut tables = Vec::new();
            for mode in modes.split(',') {
                let start = std::time::Instant::now();
                let t = SetTable::build_with(&b, 0.0, top, &[], mode == "cv").unwrap();
                let worst = t.pieces.iter().map(|p| p.rel_err).fold(0.0, f64::max);
                let narrow = t
                    .pieces
                    .iter()
                    .filter(|p| p.hi - p.lo < 2.0 * super::MIN_PIECE_DEG.to_radians())
                    .count();
                eprintln!(
                    "{name} {mode}: {} nodes, {} pieces ({narrow} narrower than twice the \
                     narrowest), worst declared {worst:.1e}, {:.1} s",
                    t.nodes(),
                    t.pieces.len(),
                    start.elapsed().as_secs_f64()
                );
                tables.push(t);
            }
            if tables.len() == 2 {
                let (mut worst, mut worst_ratio) = (0.0f64, 0.0f64);
                for k in 0..=600 {
                    let t = top * k as f64 / 600.0;
                    let ((a, ea), (c, ec)) = (tables[0].at(t), tables[1].at(t));
                    let g = (c / a - 1.0).abs();
                    worst = worst.max(g);
                    worst_ratio = worst_ratio.max(g / (ea + ec));
                }
                eprintln!(
                    "{name}: max |A_cv/A_plain − 1| on 601 angles {worst:.1e}, max gap / (sum \
                     of declared) {worst_ratio:.2}"
                );
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
