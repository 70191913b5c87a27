//! Deterministic mutation fuzzer of every reader (stable Rust; `cargo-fuzz` needs nightly).
//!
//! `cargo run --release -p brdf-sampling --example fuzz_readers -- READER EXECUTIONS [SEED]`
//! with `READER` one of `merl rgl cornell hdr exr pfm set tree`.
//!
//! Each execution mutates one of the reader's seed files (byte flips and sets, 4- and 8-byte
//! words set to NaN, ±inf, negative, 1e38, `f32::MAX`, 0 or huge integers such as 2^40 and
//! `u64::MAX`, header edits, truncation, insertion and deletion of bytes, ASCII tokens replaced
//! by huge, negative or non-numeric ones), parses it and, when parsing succeeds, does what a
//! user does next: evaluates a few direction pairs (BRDFs), builds the piecewise-constant and
//! adaptive samplers and draws from them (maps), or draws samples and pdfs (saved sets). Every
//! execution runs under `catch_unwind` (a panic is counted and its input saved); a watchdog
//! thread aborts the run, saving the input, if one execution exceeds `HANG_SECONDS`. The
//! summary gives the executions, parse successes, panics, hangs and the longest execution.
//!
//! Seeds are small files made here (a 16×8 map, a 4-slice RGL tensor, 40 Cornell samples) so
//! that an execution costs microseconds, plus the repository's real RGL fixture. MERL files
//! have one legal size (34,992,012 bytes), so MERL mutants are done in place on one buffer
//! (with undo): most change the size or the header (rejected before the data), and a fixed
//! share (`MERL_FULL_SHARE`) keep the size and reach the full parse and evaluation.

