//! Rankings with uncertainty: for each comparison (BRDF, θo, light, estimator), the most
//! efficient sampler, the samplers statistically tied with it, and the ones significantly
//! worse.
//!
//! # The rule
//!
//! Efficiency is `1 / (MSE per sample at the budget N × estimator time per sample)`. On the log
//! scale its uncertainty is the sum of two independent parts:
//!
//! * the MSE's: `se(ln MSE) = √((ci95 / z95)² + (reference_err / z95)²) / MSE` — the cell's
//!   sampling interval (module [`crate::dispersion`]: delta method from the fourth moment in
//!   one-sample mode, the spread of the `R` repetitions' squared errors in batch mode) with the
//!   reference's own error bound read as one more 95 % half-width;
//! * the time's: `se(ln t)` = the sample standard deviation of `ln t` over the cell's timing
//!   repeats, which are interleaved with every other cell's (repeat 1 of every cell, then
//!   repeat 2, …), so the load changes of the whole timing phase show in each cell's spread.
//!   It is the spread of single repeats, not the standard error of their median: a rerun's
//!   time falls in it (a prediction interval, wider on purpose).
//!
//! The point-estimate best `b` is compared with each of the `m` other samplers `x` of the
//! comparison: `d = ln E_b − ln E_x ≥ 0`, `se(d) = √(se_b² + se_x²)`, and the interval of the
//! ratio `E_b / E_x` is `exp(d ± z se(d))` with `z` the two-sided normal quantile at the
//! **Šidák-corrected level** `1 − (1 − α)^(1/m)`, `α = 0.05` ([`ALPHA`]): the probability that
//! any of the `m` intervals misses its true ratio is at most α (Šidák's inequality holds for
//! two-sided normal statistics whatever their correlation, here positive through the shared
//! best). `x` is **tied** when its interval contains 1, **worse** otherwise.
//!
//! A sampler with zero variance (exact, e.g. cosine sampling of a Lambertian BRDF under
//! constant light) has no finite efficiency; when a comparison has one it is `best`, the other
//! exact ones `tied`, every other one `worse`. Cells that did not run or have no timing are
//! listed in `excluded` with the reason.
//!
//! A `worse` verdict that the MSEs alone would not give (the MSE ratio's interval at the same
//! level contains 1) rests on the time difference: marked `by_time` (such a verdict depends on
//! the machine; the load-independent costs of the cells, BRDF evaluations per sample, are in
//! results.csv).

use serde::{Deserialize, Serialize};

use crate::dispersion::Z95;
use crate::groups::groups;
use crate::{CellResult, StudyResults};

pub use crate::verdict::{
    ALPHA, ESTIMATOR_BRDF, ESTIMATOR_LIGHT, Entry, Excluded, RULE, Ranking, Verdict,
};

/// `se(ln MSE)` of a cell, `None` when its MSE is not positive.
fn se_log_mse(c: &CellResult) -> Option<f64> {
    let m = c.mse.value;
    (m > 0.0 && m.is_finite()).then(|| {
        let a = c.mse.ci95 / Z95;
        let b = c.mse.reference_err / Z95;
        (a * a + b * b).sqrt() / m
    })
}

/// The two-sided standard-normal quantile `z` with `P(|Z| > z) = p`.
pub fn two_sided_z(p: f64) -> f64 {
    std::f64::consts::SQRT_2 * statrs::function::erf::erf_inv(1.0 - p)
}

/// The Šidák per-comparison two-sided level `1 − (1 − α)^(1/m)` (α for `m ≤ 1`).
pub fn sidak_alpha(alpha: f64, m: usize) -> f64 {
    if m <= 1 {
        alpha
    } else {
        1.0 - (1.0 - alpha).powf(1.0 / m as f64)
    }
}

/// One ranked candidate before the verdicts.
struct Candidate<'a> {
    cell: &'a CellResult,
    eff: Option<f64>,
    se_mse: f64,
    se_time: f64,
}

