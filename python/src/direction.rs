//! `brdf_lab.DirectionSampler`: any direction sampler of the registry, built for a BRDF.

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

use ::samplers::{BuiltDirection, DirectionRequest, SamplerEntry};
use brdf::Vec3;
use numpy::{PyArray1, PyArray2};
use partition_sampler::{PAR_CHUNK, UniformSource, chunk_rng};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;

use crate::arrays::{ArrayIn, dirs, flat_rows, pair_len, uniforms, vec1};
use crate::brdf_py::Brdf;
use crate::callable::PyBrdf;
use crate::errors::{invalid, value_error};
use crate::options::{BASELINE_KEYS, direction_options, set_keys};
use crate::threads::{install, next_seed, par_map};

/// A uniform source that hands out a query's two given uniforms first, then continues from the
/// chunk's generator (rejection samplers and lobe choices may need more than two).
pub(crate) struct Lead<'a, R: UniformSource> {
    lead: [f64; 2],
    used: usize,
    rest: &'a mut R,
}

impl<'a, R: UniformSource> Lead<'a, R> {
    /// `lead`, then `rest`.
    pub(crate) fn new(lead: [f64; 2], rest: &'a mut R) -> Self {
        Self {
            lead,
            used: 0,
            rest,
        }
    }
}

impl<R: UniformSource> UniformSource for Lead<'_, R> {
    #[inline]
    fn next_uniform(&mut self) -> f64 {
        if self.used < 2 {
            self.used += 1;
            self.lead[self.used - 1]
        } else {
            self.rest.next_uniform()
        }
    }
}

/// The uniforms argument of `sample`: a count (all uniforms from the generator) or `(N, 2)`
/// values (borrowed from the NumPy array when it is C-contiguous float64).
pub(crate) enum UArg<'a> {
    /// Draw this many samples.
    Count(usize),
    /// One query per row (flat, 2 per row); the row gives its first two uniforms.
    Given(Cow<'a, [f64]>),
}

/// The Python value of `u`: an int or an array-like (kept alive while its values are read).
pub(crate) enum UIn<'py> {
    /// A sample count.
    Count(usize),
    /// An array-like.
    Array(ArrayIn<'py>),
}

impl<'py> UIn<'py> {
    /// Reads `u`: a non-negative int or an `(N, 2)` array-like.
    pub(crate) fn read(u: &Bound<'py, PyAny>) -> PyResult<Self> {
        if u.is_instance_of::<pyo3::types::PyInt>() {
            let n: i64 = u.extract()?;
            return usize::try_from(n)
                .map(UIn::Count)
                .map_err(|_| invalid(format!("the sample count must be ≥ 0, got {n}")));
        }
        u.extract().map(UIn::Array).map_err(|e| {
            invalid(format!(
                "u must be an (N, 2) array of floats or an int: {e}"
            ))
        })
    }
}

impl<'a> UArg<'a> {
    /// The checked uniforms of `u` (values in [0, 1]).
    pub(crate) fn of(
        u: &'a UIn<'_>,
        view: &'a Option<numpy::ndarray::ArrayViewD<'a, f64>>,
    ) -> PyResult<Self> {
        match (u, view) {
            (UIn::Count(n), _) => Ok(UArg::Count(*n)),
            (UIn::Array(_), Some(v)) => Ok(UArg::Given(uniforms(v, "u")?)),
            (UIn::Array(_), None) => Err(invalid("internal: u without its view")),
        }
    }

    /// Number of queries.
    pub(crate) fn len(&self) -> usize {
        match self {
            UArg::Count(n) => *n,
            UArg::Given(v) => v.len() / 2,
        }
    }

    /// Query `k`'s two uniforms (1 mapped below 1).
    #[inline]
    pub(crate) fn row(v: &[f64], k: usize) -> [f64; 2] {
        const BELOW_ONE: f64 = 1.0 - f64::EPSILON / 2.0;
        [v[2 * k].min(BELOW_ONE), v[2 * k + 1].min(BELOW_ONE)]
    }
}