use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use brdf::measured::cornell::CornellBrdf;
use brdf::measured::rgl::RglBrdf;
use brdf::merl::MerlBrdf;
use brdf::{Brdf, Vec3, direction_from_angles, parse_spec};
use brdf_sampling::{DirectionSampler, QuadTreeSet, SetOptions, Variant};
use envmap::{AdaptiveOptions, EnvMap, EnvMapSampler, MapFormat, SamplerKind};
use partition_sampler::QuadTree;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// An execution longer than this is reported as a hang (and ends the run).
const HANG_SECONDS: u64 = 10;
/// Share of MERL executions that keep the file's size (full parse).
const MERL_FULL_SHARE: f64 = 0.002;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: fuzz_readers READER EXECUTIONS [SEED]");
        std::process::exit(2);
    }
    let reader = args[1].clone();
    let execs: u64 = args[2].parse().expect("EXECUTIONS is a number");
    let seed: u64 = args
        .get(3)
        .map_or(1, |s| s.parse().expect("SEED is a number"));
    // FUZZ_DUMP=N writes the input of execution N to target/fuzz-out and stops.
    let dump: Option<u64> = std::env::var("FUZZ_DUMP").ok().and_then(|v| v.parse().ok());
    std::panic::set_hook(Box::new(|_| {}));
    let target = Target::new(&reader);
    // FUZZ_FILE=PATH runs that one input (e.g. a saved panic or hang) and reports.
    if let Ok(path) = std::env::var("FUZZ_FILE") {
        let input = std::fs::read(&path).expect("FUZZ_FILE is readable");
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| target.run(&input)));
        println!(
            "{path}: {} in {:.3} ms",
            match r {
                Ok(true) => "parsed",
                Ok(false) => "typed error",
                Err(_) => "PANIC",
            },
            t.elapsed().as_secs_f64() * 1e3
        );
        return;
    }
    let current = Arc::new(AtomicU64::new(u64::MAX));
    let started = Arc::new(AtomicU64::new(0));
    let epoch = Instant::now();
    let done = Arc::new(AtomicBool::new(false));
    let out_dir = PathBuf::from("target/fuzz-out");
    std::fs::create_dir_all(&out_dir).ok();
    let last_input: Arc<std::sync::Mutex<Vec<u8>>> = Arc::default();
    {
        let (current, started, done, last_input, reader, out_dir) = (
            Arc::clone(&current),
            Arc::clone(&started),
            Arc::clone(&done),
            Arc::clone(&last_input),
            reader.clone(),
            out_dir.clone(),
        );
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let i = current.load(Ordering::Relaxed);
                let t0 = started.load(Ordering::Relaxed);
                let now = epoch.elapsed().as_millis() as u64;
                if i != u64::MAX && now.saturating_sub(t0) > HANG_SECONDS * 1000 {
                    let path = out_dir.join(format!("{reader}-hang-{i}.bin"));
                    if let Ok(b) = last_input.try_lock() {
                        std::fs::write(&path, &*b).ok();
                    }
                    println!(
                        "HANG reader {reader} execution {i}: input in {}",
                        path.display()
                    );
                    std::process::exit(3);
                }
            }
        });
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut ok, mut panics) = (0u64, 0u64);
    let mut max_time = Duration::ZERO;
    let mut max_at = 0;
    let t_all = Instant::now();
    let mut buf = Vec::new();
    for i in 0..execs {
        let mut merl_state = target.merl.borrow_mut();
        let input: &[u8] = if target.kind == "merl" {
            merl_mutate(&mut rng, &mut merl_state);
            &merl_state.buf[..merl_state.len]
        } else {
            target.mutant(&mut rng, &mut buf);
            &buf
        };
        if i % 1024 == 0 {
            // The watchdog saves the last recorded input of a hang (recording every input
            // would dominate the cost): the run is deterministic, so execution `i` is
            // reproduced by the same seed.
            if let Ok(mut l) = last_input.lock() {
                l.clear();
                l.extend_from_slice(&input[..input.len().min(1 << 20)]);
            }
        }
        if let Some(n) = dump {
            // Replay: the inputs do not depend on the executions, so execution `n` is rebuilt
            // without running the ones before it.
            if i == n {
                let path = out_dir.join(format!("{reader}-{n}.bin"));
                std::fs::write(&path, input).expect("write the input");
                println!("input of execution {n} in {}", path.display());
                return;
            }
            if target.kind == "merl" {
                merl_undo(&mut merl_state);
            }
            continue;
        }
        started.store(epoch.elapsed().as_millis() as u64, Ordering::Relaxed);
        current.store(i, Ordering::Relaxed);
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| target.run(input)));
        let dt = t.elapsed();
        current.store(u64::MAX, Ordering::Relaxed);
        if dt > max_time {
            max_time = dt;
            max_at = i;
        }
        match r {
            Ok(true) => ok += 1,
            Ok(false) => {}
            Err(_) => {
                panics += 1;
                let path = out_dir.join(format!("{reader}-panic-{i}.bin"));
                std::fs::write(&path, input).ok();
                println!(
                    "PANIC reader {reader} execution {i}: input in {}",
                    path.display()
                );
            }
        }
        if target.kind == "merl" {
            merl_undo(&mut merl_state);
        }
    }
    done.store(true, Ordering::Relaxed);
    println!(
        "reader {reader}: {execs} executions (seed {seed}), {ok} parsed, {panics} panics, 0 hangs \
         (> {HANG_SECONDS} s), max {:.3} ms per execution (execution {max_at}), total {:.1} s",
        max_time.as_secs_f64() * 1e3,
        t_all.elapsed().as_secs_f64()
    );
    if panics > 0 {
        std::process::exit(1);
    }
}

/// What is fuzzed: the seeds and the operation after a successful parse.
struct Target {
    kind: String,
    seeds: Vec<Vec<u8>>,
    /// MERL: the one buffer mutated in place, its length and the bytes to restore.
    merl: std::cell::RefCell<MerlState>,
    set_brdf: Option<Arc<dyn Brdf>>,
}

#[derive(Default)]
struct MerlState {
    buf: Vec<u8>,
    len: usize,
    saved: Vec<(usize, u8)>,
}

const SPEC: &str = "phong:n=50";

fn pairs() -> Vec<(Vec3, Vec3)> {
    let mut v = Vec::new();
    for (a, b) in [
        (0.0, 0.0),
        (30.0, 10.0),
        (60.0, 45.0),
        (85.0, 89.0),
        (45.0, 80.0),
    ] {
        v.push((
            direction_from_angles(a, 0.0),
            direction_from_angles(b, 130.0),
        ));
        v.push((
            direction_from_angles(a, 20.0),
            direction_from_angles(b, 200.0),
        ));
    }
    v
}

