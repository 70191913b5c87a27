//! `brdf_lab.EnvMapSampler` (lat-long maps) and `brdf_lab.PartitionSampler` (any bounded 2D
//! density given as a NumPy table).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

use envmap::{AdaptiveOptions, EnvMap, EnvSample, LeafChoice};
use numpy::{PyArray1, PyArray2};
use partition_sampler::{
    InvertibleSampler2D, PiecewiseConstant2D, QuadTreeBuilder, QuadTreeSampler, Rect, Sample2,
    Sampler2D, TabulatedDensity, TreeParams, UniformSource,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::arrays::{ArrayIn, dirs, points, rows, vec1};
use crate::direction::{UArg, UIn, chunked, view_of};
use crate::errors::{invalid, value_error};
use crate::threads::{install, next_seed, par_map};

/// The uniforms that `t` maps to each point (N, 2); NaN rows where the density is zero.
fn invert_points<'py>(
    py: Python<'py>,
    t: &(impl InvertibleSampler2D + Sync),
    p: &[[f64; 2]],
) -> Bound<'py, PyArray2<f64>> {
    rows(
        py,
        par_map(py, p, |q| t.invert(*q).unwrap_or([f64::NAN; 2])),
    )
}

/// Tree options shared by both planar samplers.
fn tree_params(
    mut t: TreeParams,
    n_max: Option<f64>,
    max_depth: Option<u32>,
    leaf_choice: Option<&str>,
) -> PyResult<TreeParams> {
    if let Some(n) = n_max {
        t.n_max = n;
    }
    if let Some(d) = max_depth {
        t.max_depth = d;
    }
    if let Some(c) = leaf_choice {
        t.leaf_choice = match c {
            "alias" => LeafChoice::Alias,
            "descent" => LeafChoice::Descent,
            other => {
                return Err(invalid(format!(
                    "leaf_choice must be \"alias\" or \"descent\", got {other:?}"
                )));
            }
        };
    }
    t.validate().map_err(|e| value_error(&e))?;
    Ok(t)
}

/// Draws `u.len()` planar samples of `s`: with given uniforms, each query starts from its row
/// (an invertible sampler warps it exactly, `warp`); with a count, the library's reproducible
/// parallel path (`partition_sampler::sample_par`).
fn sample_planar<S: Sampler2D + Sync + ?Sized>(
    s: &S,
    warp: Option<&(dyn Fn([f64; 2]) -> Sample2 + Sync)>,
    u: &UArg<'_>,
    seed: u64,
) -> Vec<Sample2> {
    match (u, warp) {
        (UArg::Count(n), _) => install(|| partition_sampler::sample_par(s, *n, seed)),
        (UArg::Given(v), Some(w)) => {
            let v: &[f64] = v;
            install(|| {
                (0..v.len() / 2)
                    .into_par_iter()
                    .with_min_len(1024)
                    .map(|k| w(UArg::row(v, k)))
                    .collect()
            })
        }
        (UArg::Given(_), None) => chunked(u.len(), u, seed, |_, src: &mut dyn UniformSource| {
            let x = s.sample(src);
            (x.point, x.pdf)
        })
        .into_iter()
        .map(|(point, pdf)| Sample2 { point, pdf })
        .collect(),
    }
}

/// Statistics of a quadtree sampler as a dict.
fn tree_report<'py, D: partition_sampler::RegionStats>(
    py: Python<'py>,
    t: &QuadTreeSampler<D>,
    d: &Bound<'py, PyDict>,
) -> PyResult<()> {
    let s = t.stats();
    d.set_item("nodes", s.nodes)?;
    d.set_item("leaves", s.leaves)?;
    d.set_item("active_leaves", s.active_leaves)?;
    d.set_item("depth", s.depth)?;
    d.set_item("expected_mean_trials", s.expected_mean_trials)?;
    d.set_item("bound_violations", s.bound_violations)?;
    let m = t.memory();
    let mem = PyDict::new(py);
    mem.set_item("leaves", m.leaves)?;
    mem.set_item("nodes", m.nodes)?;
    mem.set_item("density", m.density)?;
    mem.set_item("total", m.total)?;
    d.set_item("memory", mem)?;
    Ok(())
}

