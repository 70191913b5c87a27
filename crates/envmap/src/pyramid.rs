//! A prefiltered lat-long map for product sampling: a pyramid of **powers** (luminance ×
//! solid angle summed over blocks of pixels), each coarse cell with its power-weighted mean
//! direction and a bounding cone, and exact sampling inside any cell ∝ radiance.
//!
//! **Levels.** Level 0 is the map's pixels: pixel `(x, y)` of a `W × H` map has the power
//! `P = Y(x, y) · Ω_y`, `Ω_y = (2π/W)(cos πy/H − cos π(y+1)/H)` its exact solid angle and `Y`
//! its luminance ([`crate::luminance`]). Level `k` has `⌈W/2^k⌉ × ⌈H/2^k⌉` cells; cell
//! `(x, y)` covers the pixels `[x·2^k, (x+1)·2^k) × [y·2^k, (y+1)·2^k)` inside the map and its
//! power is the sum of its (up to four) children's. Levels stop at one cell along either axis.
//!
//! **Sampling in a cell.** From cell `c`, one uniform descends to a pixel choosing each child
//! with probability `P_child / P_parent` (the uniform rescaled at each level); inside the pixel
//! the direction is uniform in solid angle (`φ` uniform over the pixel's columns, `cos θ`
//! uniform over its rows). The density of a direction `ω` in pixel `p ⊂ c` is therefore
//! `p(ω | c) = P_p / (P_c Ω_p) = Y_p / P_c` w.r.t. solid angle (the per-level ratios telescope),
//! 0 outside `c` and on black pixels.
//!
//! **Cell geometry** (levels ≥ [`GEOMETRY_LEVEL`] only, to keep memory small): the unit
//! direction of the cell's centre in `(u, v)`, the sine of an angular radius that bounds every
//! direction of the cell around that centre (from its corners and edge midpoints, plus a
//! margin), and its power-weighted mean direction `Σ P_p ω_p / |Σ P_p ω_p|` (`ω_p` pixel
//! centres; the centre when the cell is black).

use std::f64::consts::{PI, TAU};

use crate::EnvMap;
use crate::latlong::{direction_to_uv, uv_to_direction};

/// The finest level that stores its cells' geometry ([`CellGeometry`]).
pub const GEOMETRY_LEVEL: usize = 2;

/// A coarse cell's directions: centre, bounding cone, power-weighted mean direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellGeometry {
    /// Unit direction of the cell's centre in `(u, v)`.
    pub centre: [f64; 3],
    /// `sin r`, `r` an angular radius around `centre` containing every direction of the cell
    /// (1 when `r ≥ π/2`): the cell lies below a plane of normal `n` when `n · centre < −sin r`.
    pub sin_radius: f64,
    /// Unit power-weighted mean direction of the cell's pixels (the centre for a black cell).
    pub centroid: [f64; 3],
}

/// One level of the pyramid.
#[derive(Debug, Clone)]
struct Level {
    width: usize,
    height: usize,
    power: Vec<f64>,
    geometry: Vec<CellGeometry>,
}

/// A direction drawn inside a cell (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellSample {
    /// The pixel it lies in (column, row).
    pub pixel: (usize, usize),
    /// The unit world direction.
    pub direction: [f64; 3],
    /// Its density w.r.t. solid angle given the cell, `Y_p / P_c`.
    pub pdf_sa: f64,
}

/// The power pyramid of a map (module docs).
#[derive(Debug, Clone)]
pub struct PowerPyramid {
    width: usize,
    height: usize,
    /// Per-pixel luminance `Y`.
    luminance: Vec<f64>,
    levels: Vec<Level>,
}

