//! Helpers shared by this crate's examples (`mod support;`), each of which uses a subset.
#![allow(dead_code)]

/// `∫ g dω` over the upper hemisphere by the midpoint rule in (cosθ, φ).
#[allow(unused_imports)]
pub(crate) use brdf_sampling::upper_hemisphere_integral as integrate;

/// CPU seconds (user + system) of this process so far, from `/proc/self/stat`; NaN where it
/// cannot be read.
pub(crate) fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    let after = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    // Fields 14 and 15 of stat (utime, stime) are at 11 and 12 after the command name.
    (ticks(11) + ticks(12)) / 100.0
}

/// The value after `key` in `args`, parsed; `None` when absent or unparsable.
pub(crate) fn arg<T: std::str::FromStr>(args: &[String], key: &str) -> Option<T> {
    args.iter()
        .position(|a| a == key)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
}

/// Every model of `brdf::models()` at its defaults, then the synthetic MERL table
/// `merl(phong:n=50)`: the BRDFs the tables and loops of these examples run over.
pub(crate) fn all_specs() -> Vec<String> {
    let mut specs: Vec<String> = brdf::models()
        .iter()
        .filter(|m| !m.needs_argument())
        .map(|m| m.name.to_string())
        .collect();
    specs.push("merl(phong:n=50)".to_string());
    specs
}

/// The specs of `--specs a;b;…` in `args`, else [`all_specs`].
pub(crate) fn table_specs(args: &[String]) -> Vec<String> {
    match arg::<String>(args, "--specs") {
        Some(list) => list.split(';').map(str::to_string).collect(),
        None => all_specs(),
    }
}
