//! `brdf-lab list`: the BRDF models with their parameters, and the samplers.

use std::io::Write;

use crate::error::CliResult;

/// Runs `brdf-lab list` (a closed pipe, as in `brdf-lab list | head`, ends it quietly).
pub(crate) fn run() -> CliResult<()> {
    crate::output::write_stdout(|out| write_listing(out))
}

fn write_listing(out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        out,
        "BRDF models (SPEC = name or name:key=value,...; also merl:PATH, rgl:PATH, cornell:PATH, sgd:material=NAME, abc:material=NAME)"
    )?;
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
        writeln!(out, "\n  {}{aliases} — {iso}", m.name)?;
        writeln!(out, "      {}", m.summary)?;
        if let Some(names) = brdf::preset_names(m.name) {
            writeln!(
                out,
                "      materials ({}): {}",
                names.len(),
                names.join(", ")
            )?;
        }
        for p in m.params {
            writeln!(
                out,
                "      {:<10} default {:<10} range {:<16} {}",
                p.key,
                p.default.to_string(),
                p.range.to_string(),
                p.doc
            )?;
        }
    }
    writeln!(
        out,
        "\nSamplers (--sampler NAME; direction samplers for sample/eval/build/validate,"
    )?;
    writeln!(
        out,
        "disc and grid samplers for validate, envmap samplers for envmap/validate)"
    )?;
    for kind in ["direction", "disc", "envmap", "grid"] {
        writeln!(out, "\n  {kind}")?;
        for e in samplers::samplers()
            .iter()
            .filter(|e| e.constructor.kind() == kind)
        {
            writeln!(out, "    {:<24} {}", e.name, e.summary)?;
            writeln!(out, "    {:<24} [{}]", "", e.capabilities.flags())?;
        }
    }
    Ok(())
}