/// Ranks the cells of one comparison at family-wise level `alpha` (see the module docs).
/// `None` when no cell can be ranked.
pub fn rank_cells(
    cells: &[&CellResult],
    estimator: &str,
    alpha: f64,
    sidak: bool,
) -> Option<Ranking> {
    let first = cells.first()?;
    let mut excluded = Vec::new();
    let mut cands: Vec<Candidate<'_>> = Vec::new();
    for c in cells {
        let reason = if let Some(why) = &c.status {
            Some(format!("did not run: {why}"))
        } else if c.zero_variance {
            None
        } else {
            match (c.timing.and_then(|t| t.efficiency), se_log_mse(c)) {
                (None, _) => Some("no timing".to_string()),
                (_, None) => Some("no positive MSE".to_string()),
                _ => None,
            }
        };
        if let Some(reason) = reason {
            excluded.push(Excluded {
                sampler: c.label(),
                cell: c.index,
                reason,
            });
            continue;
        }
        cands.push(Candidate {
            cell: c,
            eff: if c.zero_variance {
                None
            } else {
                c.timing.and_then(|t| t.efficiency)
            },
            se_mse: se_log_mse(c).unwrap_or(0.0),
            se_time: c.timing.map_or(0.0, |t| t.estimator_log_sd),
        });
    }
    if cands.is_empty() {
        return None;
    }
    // Exact samplers first (infinite efficiency), then by decreasing efficiency; ties keep
    // grid order.
    cands.sort_by(|a, b| match (a.eff, b.eff) {
        (None, None) => std::cmp::Ordering::Equal,
        (None, Some(_)) => std::cmp::Ordering::Less,
        (Some(_), None) => std::cmp::Ordering::Greater,
        (Some(x), Some(y)) => y.total_cmp(&x),
    });
    let m = cands.len() - 1;
    let per = if sidak { sidak_alpha(alpha, m) } else { alpha };
    let z = two_sided_z(per);
    let best = &cands[0];
    let se = |c: &Candidate<'_>| (c.se_mse * c.se_mse + c.se_time * c.se_time).sqrt();
    let mut entries = Vec::with_capacity(cands.len());
    for (i, c) in cands.iter().enumerate() {
        let unreliable = !c.cell.warnings.is_empty();
        let base = Entry {
            sampler: c.cell.label(),
            cell: c.cell.index,
            verdict: Verdict::Best,
            efficiency: c.eff,
            se_log_efficiency: c.eff.map(|_| se(c)),
            se_log_mse: c.eff.map(|_| c.se_mse),
            se_log_time: c.eff.map(|_| c.se_time),
            ratio: None,
            ratio_lo: None,
            ratio_hi: None,
            by_time: false,
            unreliable,
            evaluations_per_sample: c.cell.evaluations_per_sample,
        };
        if i == 0 {
            entries.push(Entry {
                ratio: best.eff.map(|_| 1.0),
                ratio_lo: best.eff.map(|_| 1.0),
                ratio_hi: best.eff.map(|_| 1.0),
                ..base
            });
            continue;
        }
        let e = match (best.eff, c.eff) {
            // Both exact: tied.
            (None, None) => Entry {
                verdict: Verdict::Tied,
                ..base
            },
            (Some(eb), Some(ex)) => {
                let d = eb.ln() - ex.ln();
                let sd = se(best).hypot(se(c));
                let (lo, hi) = ((d - z * sd).exp(), (d + z * sd).exp());
                let verdict = if lo <= 1.0 {
                    Verdict::Tied
                } else {
                    Verdict::Worse
                };
                // The MSE ratio alone, at the same level.
                let dm = c.cell.mse.value.ln() - best.cell.mse.value.ln();
                let sm = best.se_mse.hypot(c.se_mse);
                let by_time = verdict == Verdict::Worse && dm - z * sm <= 0.0;
                Entry {
                    verdict,
                    ratio: Some(eb / ex),
                    ratio_lo: Some(lo),
                    ratio_hi: Some(hi),
                    by_time,
                    ..base
                }
            }
            // The best is exact, this one is not: worse, with certainty (exact samplers
            // sort first, so a finite best is never followed by an exact one).
            _ => Entry {
                verdict: Verdict::Worse,
                ..base
            },
        };
        entries.push(e);
    }
    let of = |v: Verdict| -> Vec<String> {
        entries
            .iter()
            .filter(|e| e.verdict == v)
            .map(|e| e.sampler.clone())
            .collect()
    };
    Some(Ranking {
        brdf: first.brdf.clone(),
        theta_o: first.theta_o_deg,
        light: first.light.clone(),
        estimator: estimator.to_string(),
        light_sampler: None,
        best: entries[0].sampler.clone(),
        tied: of(Verdict::Tied),
        worse: of(Verdict::Worse),
        alpha,
        rule: if sidak { RULE } else { "none" }.to_string(),
        comparisons: m,
        level: 1.0 - per,
        entries,
        excluded,
    })
}

