//! The tables' unit tests: bins, filters, poles, and the fast build against the reference.

use super::build::{downsample, overlap_weights};
use super::*;
use crate::scene::image::LUMINANCE_WEIGHTS;

fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> Vec3) -> RgbImage {
    RgbImage { width: w, height: h, pixels: (0..w * h).map(|i| f(i % w, i / w)).collect() }
}

#[test]
fn cached_row_divisors_give_cell_pdf_to_solid_angle_bit_for_bit() {
    let img = image(37, 19, |x, y| Vec3::splat(1.0 + (x * 7 + y * 3) as f32 % 5.0));
    let t = EnvMapTables::build_with(&img, EnvTableOptions::default());
    let (d, nv) = (t.distribution(false).unwrap(), t.resolution[1]);
    for i in 0..4000 {
        let uv = Vec2::new((i % 63) as f32 / 63.0, (i / 63) as f32 / 63.0 + 1e-3);
        let row = ((uv.y as f64 * nv as f64) as usize).min(nv - 1);
        assert_eq!(t.pdf_solid_angle(uv, false).to_bits(), cell_pdf_to_solid_angle(d.pdf(uv), row, nv).to_bits());
    }
}

#[test]
fn overlap_weights_cover_each_coarse_cell_once() {
    for (fine, coarse) in [(8, 4), (7, 3), (1000, 256), (5, 5), (3, 1), (1, 1)] {
        let ws = overlap_weights(fine, coarse);
        assert_eq!(ws.len(), coarse);
        for (c, w) in ws.iter().enumerate() {
            let s: f64 = w.iter().map(|&(_, k)| k).sum();
            assert!((s - 1.0).abs() < 1e-12, "{fine}->{coarse} cell {c}: {s}");
        }
        // Every fine cell carries the same total weight, so the mean is preserved.
        let mut per_fine = vec![0.0; fine];
        ws.iter().flatten().for_each(|&(i, k)| per_fine[i] += k);
        let expect = coarse as f64 / fine as f64;
        assert!(per_fine.iter().all(|&k| (k - expect).abs() < 1e-12), "{fine}->{coarse}: {per_fine:?}");
    }
}

#[test]
fn downsampling_keeps_the_mean_and_the_support() {
    let (w, h) = (37, 19);
    let f: Vec<f64> = (0..w * h).map(|i| if i % 53 == 0 { (i as f64).sqrt() } else { 0.0 }).collect();
    let (nw, nh) = (8, 4);
    let g = downsample(&f, w, h, nw, nh);
    let mean_f = f.iter().sum::<f64>() / (w * h) as f64;
    let mean_g = g.iter().sum::<f64>() / (nw * nh) as f64;
    assert!((mean_f - mean_g).abs() < 1e-12 * mean_f.max(1.0));
    // A coarse cell is zero only if every fine cell under it is.
    for y in 0..nh {
        for x in 0..nw {
            let any = (0..h).any(|j| {
                (0..w).any(|i| {
                    let over_u = i * nw < (x + 1) * w && (i + 1) * nw > x * w;
                    let over_v = j * nh < (y + 1) * h && (j + 1) * nh > y * h;
                    over_u && over_v && f[j * w + i] > 0.0
                })
            });
            assert_eq!(any, g[y * nw + x] > 0.0, "cell ({x}, {y})");
        }
    }
}

#[test]
fn bilinear_footprint_matches_the_interpolants_mean() {
    let img = image(5, 4, |x, y| Vec3::splat(((x * 7 + y * 3) % 5) as f32));
    let (lum, bad) = texel_luminance(&img, EnvLookup::Bilinear);
    assert_eq!(bad, 0);
    let y_weight = LUMINANCE_WEIGHTS.element_sum() as f64;
    for (x, y) in [(0, 0), (2, 1), (4, 3), (1, 2)] {
        // Midpoint rule on a 64 x 64 grid inside the texel: bilinear is smooth there, so this
        // converges quickly.
        let n = 64;
        let mut s = 0.0;
        for j in 0..n {
            for i in 0..n {
                let uv = Vec2::new(
                    (x as f32 + (i as f32 + 0.5) / n as f32) / 5.0,
                    (y as f32 + (j as f32 + 0.5) / n as f32) / 4.0,
                );
                s += img.bilinear(uv).x as f64;
            }
        }
        let mean = s / (n * n) as f64 * y_weight;
        assert!((lum[y * 5 + x] - mean).abs() < 1e-4, "({x}, {y}): {} vs {mean}", lum[y * 5 + x]);
    }
}

