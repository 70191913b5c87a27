//! The report's answer in words, per material family: "for X use Y (tied: Z), because …",
//! with the numbers and results.csv rows behind each sentence.
//!
//! Rule, per family (module `groups`, [`Family`]) and estimator `brdf`: over the family's
//! comparisons (every BRDF, θo and light of the family that was ranked), each sampler counts
//! the comparisons in which it is **best or tied with the best** (module `ranking`: Šidák,
//! family-wise α = 0.05 per comparison). The recommended sampler has the largest count; ties
//! are broken by the smaller geometric mean of the efficiency ratio best / this (1 when it is
//! the best). "Tied" names the samplers with the same count. The "because" compares the
//! recommendation with the runner-up on the comparisons both were ranked in: the geometric
//! mean of their MSE ratio and of their time ratio, each with a 95 % interval (from the
//! per-cell standard errors of ln MSE and ln t, independent across comparisons), so a reader
//! sees whether the choice rests on fewer errors or on faster samples. The recommendation's
//! worst comparison is named with its ratio and interval.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::CellResult;
use crate::groups::{Family, short_brdf, short_light};
use crate::ranking::{ESTIMATOR_BRDF, Ranking, Verdict};

/// Samplers named in a sentence's "tied" list (the rest are counted).
const TIED_SHOWN: usize = 5;

/// How one sampler fares over a set of comparisons.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Tally {
    /// Sampler label.
    pub label: String,
    /// Comparisons in which it was ranked.
    pub ranked: usize,
    /// Comparisons in which it is the best.
    pub best: usize,
    /// Comparisons in which it is best or tied with the best.
    pub top: usize,
    /// Geometric mean of best / this over the comparisons with a finite ratio.
    pub geo_ratio: f64,
    /// 95 % interval of `geo_ratio` from the entries' `se(ln E)` (the best's and this one's,
    /// in quadrature; 0 where this one is the best, whose ratio is 1 by definition).
    pub geo_ci: (f64, f64),
    /// Its cells (results.csv `index`).
    pub rows: Vec<usize>,
}

/// The tallies of every sampler over `rankings`, recommended first (most often best or
/// tied, then the smaller geometric-mean ratio, then the name).
pub(crate) fn tallies(rankings: &[&Ranking]) -> Vec<Tally> {
    let mut by: BTreeMap<String, (Tally, f64, usize, f64)> = BTreeMap::new();
    for r in rankings {
        let se_best = r
            .entries
            .first()
            .and_then(|b| b.se_log_efficiency)
            .unwrap_or(0.0);
        for e in &r.entries {
            let t = by.entry(e.sampler.clone()).or_insert_with(|| {
                (
                    Tally {
                        label: e.sampler.clone(),
                        ranked: 0,
                        best: 0,
                        top: 0,
                        geo_ratio: 1.0,
                        geo_ci: (1.0, 1.0),
                        rows: Vec::new(),
                    },
                    0.0,
                    0,
                    0.0,
                )
            });
            t.0.ranked += 1;
            t.0.rows.push(e.cell);
            if e.verdict == Verdict::Best {
                t.0.best += 1;
            }
            if e.verdict != Verdict::Worse {
                t.0.top += 1;
            }
            if let Some(x) = e.ratio.filter(|x| *x > 0.0 && x.is_finite()) {
                t.1 += x.ln();
                t.2 += 1;
                if e.verdict != Verdict::Best {
                    let se = e.se_log_efficiency.unwrap_or(0.0);
                    t.3 += se * se + se_best * se_best;
                }
            }
        }
    }
    let mut v: Vec<Tally> = by
        .into_values()
        .map(|(mut t, sum, n, var)| {
            if n > 0 {
                let (m, h) = (sum / n as f64, 1.96 * var.sqrt() / n as f64);
                t.geo_ratio = m.exp();
                t.geo_ci = ((m - h).exp(), (m + h).exp());
            } else {
                t.geo_ratio = f64::INFINITY;
                t.geo_ci = (f64::INFINITY, f64::INFINITY);
            }
            t
        })
        .collect();
    v.sort_by(|a, b| {
        b.top
            .cmp(&a.top)
            .then(a.geo_ratio.total_cmp(&b.geo_ratio))
            .then(a.label.cmp(&b.label))
    });
    v
}

