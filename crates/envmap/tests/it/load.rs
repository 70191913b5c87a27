//! Loading maps: Radiance HDR (both signatures, flat and RLE), OpenEXR, PFM; error paths;
//! garbled input never panics.

use std::io::Cursor;
use std::path::Path;

use envmap::{EnvMap, EnvMapError, MapFormat};

use crate::support;

// ---------------------------------------------------------------- a tiny RGBE writer

/// Encodes a colour as RGBE: shared exponent of the largest channel, 8-bit mantissas.
fn rgbe(c: [f32; 3]) -> [u8; 4] {
    let v = c[0].max(c[1]).max(c[2]) as f64;
    if v < 1e-32 {
        return [0, 0, 0, 0];
    }
    let e = v.log2().floor() as i32 + 1; // v = m · 2^e with m ∈ [0.5, 1)
    let scale = 256.0 / 2f64.powi(e);
    let q = |x: f32| ((x as f64 * scale) as u32).min(255) as u8;
    [q(c[0]), q(c[1]), q(c[2]), (e + 128) as u8]
}

/// What `image` (and Radiance) decode from an RGBE quadruple: `c · 2^(e − 136)`.
fn unrgbe(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let f = 2f64.powi(p[3] as i32 - 136);
    [0, 1, 2].map(|i| (p[i] as f64 * f) as f32)
}

