//! The sphere renderer: direct lighting of a row of spheres (one per BRDF of the study) under
//! one light, orthographic camera, one image per sampler at equal samples and at equal time,
//! and a reference image; the papers' relative error per image.
//!
//! **Scene.** World up is `+z`, the zenith of the lat-long maps. The camera looks along `+y`
//! (orthographic, `ωo = (0, −1, 0)` at every pixel); sphere `j` covers a square of
//! `sphere_px²` pixels. A pixel whose centre hits a sphere has the normal
//! `n = (x, −√(1 − x² − z²), z)` and a tangent frame `t = normalize(z × n)` (or `+x` at the
//! poles), `b = n × t`; directions are sampled in that frame and looked up in world space.
//! There are no shadows (the spheres are convex and do not occlude each other in the lit
//! hemisphere of any pixel to first order) and no background (black).
//!
//! **Pixel estimate.** `(1/N) Σ f_r(ωo, ωk) ⊙ L(ωk) cos θk / p_σ(ωk)` (RGB), one pixel's RNG
//! seeded from `(seed, sampler, pixel)`: reproducible for any thread count.
//!
//! **Reference.** Multiple importance sampling (balance heuristic, equal counts) of the
//! reference BRDF sampler (`adaptive`, checked by the validation suite) and the light's own
//! sampler (the `envmap-adaptive` registry sampler for maps, uniform directions in the cone of
//! the area light; BRDF sampling alone under constant light), `reference_spp` samples of each
//! per pixel.
//!
//! **Error.** The papers' relative error: the mean over pixels with non-null reference
//! luminance of `|Y(I) − Y(I_ref)| / Y(I_ref)`.
//!
//! **Equal time.** Each sampler's time per pixel sample is measured on one thread on a fixed
//! subset of pixels; at equal time a sampler gets `spp × t_adaptive / t_sampler` samples per
//! pixel (at least 1), `t_adaptive` the `adaptive` sampler's time (or the mean time when it is
//! not in the study). Equal-time images therefore depend on timings.

use std::time::Instant;

use brdf::{Brdf, Vec3};
use brdf_sampling::DirectionSampler;
use distributions::{UniformSource, chunk_seed};
use envmap::{AdaptiveOptions, EnvMapSampler};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{Light, StudyError, StudyPlan};

/// Timing runs per sampler for the equal-time budget (the median is used).
const TIMING_REPEATS: usize = 5;

/// Settings of the sphere images.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RenderConfig {
    /// Pixels per sphere side.
    pub sphere_px: usize,
    /// Samples per pixel of the equal-samples images.
    pub spp: usize,
    /// Samples per pixel of each strategy of the reference.
    pub reference_spp: usize,
    /// Index of the study's light to render under.
    pub light: usize,
    /// Seed of the images.
    pub seed: u64,
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            sphere_px: 80,
            spp: 64,
            reference_spp: 512,
            light: 0,
            seed: 1,
        }
    }
}

/// A rendered image (linear RGB, row-major, top row first).
#[derive(Debug, Clone)]
pub struct Image {
    /// Sampler name (or `reference`).
    pub sampler: String,
    /// `equal samples`, `equal time` or `reference`.
    pub kind: String,
    /// Samples per pixel (per strategy for the reference).
    pub spp: usize,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Linear RGB radiance per pixel.
    pub rgb: Vec<[f64; 3]>,
    /// Relative error against the reference (`None` for the reference).
    pub rel_error: Option<f64>,
    /// Render time (s, all threads) — a timing.
    pub seconds: f64,
}

/// The images of a study.
#[derive(Debug, Clone)]
pub struct Render {
    /// The settings.
    pub config: RenderConfig,
    /// The light spec.
    pub light: String,
    /// The BRDFs, left to right.
    pub brdfs: Vec<String>,
    /// How the reference was made.
    pub reference_method: String,
    /// The reference.
    pub reference: Image,
    /// One equal-samples and one equal-time image per sampler that could be built.
    pub images: Vec<Image>,
    /// Measured ns per pixel sample per sampler (timings).
    pub ns_per_sample: Vec<(String, f64)>,
}

