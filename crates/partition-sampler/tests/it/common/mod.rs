//! Shared helpers of the integration tests: densities with independently computed bin masses
//! and a small chi-square goodness-of-fit test.
#![allow(dead_code, unreachable_pub)]

use partition_sampler::{
    Density, DensityShape, Domain, IntegralSource, Point2, Rect, RegionEstimate, RegionStats,
    SinPiRows, TabulatedDensity,
};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Significance level of every statistical test.
pub const ALPHA: f64 = 0.01;

/// A `nx × ny` binning of a rectangle.
#[derive(Debug, Clone, Copy)]
pub struct Bins {
    pub rect: Rect,
    pub nx: usize,
    pub ny: usize,
}

impl Bins {
    pub fn index(&self, p: Point2) -> Option<usize> {
        if !self.rect.contains(p) {
            return None;
        }
        let i = (((p[0] - self.rect.x0) / self.rect.width() * self.nx as f64) as usize)
            .min(self.nx - 1);
        let j = (((p[1] - self.rect.y0) / self.rect.height() * self.ny as f64) as usize)
            .min(self.ny - 1);
        Some(j * self.nx + i)
    }

    pub fn bin(&self, i: usize, j: usize) -> Rect {
        let w = self.rect.width() / self.nx as f64;
        let h = self.rect.height() / self.ny as f64;
        Rect::new(
            self.rect.x0 + i as f64 * w,
            self.rect.y0 + j as f64 * h,
            self.rect.x0 + (i + 1) as f64 * w,
            self.rect.y0 + (j + 1) as f64 * h,
        )
    }

    /// Bin masses of `f` (restricted to `inside`) by a `k × k` midpoint rule per bin, normalised.
    pub fn masses(
        &self,
        k: usize,
        f: impl Fn(Point2) -> f64,
        inside: impl Fn(Point2) -> bool,
    ) -> Vec<f64> {
        let mut m = vec![0.0; self.nx * self.ny];
        for j in 0..self.ny {
            for i in 0..self.nx {
                let b = self.bin(i, j);
                let mut s = 0.0;
                for bb in 0..k {
                    for aa in 0..k {
                        let p = [
                            b.x0 + (aa as f64 + 0.5) / k as f64 * b.width(),
                            b.y0 + (bb as f64 + 0.5) / k as f64 * b.height(),
                        ];
                        if inside(p) {
                            s += f(p);
                        }
                    }
                }
                m[j * self.nx + i] = s * b.area() / (k * k) as f64;
            }
        }
        let t: f64 = m.iter().sum();
        m.iter().map(|v| v / t).collect()
    }

    pub fn histogram(&self, pts: impl IntoIterator<Item = Point2>) -> (Vec<u64>, u64) {
        let mut h = vec![0u64; self.nx * self.ny];
        let mut outside = 0;
        for p in pts {
            match self.index(p) {
                Some(k) => h[k] += 1,
                None => outside += 1,
            }
        }
        (h, outside)
    }
}

/// Pearson chi-square p-value of `observed` counts against probabilities `expected`
/// (bins with expected count < 5 are pooled in index order; observations in bins of
/// zero probability give p = 0).
pub fn chi_square_p(observed: &[u64], expected: &[f64]) -> f64 {
    let n: u64 = observed.iter().sum();
    let nf = n as f64;
    let mut stat = 0.0;
    let mut cells = 0usize;
    let (mut po, mut pe) = (0.0f64, 0.0f64);
    for (&o, &p) in observed.iter().zip(expected) {
        if p <= 0.0 {
            if o > 0 {
                return 0.0;
            }
            continue;
        }
        po += o as f64;
        pe += p * nf;
        if pe >= 5.0 {
            stat += (po - pe).powi(2) / pe;
            cells += 1;
            po = 0.0;
            pe = 0.0;
        }
    }
    if pe > 0.0 {
        stat += (po - pe).powi(2) / pe.max(1e-300);
        cells += 1;
    }
    if cells < 2 {
        return 1.0;
    }
    1.0 - ChiSquared::new((cells - 1) as f64).unwrap().cdf(stat)
}