/// The view of an array argument (None for a count).
pub(crate) fn view_of<'a>(u: &'a UIn<'_>) -> Option<numpy::ndarray::ArrayViewD<'a, f64>> {
    match u {
        UIn::Count(_) => None,
        UIn::Array(a) => Some(a.as_array()),
    }
}

/// Runs `one(k, source)` for every query `k < n` in fixed chunks of `PAR_CHUNK`, chunk `c`'s
/// generator seeded from `(seed, c)`, so the output depends on `seed` only.
pub(crate) fn chunked<T, F>(n: usize, u: &UArg<'_>, seed: u64, one: F) -> Vec<T>
where
    T: Default + Clone + Send,
    F: Fn(usize, &mut dyn UniformSource) -> T + Sync,
{
    let mut out = vec![T::default(); n];
    install(|| {
        out.par_chunks_mut(PAR_CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let mut rng = chunk_rng(seed, c as u64);
                for (j, slot) in chunk.iter_mut().enumerate() {
                    let k = c * PAR_CHUNK + j;
                    *slot = match u {
                        UArg::Count(_) => one(k, &mut rng),
                        UArg::Given(v) => one(k, &mut Lead::new(UArg::row(v, k), &mut rng)),
                    };
                }
            });
    });
    out
}

/// A direction sampler of the registry (`brdf_lab.samplers()` lists them), built for one BRDF.
///
/// ``DirectionSampler(name, brdf, seed=1, **options)``: `brdf` is a :class:`Brdf` or a spec
/// string; `options` are the adaptive sets' (``slices``, ``grid``, ``n_max``, ``max_depth``,
/// ``mixture``, …) and the baselines' (``lobe_*``, ``cdf_*``, ``factored_*``, ``srbf_*``)
/// settings — ``brdf_lab.option_names()`` lists them. The build runs once, here, with the GIL
/// released. pdfs are per unit solid angle; directions in the local frame (z = normal).
#[pyclass(module = "brdf_lab._native", name = "DirectionSampler", frozen)]
pub(crate) struct DirectionSampler {
    name: String,
    brdf: Arc<dyn brdf::Brdf>,
    spec: String,
    built: BuiltDirection,
    seed: u64,
    calls: AtomicU64,
    build_seconds: f64,
}

impl DirectionSampler {
    fn brdf_of(brdf: &Bound<'_, PyAny>) -> PyResult<(Arc<dyn brdf::Brdf>, String)> {
        if let Ok(b) = brdf.extract::<PyRef<'_, Brdf>>() {
            return Ok((Arc::clone(&b.inner), b.spec.clone()));
        }
        let spec: String = brdf
            .extract()
            .map_err(|_| invalid("brdf must be a brdf_lab.Brdf or a spec string"))?;
        let b = Brdf::parse(&spec)?;
        Ok((b.inner, spec))
    }

    fn next_seed(&self, seed: Option<u64>) -> u64 {
        next_seed(self.seed, &self.calls, seed)
    }

    /// The sampler `built` of registry `entry` for `(brdf, spec)`, whose build started at
    /// `start`.
    fn built(
        entry: &SamplerEntry,
        (brdf, spec): (Arc<dyn brdf::Brdf>, String),
        built: BuiltDirection,
        seed: u64,
        start: Instant,
    ) -> Self {
        Self {
            name: entry.name.to_string(),
            brdf,
            spec,
            built,
            seed,
            calls: AtomicU64::new(0),
            build_seconds: start.elapsed().as_secs_f64(),
        }
    }
}

/// `f = 1`: the BRDF handed to a batch call when the caller evaluates `eval_rgb` itself (a
/// luminance `f` would be wasted).
struct NoEval;

impl brdf::Brdf for NoEval {
    fn eval(&self, _wo: &Vec3, _wi: &Vec3) -> f64 {
        1.0
    }
}

