//! The study's `report.md`: setup, the honest outcome, one table per (light, BRDF, θo), and
//! the plots and images the caller wrote.

use std::fmt::Write as _;

use crate::groups::{Group, groups, is_adaptive, short_light};
use crate::ranking::{Entry, Ranking, Verdict};
use crate::{CellResult, StudyResults};

/// Files beside `report.md` that the report embeds (paths relative to the report).
#[derive(Debug, Clone, Default)]
pub struct ReportAssets {
    /// Per group slug: `(caption, path)` of its plots.
    pub plots: Vec<(String, String, String)>,
    /// Summary plots (across groups): `(caption, path)`.
    pub summary_plots: Vec<(String, String)>,
    /// Rendered images: `(caption, path)`.
    pub images: Vec<(String, String)>,
    /// Extra Markdown sections appended at the end (e.g. the paper tables).
    pub sections: Vec<String>,
}

/// The Markdown report of `results` with `assets` embedded.
pub fn report_markdown(results: &StudyResults, assets: &ReportAssets) -> String {
    let cfg = &results.config;
    let mut s = String::new();
    let _ = writeln!(s, "# brdf-lab study report ({})\n", cfg.preset);
    let _ = writeln!(
        s,
        "Samplers: {}. BRDFs: {}. θo: {} (φo = 0). N ∈ {{{}}}, {} repetitions per N (one-sample cells: nested, each repetition one stream of the largest N's values, its estimate at each N the mean of the stream's first N), {} more one-sample values for the variance and the MSE, seed {}, {} outgoing slices for the adaptive sets. {} cells{}.\n",
        cfg.samplers.join(", "),
        cfg.brdfs
            .iter()
            .map(|b| format!("`{}`", crate::names::short_brdf(b)))
            .collect::<Vec<_>>()
            .join(", "),
        cfg.theta_o_deg
            .iter()
            .map(|t| format!("{t}°"))
            .collect::<Vec<_>>()
            .join(", "),
        cfg.n_grid
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        cfg.repetitions,
        cfg.variance_samples,
        cfg.seed,
        cfg.slices,
        results.total_cells,
        results.shard.map_or(String::new(), |sh| format!(
            " (this is shard {}/{}: {} of them)",
            sh.index,
            sh.count,
            results.cells.len()
        )),
    );
    for n in &results.notes {
        let _ = writeln!(s, "> **Note:** {n}\n");
    }
    for w in &results.build_warnings {
        let _ = writeln!(s, "> **Warning:** {w}\n");
    }
    s.push_str("## Lights\n\n");
    for l in &results.lights {
        let _ = writeln!(s, "* `{}`: {}", short_light(&l.spec), l.description);
    }
    run_section(&mut s, results);
    s.push_str(concat!(
        "\n## What is measured\n\n",
        "For each cell the estimator of L_r(ωo) = ∫ f_r L cosθ dσ is (1/N) Σ Y(f_r ⊙ L) cosθ / p_σ with the sampler's ",
        "solid-angle pdf (samples below the horizon count 0). *Relative error* is the mean over the repetitions of ",
        "|L̂ − L_ref| / L_ref (± half-width of the 95 % interval; one-sample mode: each repetition's estimates at the ",
        "N of the grid are the means of the first N values of one stream, so its curve's points are correlated across N ",
        "while the repetitions stay independent at each N, and each band holds per N). *Variance* is the per-sample variance of the estimator ",
        "(one-sample mode: of f L cos/p over every value the cell drew; batch mode: N·Var(L̂_N) at the largest N). ",
        "*MSE* is the per-sample mean squared error against the reference at the budget (largest) N, ",
        "N·E[(L̂_N − L)²] = σ² + N·b²: one-sample mode σ̂² + N·max(0, b̂² − σ̂²/n) from all n values with b̂ = ȳ − L_ref, ",
        "batch mode N·mean((L̂_N − L_ref)²) over the repetitions; ± its 95 % interval, and the part the reference's own ",
        "error could change. A sample variance misses the rare large values of a heavy-tailed estimator (a narrow lobe ",
        "sampled uniformly under a small bright sun); measured against the reference, the mass it has not reached shows ",
        "as a bias, so the MSE ranks such a sampler honestly. ⚠ marks a cell whose spread is unreliable: one value holds ",
        "more than max(5 %, 5 ln m/m) of the m values' sum of squared deviations (a heavy tail), the variance's 95 % ",
        "interval exceeds ±50 %, or the mean of the one-sample values is more than 3.29 standard errors (99.9 %) plus ",
        "the reference's error away from the reference (a bias, or a part of the integral rarely reached); its ranking is ",
        "uncertain. *Evals* are BRDF evaluations made by ",
        "the sampler per sample (the estimator's own evaluation excluded). The reference is a deterministic quadrature ",
        "(method and error per table).\n\n",
        "**Timings** (marked †) are the only numbers that change between runs: build time, ns per sample of the sampler ",
        "and of the whole estimator (one thread, median of the repeats), and efficiency = 1 / (MSE × estimator ",
        "time per sample in s). Everything else is reproducible from the seed, for any thread count and any sharding.\n\n",
    ));
    outcome(&mut s, results);
    for p in &assets.summary_plots {
        let _ = writeln!(s, "![{}]({})\n", p.0, p.1);
    }
    s.push_str("## Results\n\n");
    for g in groups(results) {
        let ranking = results.rankings.iter().find(|r| {
            r.brdf == g.brdf
                && r.theta_o == g.theta_o_deg
                && r.light == g.light
                && r.estimator == crate::ranking::ESTIMATOR_BRDF
        });
        group_table(&mut s, &g, cfg.n_grid.last().copied().unwrap_or(0), ranking);
        for (slug, caption, path) in &assets.plots {
            if *slug == g.slug {
                let _ = writeln!(s, "![{caption}]({path})\n");
            }
        }
    }
    if !assets.images.is_empty() {
        s.push_str("## Images\n\n");
        for (caption, path) in &assets.images {
            let _ = writeln!(s, "**{caption}**\n\n![{caption}]({path})\n");
        }
    }
    for sec in &assets.sections {
        s.push_str(sec);
        s.push('\n');
    }
    s
}