impl PowerPyramid {
    /// The pyramid of `map` (its pixels' luminance; cost `O(W·H)`).
    pub fn new(map: &EnvMap) -> Self {
        let (w, h) = (map.width(), map.height());
        let luminance = map.luminance();
        let row_omega: Vec<f64> = (0..h)
            .map(|y| {
                TAU / w as f64
                    * ((PI * y as f64 / h as f64).cos() - (PI * (y + 1) as f64 / h as f64).cos())
            })
            .collect();
        let power: Vec<f64> = luminance
            .iter()
            .enumerate()
            .map(|(i, y)| y * row_omega[i / w])
            .collect();
        // Power-weighted direction sums per pixel, summed up the levels with the powers.
        let mut sums: Vec<[f64; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let d = uv_to_direction((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
                d.map(|c| c * power[i])
            })
            .collect();
        let mut levels = vec![Level {
            width: w,
            height: h,
            power,
            geometry: Vec::new(),
        }];
        let mut k = 0;
        while levels[k].width > 1 && levels[k].height > 1 {
            let fine = &levels[k];
            let (fw, fh) = (fine.width, fine.height);
            let (cw, ch) = (fw.div_ceil(2), fh.div_ceil(2));
            let mut power = vec![0.0; cw * ch];
            let mut next_sums = vec![[0.0; 3]; cw * ch];
            for y in 0..fh {
                for x in 0..fw {
                    let c = (y / 2) * cw + x / 2;
                    power[c] += fine.power[y * fw + x];
                    let s = sums[y * fw + x];
                    for i in 0..3 {
                        next_sums[c][i] += s[i];
                    }
                }
            }
            let level = k + 1;
            let geometry = if level >= GEOMETRY_LEVEL {
                (0..cw * ch)
                    .map(|c| geometry_of(w, h, level, c % cw, c / cw, next_sums[c]))
                    .collect()
            } else {
                Vec::new()
            };
            levels.push(Level {
                width: cw,
                height: ch,
                power,
                geometry,
            });
            sums = next_sums;
            k += 1;
        }
        Self {
            width: w,
            height: h,
            luminance,
            levels,
        }
    }

    /// Number of levels (level 0 = the pixels).
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Cells of level `k` along `u` and `v` (`None` past the coarsest level).
    pub fn dims(&self, k: usize) -> Option<(usize, usize)> {
        self.levels.get(k).map(|l| (l.width, l.height))
    }

    /// The power `Σ Y_p Ω_p` of cell `(x, y)` of level `k` (0 outside the pyramid).
    #[inline]
    pub fn power(&self, k: usize, x: usize, y: usize) -> f64 {
        match self.levels.get(k) {
            Some(l) if x < l.width && y < l.height => l.power[y * l.width + x],
            _ => 0.0,
        }
    }

    /// The geometry of cell `(x, y)` of level `k ≥ GEOMETRY_LEVEL` (`None` elsewhere).
    #[inline]
    pub fn geometry(&self, k: usize, x: usize, y: usize) -> Option<&CellGeometry> {
        let l = self.levels.get(k)?;
        if x < l.width && y < l.height {
            l.geometry.get(y * l.width + x)
        } else {
            None
        }
    }

    /// The luminance `Y` of pixel `(x, y)` (0 outside the map).
    #[inline]
    pub fn luminance(&self, x: usize, y: usize) -> f64 {
        if x < self.width && y < self.height {
            self.luminance[y * self.width + x]
        } else {
            0.0
        }
    }

    /// The pixel a direction falls in — the lookup of [`EnvMap::radiance_uv`] after
    /// [`direction_to_uv`].
    #[inline]
    pub fn pixel_of(&self, d: [f64; 3]) -> (usize, usize) {
        let (u, v) = direction_to_uv(d);
        let x = ((u * self.width as f64).max(0.0) as usize).min(self.width - 1);
        let y = ((v * self.height as f64).max(0.0) as usize).min(self.height - 1);
        (x, y)
    }

    /// A direction inside cell `(x, y)` of level `k` ∝ radiance (module docs) from three
    /// uniforms in `[0, 1)`: `u[0]` descends, `u[1]`, `u[2]` place it in the pixel. `None` for a
    /// black cell or one outside the pyramid.
    pub fn sample_in_cell(&self, k: usize, x: usize, y: usize, u: [f64; 3]) -> Option<CellSample> {
        let total = self.power(k, x, y);
        if !(total > 0.0) {
            return None;
        }
        let (mut cx, mut cy, mut t) = (x, y, u[0]);
        for level in (0..k).rev() {
            let l = &self.levels[level];
            let parent = self.levels[level + 1].power[cy * self.levels[level + 1].width + cx];
            let (x0, y0) = (2 * cx, 2 * cy);
            let mut target = t * parent;
            let mut chosen = None;
            let mut last = None;
            'pick: for dy in 0..2 {
                for dx in 0..2 {
                    let (px, py) = (x0 + dx, y0 + dy);
                    if px >= l.width || py >= l.height {
                        continue;
                    }
                    let p = l.power[py * l.width + px];
                    if p > 0.0 {
                        last = Some((px, py, p, target));
                        if target < p {
                            chosen = Some((px, py, p, target));
                            break 'pick;
                        }
                        target -= p;
                    }
                }
            }
            // Rounding can leave `target` just past the last positive child: take it.
            let (px, py, p, rest) = chosen.or(last)?;
            t = (rest / p).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
            cx = px;
            cy = py;
        }
        let (w, h) = (self.width as f64, self.height as f64);
        let phi = TAU * (cx as f64 + u[1]) / w;
        let (z0, z1) = ((PI * cy as f64 / h).cos(), (PI * (cy + 1) as f64 / h).cos());
        let z = (z0 - u[2] * (z0 - z1)).clamp(-1.0, 1.0);
        let s = (1.0 - z * z).max(0.0).sqrt();
        let (sp, cp) = phi.sin_cos();
        Some(CellSample {
            pixel: (cx, cy),
            direction: [s * cp, s * sp, z],
            pdf_sa: self.luminance[cy * self.width + cx] / total,
        })
    }