/// One chunk of `sample` with every uniform from `rng`: its above-horizon queries (queries
/// `first..first + pdf.len()` of `wo`) in one `sample_eval_batch` call, written into the
/// chunk's output slices (below-horizon queries keep their zeros). `f` is the batch's (the
/// sampler's own accepted-trial value where it has one) or, with `rgb`, `eval_rgb`.
fn batch_chunk(
    sampler: &dyn brdf_sampling::DirectionSampler,
    brdf: &dyn brdf::Brdf,
    wo: &crate::arrays::Dirs,
    first: usize,
    rgb: bool,
    rng: &mut dyn UniformSource,
    (wi, pdf, f): (&mut [f64], &mut [f64], &mut [f64]),
) {
    let (ks, wos): (Vec<usize>, Vec<Vec3>) = (0..pdf.len())
        .map(|j| (j, *wo.get(first + j)))
        .filter(|(_, o)| above(o))
        .unzip();
    let mut out = Vec::with_capacity(wos.len());
    sampler.sample_eval_batch(if rgb { &NoEval } else { brdf }, &wos, rng, &mut out);
    for ((&j, o), s) in ks.iter().zip(&wos).zip(&out) {
        write_draw(j, o, (&s.wi, s.pdf), brdf, rgb, || s.f, (wi, pdf, f));
    }
}

/// Writes draw `j` (`(wi, pdf)` at `wo`) into the output slices, and its `f` where the draw is
/// valid (`pdf > 0`, `wi` above the horizon): with `rgb` the BRDF's `eval_rgb`, else `lum()`.
fn write_draw(
    j: usize,
    wo: &Vec3,
    (s_wi, s_pdf): (&Vec3, f64),
    brdf: &dyn brdf::Brdf,
    rgb: bool,
    lum: impl FnOnce() -> f64,
    (wi, pdf, f): (&mut [f64], &mut [f64], &mut [f64]),
) {
    wi[3 * j..3 * j + 3].copy_from_slice(&[s_wi.x, s_wi.y, s_wi.z]);
    pdf[j] = s_pdf;
    if s_pdf > 0.0 && s_wi.z > 0.0 {
        if rgb {
            f[3 * j..3 * j + 3].copy_from_slice(&brdf.eval_rgb(wo, s_wi));
        } else {
            f[j] = lum();
        }
    }
}

/// The recorded error of `brdf` if it is a callable BRDF (raised as `ValueError`).
fn callable_error(py: Python<'_>, brdf: &Arc<dyn brdf::Brdf>) -> PyResult<()> {
    PyBrdf::of(brdf.as_ref()).map_or(Ok(()), |c| c.take_error(py))
}

/// The `f` of drawn samples (`wi` flat, `pdf`) for a callable BRDF: one call on the valid
/// draws (`pdf > 0`, `wi` above the horizon, `wo` above it), 0 elsewhere; RGB grey with `rgb`.
fn callable_f(
    py: Python<'_>,
    c: &PyBrdf,
    wo: &crate::arrays::Dirs,
    wi: &[f64],
    pdf: &[f64],
    rgb: bool,
) -> PyResult<Vec<f64>> {
    let valid: Vec<usize> = (0..pdf.len())
        .filter(|&k| pdf[k] > 0.0 && wi[3 * k + 2] > 0.0 && above(wo.get(k)))
        .collect();
    let wis: Vec<Vec3> = valid
        .iter()
        .map(|&k| Vec3::new(wi[3 * k], wi[3 * k + 1], wi[3 * k + 2]))
        .collect();
    let wos: Vec<Vec3> = if wo.single {
        vec![*wo.get(0)]
    } else {
        valid.iter().map(|&k| *wo.get(k)).collect()
    };
    let values = if wis.is_empty() {
        Vec::new()
    } else {
        c.eval_batch(py, &wos, &wis)
    };
    c.take_error(py)?;
    let fw = if rgb { 3 } else { 1 };
    let mut f = vec![0.0; fw * pdf.len()];
    for (&k, v) in valid.iter().zip(values) {
        f[fw * k..fw * (k + 1)].fill(v);
    }
    Ok(f)
}