/// Where and how the study ran.
fn run_section(s: &mut String, results: &StudyResults) {
    if results.runs.is_empty() {
        return;
    }
    s.push_str("\n## Run\n\n");
    let fmt_load = |l: &[f64]| {
        if l.is_empty() {
            "unknown".to_string()
        } else {
            l.iter()
                .map(|x| format!("{x:.2}"))
                .collect::<Vec<_>>()
                .join(" / ")
        }
    };
    for r in &results.runs {
        let _ = writeln!(
            s,
            "* commit `{}`, CPU {} ({} logical CPUs), {} threads for the statistics and the timings (each timing on its own thread's CPU clock); load average (1 / 5 / 15 min) {} at the start, {} at the end; {:.0} s wall, {} CPU.",
            r.commit,
            r.cpu_model,
            r.logical_cpus,
            r.threads,
            fmt_load(&r.load_start),
            fmt_load(&r.load_end),
            r.wall_seconds,
            r.cpu_seconds
                .map_or("unknown".to_string(), |c| format!("{c:.0} s")),
        );
        if let Some(p) = r.phase_summary() {
            let _ = writeln!(s, "  CPU time by phase: {p}.");
        }
    }
    let spread = |f: &dyn Fn(&crate::Timing) -> f64| {
        let mut v: Vec<f64> = results
            .cells
            .iter()
            .filter_map(|c| c.timing.as_ref().map(f))
            .collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| 100.0 * v[((v.len() - 1) as f64 * p).round() as usize];
        Some(format!(
            "median {:.1} %, 90th percentile {:.1} %, largest {:.1} %",
            q(0.5),
            q(0.9),
            q(1.0)
        ))
    };
    let clock = results
        .cells
        .iter()
        .find_map(|c| c.timing.map(|t| t.clock))
        .unwrap_or(crate::Clock::Wall);
    if let (Some(cpu), Some(wall)) = (
        spread(&|t| t.estimator_log_sd),
        spread(&|t| t.estimator_wall_log_sd),
    ) {
        let _ = writeln!(
            s,
            "* timings on the {} clock; their spread (standard deviation of ln t over a cell's {}–{} interleaved repeats, stopped by the rule of the Outcome section): {cpu}; on the wall clock: {wall}.",
            match clock {
                crate::Clock::ThreadCpu => "timing thread's CPU-time",
                crate::Clock::Wall => "wall",
            },
            crate::harness::TIMING_MIN_REPEATS.min(results.config.timing_repeats),
            results.config.timing_repeats,
        );
    }
}

