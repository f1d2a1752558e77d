//! Sampling tables for lat-long environment maps: a [`PiecewiseConstant2D`] over the map's
//! (u, v) square whose cell masses are proportional to luminance times the cell's solid angle,
//! and its MIS-compensated variant.
//!
//! The lat-long map takes (u, v) to theta = pi v, phi = 2 pi (u - 1/2), so
//! d(omega) = 2 pi^2 sin(theta) du dv (pbrt-v3 section 14.2.4 weights by sin(theta) at row centres
//! and divides the uv density by 2 pi^2 sin(theta), which blows up at the poles). Here each row
//! is weighted by its exact solid angle, 2 pi (cos theta0 - cos theta1), and inside its row a
//! sample's v is remapped so cos(theta) is uniform: the density is then constant in solid angle
//! within each cell, p(omega) = P(cell) / Omega(cell), finite everywhere including the poles,
//! and exactly proportional to luminance for texel-constant radiance.
//!
//! Compensation (Karlik, Sik, Vevoda, Skrivan, Krivanek 2019, "MIS compensation: optimizing
//! sampling techniques in multiple importance sampling"; pbrt-v4 `ImageInfiniteLight`): when light
//! samples are combined with BSDF samples by MIS, sampling max(0, L - mean L) instead of L leaves
//! the dim, broad part of the sky to the BSDF and spends light samples on what stands out. Its
//! pdf is zero where L <= mean, so it is only unbiased under MIS.
//!
//! Support: the table is built from the radiance the light will actually return. With
//! [`EnvLookup::Nearest`] that is the texel; with [`EnvLookup::Bilinear`] it is the average of the
//! bilinear interpolant over the texel's footprint, the separable [1, 6, 1] / 8 filter (wrapping
//! in u, clamping in v as [`RgbImage::bilinear`] does), which is nonzero exactly where the
//! interpolant is nonzero somewhere in the texel: no direction with radiance has pdf 0.

use std::f64::consts::PI as PI64;

use glam::{Vec2, Vec3};

use crate::sampling::PiecewiseConstant2D;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage, direction_to_lat_long, lat_long_direction};

/// How radiance is looked up between texel centres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EnvLookup {
    /// The texel the direction falls in (pbrt-v4 `LookupNearest`): sampling matches radiance
    /// exactly, texel by texel.
    Nearest,
    /// Bilinear between texel centres: smoother backgrounds when the camera sees the map.
    #[default]
    Bilinear,
}

/// How to build [`EnvMapTables`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnvTableOptions {
    /// Also build the MIS-compensated distribution. Defaults to true.
    pub compensate: bool,
    /// Largest table width in cells: the importance is area-averaged down to this width (height
    /// in proportion) so the accuracy report can sweep table size. None (the default) keeps the
    /// image's resolution. 0 counts as 1.
    pub max_width: Option<usize>,
    /// The lookup whose radiance the table must cover. Defaults to bilinear.
    pub lookup: EnvLookup,
}

impl Default for EnvTableOptions {
    fn default() -> Self {
        Self { compensate: true, max_width: None, lookup: EnvLookup::Bilinear }
    }
}

/// Sampling tables of one lat-long image, in the image's own (u, v) square (the light's rotation
/// is applied outside, so turning the sky does not rebuild them).
///
/// Invariants: `distribution` is None exactly when the importance is zero everywhere (a black
/// map); `compensated` is None when not requested or when compensation left nothing (a constant
/// map), in which case MIS sampling uses `distribution`.
#[derive(Clone, PartialEq)]
pub struct EnvMapTables {
    /// Table resolution in cells, [width, height].
    pub resolution: [usize; 2],
    /// Cell masses proportional to luminance * solid angle; None for a black map.
    pub distribution: Option<PiecewiseConstant2D>,
    /// Cell masses proportional to max(0, luminance - mean) * solid angle; None if not built.
    pub compensated: Option<PiecewiseConstant2D>,
    /// Texels with a NaN or infinite channel, counted and treated as black (the loader rejects
    /// them, so this is 0 for loaded maps).
    pub bad_texels: usize,
    /// The lookup the table was built for.
    pub lookup: EnvLookup,
    /// Per table row, [`cell_pdf_to_solid_angle`]'s divisor 2 pi nv band: its sines once per
    /// row at build rather than per lookup.
    row_divisor: Vec<f64>,
}

