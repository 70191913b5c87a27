//! Prints a few values and albedos of an RGL file (development probe).
use brdf::{Brdf, RglBrdf, direction_from_angles, directional_albedo};
fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "data/measured/rgl/paper_white_rgb.bsdf".into());
    let t = std::time::Instant::now();
    let b = RglBrdf::load(std::path::Path::new(&path)).unwrap();
    println!(
        "load {:?} {} clamped {:?} iso {} mirror {}",
        t.elapsed(),
        b.description(),
        b.clamped(),
        b.is_isotropic(),
        b.is_mirror_symmetric()
    );
    for th in [0.0, 30.0, 60.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        let a = directional_albedo(&b, &wo, 64, 128);
        let m = brdf::mirror(&wo);
        let wi = direction_from_angles(40.0, 120.0);
        let wi2 = direction_from_angles(40.0, -120.0);
        println!(
            "θo {th}: albedo {a:.4} f(mirror) {:?} f {:.5} f(mirrored) {:.5} recip {:.5}",
            b.eval_rgb(&wo, &m),
            b.eval(&wo, &wi),
            b.eval(&wo, &wi2),
            b.eval(&wi, &wo)
        );
    }
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    let wo = direction_from_angles(30.0, 0.0);
    for i in 0..1_000_000 {
        let a = i as f64 * 0.000_001;
        acc += b.eval(&wo, &direction_from_angles(80.0 * a, 360.0 * a * 37.0));
    }
    println!("1e6 evals: {:?} ({acc})", t.elapsed());
    for th in [0.0, 45.0, 80.0] {
        let wo = direction_from_angles(th, 0.0);
        for ti in [85.0, 89.0, 89.9, 89.999] {
            println!(
                "θo {th} θi {ti}: {:.5} {:.5}",
                b.eval(&wo, &direction_from_angles(ti, 180.0)),
                b.eval(&wo, &direction_from_angles(ti, 60.0))
            );
        }
    }
}
