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
            assert!(d.conditional(y).unwrap().func().iter().all(|v| v.is_finite()));
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
