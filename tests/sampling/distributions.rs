//! Piecewise-constant distributions and alias tables: chi-square against the function, pdf of a
//! sample == pdf function, inverses, the 1e9 "sun pixel" outlier, zero weights.

use glam::Vec2;
use kelvin::rng::SplitMix64;
use kelvin::sampling::*;

use crate::common::*;

/// A function with zeros, a spread of magnitudes and one negative value (counts as its magnitude).
fn bumpy(n: usize, rng: &mut SplitMix64) -> Vec<f32> {
    (0..n)
        .map(|i| match i % 7 {
            0 => 0.0,
            3 => -(rng.f32() * 2.0),
            _ => 0.05 + rng.f32() * 3.0,
        })
        .collect()
}

#[test]
fn piecewise_1d_sample_frequencies_match_function_chi_square() {
    let mut rng = SplitMix64::new(1);
    let f = bumpy(40, &mut rng);
    let d = PiecewiseConstant1D::new(&f, -2.0, 3.0);
    let sum: f64 = f.iter().map(|v| v.abs() as f64).sum();
    let probs: Vec<f64> = f.iter().map(|v| v.abs() as f64 / sum).collect();
    let mut counts = vec![0u64; f.len()];
    for _ in 0..200_000 {
        let (_, _, o) = d.sample(rng.f32());
        counts[o] += 1;
    }
    let stat = assert_chi_square("1D", &counts, &probs);
    println!("piecewise 1D: chi-square {stat:.1} over {} bins", f.len());
    assert!(rel(d.integral() as f64, sum * 5.0 / 40.0) < 1e-6);
}

#[test]
fn piecewise_1d_pdf_of_sample_equals_pdf_function_and_invert_round_trips() {
    let mut rng = SplitMix64::new(2);
    let f = bumpy(33, &mut rng);
    let d = PiecewiseConstant1D::new(&f, 1.0, 4.0);
    let (mut worst_pdf, mut worst_u) = (0.0f64, 0.0f32);
    for _ in 0..20_000 {
        let u = rng.f32();
        let (x, pdf, o) = d.sample(u);
        assert!(f[o] != 0.0, "zero bin {o} sampled at u = {u}");
        worst_pdf = worst_pdf.max(rel(d.pdf(x) as f64, pdf as f64));
        let back = d.invert(x).expect("a sampled x has positive density");
        worst_u = worst_u.max((back - u).abs());
    }
    println!("piecewise 1D: pdf mismatch {worst_pdf:.1e}, inverse round trip {worst_u:.1e}");
    assert!(worst_pdf < 1e-6 && worst_u < 1e-5);
    // The density integrates to 1 (midpoint rule is exact for a piecewise-constant function).
    let n = 3300;
    let integral: f64 = (0..n).map(|i| d.pdf(1.0 + 3.0 * (i as f32 + 0.5) / n as f32) as f64 * 3.0 / n as f64).sum();
    assert!((integral - 1.0).abs() < 1e-5, "{integral}");
    assert_eq!(d.pdf(0.999), 0.0);
    assert!(d.invert(4.5).is_none());
}