/// The outcome in words, from the rankings: how often an adaptive sampler is significantly
/// the most efficient, tied for best, significantly worse; one sentence per comparison naming
/// the results.csv rows (`index`) it rests on.
fn outcome(s: &mut String, results: &StudyResults) {
    s.push_str("## Outcome\n\n");
    if results.shard.is_some() {
        s.push_str("This is one shard: the rankings are made on the whole grid by `brdf-lab study merge`.\n\n");
    } else {
        let _ = writeln!(
            s,
            "Each comparison (BRDF, θo, light; estimator: BRDF sampling alone) names the most efficient sampler (lowest MSE × time at the budget N), the samplers **statistically tied** with it and the ones **significantly worse**: the ratio of efficiencies best / x has an interval that carries the MSE's uncertainty (its 95 % interval and the reference's error) and the time's (the spread of {}–{} interleaved timing repeats, stopped once the median's standard error is ≤ {} %, on the timing thread's CPU clock where the platform has one), at the Šidák-corrected level 1 − (1 − α)^(1/m) for the m comparisons with the best, family-wise α = {}; x is tied when the interval contains 1. `(rows …)` are the `index` values of results.csv (one row per N) the sentence rests on. † marks a verdict that the MSEs alone would not give (it rests on the measured times); ⚠ a cell whose spread estimate is unreliable (its interval is optimistic).\n",
            crate::harness::TIMING_MIN_REPEATS.min(results.config.timing_repeats),
            results.config.timing_repeats,
            crate::harness::TIMING_PRECISION * 100.0,
            crate::ranking::ALPHA,
        );
        let brdf_only: Vec<Ranking> = results
            .rankings
            .iter()
            .filter(|r| r.estimator == crate::ranking::ESTIMATOR_BRDF)
            .cloned()
            .collect();
        verdicts(s, &brdf_only);
        s.push_str(&crate::answers::family_answers(&brdf_only, &results.cells));
        mis_outcome(s, results);
    }
    let flagged: Vec<&CellResult> = results
        .cells
        .iter()
        .filter(|c| c.ok() && !c.warnings.is_empty())
        .collect();
    if !flagged.is_empty() {
        let _ = writeln!(
            s,
            "⚠ {} of {} cells that ran have an unreliable spread estimate (listed under each table); rankings that involve them are uncertain.\n",
            flagged.len(),
            results.cells.iter().filter(|c| c.ok()).count()
        );
    }
    let exact: Vec<String> = groups(results)
        .iter()
        .flat_map(|g| {
            g.cells
                .iter()
                .filter(|c| c.ok() && c.zero_variance)
                .map(|c| format!("{} ({}, row {})", c.label(), g.title(), c.index))
                .collect::<Vec<_>>()
        })
        .collect();
    if !exact.is_empty() {
        let _ = writeln!(
            s,
            "Zero variance (the sampler is exactly ∝ f·cos·L here — under constant light a correctness check, not a win): {}.\n",
            exact.join("; ")
        );
    }
}

/// How an adaptive sampler fares in one ranking.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AdaptiveOutcome {
    /// An adaptive sampler is best and no other family is tied with it.
    SignificantlyBest,
    /// An adaptive sampler is best or tied, and so is another family's.
    TiedForBest,
    /// Every adaptive sampler is significantly worse than the best.
    SignificantlyWorse,
}

/// The adaptive family's outcome in `r`; `None` when no adaptive sampler was ranked.
pub(crate) fn adaptive_outcome(r: &Ranking) -> Option<AdaptiveOutcome> {
    if !r.entries.iter().any(|e| is_adaptive(&e.sampler)) {
        return None;
    }
    let top: Vec<&str> = std::iter::once(r.best.as_str())
        .chain(r.tied.iter().map(String::as_str))
        .collect();
    Some(if !top.iter().any(|t| is_adaptive(t)) {
        AdaptiveOutcome::SignificantlyWorse
    } else if top.iter().all(|t| is_adaptive(t)) {
        AdaptiveOutcome::SignificantlyBest
    } else {
        AdaptiveOutcome::TiedForBest
    })
}

/// `r× [lo, hi]` of an entry's ratio to the best.
fn ratio_text(e: &Entry) -> String {
    match (e.ratio, e.ratio_lo, e.ratio_hi) {
        (Some(r), Some(lo), Some(hi)) => format!("{r:.2}× [{lo:.2}, {hi:.2}]"),
        _ => "∞× (the best is exact)".into(),
    }
}