/// The rankings of every comparison of `results`, at [`ALPHA`] with the Šidák rule: first
/// one per (light, BRDF, θo) of the BRDF samplers alone (estimator `brdf`), then, in config
/// order, one per (light, BRDF, θo) of the map samplers alone (`light`) and one per (light,
/// BRDF, θo, estimator `mis-balance` / `mis-power`, map sampler) of the BRDF samplers inside
/// MIS with that map sampler. The significance rules are the same for all.
pub fn rankings(results: &StudyResults) -> Vec<Ranking> {
    let mut out: Vec<Ranking> = groups(results)
        .iter()
        .filter_map(|g| rank_cells(&g.cells, ESTIMATOR_BRDF, ALPHA, true))
        .collect();
    let cfg = &results.config;
    for light in &cfg.lights {
        for brdf in &cfg.brdfs {
            for &theta in &cfg.theta_o_deg {
                for estimator in &cfg.estimators {
                    let light_samplers: Vec<Option<&str>> = if estimator == ESTIMATOR_LIGHT {
                        vec![None]
                    } else {
                        cfg.light_samplers
                            .iter()
                            .map(|l| Some(l.as_str()))
                            .collect()
                    };
                    for ls in light_samplers {
                        let cells: Vec<&CellResult> = results
                            .cells
                            .iter()
                            .filter(|c| {
                                &c.light == light
                                    && &c.brdf == brdf
                                    && c.theta_o_deg == theta
                                    && &c.estimator == estimator
                                    && c.light_sampler.as_deref() == ls
                            })
                            .collect();
                        if let Some(mut r) = rank_cells(&cells, estimator, ALPHA, true) {
                            r.light_sampler = ls.map(str::to_string);
                            out.push(r);
                        }
                    }
                }
            }
        }
    }
    out
}

/// A significant order `better ≻ worse` of one comparison that another run reverses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Flip {
    /// `BRDF at θo under light (estimator)`.
    pub comparison: String,
    /// Significantly better in run A (the best of A).
    pub better_in_a: String,
    /// Significantly better in run B (the best of B).
    pub better_in_b: String,
}

/// How two runs' significant rankings compare.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RankingComparison {
    /// Comparisons present in both runs.
    pub comparisons: usize,
    /// Significant pairs (best ≻ worse) in run A, in run B.
    pub significant_pairs: (usize, usize),
    /// Significant pairs of A that are also significant in B.
    pub agreeing_pairs: usize,
    /// Comparisons with the same best in both runs.
    pub same_best: usize,
    /// Comparisons whose best in one run is among the other's best or tied.
    pub best_compatible: usize,
    /// Significant pairs that the other run reverses significantly (must be empty).
    pub flips: Vec<Flip>,
}