/// Geometric mean over the shared comparisons of `num / den` for a per-cell quantity, with
/// its 95 % interval from the per-cell standard errors of the logs: `(gm, lo, hi, k)`.
fn paired_ratio(
    rankings: &[&Ranking],
    num: &str,
    den: &str,
    value: &dyn Fn(&CellResult) -> Option<f64>,
    se: &dyn Fn(&crate::ranking::Entry) -> Option<f64>,
    cells: &BTreeMap<usize, &CellResult>,
) -> Option<(f64, f64, f64, usize)> {
    let (mut sum, mut var, mut k) = (0.0, 0.0, 0usize);
    for r in rankings {
        let (Some(a), Some(b)) = (r.entry(num), r.entry(den)) else {
            continue;
        };
        let (Some(ca), Some(cb)) = (cells.get(&a.cell), cells.get(&b.cell)) else {
            continue;
        };
        let (Some(va), Some(vb), Some(sa), Some(sb)) = (value(ca), value(cb), se(a), se(b)) else {
            continue;
        };
        if !(va > 0.0 && vb > 0.0) {
            continue;
        }
        sum += va.ln() - vb.ln();
        var += sa * sa + sb * sb;
        k += 1;
    }
    if k == 0 {
        return None;
    }
    let (m, h) = (sum / k as f64, 1.96 * var.sqrt() / k as f64);
    Some(((m).exp(), (m - h).exp(), (m + h).exp(), k))
}

