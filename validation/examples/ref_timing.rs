//! Development aid: cost of the reference quadrature for every model and full-tier angle.
use std::time::Instant;
fn main() {
    for m in brdf::models().iter().filter(|m| m.name != "merl") {
        let b = brdf::parse_spec(m.name).unwrap();
        for &t in validation::FULL_THETA_O {
            let wo = brdf::direction_from_angles(t, 0.0);
            let s = Instant::now();
            let a = validation::references::albedo_reference(b.as_ref(), &wo).unwrap();
            println!(
                "{:>18} {t:>4}: {:.3}s {:.10} err {:.1e} {}",
                m.name,
                s.elapsed().as_secs_f64(),
                a.value,
                a.abs_error,
                a.rule.split(';').nth(1).unwrap_or("")
            );
        }
    }
}