#[test]
fn piecewise_1d_sun_outlier_1e9_keeps_the_mass_of_the_sky() {
    // 1023 sky bins of 1 and one sun bin of 1e9 (a sun pixel in an environment map row).
    let (n, sun) = (1024usize, 700usize);
    let mut f = vec![1.0f32; n];
    f[sun] = 1e9;
    let d = PiecewiseConstant1D::new(&f, 0.0, 1.0);
    let total = 1e9 + (n - 1) as f64;
    assert!(rel(d.integral() as f64, total / n as f64) < 1e-7, "integral {}", d.integral());
    // The CDF keeps every sky bin's step: in f32, 1e9 + 1 == 1e9 would make all after the sun 0.
    let cdf = d.cdf();
    assert_eq!(cdf[n], 1.0);
    assert!(rel(cdf[sun], sun as f64 / total) < 1e-12);
    assert!(rel(1.0 - cdf[sun + 1], (n - sun - 1) as f64 / total) < 1e-6, "sky after the sun: {}", 1.0 - cdf[sun + 1]);
    for i in (0..n).filter(|&i| i != sun) {
        assert!(rel(cdf[i + 1] - cdf[i], 1.0 / total) < 1e-6, "bin {i}");
    }
    // Sky bins before the sun: u in [0, cdf[sun]) hits each equally, with the sky pdf.
    let sky_pdf = (n as f64 / total) as f32;
    let m = 70_000;
    let mut counts = vec![0u32; sun];
    for j in 0..m {
        let u = ((j as f64 + 0.5) / m as f64 * cdf[sun]) as f32;
        let (x, pdf, o) = d.sample(u);
        assert!(o < sun, "u = {u} reached bin {o}");
        assert!(rel(pdf as f64, sky_pdf as f64) < 1e-6 && d.pdf(x) == pdf);
        counts[o] += 1;
        let back = d.invert(x).unwrap();
        assert!(rel(back as f64, u as f64) < 1e-4, "invert({x}) = {back}, sampled with {u}");
    }
    assert!(counts.iter().all(|&c| c.abs_diff((m / sun) as u32) <= 1), "stratified counts {counts:?}");
    // Sky bins after the sun are reachable by the f32 samples just below 1, with the sky pdf.
    let (_, pdf, o) = d.sample(1.0 - f32::EPSILON / 2.0);
    assert!(o > sun && rel(pdf as f64, sky_pdf as f64) < 1e-6, "bin {o}, pdf {pdf}");
    let (_, pdf, o) = d.sample(0.5);
    assert!(o == sun && rel(pdf as f64, 1e9 * n as f64 / total) < 1e-6);
}

#[test]
fn piecewise_2d_sample_frequencies_match_function_chi_square() {
    let mut rng = SplitMix64::new(3);
    let (nu, nv) = (8, 5);
    let mut f = bumpy(nu * nv, &mut rng);
    f[nu..2 * nu].iter_mut().for_each(|v| *v = 0.0); // an all-zero row
    let d = PiecewiseConstant2D::new(&f, nu, nv);
    let sum: f64 = f.iter().map(|v| v.abs() as f64).sum();
    let probs: Vec<f64> = f.iter().map(|v| v.abs() as f64 / sum).collect();
    let mut counts = vec![0u64; nu * nv];
    for _ in 0..200_000 {
        let (_, _, [iu, iv]) = d.sample(rng.vec2());
        counts[iv * nu + iu] += 1;
    }
    let stat = assert_chi_square("2D", &counts, &probs);
    println!("piecewise 2D: chi-square {stat:.1} over {} cells", nu * nv);
}

#[test]
fn piecewise_2d_pdf_of_sample_equals_pdf_function_and_invert_round_trips_on_a_domain() {
    let mut rng = SplitMix64::new(4);
    let (nu, nv) = (16, 9);
    let f = bumpy(nu * nv, &mut rng);
    let (lo, hi) = (Vec2::new(-1.0, 0.0), Vec2::new(1.0, std::f32::consts::PI));
    let d = PiecewiseConstant2D::try_new(&f, nu, nv, lo, hi).unwrap();
    let (mut worst_pdf, mut worst_u) = (0.0f64, 0.0f32);
    for _ in 0..20_000 {
        let u = rng.vec2();
        let (p, pdf, [iu, iv]) = d.sample(u);
        assert!(f[iv * nu + iu] != 0.0);
        worst_pdf = worst_pdf.max(rel(d.pdf(p) as f64, pdf as f64));
        let back = d.invert(p).expect("a sampled point has positive density");
        worst_u = worst_u.max((back - u).abs().max_element());
    }
    println!("piecewise 2D: pdf mismatch {worst_pdf:.1e}, inverse round trip {worst_u:.1e}");
    assert!(worst_pdf < 1e-5 && worst_u < 1e-5);
    let area = (hi - lo).x as f64 * (hi - lo).y as f64;
    let (m, e) = mean_and_error(200_000, || d.pdf(lo + (hi - lo) * rng.vec2()) as f64 * area);
    assert!((m - 1.0).abs() < 3.0 * e, "pdf integrates to {m} +- {e}");
    assert_eq!(d.pdf(Vec2::new(1.5, 1.0)), 0.0);
}

