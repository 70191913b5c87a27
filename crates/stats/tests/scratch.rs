mod common;
use common::*;
use stats::*;
#[test]
fn scratch() {
    let seeds: Vec<u64> = (2000..2600).collect();
    let bins = SphereBinning::sphere(20, 40).unwrap();
    let lobe = test_lobe();
    let n = 1_000_000;
    let expected: Vec<f64> = expected_masses(&|d| lobe.pdf(d), &bins, n as u64).iter().map(|m| m * n as f64).collect();
    let c = calibrate(&seeds, 0.05, |seed| {
        let h = histogram(&bins, &lobe.points(seed, n));
        Ok(chi_square_gof(&h.counts, &expected, 5.0)?.p_value)
    }).unwrap();
    let unif = ks_onesample(&c.p_values, &|p| p.clamp(0.0, 1.0)).unwrap();
    eprintln!("lobe 600 seeds: {} rejections rate {} binom p {} unif p {}", c.rejections, c.rate, c.binomial_p_value, unif.p_value);
    let c1 = c.with_alpha(0.01).unwrap();
    eprintln!("at 0.01: {} rate {} binom p {}", c1.rejections, c1.rate, c1.binomial_p_value);
}
