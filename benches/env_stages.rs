//! Per-stage profile of `EnvMapTables::rebuild` (docs/performance.md, "Environment-map tables").
//! The stages are inlined into one `lanes::widest` closure in the library, so they are timed as
//! differences of runs that each stop after a stage, every one through the library's own code:
//!
//! - `cdf1`, `cdf2`: `PiecewiseConstant2D::fill_rows` over one and two tables whose rows are
//!   filled with a constant (the row CDFs: normalise, f32 rounding, stores; the marginals, tasks);
//! - `lum`: the same over one table filled with each texel row's luminance (`lum_row`, the
//!   pixels read and converted), so lum - cdf1 is the luminance;
//! - `nearest`, `bilinear`, `default`: `rebuild` without compensation for nearest and bilinear
//!   lookup, and with it (the default): bilinear - nearest is the footprint filter, default -
//!   bilinear the compensation (a second read of the pixels for the mean, the excess cells and
//!   a second table);
//! - `fresh`: `EnvMapTables::build`, allocating its tables (fresh - default: page faults);
//! - memcpy of the pixels on all cores, into a kept buffer and into a fresh one.
//!
//! Each round runs every variant once, in turn, on one map; medians over the rounds.
//! `cargo bench --features internals --bench env_stages`

use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};
use kelvin::light::infinite::tables::lum_row;
use kelvin::light::{EnvLookup, EnvMapTables, EnvTableOptions};
use kelvin::sampling::PiecewiseConstant2D;
use kelvin::scene::image::{RgbImage, load_image};
use rayon::prelude::*;

/// The real map (with its sun) resampled, nearest, to `w` x `h`, as benches/env_tables.rs.
fn map(w: usize, h: usize) -> RgbImage {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/spiaggia_di_mondello_1k.hdr");
    let src = load_image(&path).expect("tests/data/env map loads").image;
    let pixels = (0..w * h).map(|i| src.get((i % w) * src.width / w, (i / w) * src.height / h)).collect();
    RgbImage { width: w, height: h, pixels }
}

fn par_memcpy(src: &[Vec3], dst: &mut [Vec3]) {
    dst.par_chunks_mut(1 << 16).zip(src.par_chunks(1 << 16)).for_each(|(d, s)| d.copy_from_slice(s));
}

fn time(f: impl FnOnce()) -> Duration {
    let s = Instant::now();
    f();
    s.elapsed()
}

fn main() {
    let maps: &[(usize, usize)] = &[(2048, 1024), (8192, 4096)];
    for &(w, h) in maps {
        let img = map(w, h);
        let options = |compensate, lookup| EnvTableOptions { compensate, max_width: None, lookup };
        let variants = [
            ("nearest", options(false, EnvLookup::Nearest)),
            ("bilinear", options(false, EnvLookup::Bilinear)),
            ("default", EnvTableOptions::default()),
        ];
        // One warm set of tables per variant: a rebuild with other options drops a table.
        let mut tables: Vec<EnvMapTables> = variants.iter().map(|(_, o)| EnvMapTables::build_with(&img, *o)).collect();
        let grid = || PiecewiseConstant2D::unfilled(w, h, Vec2::ZERO, Vec2::ONE);
        let (mut d1, mut d2) = (grid(), grid());
        let mut dst = vec![Vec3::ZERO; w * h];
        let names = ["memcpy", "memcpy_fresh", "cdf1", "cdf2", "lum", "nearest", "bilinear", "default", "fresh"];
        let mut t: Vec<Vec<Duration>> = vec![Vec::new(); names.len()];
        let rounds = if w * h > 1 << 24 { 11 } else { 41 };
        for _ in 0..rounds {
            t[0].push(time(|| par_memcpy(&img.pixels, &mut dst)));
            let mut fresh = Vec::new();
            t[1].push(time(|| {
                fresh = vec![Vec3::ZERO; w * h];
                par_memcpy(&img.pixels, &mut fresh);
            }));
            drop(fresh);
            let constant = |_: &mut (), _: usize, rows: &mut [&mut [f64]]| rows.iter_mut().for_each(|r| r.fill(1.0));
            t[2].push(time(|| PiecewiseConstant2D::fill_rows(&mut [&mut d1], 0..h, |_| (), constant)));
            t[3].push(time(|| PiecewiseConstant2D::fill_rows(&mut [&mut d1, &mut d2], 0..h, |_| (), constant)));
            t[4].push(time(|| {
                PiecewiseConstant2D::fill_rows(
                    &mut [&mut d1],
                    0..h,
                    |_| (),
                    #[inline(always)]
                    |_: &mut (), y: usize, rows: &mut [&mut [f64]]| {
                        black_box(lum_row(&img, y, rows[0]));
                    },
                )
            }));
            for (k, (table, (_, o))) in tables.iter_mut().zip(&variants).enumerate() {
                t[5 + k].push(time(|| table.rebuild(&img, *o)));
            }
            let mut built = None;
            t[8].push(time(|| built = Some(EnvMapTables::build(&img, true))));
            drop(built);
        }
        let med: Vec<f64> = t
            .into_iter()
            .map(|mut v| {
                v.sort();
                v[v.len() / 2].as_secs_f64() * 1e3
            })
            .collect();
        let ns = |ms: f64| ms * 1e6 / (w * h) as f64;
        eprintln!("env_stages {w}x{h}, medians of {rounds} rounds, ms (ns/texel):");
        for (name, ms) in names.iter().zip(&med) {
            eprintln!("  {name:>12} {ms:8.2} ({:.2})", ns(*ms));
        }
        let m = |n: &str| med[names.iter().position(|&x| x == n).expect("a variant")];
        let stages = [
            ("row CDFs + marginal, one table", m("cdf1")),
            ("second table's CDFs", m("cdf2") - m("cdf1")),
            ("pixels to luminance", m("lum") - m("cdf1")),
            ("window copy, band, cells", m("nearest") - m("lum")),
            ("footprint filter", m("bilinear") - m("nearest")),
            ("compensation: mean pass, excess, 2nd table", m("default") - m("bilinear")),
            ("allocation, page faults", m("fresh") - m("default")),
        ];
        eprintln!("  stages (differences):");
        for (name, ms) in stages {
            eprintln!("  {name:>44} {ms:8.2} ms ({:.2} ns/texel)", ns(ms));
        }
    }
}