/// The light's own sampler for the reference.
enum LightSampler {
    Map(Box<EnvMapSampler>),
    Cone { axis: Vec3, cos_radius: f64 },
    None,
}

impl LightSampler {
    fn new(light: &Light) -> Result<Self, StudyError> {
        Ok(match light {
            Light::Map { map, .. } => {
                let s = samplers::find("envmap-adaptive")?
                    .build_envmap(map, &AdaptiveOptions::default())?;
                LightSampler::Map(Box::new(s))
            }
            Light::Area { axis, radius, .. } => LightSampler::Cone {
                axis: *axis,
                cos_radius: radius.cos(),
            },
            Light::Constant { .. } => LightSampler::None,
        })
    }

    /// A world direction and its solid-angle pdf.
    fn sample(&self, u: &mut dyn UniformSource) -> Option<(Vec3, f64)> {
        match self {
            LightSampler::Map(s) => {
                let e = s.sample(u);
                Some((
                    Vec3::new(e.direction[0], e.direction[1], e.direction[2]),
                    e.pdf_sa,
                ))
            }
            LightSampler::Cone { axis, cos_radius } => {
                let c = 1.0 - u.next_uniform() * (1.0 - cos_radius);
                let phi = std::f64::consts::TAU * u.next_uniform();
                let (t1, t2) = frame_of(axis);
                let s = (1.0 - c * c).max(0.0).sqrt();
                let d = axis * c + t1 * (s * phi.cos()) + t2 * (s * phi.sin());
                Some((d, self.pdf(&d)))
            }
            LightSampler::None => None,
        }
    }

    fn pdf(&self, d: &Vec3) -> f64 {
        match self {
            LightSampler::Map(s) => s.pdf_sa([d.x, d.y, d.z]),
            LightSampler::Cone { axis, cos_radius } => {
                if d.dot(axis) >= *cos_radius {
                    1.0 / (std::f64::consts::TAU * (1.0 - cos_radius))
                } else {
                    0.0
                }
            }
            LightSampler::None => 0.0,
        }
    }
}

/// Two unit vectors completing `n` to an orthonormal frame.
fn frame_of(n: &Vec3) -> (Vec3, Vec3) {
    let up = Vec3::new(0.0, 0.0, 1.0);
    let t = up.cross(n);
    let t = if t.norm() > 1e-9 {
        t.normalize()
    } else {
        Vec3::new(1.0, 0.0, 0.0)
    };
    (t, n.cross(&t))
}

/// A visible sphere pixel.
#[derive(Debug, Clone, Copy)]
struct Hit {
    /// Pixel index.
    pixel: usize,
    /// Sphere (BRDF) index.
    sphere: usize,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    /// `ωo` in the shading frame.
    wo: Vec3,
}

impl Hit {
    fn world_of(&self, l: &Vec3) -> Vec3 {
        self.t * l.x + self.b * l.y + self.n * l.z
    }

    fn local_of(&self, w: &Vec3) -> Vec3 {
        Vec3::new(w.dot(&self.t), w.dot(&self.b), w.dot(&self.n))
    }
}

/// The visible sphere pixels of a `count`-sphere row.
fn hits(count: usize, px: usize) -> Vec<Hit> {
    let width = count * px;
    let view = Vec3::new(0.0, -1.0, 0.0); // towards the camera
    let mut out = Vec::new();
    for iy in 0..px {
        for ix in 0..width {
            let x = ((ix % px) as f64 + 0.5) / px as f64 * 2.0 - 1.0;
            let z = 1.0 - (iy as f64 + 0.5) / px as f64 * 2.0;
            let r2 = x * x + z * z;
            if r2 >= 1.0 {
                continue;
            }
            let n = Vec3::new(x, -(1.0 - r2).sqrt(), z);
            let (t, b) = frame_of(&n);
            let mut h = Hit {
                pixel: iy * width + ix,
                sphere: ix / px,
                t,
                b,
                n,
                wo: Vec3::zeros(),
            };
            h.wo = h.local_of(&view).normalize();
            if h.wo.z > 0.0 {
                out.push(h);
            }
        }
    }
    out
}

