//! The settings of an [`ExactSet`](crate::ExactSet)(crate::ExactSet) and its public constants.

use partition_sampler::TreeParams;

use crate::options::SetOptions;

use super::error::ExactError;

/// The largest outgoing polar angle the nodes use (degrees): `f_r` at exactly 90° is 0 or
/// undefined. A query above it is served as the direction of the same azimuth at this angle
/// (samples ∝ `f_r(ωo', ·) cos θi`, pdf normalised, bounds valid; `f_r` may diverge there).
pub const THETA_TOP_DEG: f64 = 89.99;

/// Largest azimuth spacing of an interval's δ bound nodes (degrees): an anisotropic lobe turns
/// with δ, and the envelope of nodes farther apart dips below the densities between them (a
/// 90° cell with 3 nodes let 3 trials in 10⁶ exceed their bound on `ward` with
/// `alpha_x = 0.1, alpha_y = 0.3`).
pub const MAX_DELTA_NODE_SPACING_DEG: f64 = 11.25;

/// Largest split threshold `n_max` of an RGL material's envelope trees (issue 29): a leaf is
/// split while `n_max · I_i / V_i < 1`, i.e. until its bound volume `V_i = area_i · M_i` is at
/// most `n_max` times its envelope integral `I_i`. At the sets' defaults (1.8, volume
/// tolerance 2 %) the paper_white intervals had 60–72 leaves and the leaf
/// bounds' excess over the envelope, `Σ max_i F · area_i / ∫ F`, was a factor 1.34–1.38 of
/// the 1.51–1.56 evaluations per sample (the safety factor 1.11, the θo range 1.005–1.025);
/// at 1.2 and 0.2 %, 1.11 and 1.24–1.27 per sample (docs/benchmarks.md §28.5).
pub const RGL_N_MAX: f64 = 1.2;

/// Largest `volume_tolerance` of an RGL material's envelope trees (issue 29): a leaf whose
/// bound volume is at most this share of the root's envelope integral is not split. The sets'
/// default 2 % stopped the paper_white trees at ~65 leaves whatever `n_max`.
pub const RGL_VOLUME_TOLERANCE: f64 = 2e-3;

/// Smallest `max_depth` of an RGL material's envelope trees (issue 29, docs/benchmarks.md
/// §30.1): at the sets' 7, 62–88 % of `cc_ibiza_sunset`'s bound volume lay in leaves stopped by
/// the depth limit (2 × 2 image-map pixels each); at 8 (with the image map at
/// [`envelope_grid`]'s 512 cells per axis) its evaluations per sample fell from 1.65 / 1.57 /
/// 1.43 to 1.63 / 1.53 / 1.30 at θo 30 / 60 / 80° and its build got cheaper (fewer intervals
/// split for their trials).
pub const RGL_MAX_DEPTH: u32 = 8;

/// The tree parameters of an interval's envelope tree for `brdf`: `set.tree`, with `n_max` and
/// `volume_tolerance` at most [`RGL_N_MAX`] and [`RGL_VOLUME_TOLERANCE`] for an RGL material
/// (finer leaves: fewer rejected trials, hence fewer evaluations of the costly interpolant
/// per sample). The bound rule is unchanged — `M_i = safety_factor ×` the largest image-map
/// sample over leaf `i` — so at every point the bound is still at least `safety_factor ×` the
/// samples of the image-map cells around it, the margin the coarse leaves had at their
/// maximum; finer leaves drop only the slack of a coarse leaf's maximum elsewhere in it. Other
/// BRDFs get `set.tree` unchanged. RGL materials also get `max_depth` at least
/// [`RGL_MAX_DEPTH`] (their image map at least [`envelope_grid`]'s, so that
/// `2^(max_depth + 1) ≤ grid` still holds).
pub fn envelope_tree_params(set: &SetOptions, brdf: &dyn brdf::Brdf) -> TreeParams {
    let mut tree = set.tree;
    if is_rgl(brdf) {
        tree.n_max = tree.n_max.min(RGL_N_MAX);
        tree.volume_tolerance = tree.volume_tolerance.min(RGL_VOLUME_TOLERANCE);
        tree.max_depth = tree.max_depth.max(RGL_MAX_DEPTH);
    }
    tree
}