fn touch_brdf(b: &dyn Brdf) {
    let mut acc = 0.0;
    for (wo, wi) in pairs() {
        acc += b.eval(&wo, &wi) + b.eval_rgb(&wo, &wi).iter().sum::<f64>();
    }
    std::hint::black_box(acc);
}

impl Target {
    fn new(kind: &str) -> Self {
        let mut set_brdf = None;
        let mut merl = MerlState::default();
        let seeds = match kind {
            "merl" => {
                let m = MerlBrdf::from_fn(|th, td, _| {
                    let v = 0.2 + (-(th * th) / 0.01).exp() * 50.0 * td.cos();
                    [v, 0.8 * v, 0.5 * v]
                });
                merl.buf = m.to_bytes();
                merl.len = merl.buf.len();
                merl.buf.resize(merl.len + 4096, 0);
                Vec::new()
            }
            "rgl" => vec![
                small_rgl(),
                fixture("data/measured/rgl/paper_white_rgb.bsdf"),
            ],
            "cornell" => vec![small_cornell()],
            "hdr" => vec![hdr_flat(), hdr_rle()],
            "exr" => vec![exr_seed()],
            "pfm" => vec![pfm_seed(true, true), pfm_seed(false, false)],
            "set" | "tree" => {
                let brdf: Arc<dyn Brdf> = Arc::from(parse_spec(SPEC).expect("spec"));
                let options = SetOptions {
                    slices: 3,
                    grid: 32,
                    ..SetOptions::default()
                }
                .with_depth(4);
                let set = QuadTreeSet::build(Arc::clone(&brdf), Variant::Adaptive, &options)
                    .expect("small set")
                    .with_spec(SPEC);
                set_brdf = Some(brdf);
                if kind == "set" {
                    vec![set.to_bytes()]
                } else {
                    (0..set.len())
                        .filter_map(|i| set.tree(i).map(|t| t.tree().to_bytes()))
                        .collect()
                }
            }
            other => panic!("unknown reader {other}"),
        };
        Self {
            kind: kind.to_string(),
            seeds,
            merl: std::cell::RefCell::new(merl),
            set_brdf,
        }
    }

    /// Builds the next input (in `buf`, or in the MERL buffer).
    fn mutant(&self, rng: &mut Xoshiro256PlusPlus, buf: &mut Vec<u8>) {
        // Mostly the small seed; the real RGL fixture one time in 50.
        let k = if self.seeds.len() > 1 && self.kind == "rgl" {
            usize::from(rng.random::<f64>() < 0.02)
        } else {
            rng.random_range(0..self.seeds.len())
        };
        buf.clear();
        buf.extend_from_slice(&self.seeds[k]);
        let text = matches!(self.kind.as_str(), "cornell" | "hdr" | "pfm");
        let ops = 1 + rng.random_range(0..4);
        for _ in 0..ops {
            mutate(rng, buf, text);
        }
    }

    /// Parses `input` and does the next cheap operation; `true` when parsing succeeded.
    fn run(&self, input: &[u8]) -> bool {
        match self.kind.as_str() {
            "merl" => MerlBrdf::from_bytes(input).map(|b| touch_brdf(&b)).is_ok(),
            "rgl" => RglBrdf::from_bytes(input).map(|b| touch_brdf(&b)).is_ok(),
            "cornell" => CornellBrdf::parse(&String::from_utf8_lossy(input))
                .map(|b| touch_brdf(&b))
                .is_ok(),
            "hdr" => map(input, MapFormat::Hdr),
            "exr" => map(input, MapFormat::Exr),
            "pfm" => map(input, MapFormat::Pfm),
            "set" => {
                let brdf = Arc::clone(self.set_brdf.as_ref().expect("set brdf"));
                match QuadTreeSet::from_bytes(input, brdf, SPEC) {
                    Ok(set) => {
                        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
                        for (wo, _) in pairs() {
                            let s = set.sample(&wo, &mut rng);
                            std::hint::black_box(set.pdf(&wo, &s.wi));
                        }
                        true
                    }
                    Err(_) => false,
                }
            }
            "tree" => match QuadTree::from_bytes(input) {
                Ok(t) => {
                    std::hint::black_box((t.counts(), t.integral(), t.expected_mean_trials()));
                    std::hint::black_box(t.leaves().map(|l| l.rect.x0).sum::<f64>());
                    true
                }
                Err(_) => false,
            },
            _ => unreachable!(),
        }
    }
}