fn rows_text(rows: &[usize]) -> String {
    rows.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The recommendation sentence for `rankings` (one family or one θo of it), `None` when
/// nothing was ranked.
pub(crate) fn sentence(
    what: &str,
    rankings: &[&Ranking],
    cells: &BTreeMap<usize, &CellResult>,
) -> Option<String> {
    let t = tallies(rankings);
    let y = t.first()?;
    let n = rankings.len();
    let all_tied: Vec<String> = t
        .iter()
        .skip(1)
        .filter(|x| x.top == y.top)
        .map(|x| {
            if x.best > 0 {
                format!("{} (best in {})", x.label, x.best)
            } else {
                x.label.clone()
            }
        })
        .collect();
    let mut tied: Vec<String> = all_tied.iter().take(TIED_SHOWN).cloned().collect();
    if all_tied.len() > TIED_SHOWN {
        tied.push(format!("and {} more", all_tied.len() - TIED_SHOWN));
    }
    if !all_tied.is_empty() && all_tied.len() + 1 == t.len() {
        return Some(format!(
            "For **{what}** **no sampler stands out**: all {} samplers are best or tied with the best in {} of {} comparisons (the intervals are too wide to separate them); the tie-break (geometric mean of best / this) prefers {} ({:.2} [{:.2}, {:.2}], 95 %; best in {}) (rows {}).",
            t.len(),
            y.top,
            n,
            y.label,
            y.geo_ratio,
            y.geo_ci.0,
            y.geo_ci.1,
            y.best,
            rows_text(&y.rows)
        ));
    }
    let mut s = format!(
        "For **{what}** use **{}**: best or tied with the best in {} of {} comparisons (best in {}, significantly worse in {}; geometric mean of best / {} = {:.2} [{:.2}, {:.2}], 95 %)",
        y.label,
        y.top,
        n,
        y.best,
        y.ranked - y.top,
        y.label,
        y.geo_ratio,
        y.geo_ci.0,
        y.geo_ci.1
    );
    if tied.is_empty() {
        s.push_str("; no other sampler is as often best or tied");
    } else {
        let _ = write!(s, "; tied (as often best or tied): {}", tied.join(", "));
    }
    // Its worst comparison.
    let worst = rankings
        .iter()
        .filter_map(|r| r.entry(&y.label).map(|e| (r, e)))
        .filter(|(_, e)| e.verdict == Verdict::Worse)
        .max_by(|a, b| {
            a.1.ratio
                .unwrap_or(f64::INFINITY)
                .total_cmp(&b.1.ratio.unwrap_or(f64::INFINITY))
        });
    if let Some((r, e)) = worst {
        let _ = write!(
            s,
            "; its largest shortfall: {} at θo = {}° under {}, best ({}) / {} = {} (row {})",
            short_brdf(&r.brdf),
            r.theta_o,
            short_light(&r.light),
            r.best,
            y.label,
            match (e.ratio, e.ratio_lo, e.ratio_hi) {
                (Some(x), Some(lo), Some(hi)) => format!("{x:.2}× [{lo:.2}, {hi:.2}]"),
                _ => "∞ (the best is exact)".into(),
            },
            e.cell
        );
    }
    // Because: against the runner-up.
    if let Some(r) = t.get(1) {
        let mse = paired_ratio(
            rankings,
            &y.label,
            &r.label,
            &|c| (!c.zero_variance).then_some(c.mse.value),
            &|e| e.se_log_mse,
            cells,
        );
        let time = paired_ratio(
            rankings,
            &y.label,
            &r.label,
            &|c| c.timing.map(|t| t.estimator_ns),
            &|e| e.se_log_time,
            cells,
        );
        if let (Some(m), Some(ti)) = (mse, time) {
            let word = |x: (f64, f64, f64, usize), less: &'static str, more: &'static str| {
                if x.2 < 1.0 {
                    less
                } else if x.1 > 1.0 {
                    more
                } else {
                    "not significantly different"
                }
            };
            let _ = write!(
                s,
                ", because against the runner-up {} ({}/{}), over {} shared comparisons, its MSE per sample is {:.2}× [{:.2}, {:.2}] the runner-up's ({}) and its time per sample {:.2}× [{:.2}, {:.2}] † ({}) (geometric means, 95 %)",
                r.label,
                r.top,
                r.ranked,
                m.3,
                m.0,
                m.1,
                m.2,
                word(m, "smaller", "larger"),
                ti.0,
                ti.1,
                ti.2,
                word(ti, "faster", "slower"),
            );
        }
    }
    let runner_rows = t.get(1).map(|r| r.rows.clone()).unwrap_or_default();
    let _ = write!(
        s,
        " (rows {}{}).",
        rows_text(&y.rows),
        if runner_rows.is_empty() {
            String::new()
        } else {
            format!("; runner-up {}", rows_text(&runner_rows))
        }
    );
    Some(s)
}

/// The "answers per material family" section: one sentence per family with comparisons,
/// then the recommendation by θo.
pub(crate) fn family_answers(rankings: &[Ranking], cells: &[CellResult]) -> String {
    let by_index: BTreeMap<usize, &CellResult> = cells.iter().map(|c| (c.index, c)).collect();
    let mut fam: BTreeMap<&str, Family> = BTreeMap::new();
    let brdf_rankings: Vec<&Ranking> = rankings
        .iter()
        .filter(|r| r.estimator == ESTIMATOR_BRDF)
        .collect();
    let mut s = String::from("## Which sampler for which material\n\n");
    s.push_str("Per material family (estimator: BRDF sampling alone), the sampler most often best or tied with the best (Šidák intervals above; ties broken by the geometric mean of best / this), the samplers as often best or tied, the recommendation's worst comparison, and why it wins against the runner-up (MSE and time ratios, geometric means with 95 % intervals; † timing). `rows` are results.csv `index` values of the recommended sampler's and the runner-up's cells.\n\n");
    let mut any = false;
    for f in Family::ALL {
        let rs: Vec<&Ranking> = brdf_rankings
            .iter()
            .copied()
            .filter(|r| {
                *fam.entry(r.brdf.as_str())
                    .or_insert_with(|| Family::of(&r.brdf))
                    == f
            })
            .collect();
        let Some(text) = sentence(f.describe(), &rs, &by_index) else {
            continue;
        };
        any = true;
        let materials: Vec<String> = {
            let mut m: Vec<String> = rs.iter().map(|r| short_brdf(&r.brdf)).collect();
            m.dedup();
            m
        };
        let _ = writeln!(s, "* {text} Materials: {}.", materials.join(", "));
        let mut thetas: Vec<f64> = rs.iter().map(|r| r.theta_o).collect();
        thetas.sort_by(f64::total_cmp);
        thetas.dedup();
        if thetas.len() > 1 {
            let by_theta: Vec<String> = thetas
                .iter()
                .filter_map(|th| {
                    let sub: Vec<&Ranking> =
                        rs.iter().copied().filter(|r| r.theta_o == *th).collect();
                    let t = tallies(&sub);
                    let y = t.first()?;
                    let tied = t.iter().skip(1).filter(|x| x.top == y.top).count();
                    Some(format!(
                        "{th}°: {} ({}/{}{})",
                        y.label,
                        y.top,
                        sub.len(),
                        if tied == 0 {
                            String::new()
                        } else {
                            format!(", {tied} more as often best or tied")
                        }
                    ))
                })
                .collect();
            let _ = writeln!(
                s,
                "  By θo (best or tied / comparisons): {}.",
                by_theta.join(" · ")
            );
        }
    }
    if !any {
        s.push_str("No comparison was ranked.\n");
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ranking::synthetic::cell;
    use crate::ranking::{ALPHA, rank_cells};

    /// Three glossy comparisons: `analytic` is best in two and tied in the third (where
    /// `cosine` leads by a hair); `cosine` is tied once and worse twice; `uniform` is always
    /// worse. The recommendation is analytic (3/3), because its errors per sample are smaller (its
    /// MSE is a third of cosine's at the same time), and the sentence names its rows.
    #[test]
    fn the_family_answer_recommends_the_most_often_best_or_tied() {
        let mut cells = Vec::new();
        let mut k = 0;
        let mut push = |s: &str, brdf: &str, mse: f64, cells: &mut Vec<CellResult>| {
            cells.push(cell(k, s, brdf, mse, 0.05 * mse, 100.0, 0.02));
            k += 1;
        };
        for (brdf, a, c) in [("phong", 1.0, 3.0), ("ggx", 1.0, 3.2), ("blinn", 1.02, 1.0)] {
            push("analytic", brdf, a, &mut cells);
            push("cosine", brdf, c, &mut cells);
            push("uniform", brdf, 40.0, &mut cells);
        }
        let rankings: Vec<Ranking> = cells
            .chunks(3)
            .map(|ch| {
                let refs: Vec<&CellResult> = ch.iter().collect();
                rank_cells(&refs, ESTIMATOR_BRDF, ALPHA, true).unwrap()
            })
            .collect();
        let s = family_answers(&rankings, &cells);
        let line = s
            .lines()
            .find(|l| l.starts_with("* For **glossy isotropic analytic models**"))
            .unwrap_or_else(|| panic!("{s}"));
        assert!(
            line.contains("use **analytic**: best or tied with the best in 3 of 3 comparisons (best in 2, significantly worse in 0"),
            "{line}"
        );
        assert!(
            line.contains("its MSE per sample is 0.47× [")
                && line.contains("the runner-up's (smaller)"),
            "{line}"
        );
        assert!(line.contains("runner-up cosine (1/3)"), "{line}");
        // The tie-break's geometric mean carries its 95 % interval (the one comparison in
        // which analytic is not best: ratio 1.02 of three).
        let t = tallies(&rankings.iter().collect::<Vec<_>>());
        let (g, (lo, hi)) = (t[0].geo_ratio, t[0].geo_ci);
        assert!((g - 1.02f64.powf(1.0 / 3.0)).abs() < 1e-9, "{g}");
        assert!(lo < g && g < hi && hi / lo < 1.1, "{lo} {g} {hi}");
        assert!(
            line.contains(&format!(
                "geometric mean of best / analytic = {g:.2} [{lo:.2}, {hi:.2}], 95 %)"
            )),
            "{line}"
        );
        assert!(line.contains("(rows 0, 3, 6; runner-up 1, 4, 7)"), "{line}");
        assert!(line.contains("Materials: phong, ggx, blinn."), "{line}");
        // A comparison in which everything is tied: no sampler stands out.
        let tied_cells = [
            cell(20, "analytic", "ggx", 1.0, 0.5, 100.0, 0.02),
            cell(21, "cosine", "ggx", 1.05, 0.5, 100.0, 0.02),
        ];
        let refs: Vec<&CellResult> = tied_cells.iter().collect();
        let tied_only = [rank_cells(&refs, ESTIMATOR_BRDF, ALPHA, true).unwrap()];
        assert!(tied_only[0].worse.is_empty());
        let s = family_answers(&tied_only, &tied_cells);
        assert!(
            s.contains(
                "For **glossy isotropic analytic models** **no sampler stands out**: all 2 samplers"
            ),
            "{s}"
        );
        assert!(!s.contains(" use **"), "{s}");
        let t = tallies(&rankings.iter().collect::<Vec<_>>());
        assert_eq!(t[0].label, "analytic");
        assert_eq!(t.last().unwrap().label, "uniform");
        assert_eq!(t.last().unwrap().top, 0);
    }
}
