//! `brdf-lab list`: the BRDF models with their parameters, and the samplers.

use crate::error::CliResult;

/// Runs `brdf-lab list`.
pub(crate) fn run() -> CliResult<()> {
    println!(
        "BRDF models (SPEC = name or name:key=value,...; also merl:PATH, rgl:PATH, cornell:PATH, sgd:material=NAME, abc:material=NAME)"
    );
    for m in brdf::models() {
        let iso = match m.isotropic {
            brdf::Isotropy::Always => "isotropic",
            brdf::Isotropy::Never => "anisotropic",
            brdf::Isotropy::WhenParamsEqual => "anisotropic (isotropic by default)",
        };
        let aliases = if m.aliases.is_empty() {
            String::new()
        } else {
            format!(" (also: {})", m.aliases.join(", "))
        };
        println!("\n  {}{aliases} — {iso}", m.name);
        println!("      {}", m.summary);
        if let Some(names) = brdf::preset_names(m.name) {
            println!("      materials ({}): {}", names.len(), names.join(", "));
        }
        for p in m.params {
            println!(
                "      {:<10} default {:<10} range {:<16} {}",
                p.key,
                p.default.to_string(),
                p.range.to_string(),
                p.doc
            );
        }
    }
    println!("\nSamplers (--sampler NAME; direction samplers for sample/eval/build/validate,");
    println!("disc and grid samplers for validate, envmap samplers for envmap/validate)");
    for kind in ["direction", "disc", "envmap", "grid"] {
        println!("\n  {kind}");
        for e in samplers::samplers()
            .iter()
            .filter(|e| e.constructor.kind() == kind)
        {
            println!("    {:<24} {}", e.name, e.summary);
            println!("    {:<24} [{}]", "", e.capabilities.flags());
        }
    }
    Ok(())
}