use brdf::merl;

/// A decoded map's next step: both samplers (small maps only) and a few draws.
fn map(input: &[u8], format: MapFormat) -> bool {
    let Ok(m) = EnvMap::from_bytes(input, format) else {
        return false;
    };
    if m.width() * m.height() <= 1 << 14 {
        for kind in [
            SamplerKind::PiecewiseConstant,
            SamplerKind::Adaptive(AdaptiveOptions::default()),
        ] {
            if let Ok(s) = EnvMapSampler::new(&m, kind) {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
                for _ in 0..4 {
                    std::hint::black_box(s.sample(&mut rng));
                }
            }
        }
    }
    true
}

const SPECIAL_F32: [f32; 10] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    -1.0,
    1e38,
    -1e38,
    f32::MAX,
    0.0,
    1e-38,
    -0.01,
];
const SPECIAL_U64: [u64; 7] = [0, 1, 1 << 40, u64::MAX, 1 << 32, 0xffff_ffff, 1 << 62];
const TOKENS: [&str; 12] = [
    "99999999999999999999",
    "1099511627776",
    "4294967296",
    "-5",
    "0",
    "1e38",
    "nan",
    "inf",
    "-1e38",
    "65536",
    "x",
    "",
];

/// One mutation of `b` (any length; `text` adds token edits).
fn mutate(rng: &mut Xoshiro256PlusPlus, b: &mut Vec<u8>, text: bool) {
    let n = b.len();
    let pos = |rng: &mut Xoshiro256PlusPlus| if n == 0 { 0 } else { rng.random_range(0..n) };
    // Positions near the start (headers) are chosen half of the time.
    let head = |rng: &mut Xoshiro256PlusPlus| {
        if n == 0 {
            0
        } else {
            rng.random_range(0..n.min(96))
        }
    };
    match rng.random_range(0..12) {
        0 => {
            let i = pos(rng);
            if n > 0 {
                b[i] ^= 1 << rng.random_range(0..8);
            }
        }
        1 => {
            let i = head(rng);
            if n > 0 {
                b[i] = rng.random();
            }
        }
        2 => {
            let i = pos(rng);
            if n > 0 {
                b[i] = rng.random();
            }
        }
        3 | 4 => {
            // A 4-byte word (aligned or not) set to a special float, either endianness.
            if n >= 4 {
                let i = rng.random_range(0..=n - 4);
                let v = SPECIAL_F32[rng.random_range(0..SPECIAL_F32.len())];
                let w = if rng.random() {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                };
                b[i..i + 4].copy_from_slice(&w);
            }
        }
        5 => {
            // Several aligned words at once (the 1e38 mutants).
            let k = rng.random_range(1..200);
            let v = SPECIAL_F32[rng.random_range(0..SPECIAL_F32.len())].to_le_bytes();
            for _ in 0..k {
                if n >= 4 {
                    let i = 4 * rng.random_range(0..n / 4);
                    b[i..i + 4].copy_from_slice(&v);
                }
            }
        }
        6 => {
            // An 8-byte word near the header set to a huge count/offset/extent.
            if n >= 8 {
                let i = rng.random_range(0..=(n - 8).min(400));
                let v = SPECIAL_U64[rng.random_range(0..SPECIAL_U64.len())];
                b[i..i + 8].copy_from_slice(&v.to_le_bytes());
            }
        }
        7 => {
            let cut = pos(rng);
            b.truncate(cut);
        }
        8 => {
            let i = pos(rng);
            let k = rng.random_range(1..64);
            let ins: Vec<u8> = (0..k).map(|_| rng.random()).collect();
            b.splice(i..i, ins);
        }
        9 => {
            let i = pos(rng);
            let k = rng.random_range(1..64).min(n - i);
            b.drain(i..i + k);
        }
        _ if text => {
            // Replace one whitespace-delimited token (headers: early tokens).
            let i = if rng.random() { head(rng) } else { pos(rng) };
            let start = b[..i]
                .iter()
                .rposition(u8::is_ascii_whitespace)
                .map_or(0, |p| p + 1);
            let end = b[i..]
                .iter()
                .position(u8::is_ascii_whitespace)
                .map_or(n, |p| i + p);
            let t = TOKENS[rng.random_range(0..TOKENS.len())]
                .as_bytes()
                .to_vec();
            b.splice(start..end.max(start), t);
        }
        _ => {
            // Duplicate a block (repeated fields, extra rows).
            if n > 0 {
                let i = pos(rng);
                let k = rng.random_range(1..256).min(n - i);
                let block = b[i..i + k].to_vec();
                let j = pos(rng);
                b.splice(j..j, block);
            }
        }
    }
}