/// The samplers of `r` tied with the best, each with its marks and its ratio's interval.
fn tied_samplers(r: &Ranking) -> Vec<String> {
    r.entries
        .iter()
        .filter(|e| e.verdict == Verdict::Tied)
        .map(|e| format!("{}{} ({})", e.sampler, marks(e), ratio_text(e)))
        .collect()
}

/// ` ⚠` and ` †` marks of an entry.
fn marks(e: &Entry) -> String {
    format!(
        "{}{}",
        if e.unreliable { " ⚠" } else { "" },
        if e.by_time { " †" } else { "" }
    )
}

/// The headline counts and one sentence per comparison.
pub(crate) fn verdicts(s: &mut String, rankings: &[Ranking]) {
    let outcomes: Vec<Option<AdaptiveOutcome>> = rankings.iter().map(adaptive_outcome).collect();
    let count = |o: AdaptiveOutcome| outcomes.iter().filter(|x| **x == Some(o)).count();
    let with = outcomes.iter().filter(|o| o.is_some()).count();
    let (wins, ties, losses) = (
        count(AdaptiveOutcome::SignificantlyBest),
        count(AdaptiveOutcome::TiedForBest),
        count(AdaptiveOutcome::SignificantlyWorse),
    );
    if with > 0 {
        let _ = writeln!(
            s,
            "**Headline** (significant results only): of {with} comparisons with an adaptive sampler, one is **significantly the most efficient in {wins}**, **tied for best in {ties}** (with another family's sampler inside the interval) and **significantly less efficient than the best in {losses}**.\n"
        );
    } else if !rankings.is_empty() {
        s.push_str("No comparison has a ranked adaptive sampler.\n\n");
    }
    for (r, o) in rankings.iter().zip(&outcomes) {
        let title = format!(
            "{} at θo = {}° under {}",
            crate::names::short_brdf(&r.brdf),
            r.theta_o,
            short_light(&r.light)
        );
        let Some(best) = r.entries.first() else {
            continue;
        };
        let tied = tied_samplers(r);
        let tied = if tied.is_empty() {
            "none tied".to_string()
        } else {
            format!("tied: {}", tied.join(", "))
        };
        let best_adaptive = r.entries.iter().find(|e| is_adaptive(&e.sampler));
        let runner_up = r.entries.get(1);
        let (sentence, rows) = match (o, best_adaptive) {
            (Some(AdaptiveOutcome::SignificantlyWorse), Some(a)) => (
                format!(
                    "**{}**{} is the most efficient ({tied}); the best adaptive sampler, {}{}, is {} less efficient",
                    best.sampler,
                    marks(best),
                    a.sampler,
                    marks(a),
                    ratio_text(a)
                ),
                vec![best.cell, a.cell],
            ),
            (Some(AdaptiveOutcome::SignificantlyBest), _) => (
                match runner_up {
                    Some(x) => format!(
                        "**{}**{} is significantly the most efficient ({tied}); the runner-up, {}{}, is {} less efficient",
                        best.sampler,
                        marks(best),
                        x.sampler,
                        marks(x),
                        ratio_text(x)
                    ),
                    None => format!(
                        "**{}**{} is the only sampler ranked",
                        best.sampler,
                        marks(best)
                    ),
                },
                std::iter::once(best.cell)
                    .chain(runner_up.map(|x| x.cell))
                    .collect(),
            ),
            _ => (
                format!(
                    "**{}**{} is the most efficient; {tied}",
                    best.sampler,
                    marks(best)
                ),
                r.entries
                    .iter()
                    .filter(|e| e.verdict != Verdict::Worse)
                    .map(|e| e.cell)
                    .collect(),
            ),
        };
        let rows: Vec<String> = rows.iter().map(usize::to_string).collect();
        let _ = writeln!(
            s,
            "* {title}: {sentence} (rows {}; {} comparisons, intervals at {:.2} %).",
            rows.join(", "),
            r.comparisons,
            100.0 * r.level
        );
    }
    if !rankings.is_empty() {
        s.push('\n');
    }
}

