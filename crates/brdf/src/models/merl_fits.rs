//! The published fits of the 100 MERL materials, embedded as tab-separated tables with their
//! provenance (`crates/brdf/data/*.tsv`, see `crates/brdf/data/README.md`): one row per
//! material, a `name` column then numeric columns; `#` lines are comments; the first
//! non-comment line is the header.

use std::sync::OnceLock;

/// One fitted material: its names and the numeric columns in header order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FitRow {
    /// The MERL name (e.g. `gold-metallic-paint`).
    pub name: String,
    /// Another name of the same material (SGD table's `otherName`), possibly empty.
    pub other_name: String,
    /// The numeric columns.
    pub values: Vec<f64>,
}

/// Parses an embedded table: `text_columns` leading text columns (1 or 2), then numbers.
/// The embedded tables are checked by the tests; a malformed row is skipped.
pub(crate) fn parse_table(text: &str, text_columns: usize) -> Vec<FitRow> {
    let mut rows = Vec::new();
    let mut header_seen = false;
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if !header_seen {
            header_seen = true;
            continue;
        }
        let cols: Vec<&str> = line.split('\t').collect();
        if cols.len() <= text_columns {
            continue;
        }
        let values: Option<Vec<f64>> = cols[text_columns..]
            .iter()
            .map(|c| c.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        let Some(values) = values else { continue };
        rows.push(FitRow {
            name: cols[0].trim().to_string(),
            other_name: if text_columns > 1 {
                cols[1].trim().to_string()
            } else {
                String::new()
            },
            values,
        });
    }
    rows
}

/// An embedded fit table, parsed on first use: the presets of a fitted model (`abc`, `sgd`).
pub(crate) struct FitTable {
    text: &'static str,
    text_columns: usize,
    rows: OnceLock<Vec<FitRow>>,
}

impl FitTable {
    /// The table `text` with `text_columns` leading text columns (see [`parse_table`]).
    pub(crate) const fn new(text: &'static str, text_columns: usize) -> Self {
        Self {
            text,
            text_columns,
            rows: OnceLock::new(),
        }
    }

    fn rows(&self) -> &[FitRow] {
        self.rows
            .get_or_init(|| parse_table(self.text, self.text_columns))
    }

    /// The MERL names, in table order.
    pub(crate) fn names(&self) -> Vec<&str> {
        self.rows().iter().map(|r| r.name.as_str()).collect()
    }

    /// Up to five names (MERL or other) close to `name`, best first.
    pub(crate) fn close_matches(&self, name: &str) -> Vec<String> {
        close_matches(
            name,
            self.rows()
                .iter()
                .flat_map(|r| [r.name.as_str(), r.other_name.as_str()])
                .filter(|n| !n.is_empty()),
        )
    }

    /// The row of a material by its MERL name or its (non-empty) other name.
    pub(crate) fn find(&self, material: &str) -> Option<&FitRow> {
        self.rows()
            .iter()
            .find(|r| r.name == material || (!r.other_name.is_empty() && r.other_name == material))
    }
}

/// The column names of an embedded table (its header line).
#[cfg(test)]
pub(crate) fn header(text: &str) -> Vec<&str> {
    text.lines()
        .find(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split('\t').map(str::trim).collect())
        .unwrap_or_default()
}

/// Up to five names closest to `name` (edit distance ≤ 4, or containing it / contained in it),
/// best first.
pub(crate) fn close_matches<'a>(name: &str, names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let lower = name.to_ascii_lowercase();
    let mut scored: Vec<(usize, &str)> = names
        .filter_map(|n| {
            let d = strsim::levenshtein(&lower, n);
            let contains = !lower.is_empty() && (n.contains(&lower) || lower.contains(n));
            (d <= 4 || contains).then_some((if contains { d.min(2) } else { d }, n))
        })
        .collect();
    scored.sort();
    scored.dedup_by(|a, b| a.1 == b.1);
    scored
        .into_iter()
        .take(5)
        .map(|(_, n)| n.to_string())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::{abc, sgd};

    /// The column mappings of [`Abc::preset`](abc::Abc::preset) and
    /// [`Sgd::preset`](sgd::Sgd::preset) are their tables' headers.
    #[test]
    fn preset_columns_follow_the_headers() {
        assert_eq!(
            header(abc::TABLE),
            [
                "name", "kD_r", "kD_g", "kD_b", "A_r", "A_g", "A_b", "B", "C", "ior"
            ]
        );
        let h = header(sgd::TABLE);
        let groups = [
            "rhoD", "rhoS", "alpha", "p", "f0", "f1", "kap", "lambda", "c", "k", "theta0",
        ];
        for (g, name) in groups.iter().enumerate() {
            for (ch, suffix) in ["r", "g", "b"].iter().enumerate() {
                assert_eq!(h[2 + 3 * g + ch], format!("{name}_{suffix}"));
            }
        }
        assert_eq!(&h[..2], &["name", "otherName"]);
    }

    #[test]
    fn close_matches_rank_typos_first() {
        let names = [
            "gold-metallic-paint",
            "gold-metallic-paint2",
            "gold-paint",
            "nickel",
        ];
        let m = close_matches("gold-metalic-paint", names.iter().copied());
        assert_eq!(m.first().map(String::as_str), Some("gold-metallic-paint"));
        assert!(!m.contains(&"nickel".to_string()));
        assert!(close_matches("zzzzzzzzzz", names.iter().copied()).is_empty());
    }
}