/// Whether `wo` lies strictly above the horizon.
#[inline]
fn above(wo: &Vec3) -> bool {
    wo.z > 0.0
}

#[pymethods]
impl DirectionSampler {
    #[new]
    #[pyo3(signature = (name, brdf, seed = 1, **options))]
    fn new(
        py: Python<'_>,
        name: &str,
        brdf: &Bound<'_, PyAny>,
        seed: u64,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let (brdf, spec) = Self::brdf_of(brdf)?;
        let (set_options, baselines) = direction_options(options)?;
        let entry = samplers::find(name).map_err(|e| value_error(&e))?;
        if !entry.is_direction() {
            return Err(invalid(format!(
                "`{}` is a {} sampler, not a direction sampler; direction samplers: {}",
                entry.name,
                entry.constructor.kind(),
                samplers::names_of_kind("direction")
            )));
        }
        let start = Instant::now();
        let built = py
            .detach(|| {
                install(|| {
                    let request = DirectionRequest::new(Arc::clone(&brdf), &set_options)
                        .with_baselines(baselines)
                        .with_spec(&spec);
                    entry.build_direction(&request)
                })
            })
            .map_err(|e| {
                callable_error(py, &brdf)
                    .err()
                    .unwrap_or_else(|| value_error(&e))
            })?;
        callable_error(py, &brdf)?;
        Ok(Self::built(entry, (brdf, spec), built, seed, start))
    }

