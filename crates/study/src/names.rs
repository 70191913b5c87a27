//! Short names of BRDF and light specs for reports, plots and CSV (no long paths): the
//! lowest module of the crate, used by the config, the results and the report alike.

/// A light spec without a long path (`envmap:…/grace_probe_latlong.hdr` → `envmap:grace_probe_latlong.hdr`).
pub fn short_light(spec: &str) -> String {
    match spec.split_once(':') {
        Some(("envmap", path)) => format!(
            "envmap:{}",
            std::path::Path::new(path)
                .file_name()
                .map_or_else(|| path.to_string(), |f| f.to_string_lossy().into_owned())
        ),
        _ => spec.to_string(),
    }
}

/// A BRDF spec without a long path or key: `rgl:/…/paper_white_rgb.bsdf` →
/// `rgl:paper_white_rgb`, `sgd:material=red-fabric` → `sgd:red-fabric`; analytic specs as
/// they are.
pub fn short_brdf(spec: &str) -> String {
    match spec.split_once(':') {
        Some((reader @ ("rgl" | "cornell" | "merl"), path)) => format!(
            "{reader}:{}",
            std::path::Path::new(path)
                .file_stem()
                .map_or_else(|| path.to_string(), |f| f.to_string_lossy().into_owned())
        ),
        Some((fit @ ("sgd" | "abc"), rest)) => {
            format!("{fit}:{}", rest.strip_prefix("material=").unwrap_or(rest))
        }
        _ => spec.to_string(),
    }
}
