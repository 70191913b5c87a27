//! The study's `report.md`: setup, the honest outcome, one table per (light, BRDF, θo), and
//! the plots and images the caller wrote.

use std::fmt::Write as _;

use crate::groups::{Group, groups, is_adaptive, short_light};
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
        "Samplers: {}. BRDFs: {}. θo: {} (φo = 0). N ∈ {{{}}}, {} repetitions per N, {} one-sample values for the variance, seed {}, {} outgoing slices for the adaptive sets. {} cells{}.\n",
        cfg.samplers.join(", "),
        cfg.brdfs
            .iter()
            .map(|b| format!("`{b}`"))
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
    s.push_str("## Lights\n\n");
    for l in &results.lights {
        let _ = writeln!(s, "* `{}`: {}", short_light(&l.spec), l.description);
    }
    s.push_str(concat!(
        "\n## What is measured\n\n",
        "For each cell the estimator of L_r(ωo) = ∫ f_r L cosθ dσ is (1/N) Σ Y(f_r ⊙ L) cosθ / p_σ with the sampler's ",
        "solid-angle pdf (samples below the horizon count 0). *Relative error* is the mean over the repetitions of ",
        "|L̂ − L_ref| / L_ref (± half-width of the 95 % interval). *Variance* is the per-sample variance of the estimator ",
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
        group_table(&mut s, &g, cfg.n_grid.last().copied().unwrap_or(0));
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

/// The outcome in words: the most efficient sampler per group, and where the adaptive family
/// loses, by how much.
fn outcome(s: &mut String, results: &StudyResults) {
    s.push_str("## Outcome\n\n");
    let mut wins = 0;
    let mut losses = Vec::new();
    let mut exact = Vec::new();
    for g in groups(results) {
        for c in g.cells.iter().filter(|c| c.ok() && c.zero_variance) {
            exact.push(format!("{} ({})", c.label(), g.title()));
        }
        let ranked = g.by_efficiency();
        let Some((best, best_eff)) = ranked.first() else {
            continue;
        };
        let best_adaptive = ranked.iter().find(|(c, _)| is_adaptive(&c.sampler));
        match best_adaptive {
            Some(_) if is_adaptive(&best.sampler) => wins += 1,
            Some((a, eff)) => losses.push(format!(
                "* {}: **{}**{} is the most efficient; the best adaptive sampler, {}{}, is {:.2}× less efficient{} (relative error at N = {}: {} vs {}).",
                g.title(),
                best.label(),
                flag(best),
                a.label(),
                flag(a),
                best_eff / eff,
                if significant(best, a, best_eff / eff) {
                    ""
                } else {
                    ", within the 95 % intervals of their MSEs"
                },
                a.final_error().map_or(0, |e| e.n),
                pct(a.final_error().map(|e| e.mean_rel_err)),
                pct(best.final_error().map(|e| e.mean_rel_err)),
            )),
            None => {}
        }
    }
    let total = wins + losses.len();
    if total > 0 {
        let _ = writeln!(
            s,
            "An adaptive sampler is the most efficient (lowest MSE × time at the budget N) in **{wins} of {total}** comparisons.{}\n",
            if losses.is_empty() {
                ""
            } else {
                " Where it loses:"
            }
        );
        for l in &losses {
            let _ = writeln!(s, "{l}");
        }
        if !losses.is_empty() {
            s.push('\n');
        }
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
    if !exact.is_empty() {
        let _ = writeln!(
            s,
            "Zero variance (the sampler is exactly ∝ f·cos·L here — under constant light a correctness check, not a win): {}.\n",
            exact.join("; ")
        );
    }
}

fn group_table(s: &mut String, g: &Group<'_>, n_max: usize) {
    let _ = writeln!(s, "### {}\n", g.title());
    if let Some(c) = g.cells.first() {
        let _ = writeln!(
            s,
            "Reference L_r = {:.6e} ± {:.1e} ({}).\n",
            c.reference.value, c.reference.abs_err, c.reference.method
        );
    }
    let best = g.by_efficiency().first().map(|b| b.1);
    let _ = writeln!(
        s,
        "| sampler | rel. error at N = {n_max} | variance / sample | MSE / sample at N = {n_max} | evals / sample | memory | build † | ns / sample † (sampler / estimator) | efficiency † | vs best |"
    );
    s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
    for c in &g.cells {
        row(s, c, best);
    }
    s.push('\n');
    for c in g.cells.iter().filter(|c| c.ok() && !c.warnings.is_empty()) {
        let _ = writeln!(s, "* ⚠ {}: {}.", c.label(), c.warnings.join("; "));
    }
    if g.cells.iter().any(|c| c.ok() && !c.warnings.is_empty()) {
        s.push('\n');
    }
}

/// Whether an efficiency ratio `ratio` ≥ 1 between cells `a` and `b` exceeds the combined
/// 95 % half-width of their MSEs (relative, in quadrature; timings taken as exact).
fn significant(a: &CellResult, b: &CellResult, ratio: f64) -> bool {
    let rel = |c: &CellResult| {
        if c.mse.value > 0.0 {
            c.mse.ci95 / c.mse.value
        } else {
            0.0
        }
    };
    ratio - 1.0 > (rel(a).powi(2) + rel(b).powi(2)).sqrt()
}

/// ` ⚠` for a cell whose spread estimate is unreliable.
fn flag(c: &CellResult) -> &'static str {
    if c.warnings.is_empty() { "" } else { " ⚠" }
}

fn row(s: &mut String, c: &CellResult, best: Option<f64>) {
    if let Some(why) = &c.status {
        let _ = writeln!(s, "| {} | — {why} | | | | | | | | |", c.label());
        return;
    }
    let e = c.final_error();
    let t = c.timing;
    let eff = t.and_then(|t| t.efficiency);
    let _ = writeln!(
        s,
        "| {}{} | {} ± {} | {} | {} | {:.2} | {} | {} | {} | {} | {} |",
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
            "{:.0} / {:.0}",
            t.sample_ns, t.estimator_ns
        )),
        eff.map_or("∞ (exact)".into(), |e| format!("{e:.3e}")),
        match (eff, best) {
            (Some(e), Some(b)) if e > 0.0 => format!("{:.2}×", b / e),
            _ => "—".into(),
        },
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