impl std::fmt::Debug for EnvMapTables {
    // The tables hold one value per texel: print their shape, not their contents.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvMapTables")
            .field("resolution", &self.resolution)
            .field("integral", &self.distribution.as_ref().map(|d| d.integral()))
            .field("compensated", &self.compensated.is_some())
            .field("bad_texels", &self.bad_texels)
            .field("lookup", &self.lookup)
            .finish()
    }
}

/// A texel as the light uses it: negative channels clamped to 0, a non-finite texel black.
pub fn clean_texel(t: Vec3) -> Vec3 {
    if t.is_finite() { t.max(Vec3::ZERO) } else { Vec3::ZERO }
}

/// Solid angle of row `j` of `n` lat-long rows over 2 pi: cos theta0 - cos theta1, written as
/// 2 sin(mid) sin(half-width) so it keeps its precision at the poles. The rows sum to 2.
pub fn row_band(j: usize, n: usize) -> f64 {
    let n = n as f64;
    2.0 * (PI64 * (j as f64 + 0.5) / n).sin() * (PI64 / (2.0 * n)).sin()
}

/// Moves a uniform position `t` in [0, 1] across row `j` of `n` to the polar angle at which
/// cos(theta) has moved the same fraction of the row's range (uniform in solid angle).
fn theta_in_row(t: f64, j: usize, n: usize) -> f64 {
    let (t0, t1) = (PI64 * j as f64 / n as f64, PI64 * (j + 1) as f64 / n as f64);
    // 1 - cos(theta) = 2 sin^2(theta / 2) keeps the cosines exact near the north pole; rows
    // nearer the south pole are mirrored so the same holds there.
    let mirrored = 2 * j + 1 > n;
    let (a0, a1, t) = if mirrored { (PI64 - t1, PI64 - t0, 1.0 - t) } else { (t0, t1, t) };
    let one_minus_cos = |a: f64| 2.0 * (a / 2.0).sin().powi(2);
    let c = one_minus_cos(a0) + t.clamp(0.0, 1.0) * (one_minus_cos(a1) - one_minus_cos(a0));
    let theta = 2.0 * (c / 2.0).sqrt().min(1.0).asin();
    if mirrored { PI64 - theta } else { theta }
}

/// Per-texel luminance (Rec. 709 Y, f64) of the radiance the `lookup` returns, averaged over each
/// texel's footprint; and how many texels were not finite.
pub fn texel_luminance(image: &RgbImage, lookup: EnvLookup) -> (Vec<f64>, usize) {
    let (w, h) = (image.width, image.height);
    let mut bad = 0;
    let lum: Vec<f64> = image
        .pixels
        .iter()
        .take(w * h)
        .map(|&t| {
            bad += usize::from(!t.is_finite());
            let t = clean_texel(t);
            LUMINANCE_WEIGHTS.as_dvec3().dot(t.as_dvec3())
        })
        .collect();
    let lum = match lookup {
        EnvLookup::Nearest => lum,
        EnvLookup::Bilinear => footprint_average(&lum, w, h),
    };
    (lum, bad)
}