/// `f ⊙ L · cos` (RGB) for a local `wi` (0 below the horizon).
#[inline]
fn integrand(brdf: &dyn Brdf, light: &Light, h: &Hit, wi: &Vec3) -> [f64; 3] {
    if !(wi.z > 0.0) {
        return [0.0; 3];
    }
    let f = brdf.eval_rgb(&h.wo, wi);
    let l = light.radiance(&h.world_of(wi));
    [f[0] * l[0] * wi.z, f[1] * l[1] * wi.z, f[2] * l[2] * wi.z]
}

/// A stable per-name number for seeds.
fn name_hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

impl StudyPlan {
    /// Renders the sphere images (see the module docs) for every sampler of the study.
    ///
    /// Errors: a light index outside the study, or the light's sampler failing to build.
    pub fn render(
        &self,
        cfg: &RenderConfig,
        progress: crate::ProgressFn<'_>,
    ) -> Result<Render, StudyError> {
        let light = self
            .lights
            .get(cfg.light)
            .ok_or(StudyError::EmptyGrid("light to render under"))?;
        let px = cfg.sphere_px.max(4);
        let (width, height) = (self.brdfs.len() * px, px);
        let hits = hits(self.brdfs.len(), px);
        let brdfs: Vec<&dyn Brdf> = self.brdfs.iter().map(|b| b.raw.as_ref()).collect();
        // Samplers per (sampler, BRDF), built on every core first (cached); the reference
        // sampler is `adaptive`.
        let pairs: Vec<(usize, usize)> = (0..self.entries.len())
            .flat_map(|s| (0..self.brdfs.len()).map(move |b| (s, b)))
            .collect();
        self.build_all(&pairs, &|_| {});
        let built: Vec<Vec<Option<std::sync::Arc<dyn DirectionSampler>>>> = (0..self.entries.len())
            .map(|s| {
                (0..self.brdfs.len())
                    .map(|b| self.build(s, b).ok().map(|(d, _)| d.sampler))
                    .collect()
            })
            .collect();
        let reference_entry = samplers::find("adaptive")?;
        let reference_samplers: Vec<std::sync::Arc<dyn DirectionSampler>> = match self
            .entries
            .iter()
            .position(|e| e.name == reference_entry.name)
        {
            Some(s) if built[s].iter().all(Option::is_some) => {
                built[s].iter().flatten().cloned().collect()
            }
            _ => {
                let options = brdf_sampling::SetOptions {
                    slices: self.config.slices,
                    ..Default::default()
                };
                self.brdfs
                    .iter()
                    .map(|b| {
                        reference_entry
                            .build_direction(&samplers::DirectionRequest::new(
                                std::sync::Arc::clone(&b.raw),
                                &options,
                            ))
                            .map(|d| d.sampler)
                    })
                    .collect::<Result<_, _>>()?
            }
        };
        let light_sampler = LightSampler::new(light)?;
        let start = Instant::now();
        let ref_rgb = self.render_pixels(
            &hits,
            width * height,
            |h, rng| {
                mis_pixel(
                    brdfs[h.sphere],
                    light,
                    h,
                    reference_samplers[h.sphere].as_ref(),
                    &light_sampler,
                    cfg.reference_spp,
                    rng,
                )
            },
            cfg.seed ^ name_hash("reference"),
        );
        progress(1);
        let reference = Image {
            sampler: "reference".into(),
            kind: "reference".into(),
            spp: cfg.reference_spp,
            width,
            height,
            rgb: ref_rgb,
            rel_error: None,
            seconds: start.elapsed().as_secs_f64(),
        };
        // Time per pixel sample, one thread, on every 11th visible pixel: median of
        // `TIMING_REPEATS` runs.
        let subset: Vec<Hit> = hits.iter().step_by(11).copied().collect();
        let ns_per_sample: Vec<(usize, f64)> = (0..self.entries.len())
            .filter(|&s| built[s].iter().all(Option::is_some))
            .map(|s| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(cfg.seed);
                let spp = 8;
                let mut runs: Vec<f64> = (0..TIMING_REPEATS)
                    .map(|_| {
                        let t = Instant::now();
                        let mut sink = 0.0;
                        for h in &subset {
                            sink += built[s][h.sphere].as_deref().map_or(0.0, |smp| {
                                sampler_pixel(brdfs[h.sphere], light, h, smp, spp, &mut rng)[1]
                            });
                        }
                        std::hint::black_box(sink);
                        t.elapsed().as_secs_f64() * 1e9 / (subset.len() * spp).max(1) as f64
                    })
                    .collect();
                runs.sort_by(f64::total_cmp);
                (s, runs[runs.len() / 2])
            })
            .collect();
        let budget_ns = ns_per_sample
            .iter()
            .find(|(s, _)| self.entries[*s].name == "adaptive")
            .map(|x| x.1)
            .unwrap_or_else(|| {
                ns_per_sample.iter().map(|x| x.1).sum::<f64>() / ns_per_sample.len().max(1) as f64
            });
        let mut images = Vec::new();
        for &(s, ns) in &ns_per_sample {
            let name = self.entries[s].name;
            let equal_time = ((cfg.spp as f64 * budget_ns / ns).round() as usize).max(1);
            for (kind, spp) in [("equal samples", cfg.spp), ("equal time", equal_time)] {
                let start = Instant::now();
                let rgb = self.render_pixels(
                    &hits,
                    width * height,
                    |h, rng| {
                        built[s][h.sphere].as_deref().map_or([0.0; 3], |smp| {
                            sampler_pixel(brdfs[h.sphere], light, h, smp, spp, rng)
                        })
                    },
                    cfg.seed ^ name_hash(name) ^ name_hash(kind),
                );
                images.push(Image {
                    sampler: name.to_string(),
                    kind: kind.to_string(),
                    spp,
                    width,
                    height,
                    rel_error: Some(relative_error(&rgb, &reference.rgb)),
                    rgb,
                    seconds: start.elapsed().as_secs_f64(),
                });
                progress(1);
            }
        }
        Ok(Render {
            config: cfg.clone(),
            light: self.config.lights[cfg.light].clone(),
            brdfs: self.brdfs.iter().map(|b| b.spec.clone()).collect(),
            reference_method: format!(
                "MIS (balance heuristic) of the adaptive BRDF sampler and {}, {} samples of each per pixel",
                match light_sampler {
                    LightSampler::Map(_) => "the envmap-adaptive map sampler",
                    LightSampler::Cone { .. } => "uniform sampling of the area light's cone",
                    LightSampler::None => "nothing (constant light: BRDF sampling alone)",
                },
                cfg.reference_spp
            ),
            reference,
            images,
            ns_per_sample: ns_per_sample
                .iter()
                .map(|(s, ns)| (self.entries[*s].name.to_string(), *ns))
                .collect(),
        })
    }

    /// Renders every hit pixel with `shade(hit, rng)` in parallel; pixel `i` draws from a
    /// generator seeded from `(seed, i)`.
    fn render_pixels(
        &self,
        hits: &[Hit],
        pixels: usize,
        shade: impl Fn(&Hit, &mut Xoshiro256PlusPlus) -> [f64; 3] + Sync,
        seed: u64,
    ) -> Vec<[f64; 3]> {
        let values: Vec<(usize, [f64; 3])> = hits
            .par_iter()
            .map(|h| {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(chunk_seed(seed, h.pixel as u64));
                (h.pixel, shade(h, &mut rng))
            })
            .collect();
        let mut rgb = vec![[0.0; 3]; pixels];
        for (p, c) in values {
            rgb[p] = c;
        }
        rgb
    }
}