    /// Draws one direction per query: returns ``(wi, pdf, f)`` with `wi` (N, 3), `pdf` (N,) per
    /// unit solid angle and `f` the BRDF's luminance (N,) — or linear RGB (N, 3) with
    /// ``rgb=True``.
    ///
    /// `wo`: (3,) (shared by every query) or (N, 3). `u`: (N, 2) uniforms in [0, 1), the first
    /// two uniforms of each query (rejection samplers continue from a generator seeded from
    /// the seed and the query's chunk), or an int N to draw every uniform from the generator.
    /// `seed`: this call's seed; by default the sampler's seed and a call counter, so
    /// successive calls draw fresh streams and a re-created sampler repeats them. The output
    /// never depends on the thread count. Queries with `wo` at or below the horizon give
    /// ``wi = 0, pdf = 0, f = 0``. With an int `u` each chunk of `PAR_CHUNK` queries is one
    /// batch call of the sampler (`sample_eval_batch`: a sampler may serve the queries grouped
    /// by its structure, and a rejection sampler returns the `f` of its accepted trial); with
    /// given uniforms each row is its own query's, so queries are served one by one.
    #[pyo3(signature = (wo, u, seed = None, rgb = false))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wo: ArrayIn<'py>,
        u: &Bound<'py, PyAny>,
        seed: Option<u64>,
        rgb: bool,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyAny>,
    )> {
        let wo = dirs(&wo, "wo")?;
        let u_in = UIn::read(u)?;
        let u_view = view_of(&u_in);
        let u = UArg::of(&u_in, &u_view)?;
        let n = u.len();
        if !wo.single && wo.len() != n {
            return Err(invalid(format!(
                "wo has {} rows and u {n}: give one wo per query or a single (3,) wo",
                wo.len()
            )));
        }
        let seed = self.next_seed(seed);
        let sampler = Arc::clone(&self.built.sampler);
        // A callable BRDF's `f` is evaluated after the draws, in one call of the callable.
        let callable = PyBrdf::of(self.brdf.as_ref()).is_some();
        let (brdf, rgb_out, rgb): (Arc<dyn brdf::Brdf>, bool, bool) = if callable {
            (Arc::new(NoEval), rgb, false)
        } else {
            (Arc::clone(&self.brdf), rgb, rgb)
        };
        let fw = if rgb { 3 } else { 1 };
        let mut wi = vec![0.0; 3 * n];
        let mut pdf = vec![0.0; n];
        let mut f = vec![0.0; fw * n];
        // One pass, in parallel, straight into the output buffers (no per-row temporaries).
        py.detach(|| {
            install(|| {
                wi.par_chunks_mut(3 * PAR_CHUNK)
                    .zip(pdf.par_chunks_mut(PAR_CHUNK))
                    .zip(f.par_chunks_mut(fw * PAR_CHUNK))
                    .enumerate()
                    .for_each(|(c, ((wi_c, pdf_c), f_c))| {
                        let mut rng = chunk_rng(seed, c as u64);
                        if let UArg::Count(_) = &u {
                            // Every uniform from the chunk's generator: the chunk's queries in
                            // one batch call (see `batch_chunk`).
                            batch_chunk(
                                sampler.as_ref(),
                                brdf.as_ref(),
                                &wo,
                                c * PAR_CHUNK,
                                rgb,
                                &mut rng,
                                (wi_c, pdf_c, f_c),
                            );
                            return;
                        }
                        for j in 0..pdf_c.len() {
                            let k = c * PAR_CHUNK + j;
                            let o = wo.get(k);
                            if !above(o) {
                                continue; // zeros
                            }
                            let s = match &u {
                                UArg::Count(_) => sampler.sample(o, &mut rng),
                                UArg::Given(v) => {
                                    sampler.sample(o, &mut Lead::new(UArg::row(v, k), &mut rng))
                                }
                            };
                            write_draw(
                                j,
                                o,
                                (&s.wi, s.pdf),
                                brdf.as_ref(),
                                rgb,
                                || brdf.eval(o, &s.wi),
                                (&mut *wi_c, &mut *pdf_c, &mut *f_c),
                            );
                        }
                    });
            })
        });
        let f = match PyBrdf::of(self.brdf.as_ref()) {
            Some(c) => callable_f(py, c, &wo, &wi, &pdf, rgb_out)?,
            None => f,
        };
        let f = if rgb_out {
            flat_rows(py, f, 3).into_any()
        } else {
            vec1(py, f).into_any()
        };
        Ok((flat_rows(py, wi, 3), vec1(py, pdf), f))
    }

    /// The sampler's density of `wi` given `wo`, per unit solid angle, shape (N,). `wo`, `wi`:
    /// (3,) or (N, 3). 0 when `wo` is at or below the horizon.
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wo: ArrayIn<'py>,
        wi: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let wo = dirs(&wo, "wo")?;
        let wi = dirs(&wi, "wi")?;
        let n = pair_len(&wo, "wo", &wi, "wi")?;
        let sampler = self.built.sampler.as_ref();
        let ks: Vec<usize> = (0..n).collect();
        let out = par_map(py, &ks, |&k| {
            let o = wo.get(k);
            if above(o) {
                sampler.pdf(o, wi.get(k))
            } else {
                0.0
            }
        });
        Ok(vec1(py, out))
    }

    /// The registry name.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The BRDF it samples.
    #[getter]
    fn brdf(&self) -> Brdf {
        Brdf {
            inner: Arc::clone(&self.brdf),
            spec: self.spec.clone(),
        }
    }

    /// The sampler's seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// Bytes of the precomputed structure.
    #[getter]
    fn bytes_used(&self) -> usize {
        self.built.sampler.bytes_used()
    }

    /// Wall time of the build, in seconds.
    #[getter]
    fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// The build report the CLI's `build` prints (None when the sampler has none).
    #[getter]
    fn build_report(&self) -> Option<String> {
        match &self.built.set {
            Some(set) => Some(set.report().to_string()),
            None => self.built.sampler.build_report(),
        }
    }

    /// Trials that exceeded their bound so far (rejection samplers; None otherwise).
    #[getter]
    fn bound_violations(&self) -> Option<u64> {
        self.built.sampler.bound_violations()
    }

    /// Whether it can be saved (adaptive quadtree sets).
    #[getter]
    fn can_save(&self) -> bool {
        self.built.set.is_some()
    }

    /// Writes the set to `path` (the CLI's `build --out` format). ``ValueError`` for a sampler
    /// that cannot be saved (see `can_save`).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let Some(set) = &self.built.set else {
            return Err(invalid(format!(
                "`{}` cannot be saved: only the adaptive quadtree sets (adaptive, adaptive-paper, adaptive-mixture, adaptive-paper-mixture) have a file format",
                self.name
            )));
        };
        let set = Arc::clone(set);
        let bytes = py.detach(|| set.to_bytes());
        std::fs::write(&path, bytes)
            .map_err(|e| PyOSError::new_err(format!("cannot write {}: {e}", path.display())))
    }

    /// Reads a set written by `save` (or `brdf-lab build --out`), re-attached to `brdf` (a
    /// :class:`Brdf` or spec; by default the BRDF of the spec stored in the file).
    #[staticmethod]
    #[pyo3(signature = (path, brdf = None, seed = 1))]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        brdf: Option<&Bound<'_, PyAny>>,
        seed: u64,
    ) -> PyResult<Self> {
        let bytes = std::fs::read(&path)
            .map_err(|e| PyOSError::new_err(format!("cannot read {}: {e}", path.display())))?;
        let given = brdf.map(Self::brdf_of).transpose()?;
        let start = Instant::now();
        let (entry, built) = py
            .detach(|| {
                samplers::load_set(
                    &bytes,
                    given.as_ref().map(|(b, s)| (Arc::clone(b), s.as_str())),
                )
            })
            .map_err(|e| {
                given
                    .as_ref()
                    .and_then(|(b, _)| callable_error(py, b).err())
                    .unwrap_or_else(|| value_error(&e))
            })?;
        if let Some((b, _)) = &given {
            callable_error(py, b)?;
        }
        let (brdf, spec) = match given {
            Some(g) => g,
            None => {
                let spec =
                    brdf_sampling::QuadTreeSet::stored_spec(&bytes).map_err(|e| value_error(&e))?;
                let b = Brdf::parse(&spec)?;
                (b.inner, spec)
            }
        };
        Ok(Self::built(entry, (brdf, spec), built, seed, start))
    }

    fn __repr__(&self) -> String {
        format!(
            "DirectionSampler({:?}, Brdf({:?}), seed={})",
            self.name, self.spec, self.seed
        )
    }
}

