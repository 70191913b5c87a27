use std::sync::Arc;
use std::time::Instant;
use brdf::{Brdf, models, parse_spec, direction_from_angles};
use brdf_sampling::DiscBrdf;
use partition_sampler::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let grids: Vec<usize> = args.get(1).map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![128, 256, 512]);
    let tol: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(1e-6);
    let mut specs: Vec<String> = models().iter().filter(|m| m.name != "merl").map(|m| m.name.to_string()).collect();
    specs.push("phong:n=1000".into());
    specs.push("ggx:alpha=0.1".into());
    for spec in &specs {
        let b: Arc<dyn Brdf> = Arc::from(parse_spec(spec).unwrap());
        for &n in &grids {
            let mut line = format!("{spec:<22} n={n:<4}");
            let mut tot_t = 0.0;
            for th in [0.5, 30.5, 60.5, 85.5, 89.5] {
                let wo = direction_from_angles(th, 0.0);
                let t = Instant::now();
                let g = SampledGridDensity::new(DiscBrdf::new(b.clone(), wo), Domain::UnitDisc, n).unwrap();
                let tree = QuadTreeBuilder::new().volume_tolerance(tol).build_tree(&g).unwrap().clone();
                tot_t += t.elapsed().as_secs_f64();
                let s = QuadTreeSampler::from_parts(tree, g).unwrap();
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
                for _ in 0..20000 { s.sample(&mut rng); }
                let st = s.stats();
                line += &format!(" | d{} L{} {:.2}/{:.2} v{} {}B", st.depth, st.active_leaves, st.expected_mean_trials, st.measured_mean_trials.unwrap(), st.bound_violations, s.tree().bytes_used());
            }
            println!("{line} | {:.1}ms/5", tot_t * 1e3);
        }
    }
}
