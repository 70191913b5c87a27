//! Development aid: normaliser accuracy of the disc quadtree.
use partition_sampler::Sampler2D;
fn main() {
    for spec in validation::QUICK_BRDFS {
        for &t in validation::QUICK_THETA_O {
            let b: std::sync::Arc<dyn brdf::Brdf> = std::sync::Arc::from(brdf::parse_spec(spec).unwrap());
            let wo = brdf::direction_from_angles(t, 0.0);
            let s = validation::quadtree_disc_sampler(&b, &wo).unwrap();
            let a = validation::references::albedo_reference(b.as_ref(), &wo).unwrap();
            let st = s.stats();
            let _ = s.bytes_used();
            println!("{spec:>14} {t:>4}: I={:.8} ref={:.8} rel={:+.2e} declared={:?} leaves={} trials={:.3}", st.integral, a.value, st.integral / a.value - 1.0, st.integral_rel_err, st.leaves, st.expected_mean_trials);
        }
    }
}