/// Restores the MERL buffer after an execution.
fn merl_undo(m: &mut MerlState) {
    let saved = std::mem::take(&mut m.saved);
    for &(i, b) in saved.iter().rev() {
        m.buf[i] = b;
    }
    m.len = merl::FILE_BYTES;
}

/// One in-place MERL mutation with undo: size changes, header edits, or (a fixed share) data
/// edits at the legal size.
fn merl_mutate(rng: &mut Xoshiro256PlusPlus, m: &mut MerlState) {
    let size = merl::FILE_BYTES;
    let set = |m: &mut MerlState, i: usize, v: u8| {
        m.saved.push((i, m.buf[i]));
        m.buf[i] = v;
    };
    let r: f64 = rng.random();
    if r < MERL_FULL_SHARE {
        // Values: special doubles, byte flips.
        for _ in 0..rng.random_range(1..50) {
            let i = 12 + 8 * rng.random_range(0..(size - 12) / 8);
            let v: f64 = match rng.random_range(0..6) {
                0 => f64::NAN,
                1 => f64::INFINITY,
                2 => -1.0,
                3 => 1e300,
                4 => 1e38,
                _ => f64::from_bits(rng.random()),
            };
            for (k, byte) in v.to_le_bytes().into_iter().enumerate() {
                set(m, i + k, byte);
            }
        }
    } else if r < 0.5 {
        // Header: dims set to special or random values (length kept or changed).
        let i = rng.random_range(0..12);
        let v: u8 = rng.random();
        set(m, i, v);
        if rng.random() {
            m.len = rng.random_range(0..size + 4096);
        }
    } else if r < 0.8 {
        m.len = rng.random_range(0..size);
    } else {
        let extra = rng.random_range(1..4096);
        m.len = size + extra;
        for k in 0..extra.min(64) {
            let v = rng.random();
            set(m, size + k, v);
        }
    }
    if m.len == size && r >= MERL_FULL_SHARE {
        // Keep the full-parse share exact: a header edit at the legal size is moved off it.
        m.len = size - 1;
    }
}

fn fixture(rel: &str) -> Vec<u8> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A tensor file with the given fields `(name, dtype, shape, data)`.
fn tensor(fields: &[(&str, u8, Vec<usize>, Vec<u8>)]) -> Vec<u8> {
    let header: usize = 18
        + fields
            .iter()
            .map(|f| 2 + f.0.len() + 2 + 1 + 8 + 8 * f.2.len())
            .sum::<usize>();
    let mut out = b"tensor_file\0".to_vec();
    out.extend([1, 0]);
    out.extend((fields.len() as u32).to_le_bytes());
    let mut offset = header;
    for (name, dtype, shape, data) in fields {
        out.extend((name.len() as u16).to_le_bytes());
        out.extend(name.as_bytes());
        out.extend((shape.len() as u16).to_le_bytes());
        out.push(*dtype);
        out.extend((offset as u64).to_le_bytes());
        for &e in shape {
            out.extend((e as u64).to_le_bytes());
        }
        offset += data.len();
    }
    for f in fields {
        out.extend(&f.3);
    }
    out
}

fn f32s(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter()
        .flat_map(|x| (x as f32).to_le_bytes())
        .collect()
}