#[test]
fn non_finite_texels_are_black_and_counted() {
    let img = image(4, 2, |x, _| match x {
        0 => Vec3::new(f32::NAN, 1.0, 1.0),
        1 => Vec3::splat(f32::INFINITY),
        2 => Vec3::new(-1.0, 2.0, 0.0),
        _ => Vec3::ONE,
    });
    for lookup in [EnvLookup::Nearest, EnvLookup::Bilinear] {
        let t = EnvMapTables::build_with(&img, EnvTableOptions { lookup, ..Default::default() });
        assert_eq!(t.bad_texels, 4);
        let d = t.distribution.as_ref().expect("some texels are lit");
        assert!(d.integral().is_finite() && d.integral() > 0.0);
        for y in 0..2 {
            let row = d.conditional(y).unwrap();
            assert!((0..4).all(|x| row.pdf((x as f32 + 0.5) / 4.0).is_finite()));
        }
    }
}

#[test]
fn resolution_option_gives_the_requested_width() {
    assert_eq!(table_resolution(1024, 512, Some(256)), [256, 128]);
    assert_eq!(table_resolution(1024, 512, Some(4096)), [1024, 512]);
    assert_eq!(table_resolution(1000, 1, Some(10)), [10, 1]);
    assert_eq!(table_resolution(1, 1000, Some(10)), [1, 1000]);
    assert_eq!(table_resolution(7, 3, Some(0)), [1, 1]);
}

#[test]
fn constant_map_has_no_compensated_table() {
    let img = image(8, 4, |_, _| Vec3::splat(2.0));
    let t = EnvMapTables::build(&img, true);
    assert!(t.distribution.is_some());
    assert!(t.compensated.is_none(), "max(0, L - mean) is 0 everywhere");
    assert!(std::ptr::eq(t.distribution(true).unwrap(), t.distribution.as_ref().unwrap()));
}

#[test]
fn row_bands_are_exact_and_rows_are_uniform_in_cos_theta() {
    for n in [1usize, 2, 5, 512, 100_000] {
        let sum: f64 = (0..n).map(|j| row_band(j, n)).sum();
        assert!((sum - 2.0).abs() < 1e-9, "{n}: {sum}");
        for j in [0, n / 2, n - 1] {
            let (t0, t1) = (PI64 * j as f64 / n as f64, PI64 * (j + 1) as f64 / n as f64);
            assert!((row_band(j, n) - (t0.cos() - t1.cos())).abs() < 1e-12);
            assert!((theta_in_row(0.0, j, n) - t0).abs() < 1e-12 && (theta_in_row(1.0, j, n) - t1).abs() < 1e-12);
            let mid = theta_in_row(0.5, j, n).cos();
            assert!((mid - 0.5 * (t0.cos() + t1.cos())).abs() < 1e-12, "{n} {j}");
        }
    }
}

#[test]
fn solid_angle_pdf_is_finite_at_the_poles() {
    let img = image(8, 4, |_, _| Vec3::ONE);
    let t = EnvMapTables::build_with(&img, EnvTableOptions { lookup: EnvLookup::Nearest, ..Default::default() });
    // A constant map samples the sphere uniformly.
    for d in [Vec3::Y, -Vec3::Y, Vec3::X, Vec3::new(0.3, -0.9, 0.1).normalize()] {
        let pdf = t.pdf_direction(d, false);
        assert!((pdf - 0.25 / PI64 as f32).abs() < 1e-6, "{d}: {pdf}");
    }
    assert_eq!(cell_pdf_to_solid_angle(0.0, 0, 4), 0.0);
    assert_eq!(cell_pdf_to_solid_angle(f32::NAN, 0, 4), 0.0);
}