/// Run-length encodes one component of a scanline (Radiance "new" RLE).
fn rle_component(values: &[u8], out: &mut Vec<u8>) {
    let mut i = 0;
    while i < values.len() {
        let mut run = 1;
        while i + run < values.len() && values[i + run] == values[i] && run < 127 {
            run += 1;
        }
        if run >= 3 {
            out.extend([128 + run as u8, values[i]]);
            i += run;
        } else {
            // A literal chunk up to the next run of 3 (or 128 bytes).
            let start = i;
            while i < values.len() && i - start < 128 {
                if i + 2 < values.len() && values[i] == values[i + 1] && values[i] == values[i + 2]
                {
                    break;
                }
                i += 1;
            }
            out.push((i - start) as u8);
            out.extend(&values[start..i]);
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Scanlines {
    Flat,
    Rle,
    /// Flat, with the old-style run marker (1,1,1,n) for repeated pixels.
    OldRle,
}

fn hdr_file(signature: &str, w: usize, h: usize, pixels: &[[u8; 4]], mode: Scanlines) -> Vec<u8> {
    let mut out = format!(
        "{signature}\n# written by a test\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {h} +X {w}\n"
    )
    .into_bytes();
    for row in pixels.chunks(w) {
        match mode {
            Scanlines::Flat => row.iter().for_each(|p| out.extend(p)),
            Scanlines::Rle => {
                out.extend([2, 2, (w >> 8) as u8, (w & 255) as u8]);
                for c in 0..4 {
                    let comp: Vec<u8> = row.iter().map(|p| p[c]).collect();
                    rle_component(&comp, &mut out);
                }
            }
            Scanlines::OldRle => {
                let mut i = 0;
                while i < row.len() {
                    out.extend(row[i]);
                    let mut n = 0;
                    while i + 1 + n < row.len() && row[i + 1 + n] == row[i] && n < 255 {
                        n += 1;
                    }
                    if n > 0 {
                        out.extend([1, 1, 1, n as u8]);
                    }
                    i += 1 + n;
                }
            }
        }
    }
    out
}

/// A test image whose rows and columns differ (catches flips), with runs for the RLE coder.
fn test_pixels(w: usize, h: usize) -> Vec<[f32; 3]> {
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if x >= w / 2 && y % 2 == 0 {
                [3.0, 2.0, 1.0] // runs
            } else {
                [
                    0.1 + y as f32 * 0.7,
                    0.05 * x as f32,
                    100.0 * ((x * y) % 3) as f32 + 0.01,
                ]
            }
        })
        .collect()
}

fn check_hdr(signature: &str, mode: Scanlines) {
    let (w, h) = (40, 6);
    let src = test_pixels(w, h);
    let quads: Vec<[u8; 4]> = src.iter().map(|&c| rgbe(c)).collect();
    let bytes = hdr_file(signature, w, h, &quads, mode);
    let map = EnvMap::from_bytes(&bytes, MapFormat::Hdr).unwrap();
    assert_eq!((map.width(), map.height()), (w, h));
    for (i, (&q, &got)) in quads.iter().zip(map.rgb()).enumerate() {
        assert_eq!(got, unrgbe(q), "{signature} {mode:?}: pixel {i}");
        // And within RGBE precision of the source.
        for c in 0..3 {
            let max = src[i].iter().cloned().fold(0.0, f32::max);
            assert!(
                (got[c] - src[i][c]).abs() <= max / 64.0,
                "{signature} {mode:?}: pixel {i}"
            );
        }
    }
}

#[test]
fn hdr_signatures_and_scanline_encodings_round_trip() {
    // Both signatures, flat and RLE scanlines, and old-style run markers.
    for (signature, mode) in [
        ("#?RADIANCE", Scanlines::Flat),
        ("#?RADIANCE", Scanlines::Rle),
        ("#?RGBE", Scanlines::Flat),
        ("#?RGBE", Scanlines::Rle),
        ("#?RADIANCE", Scanlines::OldRle),
    ] {
        check_hdr(signature, mode);
    }
}

fn hdr_bytes() -> Vec<u8> {
    let (w, h) = (16, 4);
    let quads: Vec<[u8; 4]> = test_pixels(w, h).iter().map(|&c| rgbe(c)).collect();
    hdr_file("#?RADIANCE", w, h, &quads, Scanlines::Rle)
}

fn decode_hdr(text: &[u8]) -> Result<EnvMap, EnvMapError> {
    EnvMap::from_bytes(text, MapFormat::Hdr)
}

/// Checks that `decode` rejects each input with the error whose `Debug` text starts with the
/// given variant name (and fields, where given).
fn assert_rejects(decode: impl Fn(&[u8]) -> Result<EnvMap, EnvMapError>, cases: &[(&[u8], &str)]) {
    for (k, &(bytes, expected)) in cases.iter().enumerate() {
        match decode(bytes) {
            Err(e) => assert!(
                format!("{e:?}").starts_with(expected),
                "case {k}: {e:?}, expected {expected}"
            ),
            Ok(_) => panic!("case {k}: accepted, expected {expected}"),
        }
    }
}

#[test]
fn hdr_errors() {
    let good = hdr_bytes();
    assert_rejects(
        decode_hdr,
        &[
            (b"P6\n1 1\n", "MalformedHeader"),
            (b"", "Truncated"),
            (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "Truncated"),
            (b"#?RADIANCE\n\n", "Truncated"),
            (b"#?RADIANCE\n\n-Y 2 +X\n", "MalformedHeader"),
            (b"#?RADIANCE\n\n-Y two +X 3\n", "MalformedHeader"),
            (b"#?RADIANCE\n\n+Y 2 +X 3\n\0\0\0\0\0\0\0\0", "Decode"),
            (
                b"#?RADIANCE\n\n-Y 0 +X 3\n",
                "Empty { width: 3, height: 0 }",
            ),
            (b"#?RADIANCE\n\n-Y 100000 +X 100000\n", "TooLarge"),
            (
                b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x80\x80\x80\x80",
                "Decode",
            ),
            // Cut inside the pixel data.
            (&good[..good.len() - 3], "Truncated"),
        ],
    );
    // All black.
    let black = hdr_file("#?RADIANCE", 8, 2, &[[0, 0, 0, 0]; 16], Scanlines::Flat);
    assert!(matches!(decode_hdr(&black), Err(EnvMapError::AllBlack)));
}

// ---------------------------------------------------------------- PFM

fn pfm_file(
    grey: bool,
    little_endian: bool,
    w: usize,
    h: usize,
    top_down: &[[f32; 3]],
    scale: f32,
) -> Vec<u8> {
    let mut out = format!(
        "{}\n{w} {h}\n{}\n",
        if grey { "Pf" } else { "PF" },
        if little_endian { -scale } else { scale }
    )
    .into_bytes();
    for row in top_down.chunks(w).rev() {
        for p in row {
            for &c in if grey { &p[..1] } else { &p[..] } {
                out.extend(if little_endian {
                    c.to_le_bytes()
                } else {
                    c.to_be_bytes()
                });
            }
        }
    }
    out
}

#[test]
fn pfm_colour_and_grey_both_endiannesses() {
    let (w, h) = (5, 3);
    let src = test_pixels(w, h);
    for little in [true, false] {
        let map =
            EnvMap::from_bytes(&pfm_file(false, little, w, h, &src, 1.0), MapFormat::Pfm).unwrap();
        assert_eq!((map.width(), map.height()), (w, h));
        assert_eq!(map.rgb(), &src[..], "PF little_endian={little}");
        let map =
            EnvMap::from_bytes(&pfm_file(true, little, w, h, &src, 1.0), MapFormat::Pfm).unwrap();
        let grey: Vec<[f32; 3]> = src.iter().map(|p| [p[0]; 3]).collect();
        assert_eq!(map.rgb(), &grey[..], "Pf little_endian={little}");
    }
    // Row 0 of the map is the last row of the file.
    let map = EnvMap::from_bytes(&pfm_file(false, true, w, h, &src, 1.0), MapFormat::Pfm).unwrap();
    assert_eq!(map.pixel(0, 0), Some(src[0]));
    // The scale magnitude multiplies the values.
    let map = EnvMap::from_bytes(&pfm_file(false, true, w, h, &src, 2.0), MapFormat::Pfm).unwrap();
    assert_eq!(map.pixel(1, 2).unwrap()[1], 2.0 * src[2 * w + 1][1]);
}

#[test]
fn pfm_tolerates_crlf_and_spaces() {
    let src: Vec<[f32; 3]> = vec![[1.0, 2.0, 3.0]];
    let mut bytes = b"PF\r\n1 1\r\n-1.0\r\n".to_vec();
    src[0].iter().for_each(|c| bytes.extend(c.to_le_bytes()));
    assert_eq!(
        EnvMap::from_bytes(&bytes, MapFormat::Pfm).unwrap().rgb(),
        &src[..]
    );
    let mut bytes = b"PF 1 1 -1 ".to_vec();
    src[0].iter().for_each(|c| bytes.extend(c.to_le_bytes()));
    assert_eq!(
        EnvMap::from_bytes(&bytes, MapFormat::Pfm).unwrap().rgb(),
        &src[..]
    );
}

#[test]
fn pfm_errors() {
    let pfm = |b: &[u8]| EnvMap::from_bytes(b, MapFormat::Pfm);
    let good = pfm_file(false, true, 3, 2, &test_pixels(3, 2), 1.0);
    let mut long = good.clone();
    long.push(0);
    assert_rejects(
        pfm,
        &[
            (b"", "Truncated"),
            (b"P6\n1 1\n255\n", "MalformedHeader"),
            (b"PF\n1 -1\n-1\n", "MalformedHeader"),
            (b"PF\n1 1\nabc\n", "MalformedHeader"),
            (b"PF\n1 1\n0\n\0\0\0\0\0\0\0\0\0\0\0\0", "MalformedHeader"),
            (b"PF\n1 1\nnan\n\0\0\0\0\0\0\0\0\0\0\0\0", "MalformedHeader"),
            (b"PF\n1 1", "Truncated"),
            (b"PF\n0 1\n-1\n", "Empty { width: 0, height: 1 }"),
            (b"PF\n99999 99999\n-1\n", "TooLarge"),
            (&good[..good.len() - 1], "Truncated"),
            (&long, "MalformedHeader"),
        ],
    );

    // Bad pixels are named in top-down coordinates: (x 1, y 0) is in the file's last row.
    let mut px = test_pixels(3, 2);
    for (value, is_nan) in [(f32::NAN, true), (f32::INFINITY, true), (-1.0, false)] {
        px[1][2] = value;
        let err = pfm(&pfm_file(false, true, 3, 2, &px, 1.0)).unwrap_err();
        if is_nan {
            assert!(
                matches!(
                    err,
                    EnvMapError::NonFinitePixel {
                        x: 1,
                        y: 0,
                        channel: 2,
                        ..
                    }
                ),
                "{err}"
            );
        } else {
            assert!(
                matches!(
                    err,
                    EnvMapError::NegativePixel {
                        x: 1,
                        y: 0,
                        channel: 2,
                        ..
                    }
                ),
                "{err}"
            );
        }
    }
    assert!(matches!(
        pfm(&pfm_file(true, false, 2, 2, &[[0.0; 3]; 4], 1.0)),
        Err(EnvMapError::AllBlack)
    ));
}

// ---------------------------------------------------------------- OpenEXR

fn exr_file(w: usize, h: usize, px: &[[f32; 3]]) -> Vec<u8> {
    let flat: Vec<f32> = px.iter().flatten().copied().collect();
    let img = image::Rgb32FImage::from_raw(w as u32, h as u32, flat).unwrap();
    let mut out = Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut out, image::ImageFormat::OpenExr)
        .unwrap();
    out.into_inner()
}

