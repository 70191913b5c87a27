//! scratch
use std::sync::Arc;
use brdf::{Brdf, MerlBrdf, parse_spec};
use brdf_sampling::*;
use partition_sampler::Density;
use rand::{SeedableRng, RngExt};
use rand::rngs::Xoshiro256PlusPlus;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let analytic = parse_spec(&args[1]).unwrap();
    let path = std::path::Path::new("/tmp/diag_merl.binary");
    brdf::write_merl(path, &|th, td, pd| {
        let (wo, wi) = brdf::merl::half_diff_to_directions(th, td, pd);
        if wo.z > 0.0 && wi.z > 0.0 { analytic.eval_rgb(&wo, &wi) } else { [-1.0; 3] }
    }).unwrap();
    let merl: Arc<dyn Brdf> = Arc::new(MerlBrdf::load(path).unwrap());
    let opts = SetOptions { slices: 9, ..SetOptions::default() };
    let set = QuadTreeSet::build(merl, Variant::Adaptive, &opts).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    for i in 0..set.len() {
        let t = set.tree(i).unwrap();
        let d = t.density().disc_brdf();
        let mut worst = (0.0, [0.0; 2], 0.0);
        let mut count = 0;
        for l in t.tree().leaves() {
            let r = l.rect;
            for _ in 0..20000 {
                let p = [r.x0 + rng.random::<f64>() * r.width(), r.y0 + rng.random::<f64>() * r.height()];
                let v = d.eval(p);
                if v > l.max_bound { count += 1; if v / l.max_bound > worst.0 { worst = (v / l.max_bound, p, r.width()); } }
            }
        }
        let p = worst.1;
        let wi = disc_to_direction(p);
        let wo = d.wo();
        let (th, td, pd) = brdf::merl::half_diff_angles(wo, &wi);
        println!("slice {i}: {count} viol, worst {:.3} at {:?} r={:.5} leafw {:.4} θh={:.4}° θd={:.3}° φd={:.2}°", worst.0, p, (p[0]*p[0]+p[1]*p[1]).sqrt(), worst.2, th.to_degrees(), td.to_degrees(), pd.to_degrees());
    }
}
