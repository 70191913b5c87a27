//! The in-memory lat-long map and its validation.

use crate::EnvMapError;

/// Largest number of pixels a map may have (2²⁵ ≈ 33.5 M, e.g. 8192 × 4096).
pub const MAX_PIXELS: usize = 1 << 25;

/// Luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B` (Rec. 709 / sRGB primaries) of a pixel's
/// `f32` radiance: [`colour::luminance`] of the triple widened to `f64`.
#[inline]
pub fn luminance(rgb: [f32; 3]) -> f64 {
    colour::luminance(rgb.map(f64::from))
}

/// A lat-long (equirectangular) environment map of linear RGB radiance.
///
/// Pixel `(x, y)` (column, row; row 0 at the top) covers
/// `u ∈ [x/W, (x+1)/W)`, `v ∈ [y/H, (y+1)/H)` in the crate's convention (see the crate docs):
/// row 0 touches the zenith `+z`, the last row the nadir `−z`.
///
/// Every pixel is finite and non-negative, and at least one is not black (checked on
/// construction).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    rgb: Vec<[f32; 3]>,
}

impl EnvMap {
    /// A map from row-major RGB pixels (row 0 at the top, `v = 0`).
    ///
    /// Errors: zero width or height, more than [`MAX_PIXELS`] pixels, a pixel count other than
    /// `width · height`, a NaN, infinite or negative channel (naming the pixel), all pixels black.
    pub fn new(width: usize, height: usize, rgb: Vec<[f32; 3]>) -> Result<Self, EnvMapError> {
        check_dimensions(width, height)?;
        let expected = width * height;
        if rgb.len() != expected {
            return Err(EnvMapError::SizeMismatch {
                width,
                height,
                expected,
                got: rgb.len(),
            });
        }
        let mut any_light = false;
        for (i, px) in rgb.iter().enumerate() {
            for (channel, &value) in px.iter().enumerate() {
                let (x, y) = (i % width, i / width);
                if !value.is_finite() {
                    return Err(EnvMapError::NonFinitePixel {
                        x,
                        y,
                        channel,
                        value,
                    });
                }
                if !(value >= 0.0) {
                    return Err(EnvMapError::NegativePixel {
                        x,
                        y,
                        channel,
                        value,
                    });
                }
                any_light |= value > 0.0;
            }
        }
        if !any_light {
            return Err(EnvMapError::AllBlack);
        }
        Ok(Self { width, height, rgb })
    }

    /// Width in pixels (along `u`, the azimuth φ = 2πu).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (along `v`, the polar angle θ = πv).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Row-major pixels, row 0 at the top.
    pub fn rgb(&self) -> &[[f32; 3]] {
        &self.rgb
    }

    /// The pixel at column `x`, row `y`; `None` out of range.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        if x < self.width && y < self.height {
            self.rgb.get(y * self.width + x).copied()
        } else {
            None
        }
    }

    /// Row-major per-pixel luminance `Y` (see [`luminance`]).
    pub fn luminance(&self) -> Vec<f64> {
        self.rgb.iter().map(|&p| luminance(p)).collect()
    }

    /// The pixel containing `(u, v) ∈ [0,1]²` (clamped; NaN maps to 0).
    pub fn pixel_at(&self, u: f64, v: f64) -> (usize, usize) {
        let x = ((u * self.width as f64).max(0.0) as usize).min(self.width - 1);
        let y = ((v * self.height as f64).max(0.0) as usize).min(self.height - 1);
        (x, y)
    }

    /// Radiance (RGB) seen in lat-long coordinates `(u, v)`, nearest pixel.
    pub fn radiance_uv(&self, u: f64, v: f64) -> [f32; 3] {
        let (x, y) = self.pixel_at(u, v);
        self.rgb[y * self.width + x]
    }

    /// Heap and inline bytes of the pixel storage.
    pub fn bytes_used(&self) -> usize {
        std::mem::size_of::<Self>() + self.rgb.capacity() * std::mem::size_of::<[f32; 3]>()
    }
}

/// Rejects empty and oversized maps.
pub(crate) fn check_dimensions(width: usize, height: usize) -> Result<(), EnvMapError> {
    if width == 0 || height == 0 {
        return Err(EnvMapError::Empty { width, height });
    }
    match width.checked_mul(height) {
        Some(n) if n <= MAX_PIXELS => Ok(()),
        _ => Err(EnvMapError::TooLarge {
            width,
            height,
            max: MAX_PIXELS,
        }),
    }
}
