//! OpenEXR through `image` (first RGB(A) layer, alpha dropped).

use std::io::Cursor;

use image::codecs::openexr::OpenExrDecoder;
use image::{DynamicImage, ImageDecoder};

use super::{MapFormat, from_image_error, guarded, to_pixels};
use crate::map::check_dimensions;
use crate::{EnvMap, EnvMapError};

const FORMAT: MapFormat = MapFormat::Exr;

/// The most pixels one byte of the file may encode: ZIP (deflate, at most 1032:1) of a
/// constant half-float RGB image gives about 172 pixels per byte, and every chunk costs an
/// 8-byte offset. Claims beyond this are refused before the decoder allocates the image and
/// its offset tables, keeping memory within about 40 KiB per byte of file.
const MAX_PIXELS_PER_BYTE: usize = 1024;

/// Decodes an OpenEXR file held in memory.
pub(super) fn decode(bytes: &[u8]) -> Result<EnvMap, EnvMapError> {
    if bytes.len() < 4 {
        return Err(EnvMapError::Truncated {
            format: FORMAT,
            detail: "the file is shorter than the magic number".into(),
        });
    }
    if bytes[..4] != [0x76, 0x2f, 0x31, 0x01] {
        return Err(EnvMapError::MalformedHeader {
            format: FORMAT,
            detail: "missing OpenEXR magic number".into(),
        });
    }
    let (width, height, image) = guarded(FORMAT, || {
        let decoder =
            OpenExrDecoder::new(Cursor::new(bytes)).map_err(|e| from_image_error(FORMAT, e))?;
        let (w, h) = decoder.dimensions();
        let (width, height) = (w as usize, h as usize);
        check_dimensions(width, height)?;
        if width * height > MAX_PIXELS_PER_BYTE * bytes.len() {
            return Err(EnvMapError::ClaimExceedsFile {
                format: FORMAT,
                width,
                height,
                bytes: bytes.len(),
                per_byte: MAX_PIXELS_PER_BYTE,
                what: "file",
            });
        }
        let image = DynamicImage::from_decoder(decoder).map_err(|e| from_image_error(FORMAT, e))?;
        Ok((width, height, image))
    })?;
    let rgb = image.into_rgb32f();
    EnvMap::new(width, height, to_pixels(rgb.as_raw()))
}
