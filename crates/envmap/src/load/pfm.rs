//! Portable float maps (`.pfm`), read here (the `image` crate has no PFM codec).
//!
//! Layout: the ASCII tokens `PF` (RGB) or `Pf` (grey), `width height` and `scale`, separated by
//! whitespace, then exactly one whitespace byte (`\r\n` is tolerated), then
//! `width·height·channels` IEEE-754 `f32`: little-endian if `scale < 0`, big-endian otherwise,
//! rows stored **bottom to top**. Pixel values are multiplied by `|scale|`.

use super::MapFormat;
use crate::map::check_dimensions;
use crate::{EnvMap, EnvMapError};

const FORMAT: MapFormat = MapFormat::Pfm;

fn malformed(detail: impl Into<String>) -> EnvMapError {
    EnvMapError::MalformedHeader {
        format: FORMAT,
        detail: detail.into(),
    }
}

/// Reads the next whitespace-delimited ASCII token of at most 64 bytes.
fn token<'a>(bytes: &'a [u8], pos: &mut usize, what: &str) -> Result<&'a str, EnvMapError> {
    while bytes.get(*pos).is_some_and(u8::is_ascii_whitespace) {
        *pos += 1;
    }
    let start = *pos;
    while bytes.get(*pos).is_some_and(|b| !b.is_ascii_whitespace()) {
        *pos += 1;
        if *pos - start > 64 {
            return Err(malformed(format!("the {what} is not a short ASCII token")));
        }
    }
    if *pos == bytes.len() {
        // A token must be followed by whitespace: the header cannot end the file.
        return Err(EnvMapError::Truncated {
            format: FORMAT,
            detail: format!("the header ends in the {what}"),
        });
    }
    std::str::from_utf8(&bytes[start..*pos])
        .map_err(|_| malformed(format!("the {what} is not ASCII")))
}

/// Decodes a PFM file held in memory.
pub(super) fn decode(bytes: &[u8]) -> Result<EnvMap, EnvMapError> {
    if bytes.is_empty() {
        return Err(EnvMapError::Truncated {
            format: FORMAT,
            detail: "the file is empty".into(),
        });
    }
    let mut pos = 0;
    let channels = match token(bytes, &mut pos, "signature")? {
        "PF" => 3,
        "Pf" => 1,
        other => {
            return Err(malformed(format!(
                "signature {:?} is neither PF nor Pf",
                other
            )));
        }
    };
    let parse_dim = |s: &str, what: &str| {
        s.parse::<usize>()
            .map_err(|_| malformed(format!("{what} {s:?} is not a non-negative integer")))
    };
    let width = parse_dim(token(bytes, &mut pos, "width")?, "width")?;
    let height = parse_dim(token(bytes, &mut pos, "height")?, "height")?;
    let scale_text = token(bytes, &mut pos, "scale")?;
    let scale: f32 = scale_text
        .parse()
        .map_err(|_| malformed(format!("scale {scale_text:?} is not a number")))?;
    if !(scale.is_finite() && scale != 0.0) {
        return Err(malformed(format!(
            "scale {scale} must be finite and non-zero"
        )));
    }
    check_dimensions(width, height)?;
    // Exactly one whitespace byte ends the header (tolerate a CRLF pair).
    pos += if bytes[pos..].starts_with(b"\r\n") {
        2
    } else {
        1
    };
    let needed = width * height * channels * 4;
    let data = &bytes[pos.min(bytes.len())..];
    if data.len() < needed {
        return Err(EnvMapError::Truncated {
            format: FORMAT,
            detail: format!(
                "{} bytes of pixel data, {needed} needed for {width}×{height}×{channels}",
                data.len()
            ),
        });
    }
    if data.len() > needed {
        return Err(malformed(format!(
            "{} bytes after the pixel data",
            data.len() - needed
        )));
    }
    let little_endian = scale < 0.0;
    let magnitude = scale.abs();
    let read = |c: &[u8]| {
        let b = [c[0], c[1], c[2], c[3]];
        (if little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }) * magnitude
    };
    let row_bytes = width * channels * 4;
    let mut rgb = Vec::with_capacity(width * height);
    // File rows go bottom to top; ours go top to bottom.
    for row in data.chunks_exact(row_bytes).rev() {
        for px in row.chunks_exact(channels * 4) {
            rgb.push(if channels == 3 {
                [read(&px[0..4]), read(&px[4..8]), read(&px[8..12])]
            } else {
                let g = read(px);
                [g, g, g]
            });
        }
    }
    EnvMap::new(width, height, rgb)
}
