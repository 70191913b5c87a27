//! Write a file in the MERL layout (here: a tabulated Blinn–Phong, since MERL data are not
//! redistributable), load it back with `merl:PATH`, build its adaptive set and sample it.
//! Point `merl:PATH` at your own MERL files in exactly the same way.
//!
//! `cargo run --release -p brdf-lab-examples --example merl [-- --out blinn.binary]`
//!
//! With `--out PATH` the MERL file is written there and kept (use it as
//! `brdf-lab sample --brdf merl:PATH …`); without it, it goes to a temporary directory that is
//! removed at the end.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use brdf::{Brdf, MerlBrdf};
use brdf_sampling::SetOptions;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut out = None;
    while let Some(a) = args.next() {
        match (a.as_str(), a.strip_prefix("--out=")) {
            (_, Some(p)) => out = Some(PathBuf::from(p)),
            ("--out", None) => {
                out = Some(args.next().ok_or("--out needs a PATH")?.into());
            }
            _ => {
                return Err(format!("unexpected argument `{a}` (usage: merl [--out PATH])").into());
            }
        }
    }
    run(out.as_deref())
}

/// Writes the MERL file to `out` (kept) or to a temporary directory (removed), then loads,
/// builds and samples it.
fn run(out: Option<&Path>) -> Result<(), Box<dyn std::error::Error>> {
    let dir = tempfile::tempdir()?;
    let path = match out {
        Some(p) => p.to_path_buf(),
        None => dir.path().join("blinn.binary"),
    };
    let analytic = brdf::parse_spec("blinn:n=200,ks=0.5,kd=0.3")?;
    MerlBrdf::tabulate(analytic.as_ref()).write(&path)?;

    let spec = format!("merl:{}", path.display());
    let measured: Arc<dyn Brdf> = Arc::from(brdf::parse_spec(&spec)?);
    let set = brdf_sampling::QuadTreeSet::build(
        measured.clone(),
        brdf_sampling::Variant::Adaptive,
        &SetOptions::default(),
    )?;

    let wo = brdf::direction_from_angles(40.0, 0.0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    let n = 200_000;
    let mut sum = 0.0;
    for _ in 0..n {
        let s = brdf_sampling::DirectionSampler::sample(&set, &wo, &mut rng);
        if s.pdf > 0.0 {
            sum += measured.eval(&wo, &s.wi) * s.wi.z / s.pdf;
        }
    }
    let r = set.report();
    println!(
        "MERL-layout set: {} trees in {:.2} s, {:.1} KiB, mean trials {:.3}",
        r.trees,
        r.build_time.as_secs_f64(),
        r.memory_bytes as f64 / 1024.0,
        r.expected_mean_trials
    );
    println!("directional albedo at 40°: {:.4}", sum / n as f64);
    match out {
        Some(p) => println!(
            "wrote {} (use it as --brdf merl:{})",
            p.display(),
            p.display()
        ),
        None => println!("(the MERL file was temporary; keep one with --out PATH)"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn out_keeps_the_merl_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("kept.binary");
        super::run(Some(&path)).expect("run");
        let b = brdf::parse_spec(&format!("merl:{}", path.display())).expect("a MERL file");
        assert_eq!(b.name(), "merl");
    }
}
