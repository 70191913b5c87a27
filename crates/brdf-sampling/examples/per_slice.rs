//! scratch: per-slice expected trials and leaves
use std::sync::Arc;
use brdf::{Brdf, parse_spec};
use brdf_sampling::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let b: Arc<dyn Brdf> = Arc::from(parse_spec(&args[1]).unwrap());
    let mut o = SetOptions::default();
    if let Some(d) = args.get(2) { o = o.with_depth(d.parse().unwrap()); }
    o.slices = 18;
    let t = std::time::Instant::now();
    let set = QuadTreeSet::build(b, Variant::Adaptive, &o).unwrap();
    println!("build {:.3}s evals {}", t.elapsed().as_secs_f64(), set.grid_evaluations());
    let mut line = String::new();
    for i in 0..set.len() {
        let s = set.tree(i).unwrap().stats();
        line += &format!("{:.0}:{:.2}/{} ", set.layout().theta_of(i).to_degrees(), s.expected_mean_trials, s.active_leaves);
    }
    println!("{line}");
}