fn group_table(s: &mut String, g: &Group<'_>, n_max: usize, ranking: Option<&Ranking>) {
    let _ = writeln!(s, "### {}\n", g.title());
    if let Some(c) = g.cells.first() {
        let _ = writeln!(
            s,
            "Reference L_r = {:.6e} ± {:.1e} ({}).\n",
            c.reference.value, c.reference.abs_err, c.reference.method
        );
    }
    let _ = writeln!(
        s,
        "| row | sampler | rel. error at N = {n_max} | variance / sample | MSE / sample at N = {n_max} | evals / sample | memory | build † | ns / sample † (sampler / estimator [min–max]) | efficiency † | verdict | best / this [interval] |"
    );
    s.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for c in &g.cells {
        row(s, c, ranking.and_then(|r| r.entry(&c.label())));
    }
    s.push('\n');
    if let Some(r) = ranking {
        let _ = writeln!(
            s,
            "Verdicts: {} comparisons with the best, intervals at {:.2} % each (Šidák, family-wise {:.0} %).\n",
            r.comparisons,
            100.0 * r.level,
            100.0 * (1.0 - r.alpha)
        );
    }
    for c in g.cells.iter().filter(|c| c.ok() && !c.warnings.is_empty()) {
        let _ = writeln!(s, "* ⚠ {}: {}.", c.label(), c.warnings.join("; "));
    }
    if g.cells.iter().any(|c| c.ok() && !c.warnings.is_empty()) {
        s.push('\n');
    }
}

/// ` ⚠` for a cell whose spread estimate is unreliable.
fn flag(c: &CellResult) -> &'static str {
    if c.warnings.is_empty() { "" } else { " ⚠" }
}

fn row(s: &mut String, c: &CellResult, entry: Option<&Entry>) {
    if let Some(why) = &c.status {
        let _ = writeln!(
            s,
            "| {} | {} | — {why} | | | | | | | | | |",
            c.index,
            c.label()
        );
        return;
    }
    let e = c.final_error();
    let t = c.timing;
    let eff = t.and_then(|t| t.efficiency);
    let _ = writeln!(
        s,
        "| {} | {}{} | {} ± {} | {} | {} | {:.2} | {} | {} | {} | {} | {} | {} |",
        c.index,
        c.label(),
        flag(c),
        pct(e.map(|e| e.mean_rel_err)),
        pct(e.map(|e| e.ci95)),
        if c.zero_variance {
            "0 (exact)".to_string()
        } else {
            format!("{:.3e} ± {:.1e}", c.variance.value, c.variance.ci95)
        },
        if c.zero_variance {
            "0 (exact)".to_string()
        } else {
            format!(
                "{:.3e} ± {:.1e} (ref. ± {:.1e})",
                c.mse.value, c.mse.ci95, c.mse.reference_err
            )
        },
        c.evaluations_per_sample,
        bytes(c.bytes),
        t.map_or("—".into(), |t| format!("{:.3} s", t.build_seconds)),
        t.map_or("—".into(), |t| format!(
            "{:.0} / {:.0} [{:.0}–{:.0}]",
            t.sample_ns, t.estimator_ns, t.estimator_ns_min, t.estimator_ns_max
        )),
        eff.map_or("∞ (exact)".into(), |e| format!("{e:.3e}")),
        entry.map_or("—".into(), |e| format!(
            "{}{}",
            e.verdict.as_str(),
            if e.by_time { " †" } else { "" }
        )),
        entry.map_or("—".into(), |e| match e.verdict {
            Verdict::Best => "1".into(),
            _ => ratio_text(e),
        }),
    );
}

/// A fraction as a percentage with 2 decimals.
pub(crate) fn pct(x: Option<f64>) -> String {
    x.map_or("—".into(), |x| format!("{:.2} %", 100.0 * x))
}

/// Bytes in B / KiB / MiB.
pub(crate) fn bytes(b: usize) -> String {
    let b = b as f64;
    if b < 1024.0 {
        format!("{b} B")
    } else if b < 1024.0 * 1024.0 {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{:.2} MiB", b / 1024.0 / 1024.0)
    }
}

