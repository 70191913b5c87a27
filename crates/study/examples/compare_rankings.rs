//! Compares the significant rankings of two study runs (e.g. `study --quick --seed 1` and
//! `--seed 2`): how many significant pairs (best ≻ worse) each has, how many agree, and every
//! flip (a pair significant one way in run A and the other way in run B).
//!
//! ```sh
//! cargo run --release -p study --example compare_rankings -- /tmp/sq-A /tmp/sq-B
//! ```
//!
//! Exits 1 when a ranking flips, 2 on a usage or file error.

use std::process::ExitCode;

use study::{StudyResults, compare_rankings};

fn load(dir: &str) -> Result<StudyResults, String> {
    let path = std::path::Path::new(dir).join("results.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    StudyResults::from_json(&text, &path.display().to_string()).map_err(|e| e.to_string())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b] = args.as_slice() else {
        eprintln!("usage: compare_rankings DIR_A DIR_B (each with a results.json)");
        return ExitCode::from(2);
    };
    let (ra, rb) = match (load(a), load(b)) {
        (Ok(ra), Ok(rb)) => (ra, rb),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("compare_rankings: {e}");
            return ExitCode::from(2);
        }
    };
    let c = compare_rankings(&ra.rankings, &rb.rankings);
    println!(
        "{} comparisons in both runs (seeds {} and {}); significant pairs best ≻ worse: {} in A, {} in B, {} of A's also significant in B; same best in {}, best of one run best or tied in the other in {}; flips: {}",
        c.comparisons,
        ra.config.seed,
        rb.config.seed,
        c.significant_pairs.0,
        c.significant_pairs.1,
        c.agreeing_pairs,
        c.same_best,
        c.best_compatible,
        c.flips.len()
    );
    for f in &c.flips {
        println!(
            "FLIP {}: {} ≻ {} in A, reversed in B",
            f.comparison, f.better_in_a, f.better_in_b
        );
    }
    if c.flips.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