/// A small valid RGL file: the uniform NDF `D = 1/π` (its projected area `(1 + cos θ)/2`),
/// 2 slices, 4×4 sampling tables, a constant albedo 0.5.
fn small_rgl() -> Vec<u8> {
    let px = 8;
    let theta = |i: usize| (i as f64 / (px - 1) as f64).powi(2) * std::f64::consts::FRAC_PI_2;
    let ndf = f32s((0..2 * px).map(|_| 1.0 / std::f64::consts::PI));
    let sigma = f32s((0..2 * px).map(|k| (1.0 + theta(k % px).cos()) / 2.0));
    let vndf = f32s((0..2 * 16).map(|k| 1.0 + 0.1 * (k % 5) as f64));
    let lum = f32s((0..2 * 16).map(|_| 0.5));
    let rgb = f32s((0..2 * 3 * 16).map(|k| 0.4 + 0.05 * (k % 3) as f64));
    tensor(&[
        ("description", 1, vec![5], b"small".to_vec()),
        ("phi_i", 10, vec![1], f32s([0.0])),
        ("theta_i", 10, vec![2], f32s([0.0, 1.2])),
        ("ndf", 10, vec![2, px], ndf),
        ("sigma", 10, vec![2, px], sigma),
        ("vndf", 10, vec![1, 2, 4, 4], vndf),
        ("luminance", 10, vec![1, 2, 4, 4], lum),
        ("rgb", 10, vec![1, 2, 3, 4, 4], rgb),
        ("jacobian", 1, vec![1], vec![1]),
    ])
}

/// A small Cornell file: 31 wavelengths, 40 samples on a grid of angles.
fn small_cornell() -> Vec<u8> {
    let mut s = String::from("# num wls\n31\n# wls\n");
    let wls: Vec<String> = (0..31).map(|k| (400 + 10 * k).to_string()).collect();
    s.push_str(&wls.join(" "));
    s.push_str("\n# theta i, phi i, theta s, phi_s, values\n");
    for k in 0..40 {
        let ti = 0.1 + 0.03 * (k % 10) as f64;
        let ts = 0.05 + 0.1 * (k / 10) as f64;
        let ps = -0.3 + 0.07 * k as f64;
        s.push_str(&format!("{ti:.6} 0.000000 {ts:.6} {ps:.6}"));
        for w in 0..31 {
            s.push_str(&format!(" {:.6}", 0.01 + 0.001 * ((k + w) % 7) as f64));
        }
        s.push('\n');
    }
    s.into_bytes()
}

fn hdr_header(w: usize, h: usize) -> Vec<u8> {
    format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {h} +X {w}\n").into_bytes()
}

/// A 16×8 Radiance file with flat scanlines.
fn hdr_flat() -> Vec<u8> {
    let mut b = hdr_header(16, 8);
    for k in 0..16 * 8 {
        b.extend([100 + (k % 50) as u8, 90, 80, 128]);
    }
    b
}

/// A 16×8 Radiance file with new-style RLE scanlines (a run and literals per channel).
fn hdr_rle() -> Vec<u8> {
    let mut b = hdr_header(16, 8);
    for row in 0..8u8 {
        b.extend([2, 2, 0, 16]);
        for ch in 0..4u8 {
            // A run of 8, then 8 literals.
            b.extend([128 + 8, 60 + ch + row]);
            b.push(8);
            b.extend((0..8).map(|k| if ch == 3 { 129 } else { 40 + k * 10 + ch }));
        }
    }
    b
}

fn exr_seed() -> Vec<u8> {
    let flat: Vec<f32> = (0..16 * 8 * 3)
        .map(|k| 0.1 + 0.01 * (k % 17) as f32)
        .collect();
    let img = image::Rgb32FImage::from_raw(16, 8, flat).expect("16×8");
    let mut out = Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut out, image::ImageFormat::OpenExr)
        .expect("EXR encode");
    out.into_inner()
}

/// A 16×8 PFM (RGB or grey, either endianness).
fn pfm_seed(rgb: bool, little: bool) -> Vec<u8> {
    let ch = if rgb { 3 } else { 1 };
    let mut b = format!(
        "{}\n16 8\n{}\n",
        if rgb { "PF" } else { "Pf" },
        if little { "-1.0" } else { "1.0" }
    )
    .into_bytes();
    for k in 0..16 * 8 * ch {
        let v = 0.2f32 + 0.01 * (k % 13) as f32;
        b.extend(if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }
    b
}