/// Compares the significant rankings of two runs of the same study (different seeds): a pair
/// `x ≻ y` significant in one run (x best, y worse) flips when the other run has `y ≻ x`
/// significantly.
pub fn compare_rankings(a: &[Ranking], b: &[Ranking]) -> RankingComparison {
    let key = |r: &Ranking| {
        (
            r.brdf.clone(),
            r.theta_o.to_bits(),
            r.light.clone(),
            r.estimator.clone(),
            r.light_sampler.clone(),
        )
    };
    let pairs = |r: &Ranking| -> Vec<(String, String)> {
        r.worse
            .iter()
            .map(|w| (r.best.clone(), w.clone()))
            .collect()
    };
    let mut out = RankingComparison {
        comparisons: 0,
        significant_pairs: (0, 0),
        agreeing_pairs: 0,
        same_best: 0,
        best_compatible: 0,
        flips: Vec::new(),
    };
    for ra in a {
        let Some(rb) = b.iter().find(|rb| key(rb) == key(ra)) else {
            continue;
        };
        out.comparisons += 1;
        let (pa, pb) = (pairs(ra), pairs(rb));
        out.significant_pairs.0 += pa.len();
        out.significant_pairs.1 += pb.len();
        out.agreeing_pairs += pa.iter().filter(|p| pb.contains(p)).count();
        if ra.best == rb.best {
            out.same_best += 1;
        }
        if ra.best == rb.best || rb.tied.contains(&ra.best) || ra.tied.contains(&rb.best) {
            out.best_compatible += 1;
        }
        let title = format!(
            "{} at θo = {}° under {} ({}{})",
            crate::names::short_brdf(&ra.brdf),
            ra.theta_o,
            crate::names::short_light(&ra.light),
            ra.estimator,
            ra.light_sampler
                .as_deref()
                .map_or(String::new(), |l| format!(" with {l}"))
        );
        for (x, y) in &pa {
            if pb.iter().any(|(bx, by)| bx == y && by == x) {
                out.flips.push(Flip {
                    comparison: title.clone(),
                    better_in_a: x.clone(),
                    better_in_b: y.clone(),
                });
            }
        }
    }
    out
}

/// Synthetic cells for the ranking and report tests.
#[cfg(test)]
pub(crate) mod synthetic {
    use crate::dispersion::BudgetMse;
    use crate::ranking::ESTIMATOR_BRDF;
    use crate::{CellResult, Mode, Reference, Timing, WithCi};