/// Cells per axis of an interval envelope's image map for `brdf`: `set.grid`, for an RGL
/// material at least `2^(max_depth + 1)` of [`envelope_tree_params`]' depth (512 at
/// [`RGL_MAX_DEPTH`]): the image map finer than the deepest leaf, as
/// [`SetOptions::tree`]'s rule asks.
pub fn envelope_grid(set: &SetOptions, brdf: &dyn brdf::Brdf) -> usize {
    if is_rgl(brdf) {
        let depth = envelope_tree_params(set, brdf).max_depth;
        set.grid.max(1usize << (depth + 1).min(16))
    } else {
        set.grid
    }
}

/// Whether `brdf` is an RGL material.
fn is_rgl(brdf: &dyn brdf::Brdf) -> bool {
    brdf.as_any().is_some_and(|a| a.is::<brdf::RglBrdf>())
}

/// Settings of [`ExactSet`](crate::ExactSet). `set` supplies the tree parameters, image map, safety factor,
/// disc-map policy and symmetries (its slice counts are unused: the intervals and azimuth cells
/// adapt).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExactOptions {
    /// The quadtree settings shared with the other adaptive sets.
    pub set: SetOptions,
    /// θ intervals before splitting (equal widths over `[0°, 90°]`).
    pub initial_intervals: usize,
    /// Azimuth cells per full turn before splitting (anisotropic BRDFs; an even count is halved
    /// over `[0, π)` for half-turn-symmetric ones, as the sets' `anisotropic_slices`).
    pub initial_phi_cells: usize,
    /// θ nodes of the bound envelope per interval (uniform, ends included; ≥ 2).
    pub bound_nodes: usize,
    /// δ nodes of the bound envelope per interval (anisotropic BRDFs; ≥ 2), more where the
    /// interval is wider in azimuth than this many nodes [`MAX_DELTA_NODE_SPACING_DEG`] apart.
    pub phi_bound_nodes: usize,
    /// Chebyshev–Lobatto θ nodes of the normaliser table (3 ..= 32).
    pub normaliser_nodes: usize,
    /// Chebyshev–Lobatto δ nodes of the normaliser table (anisotropic BRDFs; 3 ..= 32).
    pub phi_normaliser_nodes: usize,
    /// Split an interval whose mean trials `Σ V_i / A` exceed this at a normaliser node (> 1).
    pub max_trials: f64,
    /// Split an interval whose relative interpolation tail exceeds this (> 0).
    pub normaliser_tol: f64,
    /// Narrowest interval, in θ and in azimuth (degrees, > 0).
    pub min_width_deg: f64,
    /// Store the leaves' thinning bounds for RGL materials (docs/benchmarks.md §30.1): per
    /// leaf `i` and each of its 4 × 4 sub-cells `s`, `M_is ≥` the leaf rule's bound over `s`
    /// (`safety ×` the image map's largest sample there, the peak track, the rim band), `≤ M_i`;
    /// the fixed-`ωo` wavefront rejects a trial whose threshold `u₃·M_i ≥ M_is` without
    /// evaluating `f` (the same samples; fewer evaluations). Other BRDFs: unused.
    pub thinning: bool,
    /// Most θo layers of the thinning bounds (docs/benchmarks.md §30.6; ≥ 1): an RGL interval's θo
    /// range `[θ_a, θ_b]` is cut into `L = ⌊(θ_b − θ_a) / thinning_layer_deg⌋` equal layers (in
    /// the grid's rationals; `L` clamped to `[1, thinning_layers]`), each with its own
    /// codes over the same tree, leaf bounds and alias table, from the envelope of the layer's
    /// end nodes and the peak track inside it; the fixed-`ωo` wavefront reads the layer of its
    /// θo. 1: the interval's codes (§30.1).
    pub thinning_layers: usize,
    /// The narrowest θo layer of the thinning bounds (degrees, > 0), see
    /// [`ExactOptions::thinning_layers`].
    pub thinning_layer_deg: f64,
    /// The growth of a sub-cell's rectangle before the leaf rule bounds it (in image-map
    /// cells, `[0, 4]`): sub-cell `s` of leaf `i` gets `min(M_i, region(s grown by this many
    /// cells on every side).max_bound)` (docs/benchmarks.md §30.7: with 0, `f` exceeded the
    /// bare rule at one of 1.38·10⁶ checked points).
    pub thinning_growth: f64,
    /// Bound the sub-cells of an RGL material's one-layer intervals rigorously
    /// (docs/benchmarks.md §31.3): in an isotropic interval with one θo layer (narrower than
    /// `2 · thinning_layer_deg`: the grazing intervals), `M_is = min(M_i, B_s)` with `B_s = J ·
    /// max_k RglBrdf::f_cos_bound(piece k, box of ωi over s)` over the interval's θo range in
    /// pieces of ≤ 0.5° (`J` = 2 on the equal-area map, `1/min cos θi` projected, `+∞` at the
    /// projected rim): an upper bound of `g` over the sub-cell at every θo the codes serve, in
    /// place of the grown leaf rule ([`ExactOptions::thinning_growth`]), which `g` exceeds on
    /// `cc_ibiza_sunset` at 84.4°. In a layered interval (docs/benchmarks.md §31.4) layer
    /// `[θ_l, θ_{l+1}]` takes `M_ils = min(M_i, grown rule, B_s)` with `B_s` over the layer's θo
    /// range in pieces of ≤ 1° (at most the grown rule; exceeded only where both are). The
    /// samples do not change.
    pub thinning_rigorous: bool,
}

