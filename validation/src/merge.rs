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
    for (_, p) in parts {
        tests.extend(p.tests);
        mutants.extend(p.mutants);
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
    header.shard = None;
    Ok(header.judged())
}
