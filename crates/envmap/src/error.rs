//! The error type of the crate.

use std::path::PathBuf;

use thiserror::Error;

use crate::format::MapFormat;

/// Why a map could not be loaded or validated, or a sampler not built.
#[derive(Debug, Error)]
pub enum EnvMapError {
    /// Reading the file failed.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file name does not end in `.hdr`, `.exr` or `.pfm` (case-insensitive).
    #[error("unsupported map file {path}: expected a .hdr, .exr or .pfm extension")]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
    },
    /// The file ends before the pixel data it announces.
    #[error("truncated {format} file: {detail}")]
    Truncated {
        /// The file format.
        format: MapFormat,
        /// What was missing.
        detail: String,
    },
    /// The header is not a valid header of the format.
    #[error("malformed {format} header: {detail}")]
    MalformedHeader {
        /// The file format.
        format: MapFormat,
        /// What is wrong.
        detail: String,
    },
    /// The pixel data cannot be decoded, or uses a variant of the format this crate does not read.
    #[error("cannot decode {format} data: {detail}")]
    Decode {
        /// The file format.
        format: MapFormat,
        /// The decoder's message.
        detail: String,
    },
    /// The map has no pixel (`width == 0` or `height == 0`).
    #[error("empty map: {width}×{height} pixels")]
    Empty {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// The map is larger than [`crate::MAX_PIXELS`] pixels.
    #[error("map too large: {width}×{height} pixels (at most {max} allowed)")]
    TooLarge {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// The limit, in pixels.
        max: usize,
    },
    /// The header claims more pixels than the file's bytes can encode (checked before any
    /// allocation, so that memory stays bounded by the file's size).
    #[error(
        "{format} header claims {width}×{height} pixels, more than {bytes} bytes can encode \
         (at most {per_byte} pixels per byte of {what})"
    )]
    ClaimExceedsFile {
        /// The file format.
        format: MapFormat,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// The bytes available.
        bytes: usize,
        /// The most pixels a byte can encode in this format (as accepted here).
        per_byte: usize,
        /// What the bytes are (pixel data, the whole file).
        what: &'static str,
    },
    /// `rgb.len()` differs from `width · height`.
    #[error("size mismatch: a {width}×{height} map needs {expected} pixels, got {got}")]
    SizeMismatch {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// `width · height`.
        expected: usize,
        /// Number of pixels given.
        got: usize,
    },
    /// A pixel channel is NaN or ±∞.
    #[error("pixel (x {x}, y {y}) channel {channel} is not finite: {value}")]
    NonFinitePixel {
        /// Column (0 = left, u = 0).
        x: usize,
        /// Row (0 = top, v = 0, the zenith).
        y: usize,
        /// Channel: 0 = R, 1 = G, 2 = B.
        channel: usize,
        /// The value.
        value: f32,
    },
    /// A pixel channel is negative.
    #[error("pixel (x {x}, y {y}) channel {channel} is negative: {value}")]
    NegativePixel {
        /// Column (0 = left).
        x: usize,
        /// Row (0 = top).
        y: usize,
        /// Channel: 0 = R, 1 = G, 2 = B.
        channel: usize,
        /// The value.
        value: f32,
    },
    /// Every pixel is black: there is no light to sample.
    #[error("the map is black everywhere (zero luminance)")]
    AllBlack,
    /// The adaptive sampler's tabulated density rejected the luminance table.
    #[error("cannot build the adaptive sampler's density: {0}")]
    Density(#[from] partition_sampler::DensityError),
    /// The adaptive sampler's quadtree could not be built.
    #[error("cannot build the adaptive sampler's quadtree: {0}")]
    Build(#[from] partition_sampler::BuildError),
    /// A tree of the adaptive sampler's tightening ladder did not re-attach to its density
    /// (not expected: the tree was built from that density).
    #[error("cannot attach the adaptive sampler's quadtree to its density: {0}")]
    Attach(#[from] partition_sampler::AttachError),
    /// The piecewise-constant sampler rejected the luminance table.
    #[error("cannot build the piecewise-constant sampler: {0}")]
    PiecewiseConstant(#[from] distributions::PiecewiseConstantError),
}