impl ExactOptions {
    /// Default initial interval count.
    pub const DEFAULT_INITIAL_INTERVALS: usize = 6;
    /// Default azimuth cells per turn before splitting.
    pub const DEFAULT_INITIAL_PHI_CELLS: usize = 8;
    /// Default θ bound nodes.
    pub const DEFAULT_BOUND_NODES: usize = 3;
    /// Default δ bound nodes.
    pub const DEFAULT_PHI_BOUND_NODES: usize = 3;
    /// Default θ normaliser nodes.
    pub const DEFAULT_NORMALISER_NODES: usize = 9;
    /// Default δ normaliser nodes.
    pub const DEFAULT_PHI_NORMALISER_NODES: usize = 5;
    /// Default trial cap.
    pub const DEFAULT_MAX_TRIALS: f64 = 2.0;
    /// Default interpolation tolerance.
    pub const DEFAULT_NORMALISER_TOL: f64 = 1e-6;
    /// Default θo layers of the thinning bounds (RGL materials).
    pub const DEFAULT_THINNING_LAYERS: usize = 4;
    /// Default narrowest θo layer of the thinning bounds (degrees).
    pub const DEFAULT_THINNING_LAYER_DEG: f64 = 1.5;
    /// Default growth of a sub-cell before the leaf rule bounds it (image-map cells).
    pub const DEFAULT_THINNING_GROWTH: f64 = 1.0;
    /// Default narrowest interval (degrees).
    pub const DEFAULT_MIN_WIDTH_DEG: f64 = 0.25;

    /// The defaults around `set`.
    pub fn with_set(set: SetOptions) -> Self {
        Self {
            set,
            initial_intervals: Self::DEFAULT_INITIAL_INTERVALS,
            initial_phi_cells: Self::DEFAULT_INITIAL_PHI_CELLS,
            bound_nodes: Self::DEFAULT_BOUND_NODES,
            phi_bound_nodes: Self::DEFAULT_PHI_BOUND_NODES,
            normaliser_nodes: Self::DEFAULT_NORMALISER_NODES,
            phi_normaliser_nodes: Self::DEFAULT_PHI_NORMALISER_NODES,
            max_trials: Self::DEFAULT_MAX_TRIALS,
            normaliser_tol: Self::DEFAULT_NORMALISER_TOL,
            min_width_deg: Self::DEFAULT_MIN_WIDTH_DEG,
            thinning: true,
            thinning_layers: Self::DEFAULT_THINNING_LAYERS,
            thinning_layer_deg: Self::DEFAULT_THINNING_LAYER_DEG,
            thinning_growth: Self::DEFAULT_THINNING_GROWTH,
            thinning_rigorous: true,
        }
    }