/// A sampler of directions ∝ luminance per solid angle of a lat-long environment map.
///
/// ``EnvMapSampler(name, path_or_array, seed=1, n_max=None, max_depth=None, leaf_choice=None)``:
/// `name` is an envmap sampler of the registry (``"envmap-adaptive"``,
/// ``"envmap-adaptive-paper"``, ``"envmap-cdf"``); the map is a file (``.hdr``, ``.exr``,
/// ``.pfm``), ``"sky"`` (the built-in procedural sky, 1024 × 512) or an array of linear RGB
/// radiance (H, W, 3) or luminance (H, W), row 0 at the zenith (+z). `u` ∈ [0,1)² is the
/// lat-long coordinate (φ = 2πu, θ = πv); directions are in the map's frame.
#[pyclass(module = "brdf_lab._native", name = "EnvMapSampler", frozen)]
pub(crate) struct EnvMapSampler {
    name: String,
    inner: Arc<envmap::EnvMapSampler>,
    seed: u64,
    calls: AtomicU64,
    build_seconds: f64,
}

fn load_map(path_or_array: &Bound<'_, PyAny>) -> PyResult<EnvMap> {
    if let Ok(s) = path_or_array.extract::<String>()
        && s == "sky"
    {
        return envmap::procedural_sky(1024, 512).map_err(|e| value_error(&e));
    }
    if let Ok(path) = path_or_array.extract::<PathBuf>() {
        return EnvMap::load(&path).map_err(|e| value_error(&e));
    }
    let arr: ArrayIn<'_> = path_or_array
        .extract()
        .map_err(|_| invalid("the map must be a path, \"sky\", or an (H, W, 3) / (H, W) array"))?;
    let view = arr.as_array();
    let (h, w, channels) = match view.shape() {
        [h, w, 3] => (*h, *w, 3),
        [h, w] => (*h, *w, 1),
        other => {
            return Err(invalid(format!(
                "the map array must have shape (H, W, 3) or (H, W), got {other:?}"
            )));
        }
    };
    let flat: Vec<f64> = view.iter().copied().collect();
    let rgb: Vec<[f32; 3]> = if channels == 3 {
        flat.chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect()
    } else {
        flat.iter().map(|&y| [y as f32; 3]).collect()
    };
    EnvMap::new(w, h, rgb).map_err(|e| value_error(&e))
}

#[pymethods]
impl EnvMapSampler {
    #[new]
    #[pyo3(signature = (name, path_or_array, seed = 1, n_max = None, max_depth = None, leaf_choice = None))]
    fn new(
        py: Python<'_>,
        name: &str,
        path_or_array: &Bound<'_, PyAny>,
        seed: u64,
        n_max: Option<f64>,
        max_depth: Option<u32>,
        leaf_choice: Option<&str>,
    ) -> PyResult<Self> {
        let entry = samplers::find(name).map_err(|e| value_error(&e))?;
        let map = load_map(path_or_array)?;
        let mut options = AdaptiveOptions::default();
        options.tree = tree_params(options.tree, n_max, max_depth, leaf_choice)?;
        let start = Instant::now();
        let inner = py
            .detach(|| install(|| entry.build_envmap(&map, &options)))
            .map_err(|e| value_error(&e))?;
        Ok(Self {
            name: entry.name.to_string(),
            inner: Arc::new(inner),
            seed,
            calls: AtomicU64::new(0),
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Draws directions: returns ``(uv, pdf_uv, dirs, pdf_sa)`` — lat-long points (N, 2), their
    /// density w.r.t. area on [0,1]² (N,), unit directions (N, 3) and their density per unit
    /// solid angle (N,). `u`: (N, 2) uniforms (``envmap-cdf`` warps them exactly; the adaptive
    /// samplers use them as each query's first two uniforms and continue from the seeded
    /// generator) or an int N (the library's parallel batch path). Reproducible from `seed`
    /// (default: the sampler's seed and a call counter), whatever the thread count.
    #[pyo3(signature = (u, seed = None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        seed: Option<u64>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let u_in = UIn::read(u)?;
        let u_view = view_of(&u_in);
        let u = UArg::of(&u_in, &u_view)?;
        let seed = next_seed(self.seed, &self.calls, seed);
        let inner = Arc::clone(&self.inner);
        let out: Vec<EnvSample> = py.detach(|| {
            let planar = match inner.as_piecewise_constant() {
                Some(t) => {
                    let warp = |p: [f64; 2]| t.sample_square(p);
                    sample_planar(inner.as_ref(), Some(&warp), &u, seed)
                }
                None => sample_planar(inner.as_ref(), None, &u, seed),
            };
            install(|| planar.into_par_iter().map(EnvSample::from_uv).collect())
        });
        Ok((
            rows(py, out.iter().map(|s| [s.u, s.v]).collect()),
            vec1(py, out.iter().map(|s| s.pdf_uv).collect()),
            rows(py, out.iter().map(|s| s.direction).collect()),
            vec1(py, out.iter().map(|s| s.pdf_sa).collect()),
        ))
    }

    /// Density per unit solid angle of directions `dirs` (3,) or (N, 3), shape (N,).
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        dirs_: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let d = dirs(&dirs_, "dirs")?;
        let out = par_map(py, &d.v, |v| self.inner.pdf_sa([v.x, v.y, v.z]));
        Ok(vec1(py, out))
    }

    /// Density w.r.t. area on [0,1]² at lat-long points `uv` (N, 2), shape (N,).
    fn pdf_uv<'py>(
        &self,
        py: Python<'py>,
        uv: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let p = points(&uv, "uv")?;
        Ok(vec1(py, par_map(py, &p, |q| self.inner.pdf_uv(q[0], q[1]))))
    }

