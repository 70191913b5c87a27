//! Recombining the parts of a sharded run (`validate --shard K/N --json PART`) into the
//! single run's report.

use std::collections::{BTreeMap, BTreeSet};

use crate::error::MergeError;
use crate::report::{ShardInfo, ValidationReport};

/// Merges the reports of the `N` shards of one run (each named for the errors, e.g. by its
/// file) into the report the single run makes: the records of every case in the plan's order,
/// judged together (Šidák over the union of the tests, exactly as a single run judges them).
///
/// # Errors
/// [`MergeError`] when no part is given, a part is not a shard's, the parts come from
/// different configurations or shard counts, a shard is given twice or missing, or the parts
/// together do not hold every case of the plan.
pub fn merge(parts: Vec<(String, ValidationReport)>) -> Result<ValidationReport, MergeError> {
    let infos: Vec<ShardInfo> = parts
        .iter()
        .map(|(name, p)| {
            p.shard
                .clone()
                .ok_or_else(|| MergeError::NotAShard(name.clone()))
        })
        .collect::<Result<_, _>>()?;
    let (Some(first), Some((first_name, _))) = (infos.first(), parts.first()) else {
        return Err(MergeError::NoParts);
    };
    let mut seen: BTreeMap<usize, &str> = BTreeMap::new();
    for (info, (name, _)) in infos.iter().zip(&parts) {
        if info.fingerprint != first.fingerprint || info.total_cases != first.total_cases {
            return Err(MergeError::ConfigMismatch {
                first: first_name.clone(),
                part: name.clone(),
                expected: first.fingerprint.clone(),
                got: info.fingerprint.clone(),
            });
        }
        if info.count != first.count {
            return Err(MergeError::CountMismatch {
                first: first_name.clone(),
                part: name.clone(),
                expected: first.count,
                got: info.count,
            });
        }
        if let Some(other) = seen.insert(info.index, name) {
            return Err(MergeError::Duplicate {
                index: info.index,
                count: info.count,
                first: other.to_owned(),
                second: name.clone(),
            });
        }
    }
    let missing: Vec<usize> = (1..=first.count)
        .filter(|k| !seen.contains_key(k))
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing {
            missing,
            count: first.count,
        });
    }
    let total_cases = first.total_cases;
    let mut header = parts[0].1.clone();
    let mut tests = Vec::new();
    let mut mutants = Vec::new();
    let mut warnings = Vec::new();
    for (_, p) in parts {
        tests.extend(p.tests);
        mutants.extend(p.mutants);
        warnings.extend(p.warnings);
    }
    // Each case lies in one shard: a stable sort by case restores the single run's order.
    tests.sort_by_key(|t| t.case);
    mutants.sort_by_key(|m| m.case);
    let cases: BTreeSet<usize> = tests
        .iter()
        .map(|t| t.case)
        .chain(mutants.iter().map(|m| m.case))
        .collect();
    if cases.len() != total_cases || cases.last().is_some_and(|&c| c >= total_cases) {
        return Err(MergeError::Incomplete {
            got: cases.len(),
            expected: total_cases,
        });
    }
    header.tests = tests;
    header.mutants = mutants;
    header.warnings = warnings;
    header.shard = None;
    Ok(header.judged())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::TestRecord;
    use stats::{TestOutcome, sidak_level};

    fn record(case: usize, p: f64) -> TestRecord {
        let o = TestOutcome::with_p_value("chi-square", 1.0, p, 0.01, String::new());
        TestRecord {
            case,
            ..TestRecord::new("lambert", "s", Some(0.0), "hemisphere", &o)
        }
    }

    fn part(index: usize, tests: Vec<TestRecord>) -> (String, ValidationReport) {
        let cases = tests.iter().map(|t| t.case).collect::<BTreeSet<_>>().len();
        let r = ValidationReport {
            alpha: 0.01,
            passed: false,
            tests,
            mutants: Vec::new(),
            tier: "quick".into(),
            seed: 1,
            samples: 2000,
            batches: [50, 256],
            m: 0,
            per_test_level: 0.0,
            warnings: Vec::new(),
            shard: Some(ShardInfo {
                index,
                count: 2,
                total_cases: 3,
                cases,
                fingerprint: "f".into(),
            }),
        };
        (format!("part{index}"), r.judged())
    }

    #[test]
    fn the_merge_judges_the_union_at_its_sidak_level() {
        // Alone, shard 1 judges p = 0.003 at the level of m = 1 (0.01): failed. Over the
        // union (m = 4, level ≈ 0.0025) it passes, as in the single run.
        let p1 = part(1, vec![record(0, 0.003), record(2, 0.5)]);
        assert!(!p1.1.passed && !p1.1.tests[0].passed);
        let p2 = part(2, vec![record(1, 0.5), record(1, 0.6)]);
        let merged = merge(vec![p2.clone(), p1.clone()]).unwrap();
        assert_eq!(merged.m, 4);
        assert_eq!(merged.per_test_level, sidak_level(0.01, 4));
        assert!(merged.passed && merged.tests.iter().all(|t| t.passed));
        assert_eq!(
            merged.tests.iter().map(|t| t.case).collect::<Vec<_>>(),
            [0, 1, 1, 2]
        );
        assert!(merged.shard.is_none());

        assert!(matches!(merge(Vec::new()), Err(MergeError::NoParts)));
        assert!(matches!(
            merge(vec![p1.clone()]),
            Err(MergeError::Missing { missing, count: 2 }) if missing == [2]
        ));
        let mut truncated = p2.clone();
        truncated.1.tests.clear();
        assert!(matches!(
            merge(vec![p1.clone(), truncated]),
            Err(MergeError::Incomplete {
                got: 2,
                expected: 3
            })
        ));
        let mut other = p2.clone();
        other.1.shard.as_mut().unwrap().fingerprint = "g".into();
        assert!(matches!(
            merge(vec![p1.clone(), other]),
            Err(MergeError::ConfigMismatch { .. })
        ));
        let mut whole = p2.clone();
        whole.1.shard = None;
        assert!(matches!(
            merge(vec![p1, whole]),
            Err(MergeError::NotAShard(_))
        ));
    }

    #[test]
    fn a_nan_p_value_gives_the_single_runs_verdict_after_json() {
        // A NaN p-value is written as `null` in a shard's JSON; the merge must count the same
        // family (m) and reach the same verdict as the single run over the same records.
        let (nan, low) = (record(0, f64::NAN), record(2, 0.0023));
        let others = [record(1, 0.5), record(1, 0.6), record(1, 0.7)];
        let single = ValidationReport {
            tests: vec![
                nan.clone(),
                others[0].clone(),
                others[1].clone(),
                others[2].clone(),
                low.clone(),
            ],
            shard: None,
            ..part(1, Vec::new()).1
        }
        .judged();
        let through_json = |(name, r): (String, ValidationReport)| {
            let back: ValidationReport = serde_json::from_str(&r.to_json()).unwrap();
            (name, back)
        };
        let warn = |case| crate::report::BuildWarning {
            case,
            message: "sampler srbf on phong: 1 of 2 BRDF slice fits hit the iteration cap".into(),
        };
        let with_warnings = |(name, mut r): (String, ValidationReport), w: Vec<_>| {
            r.warnings = w;
            (name, r)
        };
        let single = ValidationReport {
            warnings: vec![warn(0), warn(1)],
            ..single
        }
        .judged();
        // Both shards built the sampler of case 1's job: the merge keeps one warning.
        let merged = merge(vec![
            through_json(with_warnings(
                part(1, vec![nan, low]),
                vec![warn(1), warn(0)],
            )),
            through_json(with_warnings(part(2, others.to_vec()), vec![warn(1)])),
        ])
        .unwrap();
        assert_eq!(merged.m, single.m);
        assert_eq!(merged.warnings, single.warnings);
        assert_eq!(merged.per_test_level, single.per_test_level);
        assert_eq!(merged.passed, single.passed);
        let verdicts = |r: &ValidationReport| {
            r.tests
                .iter()
                .map(|t| (t.case, t.passed))
                .collect::<Vec<_>>()
        };
        assert_eq!(verdicts(&merged), verdicts(&single));
        // The NaN test failed in both, and p = 0.0023 fails at the level of m = 4 (≈ 0.00251)
        // but would pass at that of m = 5 (≈ 0.00201): the family sizes matter.
        assert_eq!(single.m, 4);
        assert!(!single.passed && !single.tests[0].passed);
        assert!(!single.tests.iter().find(|t| t.case == 2).unwrap().passed);
    }
}
