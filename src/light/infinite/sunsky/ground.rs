//! The ground below the horizon: scenes without ground geometry see, below the horizon, a
//! Lambertian ground of the light's `ground_albedo` lit by the sun and sky, of radiance
//! L = albedo E / pi with E the horizontal irradiance of sun plus sky (the bounce Mitsuba's and
//! pbrt's skies leave black, and the same albedo the Hosek-Wilkie sky already assumes for its
//! own ground-bounce term). The atmosphere between the viewer and the ground is not modelled: a
//! viewer near the ground. Scenes with a floor hide it behind their own.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};

use super::SunDisc;
use super::hosek::{SkyModel, WAVELENGTHS_NM};
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage};

/// Cells of the cosine-weighted grid of the spectral sky irradiance: sin^2 theta by phi.
const GRID: (usize, usize) = (32, 64);

/// Horizontal irradiance of the upper half of a lat-long image of radiance (row 0 at the zenith),
/// per channel: the sum of texel x the exact integral of cos theta over the texel,
/// d_phi (cos^2 theta_0 - cos^2 theta_1) / 2.
pub fn image_horizontal_irradiance(image: &RgbImage) -> DVec3 {
    let (w, h) = (image.width, image.height);
    let d_phi = std::f64::consts::TAU / w as f64;
    let cos = |y: usize| (PI * y as f64 / h as f64).cos();
    (0..h / 2)
        .map(|y| {
            let band = 0.5 * d_phi * (cos(y).powi(2) - cos(y + 1).powi(2));
            image.pixels[y * w..(y + 1) * w].iter().map(|p| p.as_dvec3()).sum::<DVec3>() * band
        })
        .sum()
}

/// The sun's normal irradiance in photometric linear sRGB (lx per channel): its limb polynomial
/// over the disc, mu^k averaging 2 / (k + 2) (as [`SunDisc`]'s illuminance).
pub fn sun_rgb_irradiance(sun: &SunDisc) -> DVec3 {
    let mean = |k: usize| 2.0 / (k as f64 + 2.0);
    (0..6).map(|k| sun.rgb_limb[k].as_dvec3() * mean(k)).sum::<DVec3>() * sun.solid_angle() as f64
}

/// The sun's normal spectral irradiance at the model wavelengths, W/(m^2 nm).
fn sun_spectral_irradiance(sun: &SunDisc) -> [f64; 11] {
    let mean = |k: usize| 2.0 / (k as f64 + 2.0);
    std::array::from_fn(|i| {
        let limb: f64 = (0..6).map(|k| sun.model.limb[i][k] as f64 * mean(k)).sum();
        sun.model.radiance[i] as f64 * limb * (sun.solid_angle() * sun.size_factor) as f64
    })
}

/// The ground's radiance, before the light's scale: (linear sRGB nit, spectral W/(m^2 sr nm) at
/// [`WAVELENGTHS_NM`]). `sky_e` is the RGB sky's horizontal irradiance from its image
/// ([`image_horizontal_irradiance`]); `sun_up` the sine of the sun's (apparent) elevation.
///
/// The spectral sky irradiance comes from a cosine-weighted midpoint grid ([`GRID`]), scaled by
/// the ratio of the image's luminous irradiance to the same grid's for the RGB sky: the grid is
/// too coarse for the circumsolar peak, the ratio carries the image's resolution over.
pub fn ground_radiance(
    sky: &SkyModel,
    sun_dir: Vec3,
    sun: Option<&SunDisc>,
    sky_e: DVec3,
    albedo: f32,
) -> (Vec3, [f32; 11]) {
    let k = albedo as f64 / PI;
    let sun_up = sun_dir.y.max(0.0) as f64;
    let sun_rgb = sun.map_or(DVec3::ZERO, sun_rgb_irradiance);
    let rgb = (sky_e + sun_rgb * sun_up).max(DVec3::ZERO) * k;

    let (nu, nphi) = GRID;
    let (mut spec, mut grid_rgb) = ([0.0f64; 11], DVec3::ZERO);
    for i in 0..nu {
        let sin2 = (i as f64 + 0.5) / nu as f64;
        let (sin_t, cos_t) = (sin2.sqrt(), (1.0 - sin2).sqrt());
        for j in 0..nphi {
            let (s, c) = (std::f64::consts::TAU * (j as f64 + 0.5) / nphi as f64).sin_cos();
            let w = DVec3::new(sin_t * c, cos_t, sin_t * s).as_vec3();
            grid_rgb += sky.rgb_nits(w, sun_dir).as_dvec3();
            for (e, &lambda) in spec.iter_mut().zip(&WAVELENGTHS_NM) {
                *e += sky.spectral(lambda, w, sun_dir) as f64;
            }
        }
    }
    // E = pi x the mean radiance over cosine-distributed directions.
    let cells = (nu * nphi) as f64;
    let weights = LUMINANCE_WEIGHTS.as_dvec3();
    let (image_y, grid_y) = (weights.dot(sky_e), weights.dot(grid_rgb) * PI / cells);
    let fix = if grid_y > 0.0 { image_y / grid_y } else { 1.0 };
    let sun_spec = sun.map_or([0.0; 11], sun_spectral_irradiance);
    let spectral = std::array::from_fn(|i| (k * (spec[i] * PI / cells * fix + sun_spec[i] * sun_up)) as f32);
    (rgb.as_vec3(), spectral)
}

/// Fills the lower half of the sky image (below the horizon) with the ground's radiance `rgb`,
/// and its rows' luminance sums.
pub fn fill_ground(image: &mut RgbImage, row_luminance: &mut [f64], rgb: Vec3) {
    let (w, h) = (image.width, image.height);
    let lum = LUMINANCE_WEIGHTS.as_dvec3().dot(rgb.as_dvec3()) * w as f64;
    for y in h / 2..h {
        image.pixels[y * w..(y + 1) * w].fill(rgb);
        row_luminance[y] = lum;
    }
}