#[test]
fn piecewise_2d_sun_pixel_1e9_env_map_keeps_sky_rows() {
    let (nu, nv) = (64, 32);
    let mut f = vec![1.0f32; nu * nv];
    f[10 * nu + 40] = 1e9;
    let d = PiecewiseConstant2D::new(&f, nu, nv);
    let total = 1e9 + (nu * nv - 1) as f64;
    assert!(rel(d.integral() as f64, total / (nu * nv) as f64) < 1e-7);
    let sky_pdf = (nu * nv) as f64 / total;
    assert!(rel(d.pdf(Vec2::new(0.1, 0.9)) as f64, sky_pdf) < 1e-6);
    // Rows after the sun's keep their mass in the marginal CDF.
    let cdf = d.marginal().cdf();
    assert!(rel(1.0 - cdf[11], (nv - 11) as f64 * nu as f64 / total) < 1e-6);
    let (p, pdf, [iu, iv]) = d.sample(Vec2::new(0.3, 1.0 - f32::EPSILON / 2.0));
    assert!(iv > 10 && rel(pdf as f64, sky_pdf) < 1e-6 && d.pdf(p) == pdf, "{iu} {iv} {pdf}");
    // The sun's own row: in an f32 CDF the sky bins after the sun would close (1 - 1e-9 rounds
    // to 1); that row alone keeps its f64 CDF, and its sky bins keep their density.
    assert_eq!(d.wide_rows(), 1);
    for x in [0.05, 0.5, 0.7, 0.99] {
        let row_sky = d.pdf(Vec2::new(x, 10.5 / nv as f32)) as f64;
        assert!(rel(row_sky, sky_pdf) < 1e-6, "x = {x}: {row_sky} against {sky_pdf}");
    }
}

#[test]
fn piecewise_2d_rows_in_f32_sample_the_density_they_report_within_f32_of_the_function() {
    // Rows of 4096 bumpy values spanning six decades: the hard case for f32 edges is the dim
    // bins, whose width is a few ulps of the CDF near 1.
    let mut rng = SplitMix64::new(9);
    let (nu, nv) = (4096, 6);
    let f: Vec<f32> = (0..nu * nv).map(|i| 10f32.powf(6.0 * rng.f32()) * ((i % 7 != 0) as u8 as f32)).collect();
    let d = PiecewiseConstant2D::new(&f, nu, nv);
    // Dim bins are widened to one f32 step; only a row whose last bins are dim enough to need
    // more steps than are left below 1 keeps its f64 CDF (one of these six).
    assert!(d.wide_rows() <= 1, "{} rows in f64", d.wide_rows());
    let total: f64 = f.iter().map(|&v| v as f64).sum();
    // Per row, the total variation distance between the sampled distribution (the f32 widths)
    // and the function's: rounding moves an edge by half an f32 step (3e-8 below 1), widening a
    // dim bin by at most a step; over 4096 bins that stays below 1e-4.
    let mut worst_tv = 0.0f64;
    for (r, row) in f.chunks(nu).enumerate() {
        let row_sum: f64 = row.iter().map(|&x| x as f64).sum();
        let row_p = row_sum / total;
        let mut tv = 0.0;
        for (x, &v) in row.iter().enumerate() {
            let p = Vec2::new((x as f32 + 0.5) / nu as f32, (r as f32 + 0.5) / nv as f32);
            let pdf = d.pdf(p) as f64;
            assert_eq!(pdf > 0.0, v > 0.0, "row {r} bin {x}: density {pdf} for value {v}");
            // The bin's probability within its row, as sampled and as the function has it.
            tv += 0.5 * (pdf / (nu * nv) as f64 / row_p - v as f64 / row_sum).abs();
        }
        worst_tv = worst_tv.max(tv);
    }
    println!("f32 rows: worst total variation from the function {worst_tv:.1e}");
    assert!(worst_tv < 1e-4, "{worst_tv}");
    // Sampling returns the density `pdf` reports, bit for bit.
    for _ in 0..20_000 {
        let (p, pdf, _) = d.sample(rng.vec2());
        assert_eq!(d.pdf(p), pdf);
    }
}

