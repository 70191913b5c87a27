//! Prints read time, sample count and albedos of Cornell `.brdf` files (development probe).
use brdf::{Brdf, CornellBrdf, direction_from_angles, directional_albedo};
fn main() {
    for path in std::env::args().skip(1) {
        let t = std::time::Instant::now();
        match CornellBrdf::load(std::path::Path::new(&path)) {
            Ok(b) => {
                let read = t.elapsed();
                let albedos: Vec<String> = [0.0, 30.0, 60.0, 80.0]
                    .iter()
                    .map(|&th| {
                        let wo = direction_from_angles(th, 0.0);
                        format!("{:.3}", directional_albedo(&b, &wo, 48, 96))
                    })
                    .collect();
                let wo = direction_from_angles(30.0, 0.0);
                println!(
                    "{path}: {} samples read in {read:?}; albedo 0/30/60/80: {}; f(mirror) {:?}; clamped {:?}",
                    b.samples(),
                    albedos.join(" "),
                    b.eval_rgb(&wo, &brdf::mirror(&wo)),
                    b.clamped()
                );
            }
            Err(e) => println!("{path}: {e}"),
        }
    }
}