#[test]
fn exr_round_trip_and_errors() {
    let (w, h) = (7, 4);
    let src = test_pixels(w, h);
    let bytes = exr_file(w, h, &src);
    let map = EnvMap::from_bytes(&bytes, MapFormat::Exr).unwrap();
    assert_eq!((map.width(), map.height()), (w, h));
    assert_eq!(map.rgb(), &src[..]);

    let exr = |b: &[u8]| EnvMap::from_bytes(b, MapFormat::Exr);
    assert!(exr(&bytes[..bytes.len() / 2]).is_err());
    // The red channel of pixel (3, 1) replaced by `value`.
    let with = |value: f32| {
        let mut px = src.clone();
        px[w + 3][0] = value;
        exr_file(w, h, &px)
    };
    assert_rejects(
        exr,
        &[
            (b"v/", "Truncated"),
            (b"#?RADIANCE\n", "MalformedHeader"),
            (&with(f32::NAN), "NonFinitePixel { x: 3, y: 1, channel: 0,"),
            (&with(-2.0), "NegativePixel { x: 3, y: 1, channel: 0,"),
            (&exr_file(2, 2, &[[0.0; 3]; 4]), "AllBlack"),
        ],
    );
}

// ---------------------------------------------------------------- files and garbage

#[test]
fn load_by_extension_and_io_errors() {
    let dir = tempfile::tempdir().unwrap();
    let src = test_pixels(5, 3);
    let files = [
        ("a.HDR", hdr_bytes()),
        ("b.pfm", pfm_file(false, false, 5, 3, &src, 1.0)),
        ("c.exr", exr_file(5, 3, &src)),
    ];
    for (name, bytes) in &files {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        assert!(EnvMap::load(&path).is_ok(), "{name}");
    }
    let png = dir.path().join("map.png");
    std::fs::write(&png, b"x").unwrap();
    assert!(matches!(
        EnvMap::load(&png),
        Err(EnvMapError::UnsupportedExtension { .. })
    ));
    assert!(matches!(
        EnvMap::load(dir.path().join("missing.hdr")),
        Err(EnvMapError::Io { .. })
    ));
    assert_eq!(
        MapFormat::from_path(Path::new("x.Exr")),
        Some(MapFormat::Exr)
    );
    assert_eq!(MapFormat::from_path(Path::new("noext")), None);
}