/// A Phong-like lobe on the disc: `max(0, r·v)^e` with `v = (x, y, √(1 − x² − y²))` and `r`
/// the mirror direction at `theta` degrees.
pub fn phong_lobe(theta_deg: f64, e: f64) -> impl Fn(Point2) -> f64 + Sync + Send + Copy {
    let t = theta_deg.to_radians();
    let r = [t.sin(), 0.0, t.cos()];
    move |p: Point2| {
        let z2 = 1.0 - p[0] * p[0] - p[1] * p[1];
        if z2 < 0.0 {
            return 0.0;
        }
        let c = r[0] * p[0] + r[1] * p[1] + r[2] * z2.sqrt();
        if c > 0.0 { c.powf(e) } else { 0.0 }
    }
}

pub fn in_disc(p: Point2) -> bool {
    p[0] * p[0] + p[1] * p[1] <= 1.0
}

/// A `w × h` luminance map with smooth background and a `sun` of a few texels `gain` times
/// brighter (row-major, row 0 at v = 0).
pub fn sun_map(w: usize, h: usize, gain: f64) -> Vec<f64> {
    let mut v: Vec<f64> = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            0.2 + 0.8 * ((i as f64 * 0.37).sin() * (j as f64 * 0.23).cos()).abs()
        })
        .collect();
    let (si, sj) = (w / 3, h / 4);
    v[sj * w + si] = gain;
    v[sj * w + si + 1] = gain * 0.5;
    v[(sj + 1) * w + si] = gain * 0.25;
    v
}

/// Exact bin masses of a tabulated map times `sin(πv)` on `[0,1]²`, for bins aligned on texels
/// (`w % nx == 0`, `h % ny == 0`), computed texel by texel.
pub fn sun_map_masses(vals: &[f64], w: usize, h: usize, bins: &Bins) -> Vec<f64> {
    let mut m = vec![0.0; bins.nx * bins.ny];
    for j in 0..h {
        let row = ((std::f64::consts::PI * j as f64 / h as f64).cos()
            - (std::f64::consts::PI * (j + 1) as f64 / h as f64).cos())
            / std::f64::consts::PI;
        for i in 0..w {
            let b = (j * bins.ny / h) * bins.nx + i * bins.nx / w;
            m[b] += vals[j * w + i] * row / w as f64;
        }
    }
    let t: f64 = m.iter().sum();
    m.iter().map(|v| v / t).collect()
}

/// The `w × h` table `vals` over `rect` with `sin(πv)` rows (an environment map's density).
pub fn sin_rows(w: usize, h: usize, vals: Vec<f64>, rect: Rect) -> TabulatedDensity<SinPiRows> {
    TabulatedDensity::new(w, h, vals, rect)
        .unwrap()
        .with_row_factor(SinPiRows)
        .unwrap()
}

/// A provider that lies (shared by the negative and the batch-path tests): bounds scaled by `bound_scale`, integrals of cells left of x = 0.5
/// scaled by `left_integral_scale`.
pub struct Broken<D> {
    pub inner: D,
    pub bound_scale: f64,
    pub left_integral_scale: f64,
}

impl<D> Broken<D> {
    /// `inner` with its bounds scaled by `bound_scale` and its left cells' integrals by
    /// `left_integral_scale`.
    pub fn new(inner: D, bound_scale: f64, left_integral_scale: f64) -> Self {
        Self {
            inner,
            bound_scale,
            left_integral_scale,
        }
    }
}

impl<D: RegionStats> Density for Broken<D> {
    fn eval(&self, p: Point2) -> f64 {
        self.inner.eval(p)
    }
}

impl<D: RegionStats> RegionStats for Broken<D> {
    fn domain(&self) -> Domain {
        self.inner.domain()
    }
    fn region(&self, cell: &Rect) -> RegionEstimate {
        let mut e = self.inner.region(cell);
        e.max_bound *= self.bound_scale;
        if cell.x1 <= 0.5 {
            e.integral *= self.left_integral_scale;
        }
        e
    }
    fn integral_source(&self) -> IntegralSource {
        self.inner.integral_source()
    }
    fn shape(&self) -> DensityShape {
        self.inner.shape()
    }
    fn bytes_used(&self) -> usize {
        self.inner.bytes_used()
    }
}