/// The BRDF-sampling estimate of one pixel.
fn sampler_pixel(
    brdf: &dyn Brdf,
    light: &Light,
    h: &Hit,
    sampler: &dyn DirectionSampler,
    spp: usize,
    rng: &mut Xoshiro256PlusPlus,
) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for _ in 0..spp {
        let s = sampler.sample(&h.wo, rng);
        if !(s.pdf > 0.0) {
            continue;
        }
        let g = integrand(brdf, light, h, &s.wi);
        for c in 0..3 {
            acc[c] += g[c] / s.pdf;
        }
    }
    acc.map(|a| a / spp as f64)
}

/// The MIS reference estimate of one pixel.
fn mis_pixel(
    brdf: &dyn Brdf,
    light: &Light,
    h: &Hit,
    sampler: &dyn DirectionSampler,
    light_sampler: &LightSampler,
    spp: usize,
    rng: &mut Xoshiro256PlusPlus,
) -> [f64; 3] {
    if matches!(light_sampler, LightSampler::None) {
        return sampler_pixel(brdf, light, h, sampler, spp, rng);
    }
    let mut acc = [0.0; 3];
    for _ in 0..spp {
        let s = sampler.sample(&h.wo, rng);
        let p = s.pdf + light_sampler.pdf(&h.world_of(&s.wi));
        if p > 0.0 {
            let g = integrand(brdf, light, h, &s.wi);
            for c in 0..3 {
                acc[c] += g[c] / p;
            }
        }
        if let Some((d, pl)) = light_sampler.sample(rng) {
            let wi = h.local_of(&d);
            if wi.z > 0.0 {
                let p = pl + sampler.pdf(&h.wo, &wi);
                if p > 0.0 {
                    let g = integrand(brdf, light, h, &wi);
                    for c in 0..3 {
                        acc[c] += g[c] / p;
                    }
                }
            }
        }
    }
    acc.map(|a| a / spp as f64)
}