/// A tiny deterministic generator for the garbling test (no RNG dependency needed).
fn lcg(state: &mut u64) -> u64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *state >> 33
}

#[test]
fn truncated_and_garbled_files_never_panic() {
    let src = test_pixels(9, 5);
    let files = [
        (MapFormat::Hdr, hdr_bytes()),
        (
            MapFormat::Hdr,
            hdr_file(
                "#?RGBE",
                9,
                5,
                &src.iter().map(|&c| rgbe(c)).collect::<Vec<_>>(),
                Scanlines::Flat,
            ),
        ),
        (MapFormat::Pfm, pfm_file(false, true, 9, 5, &src, 1.0)),
        (MapFormat::Pfm, pfm_file(true, false, 9, 5, &src, 1.0)),
        (MapFormat::Exr, exr_file(9, 5, &src)),
    ];
    let mut state = 1u64;
    for (format, bytes) in &files {
        // Every prefix.
        for len in 0..bytes.len() {
            let _ = EnvMap::from_bytes(&bytes[..len], *format);
        }
        // Random byte corruption, a few bytes at a time, in the header and in the data.
        for _ in 0..300 {
            let mut garbled = bytes.clone();
            for _ in 0..1 + lcg(&mut state) % 4 {
                let i = (lcg(&mut state) as usize) % garbled.len();
                garbled[i] = lcg(&mut state) as u8;
            }
            let _ = EnvMap::from_bytes(&garbled, *format);
        }
    }
    // Pure noise.
    for _ in 0..50 {
        let noise: Vec<u8> = (0..200).map(|_| lcg(&mut state) as u8).collect();
        for format in [MapFormat::Hdr, MapFormat::Exr, MapFormat::Pfm] {
            let _ = EnvMap::from_bytes(&noise, format);
        }
    }
}