    /// A cell of `sampler` with per-sample MSE `mse ± mse_ci95`, estimator time `ns` per
    /// sample with log-spread `log_sd`, in the comparison (`brdf`, 30°, `sky`).
    pub(crate) fn cell(
        index: usize,
        sampler: &str,
        brdf: &str,
        mse: f64,
        mse_ci95: f64,
        ns: f64,
        log_sd: f64,
    ) -> CellResult {
        CellResult {
            index,
            sampler: sampler.to_string(),
            mode: Mode::OneSample,
            brdf: brdf.to_string(),
            theta_o_deg: 30.0,
            light: "sky".into(),
            estimator: ESTIMATOR_BRDF.into(),
            light_sampler: None,
            status: None,
            reference: Reference {
                value: 1.0,
                abs_err: 0.0,
                method: "test".into(),
            },
            bytes: 0,
            evaluations_per_sample: 0.0,
            variance: WithCi {
                value: mse,
                ci95: mse_ci95,
            },
            zero_variance: false,
            mse: BudgetMse {
                n: 2500,
                value: mse,
                ci95: mse_ci95,
                reference_err: 0.0,
            },
            tail_share: 0.0,
            warnings: Vec::new(),
            errors: Vec::new(),
            timing: Some(Timing {
                clock: crate::Clock::ThreadCpu,
                build_seconds: 0.0,
                sample_ns: ns,
                estimator_ns: ns,
                estimator_ns_min: ns,
                estimator_ns_max: ns,
                estimator_log_sd: log_sd,
                estimator_wall_ns: ns,
                estimator_wall_log_sd: log_sd,
                repeats: 5,
                efficiency: Some(1.0 / (mse * ns * 1e-9)),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::synthetic::cell;
    use super::*;
    use crate::dispersion::Z95;

    fn rank(cells: &[CellResult], sidak: bool) -> Ranking {
        let refs: Vec<&CellResult> = cells.iter().collect();
        rank_cells(&refs, ESTIMATOR_BRDF, ALPHA, sidak).unwrap()
    }

    #[test]
    fn a_clearly_better_sampler_is_best_and_the_others_worse() {
        let cells = [
            cell(0, "uniform", "ggx", 10.0, 0.5, 100.0, 0.02),
            cell(1, "adaptive", "ggx", 1.0, 0.05, 100.0, 0.02),
            cell(2, "cosine", "ggx", 5.0, 0.3, 100.0, 0.02),
        ];
        let r = rank(&cells, true);
        assert_eq!(r.best, "adaptive");
        assert!(r.tied.is_empty());
        assert_eq!(r.worse, ["cosine", "uniform"]);
        assert_eq!(r.rows(), [1, 2, 0]);
        let u = r.entry("uniform").unwrap();
        assert!((u.ratio.unwrap() - 10.0).abs() < 1e-9);
        assert!(u.ratio_lo.unwrap() > 1.0 && u.ratio_hi.unwrap() > 10.0);
        assert!(!u.by_time);
        assert_eq!(r.comparisons, 2);
    }

    #[test]
    fn overlapping_intervals_are_tied() {
        // MSE 1.0 ± 40 % against 1.2 ± 40 %, equal times: the ratio 1.2's interval holds 1.
        let cells = [
            cell(0, "analytic", "phong", 1.2, 0.48, 100.0, 0.02),
            cell(1, "adaptive-paper (batch)", "phong", 1.0, 0.4, 100.0, 0.02),
        ];
        let r = rank(&cells, true);
        assert_eq!(r.best, "adaptive-paper (batch)");
        assert_eq!(r.tied, ["analytic"]);
        assert!(r.worse.is_empty());
        let e = r.entry("analytic").unwrap();
        assert!(e.ratio_lo.unwrap() < 1.0 && e.ratio_hi.unwrap() > 1.2);
    }

    /// A borderline sampler, 2.2 combined standard errors below the best, among 9 others far
    /// below: significant at 5 % on its own (z = 1.96), not after the Šidák correction for
    /// m = 10 comparisons (z = 2.80).
    #[test]
    fn the_multiple_comparison_rule_changes_a_borderline_case() {
        // se(ln MSE) = 0.1 for both: se(d) = 0.1 √2; d = 2.2 se(d).
        let se = 0.1;
        let d = 2.2 * se * 2f64.sqrt();
        let mut cells = vec![
            cell(0, "best", "ward", 1.0, Z95 * se, 100.0, 0.0),
            cell(
                1,
                "borderline",
                "ward",
                d.exp(),
                Z95 * se * d.exp(),
                100.0,
                0.0,
            ),
        ];
        for i in 2..11 {
            cells.push(cell(i, &format!("far{i}"), "ward", 50.0, 1.0, 100.0, 0.0));
        }
        let corrected = rank(&cells, true);
        assert_eq!(corrected.comparisons, 10);
        assert_eq!(corrected.tied, ["borderline"]);
        assert_eq!(corrected.worse.len(), 9);
        assert!((corrected.level - 0.95f64.powf(0.1)).abs() < 1e-12);
        let uncorrected = rank(&cells, false);
        assert!(uncorrected.tied.is_empty());
        assert_eq!(uncorrected.worse.len(), 10);
    }

    #[test]
    fn the_timing_spread_widens_the_interval_and_time_only_verdicts_are_marked() {
        // Equal MSEs; x takes 1.5× the time.
        let quiet = [
            cell(0, "a", "ggx", 1.0, 0.02, 100.0, 0.01),
            cell(1, "x", "ggx", 1.0, 0.02, 150.0, 0.01),
        ];
        let r = rank(&quiet, true);
        assert_eq!(r.worse, ["x"]);
        assert!(r.entry("x").unwrap().by_time, "{r:?}");
        // The same times measured with a 30 % spread: tied.
        let loaded = [
            cell(0, "a", "ggx", 1.0, 0.02, 100.0, 0.3),
            cell(1, "x", "ggx", 1.0, 0.02, 150.0, 0.3),
        ];
        let r = rank(&loaded, true);
        assert_eq!(r.tied, ["x"]);
        assert!(!r.entry("x").unwrap().by_time);
        let e = r.entry("a").unwrap();
        assert!((e.se_log_time.unwrap() - 0.3).abs() < 1e-12);
        assert!(
            (e.se_log_efficiency.unwrap() - (0.3f64.powi(2) + (0.02 / Z95).powi(2)).sqrt()).abs()
                < 1e-12
        );
    }

    #[test]
    fn exact_samplers_lead_and_cells_without_numbers_are_excluded() {
        let mut exact = cell(0, "cosine", "lambert", 0.0, 0.0, 50.0, 0.0);
        exact.zero_variance = true;
        if let Some(t) = exact.timing.as_mut() {
            t.efficiency = None;
        }
        let mut failed = cell(2, "rgl-native", "lambert", 1.0, 0.1, 50.0, 0.0);
        failed.status = Some("does not apply".into());
        let cells = [
            cell(1, "uniform", "lambert", 1.0, 0.1, 50.0, 0.0),
            exact,
            failed,
        ];
        let r = rank(&cells, true);
        assert_eq!(r.best, "cosine");
        assert_eq!(r.worse, ["uniform"]);
        assert_eq!(r.excluded.len(), 1);
        assert_eq!(r.excluded[0].cell, 2);
        assert!(r.entry("uniform").unwrap().ratio.is_none());
    }

    #[test]
    fn the_json_carries_the_contract_fields() {
        let cells = [
            cell(0, "uniform", "ggx", 10.0, 0.5, 100.0, 0.02),
            cell(1, "adaptive", "ggx", 1.0, 0.05, 100.0, 0.02),
        ];
        let r = rank(&cells, true);
        let v: serde_json::Value =
            serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        for key in [
            "brdf",
            "theta_o",
            "light",
            "estimator",
            "best",
            "tied",
            "worse",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert_eq!(v["estimator"], "brdf");
        assert_eq!(v["best"], "adaptive");
        assert_eq!(v["worse"][0], "uniform");
        assert!(v["tied"].as_array().unwrap().is_empty());
        assert_eq!(v["theta_o"], 30.0);
        assert!(v["entries"][1]["ratio_lo"].as_f64().unwrap() > 1.0);
    }

    #[test]
    fn a_reversed_significant_pair_is_a_flip() {
        let a = [
            cell(0, "x", "ggx", 1.0, 0.05, 100.0, 0.02),
            cell(1, "y", "ggx", 5.0, 0.2, 100.0, 0.02),
        ];
        let b = [
            cell(0, "x", "ggx", 5.0, 0.2, 100.0, 0.02),
            cell(1, "y", "ggx", 1.0, 0.05, 100.0, 0.02),
        ];
        let tied = [
            cell(0, "x", "ggx", 1.0, 0.5, 100.0, 0.02),
            cell(1, "y", "ggx", 1.1, 0.5, 100.0, 0.02),
        ];
        let (ra, rb, rt) = (rank(&a, true), rank(&b, true), rank(&tied, true));
        let c = compare_rankings(std::slice::from_ref(&ra), std::slice::from_ref(&rb));
        assert_eq!(c.flips.len(), 1);
        assert_eq!(c.flips[0].better_in_a, "x");
        assert_eq!(c.same_best, 0);
        let c = compare_rankings(std::slice::from_ref(&ra), std::slice::from_ref(&ra));
        assert!(c.flips.is_empty());
        assert_eq!(
            (c.significant_pairs, c.agreeing_pairs, c.same_best),
            ((1, 1), 1, 1)
        );
        // A tie in one run does not contradict a significant order in the other.
        let c = compare_rankings(std::slice::from_ref(&ra), std::slice::from_ref(&rt));
        assert!(c.flips.is_empty());
        assert_eq!(c.best_compatible, 1);
    }
}
