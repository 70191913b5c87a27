//! The report of a run: JSON (the schema of docs/validation.md, plus extra fields) and markdown.

use std::fmt::Write as _;

use serde::{Deserialize, Deserializer, Serialize};

use crate::case::names;
use stats::{TestOutcome, sidak_level};

/// A number written as `null` when not finite (serde_json's way) read back as NaN.
fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// One test of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestRecord {
    /// Index of the case in the run's full plan (fixed order; the unit of `--shard K/N`).
    #[serde(default)]
    pub case: usize,
    /// BRDF spec, or the target of a standalone sampler (e.g. `map:procedural-sky-128x64`).
    pub brdf: String,
    /// Sampler name.
    pub sampler: String,
    /// Outgoing polar angle in degrees (`null` for standalone samplers).
    pub theta_o: Option<f64>,
    /// Test name (`chi-square`, `ks-phi`, `unbiasedness`, ...).
    pub test: String,
    /// The statistic (`null` in JSON when not finite; read back as NaN).
    #[serde(deserialize_with = "nan_if_null")]
    pub statistic: f64,
    /// p-value of statistical tests; `null` for deterministic checks.
    pub p_value: Option<f64>,
    /// Whether the test passed (p-values judged at the Šidák per-test level).
    pub passed: bool,
    /// Domain the sampler was tested on.
    pub domain: String,
    /// Human-readable details.
    pub detail: String,
}

impl TestRecord {
    /// A record from a stats outcome.
    pub fn new(
        brdf: &str,
        sampler: &str,
        theta_o: Option<f64>,
        domain: &str,
        o: &TestOutcome,
    ) -> Self {
        Self {
            case: 0,
            brdf: brdf.to_owned(),
            sampler: sampler.to_owned(),
            theta_o,
            test: o.name.clone(),
            statistic: o.statistic,
            p_value: o.p_value,
            passed: o.passed,
            domain: domain.to_owned(),
            detail: o.detail.clone(),
        }
    }

    /// A NaN p-value becomes no p-value, the test failed (see [`ValidationReport::judged`]).
    fn drop_nan_p_value(&mut self) {
        if self.p_value.is_some_and(f64::is_nan) {
            self.p_value = None;
            self.passed = false;
            self.detail.push_str(" (p-value NaN: the test failed)");
        }
    }

    /// Re-judges a p-valued record at `level` (deterministic ones keep their verdict).
    pub(crate) fn judge(&mut self, level: f64) {
        if let Some(p) = self.p_value {
            self.passed = p >= level;
        }
    }
}

/// The outcome of one mutant and its control.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MutantRecord {
    /// Index of the mutant's case in the run's full plan (the mutants come last).
    #[serde(default)]
    pub case: usize,
    /// Mutant name.
    pub name: String,
    /// Whether at least one test rejected the mutant.
    pub detected: bool,
    /// The tests that rejected it.
    pub caught_by: Vec<String>,
    /// Smallest p-value among its tests (`null` if none).
    pub min_p_value: Option<f64>,
    /// Whether the unbroken base passed every test in the same setting.
    pub control_passed: bool,
    /// The bug.
    pub description: String,
    /// BRDF of the setting.
    pub brdf: String,
    /// Outgoing angle of the setting.
    pub theta_o: f64,
    /// The mutant's tests.
    pub tests: Vec<TestRecord>,
    /// The control's tests.
    pub control_tests: Vec<TestRecord>,
}

/// A warning of a sampler's build (its `build_report`'s `warning: …` lines, e.g. `srbf`
/// slice fits stopped at the iteration cap unconverged).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct BuildWarning {
    /// The first case (in the plan's order) of the build.
    pub case: usize,
    /// `sampler NAME on SPEC: …`.
    pub message: String,
}

/// What a shard's report (`validate --shard K/N --json`) says about the run it is part of.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// `K` of `K/N`, from 1.
    pub index: usize,
    /// `N` of `K/N`.
    pub count: usize,
    /// Cases of the full plan (every shard's, mutants included).
    pub total_cases: usize,
    /// Cases of this shard.
    pub cases: usize,
    /// Hash (hex FNV-1a) of the configuration and of the full plan's case labels: shards of
    /// different runs (or that found different data files) do not merge.
    pub fingerprint: String,
}

/// The report of a validation run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidationReport {
    /// Family-wise significance level.
    pub alpha: f64,
    /// Every test passed (and, with mutants, every mutant was caught and every control passed),
    /// and at least one test ran: a run whose every case was skipped did not pass.
    pub passed: bool,
    /// Every test of every case, in a fixed order.
    pub tests: Vec<TestRecord>,
    /// Mutants (empty unless requested).
    pub mutants: Vec<MutantRecord>,
    /// `quick` or `full`.
    pub tier: String,
    /// Master seed.
    pub seed: u64,
    /// One-sample draws per case.
    pub samples: usize,
    /// Batches per case and their size.
    pub batches: [usize; 2],
    /// Number of p-valued tests in the family (cases and mutant controls).
    pub m: usize,
    /// Šidák per-test level `1 − (1 − α)^{1/m}`.
    pub per_test_level: f64,
    /// Warnings of the samplers' builds, in case order (absent from the JSON when none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<BuildWarning>,
    /// Set in a shard's report only (absent from a whole run's and a merged report's JSON).
    /// A shard's `passed`, `m` and `per_test_level` cover its own tests only: the run's
    /// verdict is the merge's ([`crate::merge`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardInfo>,
}