/// A map with structure at every scale: a hash of (x, y) spread over six decades, so cells near
/// the mean (where compensation cancels) and far from it both occur.
fn bumpy(w: usize, h: usize) -> RgbImage {
    image(w, h, |x, y| {
        let k = (x as u64 * 0x9E37_79B9 + y as u64 * 0x85EB_CA6B) % 1009;
        Vec3::new(1.0, 0.7, 0.4) * 10f32.powf(k as f32 / 1009.0 * 6.0 - 3.0)
    })
}

/// The hard cases the fast build must agree with the reference on, named.
fn hard_maps() -> Vec<(&'static str, RgbImage)> {
    let mut black_region = bumpy(64, 32);
    black_region
        .pixels
        .iter_mut()
        .enumerate()
        .filter(|(i, _)| (i % 64) < 40 && (i / 64) > 4)
        .for_each(|(_, p)| *p = Vec3::ZERO);
    // Lit only in the first and last rows, whose solid angle is tiny next to the equator's.
    let poles = image(256, 4096, |_, y| if y == 0 || y == 4095 { Vec3::splat(5.0) } else { Vec3::ZERO });
    let mut bad = bumpy(16, 8);
    bad.pixels[3] = Vec3::new(f32::NAN, 1.0, 1.0);
    bad.pixels[17] = Vec3::splat(f32::INFINITY);
    bad.pixels[40] = Vec3::new(-2.0, 1.0, 0.0);
    let mut short = bumpy(9, 7);
    short.pixels.truncate(20);
    vec![
        ("bumpy", bumpy(61, 37)),
        ("black region", black_region),
        ("poles", poles),
        ("non-finite texels", bad),
        ("one pixel high", bumpy(33, 1)),
        ("one pixel wide", bumpy(1, 9)),
        ("two pixels wide", bumpy(2, 5)),
        ("short pixel buffer", short),
        ("black", image(8, 4, |_, _| Vec3::ZERO)),
        ("constant", image(8, 4, |_, _| Vec3::splat(3.0))),
        ("empty", RgbImage { width: 0, height: 0, pixels: Vec::new() }),
    ]
}

fn all_options() -> impl Iterator<Item = EnvTableOptions> {
    [EnvLookup::Bilinear, EnvLookup::Nearest]
        .into_iter()
        .flat_map(|lookup| [true, false].map(|compensate| EnvTableOptions { compensate, lookup, max_width: None }))
}

#[test]
fn parallel_build_equals_the_reference_bit_for_bit_with_the_same_pdf_at_every_texel() {
    for (name, img) in hard_maps() {
        for options in all_options() {
            let fast = EnvMapTables::build_with(&img, options);
            let slow = EnvMapTables::build_reference(&img, options);
            assert_eq!(fast.distribution, slow.distribution, "{name} {options:?}");
            assert_eq!(fast.compensated, slow.compensated, "{name} {options:?}");
            assert_eq!((fast.bad_texels, fast.resolution), (slow.bad_texels, slow.resolution), "{name}");
            let [w, h] = fast.resolution;
            for mis in [false, true] {
                for i in 0..w * h {
                    let uv = Vec2::new(((i % w) as f32 + 0.5) / w as f32, ((i / w) as f32 + 0.5) / h as f32);
                    let (a, b) = (fast.pdf_solid_angle(uv, mis), slow.pdf_solid_angle(uv, mis));
                    assert!(a.is_finite() && (a - b).abs() <= 1e-5 * b, "{name} {options:?} texel {i}: {a} vs {b}");
                }
            }
        }
    }
}