    /// The density w.r.t. solid angle of [`Self::sample_in_cell`] at the direction of pixel
    /// `pixel`: `Y_p / P_c` when the pixel lies in cell `(x, y)` of level `k`, else 0.
    #[inline]
    pub fn pdf_in_cell(&self, k: usize, x: usize, y: usize, pixel: (usize, usize)) -> f64 {
        if pixel.0 >> k != x || pixel.1 >> k != y {
            return 0.0;
        }
        let total = self.power(k, x, y);
        if total > 0.0 {
            self.luminance(pixel.0, pixel.1) / total
        } else {
            0.0
        }
    }

    /// Heap and inline bytes.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.luminance.capacity() * 8
            + self
                .levels
                .iter()
                .map(|l| {
                    l.power.capacity() * 8
                        + l.geometry.capacity() * std::mem::size_of::<CellGeometry>()
                })
                .sum::<usize>()
    }
}

/// The geometry of cell `(x, y)` of level `k` of a `w × h` map, given its power-weighted
/// direction sum.
fn geometry_of(w: usize, h: usize, k: usize, x: usize, y: usize, sum: [f64; 3]) -> CellGeometry {
    let (u0, u1) = (
        (x << k) as f64 / w as f64,
        (((x + 1) << k).min(w)) as f64 / w as f64,
    );
    let (v0, v1) = (
        (y << k) as f64 / h as f64,
        (((y + 1) << k).min(h)) as f64 / h as f64,
    );
    let centre = uv_to_direction(0.5 * (u0 + u1), 0.5 * (v0 + v1));
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // The smallest cosine to the centre over a 5 × 5 grid of the cell's boundary and interior
    // points, then a margin of half a grid step's angle for what lies between them.
    let mut min_cos: f64 = 1.0;
    for i in 0..5 {
        for j in 0..5 {
            let d = uv_to_direction(
                u0 + (u1 - u0) * i as f64 / 4.0,
                v0 + (v1 - v0) * j as f64 / 4.0,
            );
            min_cos = min_cos.min(dot(d, centre));
        }
    }
    let step = (PI * (v1 - v0) / 4.0).max(TAU * (u1 - u0) / 4.0);
    let r = min_cos.clamp(-1.0, 1.0).acos() + step;
    let sin_radius = if r >= PI / 2.0 { 1.0 } else { r.sin() };
    let len = dot(sum, sum).sqrt();
    let centroid = if len > 0.0 && len.is_finite() {
        sum.map(|c| c / len)
    } else {
        centre
    };
    CellGeometry {
        centre,
        sin_radius,
        centroid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    /// A 64 × 32 map: dim background, a bright 3 × 2 patch and a black block.
    fn map() -> EnvMap {
        let (w, h) = (64, 32);
        let rgb = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (40..43).contains(&x) && (9..11).contains(&y) {
                    [50.0, 40.0, 30.0]
                } else if (5..13).contains(&x) && (20..28).contains(&y) {
                    [0.0; 3]
                } else {
                    [
                        0.2 + 0.01 * (x % 7) as f32,
                        0.3,
                        0.1 + 0.02 * (y % 5) as f32,
                    ]
                }
            })
            .collect();
        EnvMap::new(w, h, rgb).unwrap()
    }

    #[test]
    fn powers_sum_up_the_levels_and_the_cones_contain_their_pixels() {
        let m = map();
        let p = PowerPyramid::new(&m);
        let total: f64 = (0..32)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .map(|(x, y)| p.power(0, x, y))
            .sum();
        for k in 0..p.levels() {
            let (w, h) = p.dims(k).unwrap();
            let s: f64 = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| p.power(k, x, y))
                .sum();
            approx::assert_relative_eq!(s, total, max_relative = 1e-12);
        }
        // Every pixel centre and corner lies within its cell's cone.
        for k in GEOMETRY_LEVEL..p.levels() {
            for py in 0..32usize {
                for px in 0..64usize {
                    let g = p.geometry(k, px >> k, py >> k).unwrap();
                    for (a, b) in [(0.0, 0.0), (0.5, 0.5), (1.0, 1.0), (1.0, 0.0)] {
                        let d = uv_to_direction((px as f64 + a) / 64.0, (py as f64 + b) / 32.0);
                        let c = d[0] * g.centre[0] + d[1] * g.centre[1] + d[2] * g.centre[2];
                        let cos_r = (1.0 - g.sin_radius * g.sin_radius).max(0.0).sqrt();
                        assert!(
                            g.sin_radius >= 1.0 || c >= cos_r - 1e-12,
                            "k {k} pixel ({px}, {py})"
                        );
                    }
                }
            }
        }
    }

    /// In a cell, the sampled pixels follow `P_p / P_c` (χ² over the cell's pixels) and
    /// every sample lies in its pixel with the density `Y_p / P_c`; the density integrates to
    /// one over the cell. Broken: a descent that picks children ∝ luminance instead of power
    /// (the solid angle dropped) is rejected.
    #[test]
    fn samples_in_a_cell_follow_its_pixels_power() {
        let m = map();
        let p = PowerPyramid::new(&m);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let (k, cx, cy) = (3, 5, 1); // 8 × 8 pixels holding the bright patch
        let n = 200_000;
        let mut counts = vec![0u64; 64];
        for _ in 0..n {
            let u = [
                rand::RngExt::random(&mut rng),
                rand::RngExt::random(&mut rng),
                rand::RngExt::random(&mut rng),
            ];
            let s = p.sample_in_cell(k, cx, cy, u).unwrap();
            assert_eq!(p.pixel_of(s.direction), s.pixel);
            assert_eq!(p.pdf_in_cell(k, cx, cy, s.pixel), s.pdf_sa);
            counts[(s.pixel.1 - 8) * 8 + s.pixel.0 - 40] += 1;
        }
        let pc = p.power(k, cx, cy);
        let expected: Vec<f64> = (0..64)
            .map(|i| n as f64 * p.power(0, 40 + i % 8, 8 + i / 8) / pc)
            .collect();
        let r = stats::chi_square_gof(&counts, &expected, 5.0).unwrap();
        assert!(r.p_value > 1e-3, "{}", r.summary());
        // ∫ pdf over the cell = Σ_p (Y_p / P_c) Ω_p = 1.
        let integral: f64 = (0..64)
            .map(|i| {
                let (x, y) = (40 + i % 8, 8 + i / 8);
                p.pdf_in_cell(k, cx, cy, (x, y)) * p.power(0, x, y) / p.luminance(x, y).max(1e-300)
            })
            .sum();
        approx::assert_relative_eq!(integral, 1.0, max_relative = 1e-12);
        // The mutant: expected counts ∝ luminance alone (no solid angle) — rejected.
        let ysum: f64 = (0..64).map(|i| p.luminance(40 + i % 8, 8 + i / 8)).sum();
        let wrong: Vec<f64> = (0..64)
            .map(|i| n as f64 * p.luminance(40 + i % 8, 8 + i / 8) / ysum)
            .collect();
        let r = stats::chi_square_gof(&counts, &wrong, 5.0).unwrap();
        assert!(r.p_value < 1e-6, "mutant not rejected: {}", r.summary());
        // A black cell cannot be sampled.
        assert!(p.sample_in_cell(2, 2, 5, [0.5; 3]).is_none());
    }
}
