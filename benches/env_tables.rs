//! Environment-map tables against the memory they touch: the build of a 2048 x 1024 and an
//! 8192 x 4096 map (luminance, footprint filter, row weights, conditional and marginal CDFs, the
//! MIS-compensated variant) beside a parallel memcpy of the same pixels, a 16-row partial
//! rebuild, the f64 reference build, and decoding the real maps in tests/data/env and an 8k EXR
//! on one thread and on all.
//!
//! Timings swing on a shared 2-core machine, so before criterion's groups `alternating` times
//! memcpy and build in turn in one process and prints the median of each and their ratio.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput};
use glam::Vec3;
use kelvin::light::{EnvMapTables, EnvTableOptions};
use kelvin::scene::image::{RgbImage, load_image, load_image_from_bytes};
use rayon::prelude::*;

const MAPS: [(usize, usize); 2] = [(2048, 1024), (8192, 4096)];
const REAL: [&str; 4] = [
    "spiaggia_di_mondello_1k.hdr",
    "luxcore/imagemap-00000.exr",
    "luxcore/sky.exr",
    "radeonprorender/envLightImage.exr",
];

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/env").join(rel)
}

/// The real map (with its sun) resampled, nearest, to `w` x `h`: real structure at any size.
fn map(w: usize, h: usize) -> RgbImage {
    let src = load_image(&data(REAL[0])).expect("tests/data/env map loads").image;
    let pixels = (0..w * h).map(|i| src.get((i % w) * src.width / w, (i / w) * src.height / h)).collect();
    RgbImage { width: w, height: h, pixels }
}

/// The baseline: every pixel read and written once, on all cores.
fn par_memcpy(src: &[Vec3], dst: &mut [Vec3]) {
    dst.par_chunks_mut(1 << 16).zip(src.par_chunks(1 << 16)).for_each(|(d, s)| d.copy_from_slice(s));
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

/// Alternates memcpy and the build `rounds` times; prints medians, the ratio and ns per texel.
fn alternating() {
    for (w, h) in MAPS {
        let img = map(w, h);
        let mut dst = vec![Vec3::ZERO; w * h];
        let mut t = EnvMapTables::build(&img, true);
        let rounds = if w * h > 1 << 24 { 15 } else { 41 };
        let (mut copy, mut build, mut update, mut fresh) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for _ in 0..rounds {
            let s = Instant::now();
            par_memcpy(&img.pixels, &mut dst);
            copy.push(s.elapsed());
            let s = Instant::now();
            t.rebuild(&img, EnvTableOptions::default());
            build.push(s.elapsed());
            // A fresh build allocates its tables: page faults and first writes included.
            let s = Instant::now();
            black_box(EnvMapTables::build(&img, true));
            fresh.push(s.elapsed());
            let s = Instant::now();
            t.update_rows(&img, h / 2..h / 2 + 16);
            update.push(s.elapsed());
        }
        let (c, b, u, f) = (median(copy), median(build), median(update), median(fresh));
        let ns = |d: Duration| d.as_secs_f64() * 1e9 / (w * h) as f64;
        eprintln!(
            "env_tables {w}x{h}: build {:.2} ms ({:.2} ns/texel), parallel memcpy {:.2} ms ({:.2} ns/texel), ratio {:.2}; \
             fresh build {:.2} ms (ratio {:.2}); update_rows(16) {:.3} ms  [medians of {rounds}, alternating]",
            b.as_secs_f64() * 1e3,
            ns(b),
            c.as_secs_f64() * 1e3,
            ns(c),
            b.as_secs_f64() / c.as_secs_f64(),
            f.as_secs_f64() * 1e3,
            f.as_secs_f64() / c.as_secs_f64(),
            u.as_secs_f64() * 1e3
        );
    }
    for rel in REAL {
        let bytes = std::fs::read(data(rel)).expect("tests/data/env map reads");
        let (mut dec, mut copy) = (Vec::new(), Vec::new());
        let mut px = 0;
        for _ in 0..9 {
            let s = Instant::now();
            let img = load_image_from_bytes(&bytes, rel.rsplit('.').next().unwrap_or(""), rel).expect("decodes").image;
            dec.push(s.elapsed());
            let mut dst = vec![Vec3::ZERO; img.pixels.len()];
            let s = Instant::now();
            par_memcpy(&img.pixels, &mut dst);
            copy.push(s.elapsed());
            px = img.pixels.len();
        }
        let (d, c) = (median(dec), median(copy));
        eprintln!(
            "decode {rel} ({} KB, {px} px): {:.2} ms ({:.1} ns/px), memcpy of its pixels {:.3} ms",
            bytes.len() / 1024,
            d.as_secs_f64() * 1e3,
            d.as_secs_f64() * 1e9 / px as f64,
            c.as_secs_f64() * 1e3
        );
    }
}

/// An 8192 x 4096 OpenEXR (32-bit float, ZIP, as `kelvin render` writes) decoded on one thread and
/// on all of rayon's, alternating: the gain of decompressing its blocks in parallel.
fn decode_8k_threads() {
    let (w, h) = MAPS[1];
    let path = std::env::temp_dir().join(format!("kelvin-bench-{}-8k.exr", std::process::id()));
    kelvin::render::film_io::write_exr(&path, w, h, &map(w, h).pixels).expect("writes the 8k map");
    let bytes = std::fs::read(&path).expect("reads it back");
    let _ = std::fs::remove_file(&path);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
    let (mut single, mut all) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        let s = Instant::now();
        black_box(one.install(|| load_image_from_bytes(&bytes, "exr", "8k.exr").expect("decodes")));
        single.push(s.elapsed());
        let s = Instant::now();
        black_box(load_image_from_bytes(&bytes, "exr", "8k.exr").expect("decodes"));
        all.push(s.elapsed());
    }
    let (a, b) = (median(single), median(all));
    eprintln!(
        "decode 8k exr ({} MB): 1 thread {:.0} ms ({:.1} ns/px), {} threads {:.0} ms ({:.1} ns/px): {:.2}x",
        bytes.len() >> 20,
        a.as_secs_f64() * 1e3,
        a.as_secs_f64() * 1e9 / (w * h) as f64,
        rayon::current_num_threads(),
        b.as_secs_f64() * 1e3,
        b.as_secs_f64() * 1e9 / (w * h) as f64,
        a.as_secs_f64() / b.as_secs_f64()
    );
}