#[test]
fn hard_cases_have_the_expected_tables() {
    let maps: std::collections::HashMap<_, _> = hard_maps().into_iter().collect();
    let t = |name: &str| EnvMapTables::build(&maps[name], true);
    assert!(t("black").distribution.is_none() && t("black").compensated.is_none());
    assert!(t("empty").distribution.is_none());
    assert!(t("constant").compensated.is_none(), "max(0, L - mean) is 0 everywhere");
    assert_eq!(t("non-finite texels").bad_texels, 2);
    // A black region gets no samples from the nearest table (bilinear spreads a texel's edge).
    let near = EnvMapTables::build_with(
        &maps["black region"],
        EnvTableOptions { lookup: EnvLookup::Nearest, ..Default::default() },
    );
    assert_eq!(near.pdf_uv(Vec2::new(0.3, 0.5), false), 0.0);
    // Only the pole rows are lit: every sample lands in them, with the density its pdf states.
    let poles = t("poles");
    for i in 0..64 {
        let u = Vec2::new((i as f32 + 0.5) / 64.0, (i as f32 * 0.618).fract());
        let (dir, pdf) = poles.sample_direction(u, false).expect("lit");
        assert!(dir.y.abs() > (PI64 / 4096.0).cos() as f32 - 1e-6, "{dir}");
        assert!(pdf.is_finite() && (pdf - poles.pdf_direction(dir, false)).abs() <= 1e-5 * pdf);
    }
    // One row: the whole sphere in one band, sampled uniformly in cos(theta) within it.
    let one = t("one pixel high");
    let (_, pdf) = one.sample_direction(Vec2::new(0.2, 0.7), false).unwrap();
    assert!(pdf.is_finite() && pdf > 0.0);
}

/// `img` with rows `rows` rewritten by `f`.
fn rewrite(img: &RgbImage, rows: std::ops::Range<usize>, f: impl Fn(Vec3) -> Vec3) -> RgbImage {
    let mut out = img.clone();
    let w = img.width;
    out.pixels[rows.start * w..rows.end * w].iter_mut().for_each(|p| *p = f(*p));
    out
}

#[test]
fn partial_rebuild_equals_a_full_rebuild_bit_for_bit() {
    let base = bumpy(64, 40);
    for options in all_options() {
        for rows in [0..1, 5..9, 39..40, 0..40] {
            // A big change (the mean moves past the tolerance) and a small one (it stays).
            for (scale, keeps_mean) in [(50.0, false), (1.001, true)] {
                let changed = rewrite(&base, rows.clone(), |p| p * scale);
                let mut t = EnvMapTables::build_with(&base, options);
                let before = t.state.clone();
                t.update_rows(&changed, rows.clone());
                let mut full = EnvMapTables::build_with(&changed, options);
                if options.compensate && keeps_mean {
                    // The kept threshold: compare with a full build at that threshold.
                    assert_ne!(full.state.mean, before.mean);
                    full.state.mean = before.mean;
                    full.refill(&changed, 0..40, Some(before.mean));
                }
                assert!(t == full, "{options:?} rows {rows:?} scale {scale}");
            }
        }
    }
}

#[test]
fn partial_rebuild_handles_black_and_bad_texels() {
    let base = bumpy(32, 16);
    let options = EnvTableOptions::default();
    let mut t = EnvMapTables::build_with(&base, options);
    // Rows turn non-finite, then black everywhere, then lit again.
    let bad = rewrite(&base, 3..5, |_| Vec3::splat(f32::NAN));
    t.update_rows(&bad, 3..5);
    assert_eq!(t.bad_texels, 64);
    assert!(t == EnvMapTables::build_with(&bad, options));
    let black = rewrite(&base, 0..16, |_| Vec3::ZERO);
    t.update_rows(&black, 0..16);
    assert!(t.distribution.is_none() && t.bad_texels == 0);
    t.update_rows(&base, 0..16);
    assert!(t == EnvMapTables::build_with(&base, options));
    // A range past the image and an image of another size are handled, not panics.
    t.update_rows(&base, 10..1000);
    t.update_rows(&bumpy(8, 4), 0..2);
    assert!(t == EnvMapTables::build_with(&bumpy(8, 4), options));
}
