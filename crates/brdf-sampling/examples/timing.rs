//! scratch
use std::sync::Arc;
use std::time::Instant;
use brdf::{Brdf, parse_spec};
use brdf_sampling::*;
use partition_sampler::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let b: Arc<dyn Brdf> = Arc::from(parse_spec(&args[1]).unwrap());
    let n: usize = args[2].parse().unwrap();
    let wo = brdf::direction_from_angles(30.0, 0.0);
    let d = DiscBrdf::new(b.clone(), wo);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        for _ in 0..3 {
            let t = Instant::now();
            let g = SampledGridDensity::new(d.clone(), Domain::UnitDisc, n).unwrap();
            let t1 = t.elapsed().as_secs_f64();
            let tree = QuadTreeBuilder::new().max_depth(7).volume_tolerance(1e-3).build_tree(&g).unwrap();
            let t2 = t.elapsed().as_secs_f64();
            let mut acc = 0.0;
            let t3 = Instant::now();
            for i in 0..(2*(n+1)*(n+1)) { acc += d.eval([(i % 517) as f64 / 600.0, 0.1]); }
            std::hint::black_box(acc);
            println!("grid {:.2}ms tree {:.2}ms leaves {} | raw 2(n+1)^2 evals {:.2}ms", t1*1e3, (t2-t1)*1e3, tree.counts().leaves, t3.elapsed().as_secs_f64()*1e3);
        }
    });
}