/// The light and MIS estimators in words (one sentence per material, map and map sampler):
/// "inside MIS (balance) under MAP, the best BRDF sampler for BRDF is X …", per θo, with the
/// results.csv rows (`index`) each ranking rests on; then the light-only comparisons. Nothing
/// when the study ran no such estimator.
pub(crate) fn mis_outcome(s: &mut String, results: &StudyResults) {
    let others: Vec<&Ranking> = results
        .rankings
        .iter()
        .filter(|r| r.estimator != crate::ranking::ESTIMATOR_BRDF)
        .collect();
    if others.is_empty() {
        return;
    }
    s.push_str("\n### Inside MIS and light sampling\n\n");
    s.push_str("Estimators as renderers use them, under the maps: each BRDF sampler inside multiple importance sampling with a map sampler (one draw of each per sample; balance or power heuristic), and each map sampler alone; same efficiency, intervals and Šidák rule as above, comparisons per (BRDF, θo, map, estimator, map sampler).\n\n");
    // The tied samplers with their ratio's interval, or (none tied) the runner-up's: every
    // "best" rests on an interval.
    let list = |r: &Ranking| {
        let tied = tied_samplers(r);
        match (tied.is_empty(), r.entries.get(1)) {
            (false, _) => format!("tied: {}", tied.join(", ")),
            (true, Some(e)) => format!(
                "none tied; the runner-up {}{} is {} less efficient",
                e.sampler,
                marks(e),
                ratio_text(e)
            ),
            (true, None) => "the only one ranked".to_string(),
        }
    };
    let cfg = &results.config;
    for estimator in ["mis-balance", "mis-power"] {
        for light in &cfg.lights {
            for brdf in &cfg.brdfs {
                for ls in &cfg.light_samplers {
                    let parts: Vec<String> = others
                        .iter()
                        .filter(|r| {
                            r.estimator == estimator
                                && &r.light == light
                                && &r.brdf == brdf
                                && r.light_sampler.as_deref() == Some(ls.as_str())
                        })
                        .map(|r| {
                            format!(
                                "at θo = {}° **{}** ({}; rows {})",
                                r.theta_o,
                                r.best,
                                list(r),
                                r.rows_text()
                            )
                        })
                        .collect();
                    if parts.is_empty() {
                        continue;
                    }
                    let _ = writeln!(
                        s,
                        "* Inside MIS ({}) under {} with `{ls}`, the best BRDF sampler for `{}` is {}.",
                        estimator.trim_start_matches("mis-"),
                        crate::names::short_light(light),
                        crate::names::short_brdf(brdf),
                        parts.join("; ")
                    );
                }
            }
        }
    }
    for r in others
        .iter()
        .filter(|r| r.estimator == crate::ranking::ESTIMATOR_LIGHT)
    {
        let _ = writeln!(
            s,
            "* Light sampling alone under {} for `{}` at θo = {}°: the best map sampler is **{}** ({}; rows {}).",
            crate::names::short_light(&r.light),
            crate::names::short_brdf(&r.brdf),
            r.theta_o,
            r.best,
            list(r),
            r.rows_text()
        );
    }
    s.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ranking::synthetic::cell;
    use crate::ranking::{ALPHA, ESTIMATOR_BRDF, rank_cells};

    /// Four comparisons in which an adaptive sampler has the best point estimate in three:
    /// a clear win, a win inside the intervals of another family's sampler (a tie), a tie in
    /// which another family leads, and a clear loss. The headline counts 1 win, 2 ties,
    /// 1 loss — not 3 wins of 4 — and every sentence names its rows.
    #[test]
    fn the_headline_counts_only_significant_wins_and_losses() {
        let comparisons = [
            // Clear win.
            vec![
                cell(0, "adaptive", "ggx", 1.0, 0.05, 100.0, 0.02),
                cell(1, "cosine", "ggx", 4.0, 0.2, 100.0, 0.02),
            ],
            // Point-estimate win, tied with analytic.
            vec![
                cell(2, "adaptive-paper (batch)", "phong", 1.0, 0.4, 100.0, 0.02),
                cell(3, "analytic", "phong", 1.2, 0.3, 100.0, 0.02),
                cell(4, "uniform", "phong", 40.0, 2.0, 100.0, 0.02),
            ],
            // Analytic leads, adaptive tied.
            vec![
                cell(5, "analytic", "ward", 1.0, 0.3, 100.0, 0.02),
                cell(6, "adaptive", "ward", 1.1, 0.3, 100.0, 0.02),
            ],
            // Clear loss.
            vec![
                cell(7, "lobe-sphere", "cook-torrance", 1.0, 0.05, 100.0, 0.02),
                cell(
                    8,
                    "adaptive-mixture",
                    "cook-torrance",
                    2.0,
                    0.1,
                    100.0,
                    0.02,
                ),
            ],
        ];
        let rankings: Vec<Ranking> = comparisons
            .iter()
            .map(|cells| {
                let refs: Vec<&CellResult> = cells.iter().collect();
                rank_cells(&refs, ESTIMATOR_BRDF, ALPHA, true).unwrap()
            })
            .collect();
        let outcomes: Vec<_> = rankings.iter().map(adaptive_outcome).collect();
        assert_eq!(
            outcomes,
            [
                Some(AdaptiveOutcome::SignificantlyBest),
                Some(AdaptiveOutcome::TiedForBest),
                Some(AdaptiveOutcome::TiedForBest),
                Some(AdaptiveOutcome::SignificantlyWorse),
            ]
        );
        let mut s = String::new();
        verdicts(&mut s, &rankings);
        assert!(
            s.contains("of 4 comparisons with an adaptive sampler, one is **significantly the most efficient in 1**, **tied for best in 2**")
                && s.contains("**significantly less efficient than the best in 1**"),
            "{s}"
        );
        let sentences: Vec<&str> = s.lines().filter(|l| l.starts_with("* ")).collect();
        assert_eq!(sentences.len(), 4);
        assert!(sentences[0].contains("(rows 0, 1;"), "{}", sentences[0]);
        assert!(sentences[1].contains("(rows 2, 3;"), "{}", sentences[1]);
        assert!(sentences[3].contains("(rows 7, 8;"), "{}", sentences[3]);
        assert!(sentences[3].contains("the best adaptive sampler, adaptive-mixture, is 2.00× ["));
    }

    /// Measured files and maps are named by their short names in every line of the report
    /// (header, warnings, verdicts, tables) and in results.csv; the full path is kept in
    /// results.json only, and no output has a `../` path.
    #[test]
    fn the_report_and_csv_name_measured_files_without_their_paths() {
        let spec = "rgl:/data/team/shared/data/measured/rgl/paper_white_rgb.bsdf";
        let map = "envmap:/data/team/shared/data/envmaps/grace_probe_latlong.hdr";
        let mut cells = vec![
            cell(0, "adaptive", spec, 1.0, 0.05, 100.0, 0.02),
            cell(1, "cosine", spec, 4.0, 0.2, 100.0, 0.02),
        ];
        for c in &mut cells {
            c.light = map.into();
        }
        // The same two samplers inside MIS with a map sampler: a comparison of its own.
        for i in 0..2 {
            let mut c = cells[i].clone();
            c.index = 2 + i;
            c.estimator = "mis-balance".into();
            c.light_sampler = Some("envmap-cdf".into());
            cells.push(c);
        }
        let config = crate::StudyConfig::new(
            vec!["adaptive".into(), "cosine".into()],
            vec![spec.into()],
            vec![30.0],
            vec![map.into()],
        );
        let mut results = StudyResults {
            schema: crate::SCHEMA.into(),
            config,
            shard: None,
            total_cells: 4,
            notes: Vec::new(),
            build_warnings: vec!["sampler srbf on rgl:paper_white_rgb: a warning".into()],
            lights: vec![crate::LightInfo {
                spec: map.into(),
                description: "a map".into(),
            }],
            cells,
            runs: Vec::new(),
            rankings: Vec::new(),
        };
        results.rankings = crate::ranking::rankings(&results);
        assert_eq!(results.rankings.len(), 2);
        let md = report_markdown(&results, &ReportAssets::default());
        // The MIS sentence names the best with the runner-up's ratio and its interval.
        let mis = md
            .lines()
            .find(|l| l.starts_with("* Inside MIS (balance)"))
            .unwrap_or_else(|| panic!("{md}"));
        assert!(
            mis.contains("for `rgl:paper_white_rgb` is at θo = 30° **adaptive** (none tied; the runner-up cosine is 4.00× [")
                && mis.contains("] less efficient; rows 2, 3)"),
            "{mis}"
        );
        assert!(md.contains("`rgl:paper_white_rgb`"), "{md}");
        assert!(
            md.contains("* rgl:paper_white_rgb at θo = 30° under envmap:grace_probe_latlong.hdr"),
            "{md}"
        );
        let csv = results.to_csv();
        for (name, text) in [("report.md", &md), ("results.csv", &csv)] {
            assert!(!text.contains("/data/team"), "{name} has a path");
            assert!(!text.contains("../"), "{name} has a ../ path");
        }
        assert!(csv.contains(",rgl:paper_white_rgb,"));
        assert!(results.to_json().contains(spec));
    }
}