/// Every registered sampler: a list of dicts with `name`, `kind` (``"direction"``, ``"disc"``,
/// ``"envmap"``, ``"grid"``), `summary`, `support` (``"hemisphere"``/``"sphere"`` for direction
/// samplers, else None) and `capabilities` (`exact_pdf`, `batch_mode`, `needs_build`,
/// `anisotropic`, `measured`).
#[pyfunction(name = "samplers")]
pub(crate) fn list_samplers(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for e in samplers::samplers() {
        let d = PyDict::new(py);
        d.set_item("name", e.name)?;
        d.set_item("kind", e.constructor.kind())?;
        d.set_item("summary", e.summary)?;
        d.set_item(
            "support",
            e.constructor.support().map(|s| match s {
                samplers::Support::Hemisphere => "hemisphere",
                samplers::Support::Sphere => "sphere",
            }),
        )?;
        let c = PyDict::new(py);
        c.set_item("exact_pdf", e.capabilities.exact_pdf)?;
        c.set_item("batch_mode", e.capabilities.batch_mode)?;
        c.set_item("needs_build", e.capabilities.needs_build)?;
        c.set_item("anisotropic", e.capabilities.anisotropic)?;
        c.set_item("measured", e.capabilities.measured)?;
        d.set_item("capabilities", c)?;
        list.append(d)?;
    }
    Ok(list)
}

/// The keyword options `DirectionSampler` accepts: ``{"set": [...], "baselines": [...]}``.
#[pyfunction]
pub(crate) fn option_names(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("set", set_keys())?;
    d.set_item("baselines", BASELINE_KEYS.to_vec())?;
    Ok(d)
}