/// Mean over pixels with non-null reference luminance of `|Y − Y_ref| / Y_ref`.
pub fn relative_error(image: &[[f64; 3]], reference: &[[f64; 3]]) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for (i, r) in image.iter().zip(reference) {
        let yr = colour::luminance(*r);
        if yr > 0.0 {
            sum += (colour::luminance(*i) - yr).abs() / yr;
            count += 1;
        }
    }
    if count == 0 { 0.0 } else { sum / count as f64 }
}

impl Image {
    /// The exposure that maps the 99th percentile of `reference`'s non-zero luminances to 0.9.
    pub fn exposure_of(reference: &Image) -> f64 {
        let mut ys: Vec<f64> = reference
            .rgb
            .iter()
            .map(|c| colour::luminance(*c))
            .filter(|y| *y > 0.0)
            .collect();
        if ys.is_empty() {
            return 1.0;
        }
        ys.sort_by(f64::total_cmp);
        let p = ys[((ys.len() - 1) as f64 * 0.99) as usize];
        if p > 0.0 { 0.9 / p } else { 1.0 }
    }

    /// Tone-mapped 8-bit sRGB (exposure, clamp, sRGB transfer curve).
    pub fn to_rgb8(&self, exposure: f64) -> image::RgbImage {
        let mut img = image::RgbImage::new(self.width as u32, self.height as u32);
        for (i, p) in img.pixels_mut().enumerate() {
            let c = self.rgb[i];
            *p =
                image::Rgb(c.map(|x| (srgb((x * exposure).clamp(0.0, 1.0)) * 255.0).round() as u8));
        }
        img
    }

    /// The PNG bytes of [`Image::to_rgb8`].
    pub fn png(&self, exposure: f64) -> Result<Vec<u8>, StudyError> {
        encode_png(&self.to_rgb8(exposure), &self.sampler)
    }

    /// The raw linear image as PFM (colour, little endian, bottom row first).
    pub fn pfm(&self) -> Vec<u8> {
        let mut out = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        for y in (0..self.height).rev() {
            for x in 0..self.width {
                for c in self.rgb[y * self.width + x] {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
        out
    }
}

/// PNG bytes of an 8-bit image.
pub fn encode_png(img: &image::RgbImage, name: &str) -> Result<Vec<u8>, StudyError> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| StudyError::Plot {
            name: name.to_string(),
            reason: e.to_string(),
        })?;
    Ok(out.into_inner())
}

/// Stacks images vertically with a 4-pixel gap (the report's contact sheet).
pub fn stack(images: &[image::RgbImage]) -> image::RgbImage {
    let w = images.iter().map(image::RgbImage::width).max().unwrap_or(1);
    let h = images.iter().map(|i| i.height() + 4).sum::<u32>().max(1);
    let mut out = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let mut y0 = 0;
    for img in images {
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(x, y0 + y, *p);
        }
        y0 += img.height() + 4;
    }
    out
}

/// The sRGB transfer curve.
fn srgb(x: f64) -> f64 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