#[test]
fn alias_table_frequencies_match_weights_chi_square() {
    let mut rng = SplitMix64::new(5);
    let w = bumpy(50, &mut rng);
    let t = AliasTable::new(&w);
    let sum: f64 = w.iter().map(|&v| if v > 0.0 { v as f64 } else { 0.0 }).sum();
    let probs: Vec<f64> = w.iter().map(|&v| if v > 0.0 { v as f64 / sum } else { 0.0 }).collect();
    let mut counts = vec![0u64; w.len()];
    for _ in 0..500_000 {
        let (i, pmf) = t.sample(rng.f32()).unwrap();
        assert_eq!(pmf, t.pmf(i));
        counts[i] += 1;
    }
    let stat = assert_chi_square("alias", &counts, &probs);
    println!("alias table: chi-square {stat:.1} over {} outcomes", probs.iter().filter(|&&p| p > 0.0).count());
    assert!(rel(t.total_weight(), sum) < 1e-12);
}

#[test]
fn alias_table_is_exact_on_a_stratified_grid() {
    // With u on a fine regular grid each outcome is hit in proportion to its pmf, to 1 / grid.
    let w = [3.0, 0.0, 1.0, 7.5, 0.25, 2.0, 0.0, 4.0];
    let t = AliasTable::new(&w);
    let m = 1 << 20;
    let mut counts = [0u32; 8];
    for j in 0..m {
        counts[t.sample((j as f64 / m as f64) as f32).unwrap().0] += 1;
    }
    for (i, &c) in counts.iter().enumerate() {
        let err = (c as f64 / m as f64 - t.pmf(i) as f64).abs();
        assert!(err <= w.len() as f64 / m as f64, "outcome {i}: {c} of {m} vs pmf {}", t.pmf(i));
    }
}

#[test]
fn alias_pmf_sums_to_one_within_f32_rounding_over_wide_magnitudes() {
    let mut rng = SplitMix64::new(6);
    let w: Vec<f32> = (0..10_000).map(|_| 10f32.powf(rng.f32() * 60.0 - 30.0)).collect();
    let t = AliasTable::new(&w);
    let sum: f64 = (0..t.len()).map(|i| t.pmf(i) as f64).sum();
    println!("alias table: pmf sum - 1 = {:.1e}", sum - 1.0);
    assert!((sum - 1.0).abs() <= t.len() as f64 * f32::EPSILON as f64 / 2.0, "{sum}");
}

#[test]
fn alias_zero_negative_and_nan_weights_are_never_returned() {
    let w = [0.0, 2.0, -1.0, f32::NAN, 0.0, 1e-30, 5.0, 0.0, 0.0, 3.0, -0.0];
    let t = AliasTable::new(&w);
    let n = w.len();
    let bad = |i: usize| w[i].is_nan() || w[i] <= 0.0;
    // Every bin boundary k/n, the f32 on either side of it, a fine grid, and u = 1.
    let mut us: Vec<f32> = (0..=n)
        .flat_map(|k| {
            let b = k as f32 / n as f32;
            [b, f32::from_bits(b.to_bits().saturating_sub(1)), f32::from_bits(b.to_bits() + 1)]
        })
        .collect();
    us.extend((0..100_000).map(|j| j as f32 / 100_000.0));
    us.push(1.0);
    for u in us.into_iter().filter(|u| (0.0..=1.0).contains(u)) {
        let (i, pmf) = t.sample(u).unwrap();
        assert!(!bad(i) && pmf > 0.0, "u = {u} returned outcome {i} of weight {}", w[i]);
    }
    for i in (0..n).filter(|&i| bad(i)) {
        assert_eq!(t.pmf(i), 0.0);
    }
}

#[test]
fn alias_all_zero_weights_sample_none() {
    assert!(AliasTable::new(&[0.0; 16]).sample(0.3).is_none());
    assert!(AliasTable::new(&[f32::NAN, -2.0]).sample(0.3).is_none());
    assert!(AliasTable::new(&[]).sample(0.3).is_none());
}
