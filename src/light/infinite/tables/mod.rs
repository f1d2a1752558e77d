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

mod build;

/// A texel row's luminance as the build computes it: for the per-stage benchmark (benches/env_stages.rs).
#[cfg(feature = "internals")]
#[doc(hidden)]
pub use build::lum_row;
pub use build::{MEAN_TOLERANCE, texel_luminance};
#[cfg(test)]
mod tests;

use std::f64::consts::PI as PI64;

use glam::{Vec2, Vec3};

use crate::lanes::{LANES, Real, Vector};
use crate::sampling::PiecewiseConstant2D;
use crate::scene::image::{RgbImage, direction_to_lat_long, lat_long_direction};

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
    /// What the tables were built with and the buffers kept for rebuilds (build.rs).
    state: build::BuildState,
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
    clean_texel_of(t)
}

/// [`clean_texel`] for one texel or a lane each (the same bits).
#[inline(always)]
pub fn clean_texel_of<V: Vector>(t: V) -> V {
    let zero = V::Real::splat(0.0);
    let [x, y, z] = t.xyz();
    V::select(t.is_finite(), V::new(x.max(zero), y.max(zero), z.max(zero)), V::zero())
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

/// The table size for an image of `w` x `h` and an optional maximum width.
pub fn table_resolution(w: usize, h: usize, max_width: Option<usize>) -> [usize; 2] {
    let nw = max_width.map_or(w, |m| m.max(1)).min(w).max(1);
    if nw == w {
        return [w.max(1), h.max(1)];
    }
    let nh = ((h as f64 * nw as f64 / w as f64).round() as usize).clamp(1, h.max(1));
    [nw, nh]
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
        let mut t = Self::empty(options);
        t.rebuild(image, options);
        t
    }

    /// The distribution used for complete (`mis == false`) or MIS-compensated sampling.
    pub fn distribution(&self, mis: bool) -> Option<&PiecewiseConstant2D> {
        if mis { self.compensated.as_ref().or(self.distribution.as_ref()) } else { self.distribution.as_ref() }
    }

    /// A direction in the image's frame (unit, +Y up) drawn from the table, and its solid-angle
    /// density; None for a black map.
    pub fn sample_direction(&self, u: Vec2, mis: bool) -> Option<(Vec3, f32)> {
        let dist = self.distribution(mis)?;
        self.direction_in(dist.sample(u))
    }

    /// [`Self::sample_direction`] at a lane each, the same results (the table's searches in
    /// lock step: see [`PiecewiseConstant2D::sample_lanes`]).
    #[inline(always)]
    pub fn sample_direction_lanes(&self, u: &[Vec2; LANES], mis: bool) -> [Option<(Vec3, f32)>; LANES] {
        let Some(dist) = self.distribution(mis) else { return [None; LANES] };
        dist.sample_lanes(u).map(|s| self.direction_in(s))
    }

    /// The direction and solid-angle density of table sample `(uv, pdf_uv, [_, row])`.
    #[inline(always)]
    fn direction_in(&self, (uv, pdf_uv, [_, row]): (Vec2, f32, [usize; 2])) -> Option<(Vec3, f32)> {
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
