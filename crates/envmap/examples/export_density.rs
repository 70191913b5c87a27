//! Writes the density that Mitsuba's `envmap` emitter warps — Rec. 709 luminance of each pixel
//! times `sin(π (row + ½) / H)` — as a little-endian `float32` `.npy` array (rows = v), so that
//! the peer scripts (`../shared/peers/mitsuba_warp_bench.py --density FILE.npy`) sample the
//! very map brdf-lab samples, the built-in procedural sky included.
//!
//! ```sh
//! cargo run --release -p envmap --example export_density -- OUT.npy [MAP.hdr]
//! ```
//! Without `MAP` the 1024×512 procedural sky of `brdf-lab envmap` is written.

use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first() else {
        eprintln!("usage: export_density OUT.npy [MAP]");
        std::process::exit(2);
    };
    let map = match args.get(1) {
        Some(path) => envmap::EnvMap::load(path)?,
        None => envmap::procedural_sky(1024, 512)?,
    };
    let (w, h) = (map.width(), map.height());
    let lum = map.luminance();
    let mut data = Vec::with_capacity(4 * w * h);
    for (k, y) in lum.iter().enumerate() {
        let row = k / w;
        let s = (std::f64::consts::PI * (row as f64 + 0.5) / h as f64).sin();
        data.extend_from_slice(&((y * s) as f32).to_le_bytes());
    }
    // NPY 1.0: magic, version, header length, a dict padded so data starts at a multiple of 64.
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({h}, {w}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut f = std::io::BufWriter::new(std::fs::File::create(out)?);
    f.write_all(b"\x93NUMPY\x01\x00")?;
    f.write_all(&(header.len() as u16).to_le_bytes())?;
    f.write_all(header.as_bytes())?;
    f.write_all(&data)?;
    f.flush()?;
    println!("{out}: {w}x{h} float32, luminance x sin(pi v_centre)");
    Ok(())
}
