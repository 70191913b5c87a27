//! The **adaptive product** estimator of `L_r(ωo) = ∫ f_r(ωo, ωi) cos⁺θi L(ωi) dσ(ωi)` under an
//! environment map: per query point, an adaptive partition of the sphere into cells of the
//! map's power pyramid ([`envmap::PowerPyramid`]), each weighted by the product of the BRDF
//! factor at the cell and the cell's power, sampled exactly ∝ radiance inside the chosen cell,
//! in a defensive mixture with a BRDF sampler (docs/benchmarks.md §26.6).
//!
//! **The cut.** Start from the pyramid's cells at [`ProductOptions::base_cells`] cells along
//! `u` (16 × 8 on a 1024 × 512 map). A cell entirely below the point's horizon (its bounding
//! cone, [`envmap::CellGeometry`]) gets `b_c = 0`; every other cell gets
//! `b_c = f_r(ωo, ω̄_c) cos⁺θ(ω̄_c)`, `ω̄_c` the cell's power-weighted mean direction (for a
//! cell whose power is one small bright window, the window's direction). The cell weight is
//! `w_c = b_c P_c`, `P_c = Σ_{p∈c} Y_p Ω_p`. Then, [`ProductOptions::splits`] times, the cell of
//! largest weight (above [`envmap::pyramid::GEOMETRY_LEVEL`]) is replaced by its children,
//! each weighted the same way: the partition is refined where the product's mass is.
//!
//! **The product density.** Pick a cell with probability `w_c / W`, `W = Σ_c w_c`, then a
//! direction in it with the pyramid's exact density `Y_p / P_c` (pixel `p ∋ ω`): in solid angle
//!
//! `p_prod(ω) = (w_c / W) · Y_p / P_c = b_c Y_p / W`,
//!
//! exact (a piecewise-constant BRDF factor times the map's luminance), 0 on black pixels and
//! culled cells.
//!
//! **The estimator.** Of `n` samples per point, `n_d = max(1, round(α n))` come from the
//! defensive BRDF sampler (`α` = [`ProductOptions::defensive`]; all `n` when `W = 0`) and
//! `n_p = n − n_d` from the product density; every sample is weighted by the mixture
//! (balance heuristic with the actual counts)
//!
//! `F = (1/n) Σ_j g(ω_j) / q(ω_j)`, `q = (n_d/n) p_d + (n_p/n) p_prod`,
//!
//! unbiased wherever `q > 0` on the support of `g = f_r cos⁺θ L`; the defensive sampler's
//! density is positive there for any sampler that covers `f_r cos⁺θ` (`adaptive-exact`:
//! `p_d = f_r cos θ / A(ωo)`), so `g / q ≤ A L / (n_d/n)`. The numerator is always the true
//! integrand; the cut only shapes the density.

use std::collections::BinaryHeap;

use brdf::{Brdf, Vec3};
use brdf_sampling::{DirectionSampler, EvalSample};
use envmap::PowerPyramid;
use envmap::pyramid::GEOMETRY_LEVEL;
use partition_sampler::UniformSource;

use crate::batch::{Query, Radiance};

/// Settings of the adaptive product estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProductOptions {
    /// Cells along `u` of the base level (the coarsest pyramid level with at most this many).
    pub base_cells: usize,
    /// Cells split (into their pyramid children) per query point, largest weight first.
    pub splits: usize,
    /// Share `α` of the samples drawn from the defensive BRDF sampler (at least one).
    pub defensive: f64,
}

impl Default for ProductOptions {
    fn default() -> Self {
        Self {
            base_cells: 16,
            splits: 16,
            defensive: 0.25,
        }
    }
}

/// How the density is reported; only [`Variant::Correct`] is the sampling law. The others
/// exist so that the tests can show they are rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Variant {
    /// `b_c Y_p / W`.
    Correct,
    /// The pixel's share `w_c/W · P_p/P_c` reported per unit area of `[0,1]²` (`· W_px H_px`)
    /// instead of per steradian: the solid-angle Jacobian dropped.
    #[cfg_attr(not(test), allow(dead_code, reason = "a mutant the tests must reject"))]
    NoJacobian,
    /// The cell's share taken as `P_c / Σ P` (the map's) while cells are drawn by `b_c P_c`.
    #[cfg_attr(not(test), allow(dead_code, reason = "a mutant the tests must reject"))]
    ShareOff,
}

/// One cell of a point's cut.
#[derive(Debug, Clone, Copy)]
struct CutCell {
    level: usize,
    x: usize,
    y: usize,
    /// `b_c`.
    factor: f64,
    /// `w_c = b_c P_c`.
    weight: f64,
}

/// A node of the cut's lookup tree: a cell of the cut, or a split cell's first child node.
#[derive(Debug, Clone, Copy)]
enum Node {
    Leaf(u32),
    /// Node indices of the children `(dx, dy)` at `[dy * 2 + dx]` (`u32::MAX`: none).
    Split([u32; 4]),
}

/// A point's adaptive partition and product density (module docs).
#[derive(Debug, Clone)]
pub struct ProductCut {
    base_level: usize,
    base_width: usize,
    cells: Vec<CutCell>,
    /// Inclusive prefix sums of the weights, in `cells` order.
    cdf: Vec<f64>,
    /// `W`.
    total: f64,
    /// `Σ_c P_c` over the cut (the map's power).
    power: f64,
    nodes: Vec<Node>,
    /// Node of each base cell.
    base: Vec<u32>,
    /// BRDF evaluations the cut took.
    evaluations: usize,
    variant: Variant,
    pixels: f64,
}