#[test]
fn pixel_validation_in_constructor() {
    assert!(matches!(
        EnvMap::new(0, 2, vec![]),
        Err(EnvMapError::Empty { .. })
    ));
    assert!(matches!(
        EnvMap::new(2, 2, vec![[1.0; 3]; 3]),
        Err(EnvMapError::SizeMismatch {
            expected: 4,
            got: 3,
            ..
        })
    ));
    assert!(matches!(
        EnvMap::new(1 << 20, 1 << 20, vec![]),
        Err(EnvMapError::TooLarge { .. })
    ));
    let map = EnvMap::new(2, 1, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    assert_eq!(map.luminance(), vec![0.2126, 0.7152]);
    assert_eq!(map.pixel(1, 0), Some([0.0, 1.0, 0.0]));
    assert_eq!(map.pixel(2, 0), None);
}

/// The real maps shipped with the project, when present.
#[test]
fn real_maps_load() {
    let paths = match support::real_map_paths() {
        Ok(paths) => paths,
        Err(dir) => {
            eprintln!("skipping: {} is absent", dir.display());
            return;
        }
    };
    let mut loaded = 0;
    for path in paths {
        let map = EnvMap::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            map.width() >= 2 * map.height() - 1,
            "{}: not lat-long",
            path.display()
        );
        let lum = map.luminance();
        assert!(lum.iter().any(|&y| y > 0.0));
        loaded += 1;
    }
    eprintln!("loaded {loaded} real maps");
}

// ---------------------------------------------------------------- memory bounded by the file

/// The offset of the `dataWindow` box (`xmin, ymin, xmax, ymax` as `i32`) in an EXR header.
fn exr_data_window(bytes: &[u8]) -> usize {
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("dataWindow attribute");
    at + key.len() + 4
}

/// The offset of the value of the EXR header attribute `key` (name, type, then a 4-byte size).
fn exr_attribute(bytes: &[u8], key: &[u8]) -> usize {
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .unwrap_or_else(|| panic!("attribute {}", String::from_utf8_lossy(key)));
    at + key.len() + 4
}

/// Headers claiming the most pixels allowed (2^25) or 2^40 pixels over a few bytes of data get
/// a typed error before the decoder allocates the image (before the fix, a 20 KB Radiance file
/// made the decoder allocate 400 MB before finding the data short).
#[test]
fn huge_claims_are_refused_before_allocating() {
    let t = std::time::Instant::now();
    // Radiance: 8192 × 4096 with 4 bytes per scanline (enough for the old per-line check).
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4096 +X 8192\n".to_vec();
    hdr.extend(std::iter::repeat_n([2u8, 2, 32, 0], 4096).flatten());
    let r = EnvMap::from_bytes(&hdr, MapFormat::Hdr);
    assert!(
        matches!(
            r,
            Err(EnvMapError::ClaimExceedsFile {
                width: 8192,
                height: 4096,
                ..
            })
        ),
        "{r:?}"
    );
    let r = EnvMap::from_bytes(
        b"#?RADIANCE\n\n-Y 1048576 +X 1048576\n\x02\x02\x00\x10",
        MapFormat::Hdr,
    );
    assert!(matches!(r, Err(EnvMapError::TooLarge { .. })), "{r:?}");
    // OpenEXR: a valid 9×5 file whose data window is widened to 8192 × 4096.
    let src = test_pixels(9, 5);
    let mut exr = exr_file(9, 5, &src);
    let at = exr_data_window(&exr);
    exr[at + 8..at + 12].copy_from_slice(&8191i32.to_le_bytes());
    exr[at + 12..at + 16].copy_from_slice(&4095i32.to_le_bytes());
    // The writer tiles the image in 64×64 tiles; one tile of the whole window makes the chunk
    // count 1, so that the offset table (checked by the decoder) stays one entry long. The
    // decoder's own checks of the chunk table refuse it (before the image is allocated); the
    // reader's pixels-per-byte bound is the backstop for claims that pass them.
    let tiles = exr_attribute(&exr, b"tiles\0tiledesc\0");
    exr[tiles..tiles + 4].copy_from_slice(&8192u32.to_le_bytes());
    exr[tiles + 4..tiles + 8].copy_from_slice(&4096u32.to_le_bytes());
    let cc = exr_attribute(&exr, b"chunkCount\0int\0");
    exr[cc..cc + 4].copy_from_slice(&1i32.to_le_bytes());
    let r = EnvMap::from_bytes(&exr, MapFormat::Exr);
    assert!(
        matches!(
            r,
            Err(EnvMapError::ClaimExceedsFile { .. } | EnvMapError::Decode { .. })
        ),
        "{r:?}"
    );
    // PFM: the exact size is checked before the pixels are read.
    let r = EnvMap::from_bytes(b"PF\n8192 4096\n-1.0\n\0\0\0\0", MapFormat::Pfm);
    assert!(matches!(r, Err(EnvMapError::Truncated { .. })), "{r:?}");
    let r = EnvMap::from_bytes(b"PF\n1048576 1048576\n-1.0\n\0\0\0\0", MapFormat::Pfm);
    assert!(matches!(r, Err(EnvMapError::TooLarge { .. })), "{r:?}");
    assert!(t.elapsed().as_secs_f64() < 1.0, "{:?}", t.elapsed());
}