    /// The uniforms that `sample` maps to `uv` (N, 2): only ``envmap-cdf`` is invertible
    /// (``ValueError`` otherwise); NaN rows where `uv` has zero density.
    fn invert<'py>(
        &self,
        py: Python<'py>,
        uv: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let Some(t) = self.inner.as_piecewise_constant() else {
            return Err(invalid(format!(
                "`{}` is not invertible (rejection sampling); envmap-cdf is",
                self.name
            )));
        };
        Ok(invert_points(py, t, &points(&uv, "uv")?))
    }

    /// The registry name.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// Bytes of the sampler's structure.
    #[getter]
    fn bytes_used(&self) -> usize {
        self.inner.bytes_used()
    }

    /// The build report: name, map size, build time, bytes, and for the adaptive samplers the
    /// tree's statistics and memory.
    #[getter]
    fn build_report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("name", &self.name)?;
        d.set_item("width", self.inner.width())?;
        d.set_item("height", self.inner.height())?;
        d.set_item("build_seconds", self.build_seconds)?;
        d.set_item("bytes_used", self.inner.bytes_used())?;
        if let Some(t) = self.inner.as_adaptive() {
            tree_report(py, t, &d)?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "EnvMapSampler({:?}, {}×{})",
            self.name,
            self.inner.width(),
            self.inner.height()
        )
    }
}

#[allow(clippy::large_enum_variant)] // one per Python object; boxing the table adds a load per draw
enum Planar {
    Adaptive(Box<QuadTreeSampler<TabulatedDensity>>),
    Cdf(PiecewiseConstant2D),
}

/// The generic partition sampler of any bounded density given as a 2D table.
///
/// ``PartitionSampler(density, domain=(0, 0, 1, 1), method="adaptive", seed=1, n_max=None,
/// max_depth=None, leaf_choice=None)``: `density` (H, W) non-negative values, row 0 on the
/// `y0` side, piecewise constant over `domain = (x0, y0, x1, y1)`. ``"adaptive"``: the
/// adaptive quadtree (exact rejection sampling of the table); ``"cdf"``: the registry's
/// ``grid-cdf`` (marginal/conditional CDFs, invertible). Points are (x, y); pdfs are w.r.t.
/// area on the domain.
#[pyclass(module = "brdf_lab._native", name = "PartitionSampler", frozen)]
pub(crate) struct PartitionSampler {
    method: &'static str,
    inner: Arc<Planar>,
    seed: u64,
    calls: AtomicU64,
    build_seconds: f64,
}

impl Planar {
    fn pdf(&self, p: [f64; 2]) -> f64 {
        match self {
            Planar::Adaptive(s) => s.pdf(p),
            Planar::Cdf(s) => s.pdf(p),
        }
    }
}