/// Max-heap entry of a splittable cell.
#[derive(Debug, PartialEq)]
struct Candidate(f64, usize);

impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(other.1.cmp(&self.1))
    }
}

impl ProductCut {
    /// The cut of one point: `brdf` at the local `wo`, `frame` its shading frame (module docs).
    pub fn new(
        pyramid: &PowerPyramid,
        brdf: &dyn Brdf,
        point: &Query,
        options: &ProductOptions,
    ) -> Self {
        Self::with_variant(pyramid, brdf, point, options, Variant::Correct)
    }

    pub(crate) fn with_variant(
        pyramid: &PowerPyramid,
        brdf: &dyn Brdf,
        point: &Query,
        options: &ProductOptions,
        variant: Variant,
    ) -> Self {
        let top = pyramid.levels() - 1;
        let base_level = (GEOMETRY_LEVEL..=top)
            .find(|&k| {
                pyramid
                    .dims(k)
                    .is_some_and(|(w, _)| w <= options.base_cells.max(1))
            })
            .unwrap_or(top)
            .max(GEOMETRY_LEVEL.min(top));
        let (bw, bh) = pyramid.dims(base_level).unwrap_or((1, 1));
        let n = point.frame.to_world(&Vec3::z());
        let n = [n.x, n.y, n.z];
        let mut evaluations = 0usize;
        let mut factor_of = |k: usize, x: usize, y: usize| -> f64 {
            let Some(g) = pyramid.geometry(k, x, y) else {
                return 0.0;
            };
            let dot = n[0] * g.centre[0] + n[1] * g.centre[1] + n[2] * g.centre[2];
            if dot < -g.sin_radius || !(pyramid.power(k, x, y) > 0.0) {
                return 0.0;
            }
            let l = point.frame.to_local(&Vec3::from(g.centroid));
            if !(l.z > 0.0) {
                return 0.0;
            }
            evaluations += 1;
            let f = brdf.eval(&point.wo, &l);
            if f > 0.0 && f.is_finite() {
                f * l.z
            } else {
                0.0
            }
        };
        let mut cells = Vec::with_capacity(bw * bh + 3 * options.splits);
        let mut nodes = Vec::with_capacity(bw * bh + 4 * options.splits);
        let mut base = Vec::with_capacity(bw * bh);
        let mut heap = BinaryHeap::new();
        let mut power = 0.0;
        for y in 0..bh {
            for x in 0..bw {
                let factor = factor_of(base_level, x, y);
                let p = pyramid.power(base_level, x, y);
                power += p;
                let c = cells.len();
                cells.push(CutCell {
                    level: base_level,
                    x,
                    y,
                    factor,
                    weight: factor * p,
                });
                base.push(nodes.len() as u32);
                nodes.push(Node::Leaf(c as u32));
                if base_level > GEOMETRY_LEVEL && factor * p > 0.0 {
                    heap.push(Candidate(factor * p, nodes.len() - 1));
                }
            }
        }
        for _ in 0..options.splits {
            let Some(Candidate(_, node)) = heap.pop() else {
                break;
            };
            let Node::Leaf(c) = nodes[node] else {
                continue;
            };
            let parent = cells[c as usize];
            let k = parent.level - 1;
            let (kw, kh) = pyramid.dims(k).unwrap_or((0, 0));
            let mut children = [u32::MAX; 4];
            let mut first = true;
            for dy in 0..2 {
                for dx in 0..2 {
                    let (x, y) = (2 * parent.x + dx, 2 * parent.y + dy);
                    if x >= kw || y >= kh {
                        continue;
                    }
                    let factor = factor_of(k, x, y);
                    let weight = factor * pyramid.power(k, x, y);
                    // The first child takes the parent's slot in `cells`.
                    let slot = if first {
                        first = false;
                        cells[c as usize] = CutCell {
                            level: k,
                            x,
                            y,
                            factor,
                            weight,
                        };
                        c as usize
                    } else {
                        cells.push(CutCell {
                            level: k,
                            x,
                            y,
                            factor,
                            weight,
                        });
                        cells.len() - 1
                    };
                    children[dy * 2 + dx] = nodes.len() as u32;
                    nodes.push(Node::Leaf(slot as u32));
                    if k > GEOMETRY_LEVEL && weight > 0.0 {
                        heap.push(Candidate(weight, nodes.len() - 1));
                    }
                }
            }
            nodes[node] = Node::Split(children);
        }
        let mut cdf = Vec::with_capacity(cells.len());
        let mut total = 0.0;
        for c in &cells {
            total += c.weight;
            cdf.push(total);
        }
        let (pw, ph) = pyramid.dims(0).unwrap_or((1, 1));
        Self {
            base_level,
            base_width: bw,
            cells,
            cdf,
            total,
            power,
            nodes,
            base,
            evaluations,
            variant,
            pixels: (pw * ph) as f64,
        }
    }

    /// `W = Σ_c b_c P_c` (0: nothing to sample; the estimator then draws only defensive
    /// samples).
    pub fn total(&self) -> f64 {
        self.total
    }

    /// Cells of the cut.
    pub fn cells(&self) -> usize {
        self.cells.len()
    }

