//! scratch
use std::sync::Arc;
use brdf::{Brdf, parse_spec, direction_from_angles};
use brdf_sampling::DiscBrdf;
use partition_sampler::*;
use rand::{SeedableRng, RngExt};
use rand::rngs::Xoshiro256PlusPlus;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let spec = &args[1];
    let th: f64 = args[2].parse().unwrap();
    let n: usize = args[3].parse().unwrap();
    let tol: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(1e-6);
    let b: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
    let wo = direction_from_angles(th, 0.0);
    let d = DiscBrdf::new(b.clone(), wo);
    let g = SampledGridDensity::new(d.clone(), Domain::UnitDisc, n).unwrap();
    let tree = QuadTreeBuilder::new().volume_tolerance(tol).build_tree(&g).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    let mut hist = [0usize; 16];
    let mut rim = 0;
    let mut worst: Vec<(f64, [f64;2], f64, f64)> = vec![];
    for l in tree.leaves() {
        let depth = (2.0 / l.rect.width().max(l.rect.height())).log2().floor() as usize;
        hist[depth.min(15)] += 1;
        let r = &l.rect;
        let far = (r.x0.abs().max(r.x1.abs()).powi(2) + r.y0.abs().max(r.y1.abs()).powi(2)).sqrt();
        if far > 1.0 { rim += 1; }
        let mut mx: (f64, [f64;2]) = (0.0, [0.0;2]);
        for _ in 0..2048 {
            let p = [r.x0 + rng.random::<f64>() * r.width(), r.y0 + rng.random::<f64>() * r.height()];
            let v = d.eval(p);
            if v > mx.0 { mx = (v, p); }
        }
        if mx.0 > l.max_bound { worst.push((mx.0 / l.max_bound, mx.1, l.rect.width(), (mx.1[0].powi(2)+mx.1[1].powi(2)).sqrt())); }
    }
    worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    println!("leaves {} rim {} trials {:.3} depth hist {:?}", tree.leaves().len(), rim, tree.expected_mean_trials(), &hist[..10]);
    println!("violating leaves {}", worst.len());
    for w in worst.iter().take(8) { println!("  ratio {:.3} at {:?} r={:.6} leafw {:.4}", w.0, w.1, w.3, w.2); }
}