#[pymethods]
impl PartitionSampler {
    #[new]
    #[pyo3(signature = (density, domain = (0.0, 0.0, 1.0, 1.0), method = "adaptive", seed = 1, n_max = None, max_depth = None, leaf_choice = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        density: ArrayIn<'_>,
        domain: (f64, f64, f64, f64),
        method: &str,
        seed: u64,
        n_max: Option<f64>,
        max_depth: Option<u32>,
        leaf_choice: Option<&str>,
    ) -> PyResult<Self> {
        let view = density.as_array();
        let [h, w] = *view.shape() else {
            return Err(invalid(format!(
                "density must have shape (H, W), got {:?}",
                view.shape()
            )));
        };
        let values: Vec<f64> = view.iter().copied().collect();
        let rect = Rect::new(domain.0, domain.1, domain.2, domain.3);
        let start = Instant::now();
        let (method, inner) = match method {
            "adaptive" => {
                let params = tree_params(TreeParams::default(), n_max, max_depth, leaf_choice)?;
                let s = py.detach(|| {
                    let d =
                        TabulatedDensity::new(w, h, values, rect).map_err(|e| value_error(&e))?;
                    QuadTreeBuilder::from_params(params)
                        .build(d)
                        .map_err(|e| value_error(&e))
                })?;
                ("adaptive", Planar::Adaptive(Box::new(s)))
            }
            "cdf" => {
                let entry = samplers::find("grid-cdf").map_err(|e| value_error(&e))?;
                let s = py
                    .detach(|| entry.build_grid(w, h, values, rect))
                    .map_err(|e| value_error(&e))?;
                ("cdf", Planar::Cdf(s))
            }
            other => {
                return Err(invalid(format!(
                    "method must be \"adaptive\" or \"cdf\", got {other:?}"
                )));
            }
        };
        Ok(Self {
            method,
            inner: Arc::new(inner),
            seed,
            calls: AtomicU64::new(0),
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Draws points: returns ``(points, pdf)``, (N, 2) and (N,) (w.r.t. area). `u`: (N, 2)
    /// uniforms (``"cdf"`` warps them exactly; ``"adaptive"`` uses them as each query's first
    /// two uniforms and continues from the seeded generator) or an int N (the library's
    /// parallel batch path, `sample_par`). Reproducible from `seed`, whatever the thread count.
    #[pyo3(signature = (u, seed = None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        seed: Option<u64>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>)> {
        let u_in = UIn::read(u)?;
        let u_view = view_of(&u_in);
        let u = UArg::of(&u_in, &u_view)?;
        let seed = next_seed(self.seed, &self.calls, seed);
        let inner = Arc::clone(&self.inner);
        let out = py.detach(|| match inner.as_ref() {
            Planar::Adaptive(s) => sample_planar(s.as_ref(), None, &u, seed),
            Planar::Cdf(t) => {
                let warp = |p: [f64; 2]| t.sample_square(p);
                sample_planar(t, Some(&warp), &u, seed)
            }
        });
        Ok((
            rows(py, out.iter().map(|s| s.point).collect()),
            vec1(py, out.iter().map(|s| s.pdf).collect()),
        ))
    }

    /// Density w.r.t. area at `points` (N, 2), shape (N,) (0 outside the domain).
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        points_: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let p = points(&points_, "points")?;
        Ok(vec1(py, par_map(py, &p, |q| self.inner.pdf(*q))))
    }

    /// The uniforms that `sample` maps to `points` (N, 2); only ``"cdf"`` is invertible.
    fn invert<'py>(
        &self,
        py: Python<'py>,
        points_: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let Planar::Cdf(t) = self.inner.as_ref() else {
            return Err(invalid(
                "the adaptive partition sampler is not invertible (rejection sampling); method=\"cdf\" is",
            ));
        };
        Ok(invert_points(py, t, &points(&points_, "points")?))
    }

    /// ``"adaptive"`` or ``"cdf"``.
    #[getter]
    fn method(&self) -> &str {
        self.method
    }

    /// Bytes of the sampler's structure.
    #[getter]
    fn bytes_used(&self) -> usize {
        match self.inner.as_ref() {
            Planar::Adaptive(s) => s.bytes_used(),
            Planar::Cdf(s) => s.bytes_used(),
        }
    }

    /// The build report: method, build time, bytes and (adaptive) the tree's statistics.
    #[getter]
    fn build_report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("method", self.method)?;
        d.set_item("build_seconds", self.build_seconds)?;
        d.set_item("bytes_used", self.bytes_used())?;
        if let Planar::Adaptive(t) = self.inner.as_ref() {
            d.set_item("integral", t.integral())?;
            tree_report(py, t, &d)?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("PartitionSampler(method={:?})", self.method)
    }
}