fn tables(c: &mut Criterion) {
    for (w, h) in MAPS {
        let img = map(w, h);
        let mut g = c.benchmark_group(format!("env_tables/{w}x{h}"));
        g.throughput(Throughput::Bytes((w * h * 12) as u64));
        g.sample_size(10).measurement_time(Duration::from_secs(if w > 4096 { 8 } else { 3 }));
        let mut dst = vec![Vec3::ZERO; w * h];
        g.bench_function("parallel_memcpy", |b| b.iter(|| par_memcpy(black_box(&img.pixels), &mut dst)));
        let mut t = EnvMapTables::build(&img, true);
        g.bench_function("rebuild", |b| b.iter(|| t.rebuild(black_box(&img), EnvTableOptions::default())));
        g.bench_function("build_fresh", |b| b.iter(|| EnvMapTables::build(black_box(&img), true)));
        g.bench_function("update_rows_16", |b| b.iter(|| t.update_rows(black_box(&img), h / 2..h / 2 + 16)));
        if w <= 2048 {
            g.bench_function("reference", |b| {
                b.iter(|| EnvMapTables::build_reference(black_box(&img), EnvTableOptions::default()))
            });
        }
        g.finish();
    }
}

fn decode(c: &mut Criterion) {
    let mut g = c.benchmark_group("env_decode");
    g.sample_size(10);
    for rel in REAL {
        let bytes = std::fs::read(data(rel)).expect("tests/data/env map reads");
        let ext = rel.rsplit('.').next().unwrap_or("");
        g.bench_function(rel, |b| b.iter(|| load_image_from_bytes(black_box(&bytes), ext, rel)));
    }
    g.finish();
}

fn main() {
    alternating();
    decode_8k_threads();
    let mut c = Criterion::default().configure_from_args();
    tables(&mut c);
    decode(&mut c);
    c.final_summary();
}