/// The separable [1, 6, 1] / 8 filter: the mean of the bilinear interpolant over each texel
/// (in 1D, the half texel toward a neighbour averages 1/4 of it and 3/4 of the centre).
fn footprint_average(lum: &[f64], w: usize, h: usize) -> Vec<f64> {
    let mut rows = vec![0.0; w * h];
    for y in 0..h {
        let r = &lum[y * w..(y + 1) * w];
        for x in 0..w {
            let (l, c, n) = (r[(x + w - 1) % w], r[x], r[(x + 1) % w]);
            rows[y * w + x] = (l + 6.0 * c + n) / 8.0;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
        for x in 0..w {
            out[y * w + x] = (rows[up * w + x] + 6.0 * rows[y * w + x] + rows[down * w + x]) / 8.0;
        }
    }
    out
}

/// For each of `coarse` equal cells over [0, 1], the fine cells (of `fine`) it overlaps and the
/// fraction of the coarse cell each covers (the fractions sum to 1), in exact integer arithmetic.
fn overlap_weights(fine: usize, coarse: usize) -> Vec<Vec<(usize, f64)>> {
    (0..coarse)
        .map(|c| {
            // In units of 1 / (fine * coarse): coarse cell c is [c * fine, (c + 1) * fine).
            let (c0, c1) = (c * fine, (c + 1) * fine);
            (c0 / coarse..c1.div_ceil(coarse).min(fine))
                .filter_map(|i| {
                    let len = c1.min((i + 1) * coarse).saturating_sub(c0.max(i * coarse));
                    (len > 0).then_some((i, len as f64 / fine as f64))
                })
                .collect()
        })
        .collect()
}

/// Area-averages a `w` x `h` grid onto `nw` x `nh` cells. A coarse cell is nonzero exactly when
/// a fine cell it overlaps is.
fn downsample(f: &[f64], w: usize, h: usize, nw: usize, nh: usize) -> Vec<f64> {
    if (nw, nh) == (w, h) {
        return f.to_vec();
    }
    let (wu, wv) = (overlap_weights(w, nw), overlap_weights(h, nh));
    let mut rows = vec![0.0; nw * h];
    for y in 0..h {
        for (x, ws) in wu.iter().enumerate() {
            rows[y * nw + x] = ws.iter().map(|&(i, k)| f[y * w + i] * k).sum();
        }
    }
    let mut out = vec![0.0; nw * nh];
    for (y, ws) in wv.iter().enumerate() {
        for x in 0..nw {
            out[y * nw + x] = ws.iter().map(|&(j, k)| rows[j * nw + x] * k).sum();
        }
    }
    out
}

/// The table size for an image of `w` x `h` and an optional maximum width.
pub fn table_resolution(w: usize, h: usize, max_width: Option<usize>) -> [usize; 2] {
    let nw = max_width.map_or(w, |m| m.max(1)).min(w).max(1);
    if nw == w {
        return [w.max(1), h.max(1)];
    }
    let nh = ((h as f64 * nw as f64 / w as f64).round() as usize).clamp(1, h.max(1));
    [nw, nh]
}

/// A distribution of `f`, or None if it is zero everywhere.
fn distribution_of(f: &[f64], nw: usize, nh: usize) -> Option<PiecewiseConstant2D> {
    let f32s: Vec<f32> = f.iter().map(|&v| v.min(f32::MAX as f64) as f32).collect();
    if f32s.iter().all(|&v| v <= 0.0) {
        return None;
    }
    Some(PiecewiseConstant2D::new(&f32s, nw, nh))
}

impl EnvMapTables {
    /// Tables at the image's resolution for bilinear lookup; `compensate` also builds the MIS
    /// variant.
    pub fn build(image: &RgbImage, compensate: bool) -> Self {
        Self::build_with(image, EnvTableOptions { compensate, ..Default::default() })
    }

    /// Tables with explicit options. An image whose pixel count does not match its size uses
    /// the pixels present (missing ones black).
    pub fn build_with(image: &RgbImage, options: EnvTableOptions) -> Self {
        let (w, h) = (image.width.max(1), image.height.max(1));
        let (mut lum, bad_texels) = texel_luminance(image, options.lookup);
        lum.resize(w * h, 0.0);
        // Row solid angles, scaled to average 1 (a constant factor does not change the density).
        let band: Vec<f64> = (0..h).map(|y| row_band(y, h) * h as f64 / 2.0).collect();
        let importance: Vec<f64> = lum.iter().enumerate().map(|(i, l)| l * band[i / w]).collect();
        let [nw, nh] = table_resolution(w, h, options.max_width);
        let distribution = distribution_of(&downsample(&importance, w, h, nw, nh), nw, nh);
        let compensated = if options.compensate && distribution.is_some() {
            // The solid-angle mean: sum L Omega / sum Omega over all texels.
            let mean = importance.iter().sum::<f64>() / (w * h) as f64;
            // Excesses within rounding of the mean (a constant map) count as none.
            let excess = |l: f64| if l - mean > 1e-9 * mean { l - mean } else { 0.0 };
            let comp: Vec<f64> = lum.iter().enumerate().map(|(i, &l)| excess(l) * band[i / w]).collect();
            distribution_of(&downsample(&comp, w, h, nw, nh), nw, nh)
        } else {
            None
        };
        let row_divisor = (0..nh).map(|row| row_divisor(row, nh)).collect();
        Self { resolution: [nw, nh], distribution, compensated, bad_texels, lookup: options.lookup, row_divisor }
    }

    /// The distribution used for complete (`mis == false`) or MIS-compensated sampling.
    pub fn distribution(&self, mis: bool) -> Option<&PiecewiseConstant2D> {
        if mis { self.compensated.as_ref().or(self.distribution.as_ref()) } else { self.distribution.as_ref() }
    }

    /// A direction in the image's frame (unit, +Y up) drawn from the table, and its solid-angle
    /// density; None for a black map.
    pub fn sample_direction(&self, u: Vec2, mis: bool) -> Option<(Vec3, f32)> {
        let dist = self.distribution(mis)?;
        let (uv, pdf_uv, [_, row]) = dist.sample(u);
        let nv = self.resolution[1];
        let t = uv.y as f64 * nv as f64 - row as f64;
        let v = (theta_in_row(t, row, nv) / PI64) as f32;
        let dir = lat_long_direction(Vec2::new(uv.x, v));
        let pdf = density_over(pdf_uv, self.row_divisor[row]);
        (pdf > 0.0).then_some((dir, pdf))
    }

    /// Solid-angle density of [`Self::sample_direction`] at `dir` (image frame); 0 for a black map.
    pub fn pdf_direction(&self, dir: Vec3, mis: bool) -> f32 {
        self.pdf_solid_angle(direction_to_lat_long(dir), mis)
    }

    /// Solid-angle density of [`Self::sample_direction`] at the direction of lat-long `uv`.
    pub fn pdf_solid_angle(&self, uv: Vec2, mis: bool) -> f32 {
        let Some(dist) = self.distribution(mis) else { return 0.0 };
        let nv = self.resolution[1];
        // The same f64 bin arithmetic as the distribution's lookup.
        let row = ((uv.y as f64 * nv as f64) as usize).min(nv - 1);
        density_over(dist.pdf(uv), self.row_divisor[row])
    }

    /// Density in (u, v) of the table itself at `uv`; 0 for a black map or outside [0, 1]^2.
    pub fn pdf_uv(&self, uv: Vec2, mis: bool) -> f32 {
        self.distribution(mis).map_or(0.0, |d| d.pdf(uv))
    }
}

/// Solid-angle density of a cell of (u, v) density `pdf_uv` in row `row` of `nv`: its mass
/// pdf_uv / (nu nv) over its solid angle (2 pi / nu) * band, i.e. pdf_uv / (2 pi nv band).
/// 0 for a zero or non-finite result.
pub fn cell_pdf_to_solid_angle(pdf_uv: f32, row: usize, nv: usize) -> f32 {
    density_over(pdf_uv, row_divisor(row, nv))
}

/// 2 pi nv band of row `row` of `nv`.
fn row_divisor(row: usize, nv: usize) -> f64 {
    2.0 * PI64 * nv as f64 * row_band(row, nv)
}

/// pdf_uv / divisor, 0 for a zero or non-finite result.
#[inline]
fn density_over(pdf_uv: f32, divisor: f64) -> f32 {
    if !(pdf_uv > 0.0) {
        return 0.0;
    }
    let pdf = (pdf_uv as f64 / divisor) as f32;
    if pdf.is_finite() { pdf } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
