//! Regenerates `validation/references/albedo.json`: the directional albedo and the radiance
//! reflected from the analytic environment for every analytic quick-tier (BRDF, θo) and every
//! mutant setting, by the reference quadrature rule (the measured RGL fixture's references are
//! computed at run time only; name its spec to compute them here).
//!
//! ```sh
//! cargo run --release -p validation --example references > validation/references/albedo.json
//! ```
//! With arguments `SPEC...`, only the quick-tier entries of those specs are computed and printed
//! (a JSON array of entries, to merge by hand).

use validation::references::{
    ENVIRONMENT_FORMULA, REFERENCE_RULE, StoredReferences, compute_stored,
};
use validation::{QUICK_BRDFS, QUICK_THETA_O, mutants};

fn main() {
    let only: Vec<String> = std::env::args().skip(1).collect();
    let mut settings: Vec<(String, f64)> = Vec::new();
    for spec in QUICK_BRDFS
        .iter()
        .filter(|s| only.iter().any(|o| o == *s) || (only.is_empty() && !s.starts_with("rgl:")))
    {
        for &t in QUICK_THETA_O {
            settings.push(((*spec).to_owned(), t));
        }
    }
    for m in mutants().iter().filter(|_| only.is_empty()) {
        if !settings.iter().any(|(s, t)| s == m.brdf && *t == m.theta_o) {
            settings.push((m.brdf.to_owned(), m.theta_o));
        }
    }
    let mut entries = Vec::new();
    for (spec, t) in settings {
        match compute_stored(&spec, t) {
            Ok(e) => entries.push(e),
            Err(e) => {
                eprintln!("{spec} at {t}: {e}");
                std::process::exit(1);
            }
        }
    }
    if !only.is_empty() {
        match serde_json::to_string_pretty(&entries) {
            Ok(s) => println!("{s}"),
            Err(e) => eprintln!("{e}"),
        }
        return;
    }
    let table = StoredReferences {
        rule: REFERENCE_RULE.to_owned(),
        environment: ENVIRONMENT_FORMULA.to_owned(),
        generated_by: "cargo run --release -p validation --example references > validation/references/albedo.json".to_owned(),
        entries,
    };
    match serde_json::to_string_pretty(&table) {
        Ok(s) => println!("{s}"),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