fn fmt_num(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else if x.is_infinite() {
        if x > 0.0 {
            "∞".into()
        } else {
            "−∞".into()
        }
    } else if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e-3 && x.abs() < 1e5 {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

fn fmt_p(p: Option<f64>) -> String {
    match p {
        None => "—".into(),
        Some(0.0) => "0".into(),
        Some(p) if p >= 1e-3 => format!("{p:.4}"),
        Some(p) => format!("{p:.2e}"),
    }
}

fn fmt_theta(t: Option<f64>) -> String {
    t.map_or_else(|| "—".into(), |t| format!("{t}°"))
}

impl MutantRecord {
    /// Re-judges the mutant's and its control's tests at `level` and derives the verdicts
    /// (`detected`, `caught_by`, `min_p_value`, `control_passed`) from them.
    fn judge(&mut self, level: f64) {
        self.tests.iter_mut().for_each(|t| t.judge(level));
        self.control_tests.iter_mut().for_each(|t| t.judge(level));
        self.caught_by = self
            .tests
            .iter()
            .filter(|t| !t.passed && t.test != names::BUILD)
            .map(|t| t.test.clone())
            .collect();
        self.detected = !self.caught_by.is_empty();
        self.min_p_value = self
            .tests
            .iter()
            .filter_map(|t| t.p_value)
            .min_by(f64::total_cmp);
        self.control_passed = self.control_tests.iter().all(|t| t.passed);
    }
}

impl ValidationReport {
    /// Judges the report's tests together: `m` = the p-valued tests of the cases and of the
    /// mutants' controls, every p-value at the Šidák level `1 − (1 − α)^{1/m}`, the mutants'
    /// verdicts, and `passed` (every test passed, every mutant caught with its control
    /// passing, and at least one test ran). A single run and [`crate::merge`] both end here.
    ///
    /// A statistical test whose p-value is not finite (NaN) has no p-value: it becomes a failed
    /// test outside the family (`p_value` `None`, which is also what its JSON `null` reads back
    /// as), so a merge of the shards' JSON counts the same `m` and gives the same verdict as
    /// the single run.
    pub(crate) fn judged(mut self) -> Self {
        // Several shards may build the same sampler: one warning per build.
        self.warnings.sort();
        self.warnings.dedup();
        self.tests
            .iter_mut()
            .chain(
                self.mutants
                    .iter_mut()
                    .flat_map(|m| m.tests.iter_mut().chain(m.control_tests.iter_mut())),
            )
            .for_each(TestRecord::drop_nan_p_value);
        self.m = self
            .tests
            .iter()
            .chain(self.mutants.iter().flat_map(|m| m.control_tests.iter()))
            .filter(|t| t.p_value.is_some())
            .count();
        let level = sidak_level(self.alpha, self.m);
        self.per_test_level = level;
        self.tests.iter_mut().for_each(|t| t.judge(level));
        self.mutants.iter_mut().for_each(|m| m.judge(level));
        // A run in which every case was skipped (or that had no case) tested nothing: not a
        // pass.
        let ran = self.tests.iter().any(|t| t.test != names::SKIPPED);
        self.passed = ran
            && self.tests.iter().all(|t| t.passed)
            && self.mutants.iter().all(|m| m.detected && m.control_passed);
        self
    }

    /// Whether the run passed: every test, and with mutants every detection and control.
    pub fn passed(&self) -> bool {
        self.passed
    }

    /// The records of the cases skipped because the sampler does not apply to the target (one
    /// per case, with the reason in its `detail`).
    pub fn skipped(&self) -> impl Iterator<Item = &TestRecord> {
        self.tests.iter().filter(|t| t.test == names::SKIPPED)
    }

    /// The number of skipped cases ([`Self::skipped`]).
    pub fn skipped_cases(&self) -> usize {
        self.skipped().count()
    }

    /// The number of tests that ran (every record but the skipped cases').
    pub fn tests_run(&self) -> usize {
        self.tests.len() - self.skipped_cases()
    }

    /// The failed tests of the correct samplers.
    pub fn failures(&self) -> impl Iterator<Item = &TestRecord> {
        self.tests.iter().filter(|t| !t.passed)
    }

    /// JSON with the schema of docs/validation.md
    /// (`{"alpha", "passed", "tests": [{"brdf", "sampler", "theta_o", "test", "statistic",
    /// "p_value", "passed"}], "mutants": [{"name", "detected"}]}`) plus extra fields
    /// (`domain`, `detail`, `caught_by`, `control_passed`, the tier and sample counts).
    /// Non-finite statistics are written as `null`.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self)
            .unwrap_or_else(|e| format!("{{\"error\": \"serialisation failed: {e}\"}}"))
    }

    /// A readable markdown report: a summary, a table of every test with its statistic and
    /// p-value, the mutant table, and the details of every failure.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# brdf-lab validate — {} tier\n", self.tier);
        let failed = self.tests.iter().filter(|t| !t.passed).count();
        let run = self.tests_run();
        let skipped = match self.skipped_cases() {
            0 => String::new(),
            1 => ", 1 case skipped (the sampler does not apply)".to_string(),
            k => format!(", {k} cases skipped (the sampler does not apply)"),
        };
        let _ = writeln!(
            s,
            "**Result: {}** — {} run{skipped}, {} failed; family-wise α = {}, Šidák per-test level {:.3e} over m = {} p-valued tests; seed {}, {} one-sample draws per case plus {} batches of {}.\n",
            if run == 0 {
                "NO TEST RAN"
            } else if self.passed {
                "PASSED"
            } else {
                "FAILED"
            },
            if run == 1 {
                "1 test".to_string()
            } else {
                format!("{run} tests")
            },
            failed,
            self.alpha,
            self.per_test_level,
            self.m,
            self.seed,
            self.samples,
            self.batches[0],
            self.batches[1]
        );
        if !self.warnings.is_empty() {
            let _ = writeln!(s, "## Build warnings\n");
            for w in &self.warnings {
                let _ = writeln!(s, "- {}", w.message);
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(s, "## Tests\n");
        table(&mut s, &self.tests);
        if !self.mutants.is_empty() {
            let _ = writeln!(s, "\n## Mutants\n");
            let _ = writeln!(
                s,
                "| mutant | setting | bug | detected | caught by | min p | control passes |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|---|");
            for m in &self.mutants {
                let _ = writeln!(
                    s,
                    "| {} | {} at {}° | {} | {} | {} | {} | {} |",
                    m.name,
                    m.brdf,
                    m.theta_o,
                    m.description,
                    if m.detected { "yes" } else { "**NO**" },
                    if m.caught_by.is_empty() {
                        "—".to_owned()
                    } else {
                        m.caught_by.join(", ")
                    },
                    fmt_p(m.min_p_value),
                    if m.control_passed { "yes" } else { "**NO**" }
                );
            }
            for m in &self.mutants {
                let _ = writeln!(
                    s,
                    "\n### Mutant `{}` ({} at {}°)\n",
                    m.name, m.brdf, m.theta_o
                );
                table(&mut s, &m.tests);
            }
        }
        let fails: Vec<&TestRecord> = self
            .tests
            .iter()
            .chain(self.mutants.iter().flat_map(|m| m.control_tests.iter()))
            .filter(|t| !t.passed)
            .collect();
        if !fails.is_empty() {
            let _ = writeln!(s, "\n## Failures\n");
            for t in fails {
                let _ = writeln!(
                    s,
                    "- **{}** / {} / {}: `{}` — {}",
                    t.sampler,
                    t.brdf,
                    fmt_theta(t.theta_o),
                    t.test,
                    t.detail
                );
            }
        }
        s
    }
}

fn table(s: &mut String, rows: &[TestRecord]) {
    let _ = writeln!(
        s,
        "| sampler | target | θo | test | statistic | p-value | result |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for t in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} |",
            t.sampler,
            t.brdf,
            fmt_theta(t.theta_o),
            t.test,
            fmt_num(t.statistic),
            fmt_p(t.p_value),
            if t.passed { "pass" } else { "**FAIL**" }
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_formatted_for_tables() {
        assert_eq!(fmt_num(f64::INFINITY), "∞");
        assert_eq!(fmt_num(f64::NAN), "—");
        assert_eq!(fmt_num(0.5), "0.5000");
        assert_eq!(fmt_num(1.5e-7), "1.500e-7");
        assert_eq!(fmt_p(None), "—");
        assert_eq!(fmt_p(Some(0.25)), "0.2500");
        assert_eq!(fmt_p(Some(2e-9)), "2.00e-9");
        assert_eq!(fmt_theta(Some(45.0)), "45°");
    }

    #[test]
    fn non_finite_statistics_serialise_as_null() {
        let o = TestOutcome::with_p_value("chi-square", f64::INFINITY, 0.0, 0.01, "x".into());
        let r = TestRecord::new("lambert", "s", None, "disc", &o);
        let v: serde_json::Value =
            serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        assert!(v["statistic"].is_null() && v["theta_o"].is_null());
        assert_eq!(v["p_value"], 0.0);
    }
}
