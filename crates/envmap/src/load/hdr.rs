//! Radiance RGBE (`.hdr`) through `image`, after checking and normalising the header.
//!
//! `image` only accepts the `#?RADIANCE` signature; files written with `#?RGBE` are handed
//! over with their first line replaced. The header is also pre-parsed here so that errors name
//! the problem and oversized dimensions are refused before any allocation.

use std::io::{Cursor, Read};

use image::DynamicImage;
use image::codecs::hdr::HdrDecoder;

use super::{MapFormat, from_image_error, guarded, to_pixels};
use crate::map::check_dimensions;
use crate::{EnvMap, EnvMapError};

const FORMAT: MapFormat = MapFormat::Hdr;

/// The most pixels one byte of pixel data may encode. Flat scanlines hold 1/4 pixel per byte,
/// new-style RLE at most 127 pixels per 8 bytes (a run per channel), old-style run markers
/// 255 pixels per 4 bytes unless chained (`(1,1,1,n)` markers in a row multiply by 256, so a
/// few bytes could claim millions of pixels): claims beyond this are refused before the
/// decoder allocates the image, keeping memory within about 2 KiB per byte of file.
const MAX_PIXELS_PER_BYTE: usize = 64;

fn malformed(detail: impl Into<String>) -> EnvMapError {
    EnvMapError::MalformedHeader {
        format: FORMAT,
        detail: detail.into(),
    }
}

fn truncated(detail: impl Into<String>) -> EnvMapError {
    EnvMapError::Truncated {
        format: FORMAT,
        detail: detail.into(),
    }
}

/// Splits off the line starting at `pos` (without its `\n`); `None` at end of input.
fn next_line<'a>(bytes: &'a [u8], pos: &mut usize) -> Option<Option<&'a [u8]>> {
    let rest = bytes.get(*pos..)?;
    if rest.is_empty() {
        return None;
    }
    match rest.iter().position(|&b| b == b'\n') {
        Some(n) => {
            *pos += n + 1;
            Some(Some(&rest[..n]))
        }
        None => Some(None), // a line without its newline: the header is cut short
    }
}

/// Parsed header facts: the byte offset after the signature line, and the dimensions.
struct Header {
    after_signature: usize,
    width: usize,
    height: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, EnvMapError> {
    let mut pos = 0;
    let signature = match next_line(bytes, &mut pos) {
        Some(Some(line)) => line,
        Some(None) if bytes.starts_with(b"#?") => {
            return Err(truncated("the header ends after the signature"));
        }
        _ if bytes.is_empty() => return Err(truncated("the file is empty")),
        _ => return Err(malformed("missing #?RADIANCE or #?RGBE signature")),
    };
    if !(signature.starts_with(b"#?RADIANCE") || signature.starts_with(b"#?RGBE")) {
        return Err(malformed("missing #?RADIANCE or #?RGBE signature"));
    }
    let after_signature = pos;
    loop {
        let line = match next_line(bytes, &mut pos) {
            Some(Some(line)) => line,
            _ => return Err(truncated("the header is not closed by an empty line")),
        };
        if line.is_empty() {
            break;
        }
        let text = String::from_utf8_lossy(line);
        if let Some(value) = text.strip_prefix("FORMAT=")
            && value.trim() != "32-bit_rle_rgbe"
        {
            return Err(EnvMapError::Decode {
                format: FORMAT,
                detail: format!(
                    "pixel format {:?} is not supported (only 32-bit_rle_rgbe)",
                    value.trim()
                ),
            });
        }
    }
    let line = match next_line(bytes, &mut pos) {
        Some(Some(line)) => line,
        _ => return Err(truncated("the resolution line is missing")),
    };
    let text = String::from_utf8_lossy(line);
    let tokens: Vec<&str> = text.split_whitespace().collect();
    let [a, h, b, w] = tokens.as_slice() else {
        return Err(malformed(format!(
            "bad resolution line {:?}",
            truncate(&text)
        )));
    };
    if (*a, *b) != ("-Y", "+X") {
        return Err(EnvMapError::Decode {
            format: FORMAT,
            detail: format!("orientation {a} {b} is not supported (only -Y H +X W)"),
        });
    }
    let parse = |s: &str| {
        s.parse::<usize>()
            .map_err(|_| malformed(format!("bad size {:?}", truncate(s))))
    };
    let (width, height) = (parse(w)?, parse(h)?);
    check_dimensions(width, height)?;
    // Every scanline takes at least 4 bytes (one RGBE quadruple or an RLE header).
    if bytes.len() - pos < 4 * height {
        return Err(truncated(format!(
            "{} bytes of pixel data cannot hold {height} scanlines",
            bytes.len() - pos
        )));
    }
    let data = bytes.len() - pos;
    if width * height > MAX_PIXELS_PER_BYTE * data {
        return Err(EnvMapError::ClaimExceedsFile {
            format: FORMAT,
            width,
            height,
            bytes: data,
            per_byte: MAX_PIXELS_PER_BYTE,
            what: "pixel data",
        });
    }
    Ok(Header {
        after_signature,
        width,
        height,
    })
}

fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}

/// Decodes a Radiance HDR file held in memory.
pub(super) fn decode(bytes: &[u8]) -> Result<EnvMap, EnvMapError> {
    let header = parse_header(bytes)?;
    let stream =
        Cursor::new(&b"#?RADIANCE\n"[..]).chain(Cursor::new(&bytes[header.after_signature..]));
    let image = guarded(FORMAT, || {
        let decoder = HdrDecoder::new(stream).map_err(|e| from_image_error(FORMAT, e))?;
        DynamicImage::from_decoder(decoder).map_err(|e| from_image_error(FORMAT, e))
    })?;
    let rgb = image.into_rgb32f();
    if (rgb.width() as usize, rgb.height() as usize) != (header.width, header.height) {
        return Err(malformed("the decoder disagrees with the resolution line"));
    }
    EnvMap::new(header.width, header.height, to_pixels(rgb.as_raw()))
}
