//! Reading lat-long maps from Radiance HDR, OpenEXR and PFM files.

mod exr;
mod hdr;
mod pfm;

use std::path::Path;

use crate::{EnvMap, EnvMapError};

use crate::format::MapFormat;

impl EnvMap {
    /// Loads a lat-long map, choosing the decoder from the extension (`.hdr`, `.exr`, `.pfm`).
    ///
    /// The first image row is the top of the map (`v = 0`, the zenith); PFM files, stored
    /// bottom-to-top, are flipped accordingly. Header scale factors (`EXPOSURE=`, the PFM
    /// scale) are not needed for sampling: Radiance `EXPOSURE` is ignored, the PFM scale
    /// magnitude is applied. Never panics on malformed input: every failure is an
    /// [`EnvMapError`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, EnvMapError> {
        let path = path.as_ref();
        let format =
            MapFormat::from_path(path).ok_or_else(|| EnvMapError::UnsupportedExtension {
                path: path.to_path_buf(),
            })?;
        let bytes = std::fs::read(path).map_err(|source| EnvMapError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, format)
    }

    /// Decodes a map held in memory (see [`EnvMap::load`]).
    pub fn from_bytes(bytes: &[u8], format: MapFormat) -> Result<Self, EnvMapError> {
        match format {
            MapFormat::Hdr => hdr::decode(bytes),
            MapFormat::Exr => exr::decode(bytes),
            MapFormat::Pfm => pfm::decode(bytes),
        }
    }
}

/// Converts an `image` error to ours.
pub(crate) fn from_image_error(format: MapFormat, err: image::ImageError) -> EnvMapError {
    use image::ImageError as E;
    match err {
        E::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => EnvMapError::Truncated {
            format,
            detail: "the pixel data ends early".into(),
        },
        other => EnvMapError::Decode {
            format,
            detail: other.to_string(),
        },
    }
}

/// Runs a third-party decoder, turning a panic inside it (a decoder bug on hostile input)
/// into an error instead of aborting the caller.
pub(crate) fn guarded<T>(
    format: MapFormat,
    f: impl FnOnce() -> Result<T, EnvMapError>,
) -> Result<T, EnvMapError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|_| {
        Err(EnvMapError::Decode {
            format,
            detail: "the decoder rejected the data (internal panic)".into(),
        })
    })
}

/// Converts interleaved RGB `f32` samples to pixels.
pub(crate) fn to_pixels(raw: &[f32]) -> Vec<[f32; 3]> {
    raw.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}