impl Render {
    /// The report's section on the images: the setup, the reference, and per sampler the
    /// samples per pixel and relative error at equal samples and at equal time. `sheets` are
    /// `(caption, path)` of the images to embed.
    pub fn markdown(&self, sheets: &[(String, String)]) -> String {
        use std::fmt::Write as _;
        let mut s = String::from("## Sphere images\n\n");
        let _ = writeln!(
            s,
            "Spheres, left to right: {}; under `{}`; {}×{} pixels per sphere, orthographic camera, direct lighting, no shadows. Reference: {} ({:.1} s †). Relative error = mean over pixels with non-null reference luminance of |Y − Y_ref| / Y_ref. Equal time: samples per pixel scaled by the measured time per sample (†) to the `adaptive` sampler's budget of {} spp.\n",
            self.brdfs
                .iter()
                .map(|b| format!("`{b}`"))
                .collect::<Vec<_>>()
                .join(", "),
            crate::short_light(&self.light),
            self.config.sphere_px,
            self.config.sphere_px,
            self.reference_method,
            self.reference.seconds,
            self.config.spp,
        );
        s.push_str("| sampler | ns / sample † | spp (equal samples) | rel. error | spp (equal time †) | rel. error |\n|---|---|---|---|---|---|\n");
        for (name, ns) in &self.ns_per_sample {
            let find = |kind: &str| {
                self.images
                    .iter()
                    .find(|i| &i.sampler == name && i.kind == kind)
            };
            let cell = |i: Option<&Image>| {
                i.map_or("— | —".to_string(), |i| {
                    format!("{} | {:.2} %", i.spp, 100.0 * i.rel_error.unwrap_or(0.0))
                })
            };
            let _ = writeln!(
                s,
                "| {name} | {ns:.0} | {} | {} |",
                cell(find("equal samples")),
                cell(find("equal time"))
            );
        }
        s.push('\n');
        for kind in ["equal samples", "equal time"] {
            let mut ranked: Vec<&Image> = self.images.iter().filter(|i| i.kind == kind).collect();
            ranked.sort_by(|a, b| {
                a.rel_error
                    .unwrap_or(f64::MAX)
                    .total_cmp(&b.rel_error.unwrap_or(f64::MAX))
            });
            let best = ranked.first();
            let best_adaptive = ranked.iter().find(|i| crate::is_adaptive(&i.sampler));
            if let (Some(b), Some(a)) = (best, best_adaptive) {
                let (eb, ea) = (b.rel_error.unwrap_or(0.0), a.rel_error.unwrap_or(0.0));
                if crate::is_adaptive(&b.sampler) {
                    let _ = writeln!(
                        s,
                        "At {kind}, **{}** has the lowest image error ({:.2} %) (one image per sampler, no interval: an observation, not a ranking).",
                        b.sampler,
                        100.0 * eb
                    );
                } else {
                    let _ = writeln!(
                        s,
                        "At {kind}, **{}** has the lowest image error ({:.2} %); the best adaptive sampler, {}, has {:.2} % ({:.2}× the error) (one image per sampler, no interval: an observation, not a ranking).",
                        b.sampler,
                        100.0 * eb,
                        a.sampler,
                        100.0 * ea,
                        if eb > 0.0 { ea / eb } else { f64::INFINITY }
                    );
                }
            }
        }
        s.push('\n');
        for (caption, path) in sheets {
            let _ = writeln!(s, "**{caption}**\n\n![{caption}]({path})\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_ignores_black_reference_pixels() {
        let r = [[1.0; 3], [0.0; 3], [2.0; 3]];
        let i = [[1.5; 3], [5.0; 3], [2.0; 3]];
        assert!((relative_error(&i, &r) - 0.25).abs() < 1e-12);
    }

    #[test]
    fn sphere_pixels_face_the_camera() {
        let hs = hits(2, 16);
        assert!(!hs.is_empty());
        for h in &hs {
            assert!(h.wo.z > 0.0 && (h.wo.norm() - 1.0).abs() < 1e-12);
            assert!(
                (h.world_of(&h.local_of(&Vec3::new(0.3, 0.4, 0.5))) - Vec3::new(0.3, 0.4, 0.5))
                    .norm()
                    < 1e-12
            );
        }
        assert!(hs.iter().any(|h| h.sphere == 1));
    }
}
