//! Merging the results of shards (`study --shard K/N`) into the whole study's, ranked again:
//! above both the results (module `results`) and the rankings (module `ranking`), so that
//! neither imports the other.

use std::collections::BTreeSet;

use crate::StudyError;
use crate::results::{CellResult, SCHEMA, StudyResults};

impl StudyResults {
    /// Combines the results of shards into the results of the whole study: the shards must
    /// share the config, notes and shard count, be distinct, and together cover every cell.
    ///
    /// Errors: [`StudyError::Merge`] saying what does not fit.
    pub fn merge(parts: Vec<StudyResults>) -> Result<Self, StudyError> {
        let fail = |m: String| Err(StudyError::Merge(m));
        let Some(first) = parts.first() else {
            return fail("no results given".into());
        };
        let mut seen_shards = BTreeSet::new();
        for p in &parts {
            if p.config != first.config {
                return fail("the results come from different study configurations".into());
            }
            if p.total_cells != first.total_cells
                || p.notes != first.notes
                || p.lights != first.lights
            {
                return fail(
                    "the results come from different runs (cells, notes or lights differ)".into(),
                );
            }
            match (p.shard, first.shard) {
                (Some(s), Some(f)) if s.count == f.count => {
                    if !seen_shards.insert(s.index) {
                        return fail(format!("shard {}/{} given twice", s.index, s.count));
                    }
                }
                (None, _) if parts.len() == 1 => {}
                _ => return fail("every input must be a shard K/N of the same N".into()),
            }
        }
        // Every shard is required, even one without cells (more shards than BRDFs): a merge
        // of an incomplete set is refused whatever the shards hold.
        if let Some(f) = first.shard
            && seen_shards.len() != f.count
        {
            let missing: Vec<String> = (1..=f.count)
                .filter(|k| !seen_shards.contains(k))
                .map(|k| format!("{k}/{}", f.count))
                .collect();
            return fail(format!(
                "the shards do not cover every cell once (missing shards: {})",
                missing.join(", ")
            ));
        }
        let mut cells: Vec<CellResult> =
            parts.iter().flat_map(|p| p.cells.iter().cloned()).collect();
        cells.sort_by_key(|c| c.index);
        let indices: Vec<usize> = cells.iter().map(|c| c.index).collect();
        if indices != (0..first.total_cells).collect::<Vec<_>>() {
            let missing = first
                .shard
                .map(|s| {
                    (1..=s.count)
                        .filter(|k| !seen_shards.contains(k))
                        .map(|k| format!("{k}/{}", s.count))
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_default();
            return fail(format!(
                "the shards do not cover every cell once (missing shards: {missing})"
            ));
        }
        let mut merged = Self {
            schema: SCHEMA.to_string(),
            config: first.config.clone(),
            shard: None,
            total_cells: first.total_cells,
            notes: first.notes.clone(),
            build_warnings: {
                let mut w: Vec<String> = parts
                    .iter()
                    .flat_map(|p| p.build_warnings.iter().cloned())
                    .collect();
                w.sort();
                w.dedup();
                w
            },
            lights: first.lights.clone(),
            cells,
            runs: parts.iter().flat_map(|p| p.runs.iter().cloned()).collect(),
            rankings: Vec::new(),
        };
        merged.rankings = crate::ranking::rankings(&merged);
        Ok(merged)
    }
}
