//! `brdf-lab list`: the BRDF models with their parameters, and the samplers.

use crate::error::CliResult;

/// Samplers the `sample`, `eval` and `validate` commands accept, with one line each.
pub(crate) const SAMPLERS: &[(&str, &str)] = &[
    ("adaptive", "adaptive partition (quadtree + rejection), envelope scheme: exact, default"),
    ("adaptive-paper", "adaptive partition as in the papers: leaf ∝ I_i, CDF descent, image-map bounds"),
];

/// Runs `brdf-lab list`.
pub(crate) fn run() -> CliResult<()> {
    println!("BRDF models (SPEC = name or name:key=value,...; also merl:PATH for MERL files)");
    for m in brdf::models() {
        let iso = match m.isotropic {
            brdf::Isotropy::Always => "isotropic",
            brdf::Isotropy::Never => "anisotropic",
            brdf::Isotropy::WhenParamsEqual => "anisotropic (isotropic by default)",
        };
        let aliases = if m.aliases.is_empty() { String::new() } else { format!(" (also: {})", m.aliases.join(", ")) };
        println!("\n  {}{aliases} — {iso}", m.name);
        println!("      {}", m.summary);
        for p in m.params {
            println!("      {:<10} default {:<10} range {:<16} {}", p.key, p.default.to_string(), p.range.to_string(), p.doc);
        }
    }
    println!("\nSamplers (--sampler NAME)");
    for (name, doc) in SAMPLERS {
        println!("  {name:<16} {doc}");
    }
    Ok(())
}