    /// BRDF evaluations the cut took (one per cell that is not culled).
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// The cut cell holding pixel `(px, py)`.
    #[inline]
    fn cell_of(&self, px: usize, py: usize) -> Option<&CutCell> {
        let (bx, by) = (px >> self.base_level, py >> self.base_level);
        let mut node = *self.base.get(by * self.base_width + bx)?;
        let mut k = self.base_level;
        loop {
            match self.nodes.get(node as usize)? {
                Node::Leaf(c) => return self.cells.get(*c as usize),
                Node::Split(ch) => {
                    k -= 1;
                    node = ch[((py >> k) & 1) * 2 + ((px >> k) & 1)];
                }
            }
        }
    }

    /// The density of `c`'s pixel `(px, py)` as the variant reports it.
    #[inline]
    fn density(&self, pyramid: &PowerPyramid, c: &CutCell, px: usize, py: usize) -> f64 {
        if !(self.total > 0.0) {
            return 0.0;
        }
        let y = pyramid.luminance(px, py);
        match self.variant {
            Variant::Correct => c.factor * y / self.total,
            Variant::NoJacobian => {
                c.weight / self.total * pyramid.power(0, px, py) / pyramid.power(c.level, c.x, c.y)
                    * self.pixels
            }
            Variant::ShareOff => {
                pyramid.power(c.level, c.x, c.y) / self.power * y / pyramid.power(c.level, c.x, c.y)
            }
        }
    }

    /// `p_prod` w.r.t. solid angle at the **world** direction `d` (module docs).
    #[inline]
    pub fn pdf_world(&self, pyramid: &PowerPyramid, d: &Vec3) -> f64 {
        let (px, py) = pyramid.pixel_of([d.x, d.y, d.z]);
        match self.cell_of(px, py) {
            Some(c) => self.density(pyramid, c, px, py),
            None => 0.0,
        }
    }

    /// A world direction and its density `p_prod` from three uniforms (`None` when `W = 0`).
    pub fn sample_world(&self, pyramid: &PowerPyramid, u: [f64; 3]) -> Option<(Vec3, f64)> {
        if !(self.total > 0.0) {
            return None;
        }
        let target = u[0] * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cells.len() - 1);
        // Skip zero-weight cells that rounding could land on.
        let i = (i..self.cells.len())
            .chain((0..i).rev())
            .find(|&j| self.cells[j].weight > 0.0)?;
        let c = &self.cells[i];
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let t = ((target - lo) / c.weight).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
        let s = pyramid.sample_in_cell(c.level, c.x, c.y, [t, u[1], u[2]])?;
        Some((
            Vec3::from(s.direction),
            self.density(pyramid, c, s.pixel.0, s.pixel.1),
        ))
    }
}

/// The adaptive product estimator over a batch of points (module docs): the defensive
/// sampler's samples of every point in one [`DirectionSampler::sample_eval_batch`] call, then
/// per point its cut and its product samples.
pub struct ProductBatch<'a> {
    /// The defensive BRDF sampler.
    pub sampler: &'a dyn DirectionSampler,
    /// The BRDF (its `f` reaches the integrand; the cut's factors are its values).
    pub brdf: &'a dyn Brdf,
    /// The map's power pyramid.
    pub pyramid: &'a PowerPyramid,
    /// Samples per point (both techniques together).
    pub spp: usize,
    /// The cut's settings and the defensive share.
    pub options: ProductOptions,
}