    /// Checks every field (and `set`).
    pub fn validate(&self) -> Result<(), ExactError> {
        self.set.validate()?;
        let bad = |what: &'static str, value: f64| Err(ExactError::Invalid { what, value });
        if !(1..=90).contains(&self.initial_intervals) {
            return bad(
                "initial_intervals (1 ..= 90)",
                self.initial_intervals as f64,
            );
        }
        if !(1..=64).contains(&self.initial_phi_cells) {
            return bad(
                "initial_phi_cells (1 ..= 64)",
                self.initial_phi_cells as f64,
            );
        }
        if !(2..=64).contains(&self.bound_nodes) {
            return bad("bound_nodes (2 ..= 64)", self.bound_nodes as f64);
        }
        if !(2..=64).contains(&self.phi_bound_nodes) {
            return bad("phi_bound_nodes (2 ..= 64)", self.phi_bound_nodes as f64);
        }
        if !(3..=32).contains(&self.normaliser_nodes) {
            return bad("normaliser_nodes (3 ..= 32)", self.normaliser_nodes as f64);
        }
        if !(3..=32).contains(&self.phi_normaliser_nodes) {
            return bad(
                "phi_normaliser_nodes (3 ..= 32)",
                self.phi_normaliser_nodes as f64,
            );
        }
        if !(self.max_trials > 1.0 && self.max_trials.is_finite()) {
            return bad("max_trials (> 1)", self.max_trials);
        }
        if !(self.normaliser_tol > 0.0 && self.normaliser_tol.is_finite()) {
            return bad("normaliser_tol (> 0)", self.normaliser_tol);
        }
        if !(self.min_width_deg > 0.0 && self.min_width_deg <= 90.0) {
            return bad("min_width_deg (0, 90]", self.min_width_deg);
        }
        if !(1..=16).contains(&self.thinning_layers) {
            return bad("thinning_layers (1 ..= 16)", self.thinning_layers as f64);
        }
        if !(self.thinning_layer_deg > 0.0 && self.thinning_layer_deg <= 90.0) {
            return bad("thinning_layer_deg (0, 90]", self.thinning_layer_deg);
        }
        if !(0.0..=4.0).contains(&self.thinning_growth) {
            return bad("thinning_growth [0, 4]", self.thinning_growth);
        }
        Ok(())
    }
}

impl Default for ExactOptions {
    fn default() -> Self {
        Self::with_set(SetOptions::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RGL materials get `n_max` and `volume_tolerance` capped at the RGL values (a tighter
    /// setting of the caller's is kept); other BRDFs get `set.tree` unchanged.
    #[test]
    fn envelope_tree_params_cap_rgl_materials_only() {
        let set = SetOptions::default();
        let phong = brdf::parse_spec("phong:n=50").unwrap();
        assert_eq!(envelope_tree_params(&set, phong.as_ref()), set.tree);
        // The repository's RGL fixture, loaded here (not through `exact::tests`: no file
        // imports another round a loop).
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/measured/rgl/paper_white_rgb.bsdf");
        let Ok(rgl) = brdf::RglBrdf::load(&path) else {
            eprintln!("skipped: the RGL fixture {} is missing", path.display());
            return;
        };
        let tree = envelope_tree_params(&set, &rgl);
        assert_eq!(tree.n_max, RGL_N_MAX);
        assert_eq!(tree.volume_tolerance, RGL_VOLUME_TOLERANCE);
        assert_eq!(tree.max_depth, RGL_MAX_DEPTH);
        assert_eq!(envelope_grid(&set, &rgl), 512);
        assert_eq!(envelope_grid(&set, phong.as_ref()), set.grid);
        let deep = set.with_depth(9);
        assert_eq!(envelope_tree_params(&deep, &rgl).max_depth, 9);
        assert_eq!(envelope_grid(&deep, &rgl), 1024);
        let mut tight = set;
        tight.tree.n_max = 1.1;
        tight.tree.volume_tolerance = 1e-4;
        let tree = envelope_tree_params(&tight, &rgl);
        assert_eq!((tree.n_max, tree.volume_tolerance), (1.1, 1e-4));
    }
}