mod bytes {
    use super::*;
    use envmap::{AdaptiveOptions, EnvMapSampler, SamplerKind};
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    const SPECIAL: [f32; 8] = [
        f32::NAN,
        f32::INFINITY,
        -1.0,
        1e38,
        f32::MAX,
        0.0,
        1e-38,
        65504.0,
    ];

    fn seeds() -> Vec<(MapFormat, Vec<u8>)> {
        let src = test_pixels(12, 6);
        let quads: Vec<[u8; 4]> = src.iter().map(|&c| rgbe(c)).collect();
        vec![
            (
                MapFormat::Hdr,
                hdr_file("#?RADIANCE", 12, 6, &quads, Scanlines::Rle),
            ),
            (
                MapFormat::Hdr,
                hdr_file("#?RGBE", 12, 6, &quads, Scanlines::OldRle),
            ),
            (MapFormat::Exr, exr_file(12, 6, &src)),
            (MapFormat::Pfm, pfm_file(false, true, 12, 6, &src, 1.0)),
            (MapFormat::Pfm, pfm_file(true, false, 12, 6, &src, 2.0)),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]
        /// Byte edits, special floats in either byte order, truncation: a typed error, or a map
        /// whose pixels are finite and non-negative and whose samplers build or fail typed.
        #[test]
        fn edits_give_a_typed_error_or_a_valid_map(
            which in 0usize..5,
            edits in proptest::collection::vec((any::<proptest::sample::Index>(), any::<u8>()), 0..6),
            words in proptest::collection::vec((any::<proptest::sample::Index>(), 0usize..8, any::<bool>()), 0..6),
            cut in proptest::option::of(any::<proptest::sample::Index>()),
        ) {
            let (format, mut b) = seeds().swap_remove(which);
            for (at, v) in edits {
                let i = at.index(b.len());
                b[i] = v;
            }
            for (at, k, le) in words {
                let i = at.index(b.len() - 3);
                let w = if le { SPECIAL[k].to_le_bytes() } else { SPECIAL[k].to_be_bytes() };
                b[i..i + 4].copy_from_slice(&w);
            }
            if let Some(c) = cut {
                let n = c.index(b.len());
                b.truncate(n);
            }
            if let Ok(map) = EnvMap::from_bytes(&b, format) {
                let (w, h) = (map.width(), map.height());
                prop_assert!(w > 0 && h > 0 && w * h == map.rgb().len());
                prop_assert!(map.rgb().iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
                for kind in [SamplerKind::PiecewiseConstant, SamplerKind::Adaptive(AdaptiveOptions::default())] {
                    if let Ok(s) = EnvMapSampler::new(&map, kind) {
                        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
                        for _ in 0..4 {
                            let e = s.sample(&mut rng);
                            prop_assert!(e.pdf_uv.is_finite() && e.pdf_uv > 0.0, "{:?}", e);
                        }
                    }
                }
            }
        }
    }
}