impl std::fmt::Debug for ProductBatch<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProductBatch")
            .field("spp", &self.spp)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl ProductBatch<'_> {
    /// `(n_d, n_p)` for `spp` samples.
    pub fn counts(&self) -> (usize, usize) {
        let n = self.spp.max(1);
        let a = self.options.defensive.clamp(0.0, 1.0);
        let nd = ((a * n as f64).round() as usize).clamp(1, n);
        (nd, n - nd)
    }

    /// Per point `F = (1/n) Σ_j g(k, ω_j, f_j) / q(ω_j)` (module docs); `g(k, ωi, f)` is point
    /// `k`'s integrand at the local `ωi` with `f = f_r(ωo, ωi)` of `self.brdf` there.
    pub fn estimate<V: Radiance>(
        &self,
        points: &[Query],
        g: impl Fn(usize, &Vec3, f64) -> V,
        u: &mut dyn UniformSource,
    ) -> Vec<V> {
        self.estimate_with(points, g, u, Variant::Correct)
    }

    pub(crate) fn estimate_with<V: Radiance>(
        &self,
        points: &[Query],
        g: impl Fn(usize, &Vec3, f64) -> V,
        u: &mut dyn UniformSource,
        variant: Variant,
    ) -> Vec<V> {
        let n = self.spp.max(1);
        let (nd0, _) = self.counts();
        let wos: Vec<Vec3> = points
            .iter()
            .flat_map(|p| std::iter::repeat_n(p.wo, nd0))
            .collect();
        let mut drawn: Vec<EvalSample> = Vec::new();
        self.sampler
            .sample_eval_batch(self.brdf, &wos, u, &mut drawn);
        let mut wis: Vec<Vec3> = Vec::with_capacity(n);
        let mut fs: Vec<f64> = Vec::with_capacity(n);
        let mut terms: Vec<(V, f64)> = Vec::with_capacity(n);
        points
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let cut =
                    ProductCut::with_variant(self.pyramid, self.brdf, p, &self.options, variant);
                // All samples defensive when there is nothing to sample by the product.
                let (nd, np) = if cut.total() > 0.0 {
                    (nd0, n - nd0)
                } else {
                    (nd0, 0)
                };
                let total = (nd + np) as f64;
                let (rd, rp) = (nd as f64 / total, np as f64 / total);
                let mut sum = V::default();
                for s in &drawn[k * nd0..(k + 1) * nd0] {
                    if !(s.pdf > 0.0 && s.wi.z > 0.0) {
                        continue;
                    }
                    let gv = g(k, &s.wi, s.f);
                    if gv.any_positive() {
                        let pp = if np > 0 {
                            cut.pdf_world(self.pyramid, &p.frame.to_world(&s.wi))
                        } else {
                            0.0
                        };
                        sum = sum.plus(gv.scale(1.0 / (rd * s.pdf + rp * pp)));
                    }
                }
                wis.clear();
                fs.clear();
                terms.clear();
                for _ in 0..np {
                    let r = [u.next_uniform(), u.next_uniform(), u.next_uniform()];
                    let Some((d, pp)) = cut.sample_world(self.pyramid, r) else {
                        continue;
                    };
                    let wi = p.frame.to_local(&d);
                    if !(wi.z > 0.0 && pp > 0.0) {
                        continue;
                    }
                    let f = self.brdf.eval(&p.wo, &wi);
                    let gv = g(k, &wi, f);
                    if gv.any_positive() {
                        terms.push((gv, pp));
                        wis.push(wi);
                        fs.push(f);
                    }
                }
                if !terms.is_empty() {
                    let pds = self.sampler.pdf_many_given_f(self.brdf, &p.wo, &wis, &fs);
                    for (&(gv, pp), &pd) in terms.iter().zip(&pds) {
                        sum = sum.plus(gv.scale(1.0 / (rd * pd + rp * pp)));
                    }
                }
                sum.scale(1.0 / total)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LocalFrame, ProductScene, estimate_srbf_product, quadrature_reference};
    use baselines::CosineHemisphere;
    use envmap::EnvMap;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// A 128 × 64 map: a dim, slightly varying background, a small bright window and a wide
    /// warm patch.
    fn map() -> EnvMap {
        let (w, h) = (128, 64);
        let rgb = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (80..82).contains(&x) && (20..22).contains(&y) {
                    [400.0, 380.0, 300.0]
                } else if (20..40).contains(&x) && (10..22).contains(&y) {
                    [3.0, 2.0, 1.0]
                } else {
                    [
                        0.1 + 0.005 * (x % 9) as f32,
                        0.12,
                        0.2 + 0.01 * (y % 4) as f32,
                    ]
                }
            })
            .collect();
        EnvMap::new(w, h, rgb).unwrap()
    }

    /// The measurements' map: env `PRODUCT_MAP`, by default the Grace probe of the team's data
    /// directory beside the repository (`../shared/data/envmaps`; not in a user's clone).
    fn measurement_map() -> EnvMap {
        let path = std::env::var("PRODUCT_MAP").unwrap_or_else(|_| {
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../../shared/data/envmaps/grace_probe_latlong.hdr"
            )
            .into()
        });
        EnvMap::load(std::path::Path::new(&path))
            .unwrap_or_else(|e| panic!("measurement map {path}: {e} (set PRODUCT_MAP)"))
    }

    /// The measurements' fixed setup: [`measurement_map`], the sphere images' glossy Phong, its
    /// power pyramid, the map's adaptive sampler and `adaptive-exact`.
    fn phong_on_the_map() -> (
        EnvMap,
        std::sync::Arc<dyn Brdf>,
        PowerPyramid,
        envmap::EnvMapSampler,
        std::sync::Arc<dyn DirectionSampler>,
    ) {
        let map = measurement_map();
        let brdf: std::sync::Arc<dyn Brdf> =
            std::sync::Arc::from(brdf::parse_spec("phong:n=50,ks=0.7,kd=0.3").unwrap());
        let pyr = PowerPyramid::new(&map);
        let light = envmap::EnvMapSampler::new(
            &map,
            envmap::SamplerKind::Adaptive(envmap::AdaptiveOptions::default()),
        )
        .unwrap();
        let sampler = adaptive_exact(&brdf);
        (map, brdf, pyr, light, sampler)
    }

    /// `adaptive-exact` built for `brdf` with the default set options (the defensive sampler
    /// of these tests).
    fn adaptive_exact(brdf: &std::sync::Arc<dyn Brdf>) -> std::sync::Arc<dyn DirectionSampler> {
        samplers::find("adaptive-exact")
            .unwrap()
            .build_direction(&samplers::DirectionRequest::new(
                std::sync::Arc::clone(brdf),
                &brdf_sampling::SetOptions::default(),
            ))
            .unwrap()
            .sampler
    }

    fn options() -> ProductOptions {
        ProductOptions {
            base_cells: 16,
            splits: 12,
            defensive: 0.25,
        }
    }

    /// (normal, θo, φo) of the test points.
    const POINTS: [([f64; 3], f64, f64); 3] = [
        ([0.3, -0.5, 0.8], 35.0, 20.0),
        ([-0.6, 0.2, 0.3], 60.0, 200.0),
        ([0.0, 0.0, 1.0], 10.0, 90.0),
    ];

    fn query(normal: [f64; 3], theta: f64, phi: f64) -> Query {
        Query {
            wo: brdf::direction_from_angles(theta, phi),
            frame: LocalFrame::new(normal, 0.3).unwrap(),
        }
    }

    /// A pixel of the measurements: a uniform normal on the sphere (two uniforms), then
    /// `θo` uniform in [0°, 80°] and `φo` in [0°, 360°), the frame's tangent at angle 0.
    fn random_pixel(pick: &mut Xoshiro256PlusPlus) -> Query {
        let (a, b) = (pick.next_uniform(), pick.next_uniform());
        let z = 1.0 - 2.0 * a;
        let r = (1.0 - z * z).sqrt();
        let normal = [
            r * (std::f64::consts::TAU * b).cos(),
            r * (std::f64::consts::TAU * b).sin(),
            z,
        ];
        let theta = 80.0 * pick.next_uniform();
        Query {
            wo: brdf::direction_from_angles(theta, 360.0 * pick.next_uniform()),
            frame: LocalFrame::new(normal, 0.0).unwrap(),
        }
    }

    /// `∫ p_prod dσ` over the sphere by the map's pixels, each split `s × s` (exact for the
    /// correct density, piecewise constant per pixel).
    fn integral(cut: &ProductCut, pyr: &PowerPyramid, map: &EnvMap, s: usize) -> f64 {
        let (w, h) = (map.width() * s, map.height() * s);
        let mut sum = 0.0;
        for j in 0..h {
            let (v0, v1) = (j as f64 / h as f64, (j + 1) as f64 / h as f64);
            let omega = std::f64::consts::TAU / w as f64
                * ((std::f64::consts::PI * v0).cos() - (std::f64::consts::PI * v1).cos());
            for i in 0..w {
                let d =
                    envmap::latlong::uv_to_direction((i as f64 + 0.5) / w as f64, 0.5 * (v0 + v1));
                sum += cut.pdf_world(pyr, &Vec3::from(d)) * omega;
            }
        }
        sum
    }

    /// The product density integrates to one over the sphere, and the mixture with the cosine
    /// sampler to one too; the Jacobian-dropped mutant does not.
    #[test]
    fn the_product_and_mixture_densities_integrate_to_one() {
        let m = map();
        let pyr = PowerPyramid::new(&m);
        let brdf = brdf::parse_spec("phong:n=50,ks=0.7,kd=0.3").unwrap();
        for (nrm, t, ph) in POINTS {
            let q = query(nrm, t, ph);
            let cut = ProductCut::new(&pyr, brdf.as_ref(), &q, &options());
            assert!(
                cut.total() > 0.0 && cut.cells() > 8 * 4,
                "{} cells",
                cut.cells()
            );
            let i = integral(&cut, &pyr, &m, 2);
            approx::assert_relative_eq!(i, 1.0, max_relative = 1e-9);
            // Mixture with cosine: ∫ (0.25 cos/π + 0.75 p_prod) by a finer rule.
            let (w, h) = (512, 256);
            let mut mix = 0.0;
            for j in 0..h {
                let (v0, v1) = (j as f64 / h as f64, (j + 1) as f64 / h as f64);
                let omega = std::f64::consts::TAU / w as f64
                    * ((std::f64::consts::PI * v0).cos() - (std::f64::consts::PI * v1).cos());
                for k in 0..w {
                    let d = Vec3::from(envmap::latlong::uv_to_direction(
                        (k as f64 + 0.5) / w as f64,
                        0.5 * (v0 + v1),
                    ));
                    let l = q.frame.to_local(&d);
                    mix += (0.25 * CosineHemisphere.pdf(&q.wo, &l)
                        + 0.75 * cut.pdf_world(&pyr, &d))
                        * omega;
                }
            }
            approx::assert_relative_eq!(mix, 1.0, max_relative = 1e-4);
            let bad =
                ProductCut::with_variant(&pyr, brdf.as_ref(), &q, &options(), Variant::NoJacobian);
            let ib = integral(&bad, &pyr, &m, 2);
            assert!((ib - 1.0).abs() > 0.05, "mutant integrates to {ib}");
        }
    }

    /// χ² of the product samples' pixels (grouped 4 × 4) against the reported density's masses;
    /// both mutants (Jacobian dropped, cell share off) are rejected by the same test.
    #[test]
    fn product_samples_follow_the_reported_density() {
        let m = map();
        let pyr = PowerPyramid::new(&m);
        let brdf = brdf::parse_spec("ggx:alpha=0.2").unwrap();
        let (w, h) = (m.width(), m.height());
        for (nrm, t, ph) in POINTS {
            let q = query(nrm, t, ph);
            let cut = ProductCut::new(&pyr, brdf.as_ref(), &q, &options());
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
            let n = 100_000;
            let mut counts = vec![0u64; (w / 4) * (h / 4)];
            for _ in 0..n {
                let r = [rng.next_uniform(), rng.next_uniform(), rng.next_uniform()];
                let (d, p) = cut.sample_world(&pyr, r).unwrap();
                approx::assert_relative_eq!(p, cut.pdf_world(&pyr, &d), max_relative = 1e-12);
                let (px, py) = pyr.pixel_of([d.x, d.y, d.z]);
                counts[(py / 4) * (w / 4) + px / 4] += 1;
            }
            let masses = |c: &ProductCut| -> Vec<f64> {
                let mut e = vec![0.0; (w / 4) * (h / 4)];
                for py in 0..h {
                    for px in 0..w {
                        let y = pyr.luminance(px, py);
                        if y > 0.0 {
                            let d = envmap::latlong::uv_to_direction(
                                (px as f64 + 0.5) / w as f64,
                                (py as f64 + 0.5) / h as f64,
                            );
                            let omega = pyr.power(0, px, py) / y;
                            e[(py / 4) * (w / 4) + px / 4] +=
                                n as f64 * c.pdf_world(&pyr, &Vec3::from(d)) * omega;
                        }
                    }
                }
                e
            };
            let r = stats::chi_square_gof(&counts, &masses(&cut), 5.0).unwrap();
            assert!(r.p_value > 1e-3, "{}", r.summary());
            for v in [Variant::NoJacobian, Variant::ShareOff] {
                let bad = ProductCut::with_variant(&pyr, brdf.as_ref(), &q, &options(), v);
                let r = stats::chi_square_gof(&counts, &masses(&bad), 5.0).unwrap();
                assert!(r.p_value < 1e-6, "{v:?} not rejected: {}", r.summary());
            }
        }
    }

    /// The estimator's mean over many points equals the pixel quadrature (|z| < 4) at three
    /// points, with `adaptive-exact` as the defensive sampler, also with the pyramid of another
    /// map (a poor product density); both mutants are caught.
    #[test]
    fn the_estimator_agrees_with_the_quadrature_and_broken_densities_do_not() {
        let m = map();
        let pyr = PowerPyramid::new(&m);
        let spec = "phong:n=50,ks=0.7,kd=0.3";
        let brdf: std::sync::Arc<dyn Brdf> = std::sync::Arc::from(brdf::parse_spec(spec).unwrap());
        let sampler = adaptive_exact(&brdf);
        // A pyramid of another map (the window 10× dimmer, the patch 10× dimmer, the
        // background brighter towards the right): a poor product density, the estimator must
        // stay unbiased. (A map without the window at all is also unbiased but heavy-tailed:
        // the window is then reached by the defensive samples alone, a few times in the run,
        // and the mean of 3000 points sits at z = −41 — measured; the quadrature needs a
        // bounded weight to be a fair yardstick.)
        let other = EnvMap::new(
            128,
            64,
            (0..128 * 64)
                .map(|i| {
                    let (x, y) = (i % 128, i / 128);
                    if (80..82).contains(&x) && (20..22).contains(&y) {
                        [40.0; 3]
                    } else if (20..40).contains(&x) && (10..22).contains(&y) {
                        [0.3; 3]
                    } else {
                        [0.05 + 0.01 * (x / 8) as f32; 3]
                    }
                })
                .collect(),
        )
        .unwrap();
        let other = PowerPyramid::new(&other);
        for (i, (nrm, t, ph)) in POINTS.into_iter().enumerate() {
            let q = query(nrm, t, ph);
            let scene = ProductScene::new(brdf.as_ref(), &m, q.frame, q.wo).unwrap();
            let (reference, err) = quadrature_reference(&scene, 3);
            assert!(err < 1e-3 * reference, "{reference} ± {err}");
            let batch = ProductBatch {
                sampler: sampler.as_ref(),
                brdf: brdf.as_ref(),
                pyramid: &pyr,
                spp: 8,
                options: options(),
            };
            let points = vec![q; 3000];
            let z = |v: Variant| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(5 + i as u64);
                let est = batch.estimate_with(
                    &points,
                    |_, wi, f| scene.integrand_with_f(wi, f),
                    &mut rng,
                    v,
                );
                let (mean, var) = stats::mean_variance(&est);
                (mean - reference) / (var / est.len() as f64).sqrt()
            };
            let good = z(Variant::Correct);
            assert!(good.abs() < 4.0, "point {i}: z = {good}");
            let poor = ProductBatch {
                pyramid: &other,
                ..batch
            };
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(50 + i as u64);
            let est = poor.estimate(&points, |_, wi, f| scene.integrand_with_f(wi, f), &mut rng);
            let (mean, var) = stats::mean_variance(&est);
            let zp = (mean - reference) / (var / est.len() as f64).sqrt();
            assert!(zp.abs() < 4.0, "point {i}: another map's pyramid, z = {zp}");
            for v in [Variant::NoJacobian, Variant::ShareOff] {
                let bad = z(v);
                assert!(bad.abs() > 4.0, "point {i}: {v:?} not caught, z = {bad}");
            }
        }
    }

    /// Product against product, per pixel, on a map (env `PRODUCT_MAP`, default the team's
    /// Grace probe): Tsai's SRBF product (`estimate_srbf_product`, the `product` command's
    /// default fits and settings) and the adaptive product (`adaptive-exact` defensive), each
    /// at 64 samples per pixel at 12 random (normal, ωo) of the sphere images' kind (θo ≤ 80°),
    /// 100 repeats each: ns per pixel (one thread, wall) and the variance of the pixel value
    /// relative to the quadrature; the efficiency ratio `(var·t)_srbf / (var·t)_adaptive`.
    /// docs/benchmarks.md §26.6.
    #[test]
    #[ignore = "a measurement (a minute or two): docs/benchmarks.md §26.6"]
    fn product_against_product_per_pixel() {
        use baselines::srbf::fit_envmap;
        use baselines::{SrbfOptions, SrbfSampler};
        use std::time::Instant;
        let map = measurement_map();
        let spec =
            std::env::var("PRODUCT_BRDF").unwrap_or_else(|_| "phong:n=50,ks=0.7,kd=0.3".into());
        let brdf: std::sync::Arc<dyn Brdf> = std::sync::Arc::from(brdf::parse_spec(&spec).unwrap());
        let t = Instant::now();
        let pyr = PowerPyramid::new(&map);
        eprintln!(
            "pyramid: {:.1} ms, {} bytes",
            t.elapsed().as_secs_f64() * 1e3,
            pyr.bytes_used()
        );
        let options = SrbfOptions::default();
        let t = Instant::now();
        let brdf_fit = SrbfSampler::build(brdf.as_ref(), &options).unwrap();
        let t_brdf = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let map_fit = fit_envmap(&map, &options).unwrap();
        eprintln!(
            "srbf fits: BRDF {t_brdf:.2} s, map {:.2} s ({} lobes)",
            t.elapsed().as_secs_f64(),
            map_fit.lobes.len()
        );
        let light = envmap::EnvMapSampler::piecewise_constant(&map).unwrap();
        let settings = options.product_settings();
        let sampler = adaptive_exact(&brdf);
        let mut pick = Xoshiro256PlusPlus::seed_from_u64(3);
        let (spp, reps) = (64, 100);
        let mut ratios = Vec::new();
        for i in 0..12 {
            let q = random_pixel(&mut pick);
            let theta = q.wo.z.acos().to_degrees();
            let scene = ProductScene::new(brdf.as_ref(), &map, q.frame, q.wo).unwrap();
            let (reference, _) = quadrature_reference(&scene, 1);
            if !(reference > 0.0) {
                continue;
            }
            let rel_var = |v: &[f64]| {
                let (m, var) = stats::mean_variance(v);
                let _ = m;
                var / (reference * reference)
            };
            let t = Instant::now();
            let srbf: Vec<f64> = (0..reps)
                .map(|s| {
                    estimate_srbf_product(
                        &scene, &brdf_fit, &map_fit, &light, &settings, spp, s as u64,
                    )
                    .unwrap()
                    .0
                    .estimate
                })
                .collect();
            let t_srbf = t.elapsed().as_secs_f64() * 1e9 / reps as f64;
            let batch = ProductBatch {
                sampler: sampler.as_ref(),
                brdf: brdf.as_ref(),
                pyramid: &pyr,
                spp,
                options: ProductOptions::default(),
            };
            let points = vec![q; reps];
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(9 + i);
            let t = Instant::now();
            let ours = batch.estimate(&points, |_, wi, f| scene.integrand_with_f(wi, f), &mut rng);
            let t_ours = t.elapsed().as_secs_f64() * 1e9 / reps as f64;
            let (vs, vo) = (rel_var(&srbf), rel_var(&ours));
            let ratio = (vs * t_srbf) / (vo * t_ours);
            ratios.push(ratio);
            eprintln!(
                "pixel {i}: θo {theta:.0}°, srbf {t_srbf:.0} ns/pixel, rel. sd {:.4}; adaptive product {t_ours:.0} ns/pixel, rel. sd {:.4}; efficiency ratio {ratio:.2}",
                vs.sqrt(),
                vo.sqrt()
            );
        }
        ratios.sort_by(f64::total_cmp);
        eprintln!(
            "median efficiency ratio (srbf var·t / adaptive var·t): {:.2}",
            ratios[ratios.len() / 2]
        );
    }

    /// The adaptive product's options on a map (env `PRODUCT_MAP`, default the Grace probe) and
    /// BRDF (`PRODUCT_BRDF`): at the same 12 pixels as [`product_against_product_per_pixel`],
    /// 100 repeats of 64 samples, the relative variance × ns per pixel of each variant against
    /// the default's (median over the pixels; > 1: the variant is less efficient).
    /// docs/benchmarks.md §26.6.
    #[test]
    #[ignore = "a measurement (about a minute): docs/benchmarks.md §26.6"]
    fn product_options_sweep() {
        use std::time::Instant;
        let map = measurement_map();
        let spec =
            std::env::var("PRODUCT_BRDF").unwrap_or_else(|_| "phong:n=50,ks=0.7,kd=0.3".into());
        let brdf: std::sync::Arc<dyn Brdf> = std::sync::Arc::from(brdf::parse_spec(&spec).unwrap());
        let pyr = PowerPyramid::new(&map);
        let sampler = adaptive_exact(&brdf);
        let d = ProductOptions::default();
        let variants = [
            ("default (16 cells, 16 splits, α 0.25)", d),
            ("no splits", ProductOptions { splits: 0, ..d }),
            ("48 splits", ProductOptions { splits: 48, ..d }),
            ("8 base cells", ProductOptions { base_cells: 8, ..d }),
            (
                "32 base cells",
                ProductOptions {
                    base_cells: 32,
                    ..d
                },
            ),
            (
                "α 0.1",
                ProductOptions {
                    defensive: 0.1,
                    ..d
                },
            ),
            (
                "α 0.5",
                ProductOptions {
                    defensive: 0.5,
                    ..d
                },
            ),
        ];
        let mut pick = Xoshiro256PlusPlus::seed_from_u64(3);
        let (spp, reps) = (64, 100);
        let mut ratios = vec![Vec::new(); variants.len()];
        for i in 0..12 {
            let q = random_pixel(&mut pick);
            let scene = ProductScene::new(brdf.as_ref(), &map, q.frame, q.wo).unwrap();
            let (reference, _) = quadrature_reference(&scene, 1);
            if !(reference > 0.0) {
                continue;
            }
            let points = vec![q; reps];
            let cost: Vec<f64> = variants
                .iter()
                .map(|(_, o)| {
                    let batch = ProductBatch {
                        sampler: sampler.as_ref(),
                        brdf: brdf.as_ref(),
                        pyramid: &pyr,
                        spp,
                        options: *o,
                    };
                    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9 + i);
                    let t = Instant::now();
                    let v =
                        batch.estimate(&points, |_, wi, f| scene.integrand_with_f(wi, f), &mut rng);
                    let ns = t.elapsed().as_secs_f64() * 1e9 / reps as f64;
                    let (_, var) = stats::mean_variance(&v);
                    var / (reference * reference) * ns
                })
                .collect();
            for (k, c) in cost.iter().enumerate() {
                ratios[k].push(c / cost[0]);
            }
        }
        for ((name, _), r) in variants.iter().zip(&mut ratios) {
            r.sort_by(f64::total_cmp);
            eprintln!(
                "{name}: var·t / default's, median {:.2} (min {:.2}, max {:.2}) over {} pixels",
                r[r.len() / 2],
                r[0],
                r[r.len() - 1],
                r.len()
            );
        }
    }

    /// A deterministic workload for instruction counts (`valgrind --tool=cachegrind`): env
    /// `H12_WORK` = `product` (the adaptive product) or `mis` (MIS of `adaptive-exact` and the
    /// `envmap-adaptive` sampler, `Batch::mis_given_f`), `H12_POINTS` points (random normals and
    /// ωo, θo ≤ 80°, each its own batch call) × `H12_SPP` samples (pairs for MIS), phong on the
    /// Grace probe; prints a checksum. Differences of runs cancel the setup. §26.6.
    #[test]
    #[ignore = "a workload for instruction counts: docs/benchmarks.md §26.6"]
    fn instruction_workload() {
        let env = |k: &str, d: usize| {
            std::env::var(k)
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(d)
        };
        let (points, spp) = (env("H12_POINTS", 100), env("H12_SPP", 8));
        let work = std::env::var("H12_WORK").unwrap_or_else(|_| "product".into());
        let (map, brdf, pyr, light, sampler) = phong_on_the_map();
        let mut pick = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        let mut sum = 0.0;
        for _ in 0..points {
            let q = random_pixel(&mut pick);
            let scene = ProductScene::new(brdf.as_ref(), &map, q.frame, q.wo).unwrap();
            let g = |_: usize, wi: &Vec3, f: f64| scene.integrand_with_f(wi, f);
            let v = if work == "mis" {
                crate::Batch {
                    sampler: sampler.as_ref(),
                    brdf: brdf.as_ref(),
                    spp,
                }
                .mis_given_f(
                    &[q],
                    &light,
                    crate::MisHeuristic::Balance,
                    g,
                    &mut rng,
                )
            } else {
                ProductBatch {
                    sampler: sampler.as_ref(),
                    brdf: brdf.as_ref(),
                    pyramid: &pyr,
                    spp,
                    options: ProductOptions::default(),
                }
                .estimate(&[q], g, &mut rng)
            };
            sum += v[0];
        }
        eprintln!("{work}: {points} points × {spp}: checksum {sum:.12e}");
    }

    /// At an instruction budget (§26.6: a MIS pair of `adaptive-exact` + `envmap-adaptive`
    /// costs 3 287 instructions and 4 809 per pixel; the product 1 674 per sample and 74 200 per
    /// pixel), 25 MIS pairs ≈ 87 k instructions ≈ the product's setup + 8 samples: the relative
    /// RMS error against the quadrature of each, phong on the Grace probe, the 12 pixels of
    /// [`product_options_sweep`], 100 repeats.
    #[test]
    #[ignore = "a measurement (about a minute): docs/benchmarks.md §26.6"]
    fn product_8_against_mis_25_per_pixel() {
        let (map, brdf, pyr, light, sampler) = phong_on_the_map();
        let mut pick = Xoshiro256PlusPlus::seed_from_u64(3);
        let reps = 100;
        let (mut sp, mut sm) = (Vec::new(), Vec::new());
        for i in 0..12 {
            let q = random_pixel(&mut pick);
            let theta = q.wo.z.acos().to_degrees();
            let scene = ProductScene::new(brdf.as_ref(), &map, q.frame, q.wo).unwrap();
            let (reference, _) = quadrature_reference(&scene, 1);
            if !(reference > 0.0) {
                continue;
            }
            let points = vec![q; reps];
            let rms = |v: &[f64]| {
                (v.iter().map(|x| (x / reference - 1.0).powi(2)).sum::<f64>() / v.len() as f64)
                    .sqrt()
            };
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(9 + i);
            let p = ProductBatch {
                sampler: sampler.as_ref(),
                brdf: brdf.as_ref(),
                pyramid: &pyr,
                spp: 8,
                options: ProductOptions::default(),
            }
            .estimate(&points, |_, wi, f| scene.integrand_with_f(wi, f), &mut rng);
            let m = crate::Batch {
                sampler: sampler.as_ref(),
                brdf: brdf.as_ref(),
                spp: 25,
            }
            .mis_given_f(
                &points,
                &light,
                crate::MisHeuristic::Balance,
                |_, wi, f| scene.integrand_with_f(wi, f),
                &mut rng,
            );
            let (ep, em) = (rms(&p), rms(&m));
            eprintln!(
                "pixel {i}: θo {theta:.0}°, product 8 spp rel. RMS {ep:.4}, MIS 25 pairs {em:.4}"
            );
            sp.push(ep);
            sm.push(em);
        }
        sp.sort_by(f64::total_cmp);
        sm.sort_by(f64::total_cmp);
        eprintln!(
            "median rel. RMS: product 8 spp {:.4}, MIS 25 pairs {:.4}",
            sp[sp.len() / 2],
            sm[sm.len() / 2]
        );
    }
}
