//! Goniometric light: a point light whose intensity varies with direction by a measured profile
//! (pbrt-v4 `GoniometricLight`, section 12.2.3): an IES file, or an image over the sphere of
//! directions.
//!
//! # Profiles and frame
//!
//! Profiles live in the light's local frame (the entity's rotation; local -Z is the light's
//! forward, where a downlight points):
//! - [`GonioProfile::Ies`]: candela values of an IES LM-63 file, local -Z being photometric nadir
//!   (see [`crate::scene::ies`]); continuous (the file's bilinear interpolant).
//! - [`GonioProfile::EqualAreaImage`]: a square image on Clarberg's equal-area octahedral map
//!   (pbrt-v4's goniometric images): texel (x, y) (row y from the top) covers the directions
//!   around `equal_area_square_to_sphere(((x + 0.5) / n, (y + 0.5) / n))`, the square's centre
//!   being local +Z and its corners local -Z (the layout of `IesProfile::to_equal_area_image`).
//!   Every texel covers 4 pi / n^2 sr.
//! - [`GonioProfile::LatLong`]: an equirectangular image in the light's local frame with
//!   kelvin's lat-long mapping (`scene::image::lat_long_direction`: row 0 toward local +Y).
//!
//! Image texels are looked up nearest, so each covers a sharp-edged patch of directions and the
//! light's power is exact. An image profile's value is its texel's Rec. 709 luminance and its
//! colour tints the light's spectrum.
//!
//! # Intensity and power
//!
//! I(w) = s * profile(w), with s from `amount`: a scale in cd (or W/sr) per unit of the profile,
//! or a total power to which the profile is normalised. Phi = s * integral of profile(w) dw:
//! the IES file's exactly integrated flux (`IesProfile::integrated_flux_lm`), 4 pi / n^2 * sum of
//! texel luminances for equal-area images, and sum of Y_i * dphi * (cos theta0 - cos theta1) over
//! the rows of a lat-long image.
//!
//! # Sampling
//!
//! Emission directions follow the profile: IES profiles and equal-area images through a
//! `PiecewiseConstant2D` over the equal-area square (the map preserves area, so
//! pdf_w = pdf_square / (4 pi)); lat-long images through one over the image with weights Y_i
//! Omega_i, uniformly in (phi, cos theta) within a texel (pdf_w = Y_i / sum_j Y_j Omega_j).

use std::f32::consts::PI;
use std::f64::consts::{PI as PI64, TAU};
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{Quat, Vec2, Vec3};

use super::emitter::check_amount;
use super::projection::check_image;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, Quantity};
use crate::geometry::Transform;
use crate::sampling::{PiecewiseConstant2D, equal_area_sphere_to_square, equal_area_square_to_sphere};
use crate::scene::ies::IesProfile;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage, direction_to_lat_long};
use crate::spectrum::{SampledSpectrum, Spectrum};

/// Resolution of the equal-area sampling table built for IES profiles (128^2 texels of 1.6 degrees).
pub const IES_SAMPLING_RESOLUTION: usize = 128;
/// Sub-samples per axis and texel when building that table, so that narrow beams are not missed.
const IES_SUPERSAMPLING: usize = 3;
/// Floor of the IES sampling weights, relative to their mean: every direction keeps a nonzero
/// density, so directions the table under-rates still count (unbiased; costs at most 0.1% of samples).
const IES_WEIGHT_FLOOR: f64 = 1e-3;

/// Where a goniometric light's directional distribution comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum GonioProfile {
    /// A parsed IES file; values in cd.
    Ies(Arc<IesProfile>),
    /// A square image on the equal-area octahedral map (module docs).
    EqualAreaImage(Arc<RgbImage>),
    /// An equirectangular image around the light (module docs).
    LatLong(Arc<RgbImage>),
}

/// A point light at its entity's translation with a measured directional profile.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct GoniometricLight {
    /// Relative intensity over directions in the light's local frame (module docs).
    pub profile: GonioProfile,
    /// Scale in cd (or W/sr) per unit of the profile, or total power (lm or W) to which the profile
    /// is normalised. Defaults to 1 cd: an IES file's own candela values, image texels as candela.
    pub amount: Amount,
    /// Spectral shape; image texels tint it. Defaults to D65 (white).
    pub spectrum: Spectrum,
    /// Whether shadow rays are traced for this light. Defaults to true.
    pub casts_shadows: bool,
}

impl GoniometricLight {
    /// A white light with `profile` at its own values (1 cd per unit).
    pub fn new(profile: GonioProfile) -> Self {
        Self { profile, amount: Amount::Candela(1.0), spectrum: Spectrum::d65(), casts_shadows: true }
    }

    /// A white light emitting as the IES file says.
    pub fn from_ies(profile: Arc<IesProfile>) -> Self {
        Self::new(GonioProfile::Ies(profile))
    }

    /// World-space form with its sampling table; errors for bad amounts and images.
    pub fn resolve(&self, transform: &Transform) -> Result<ResolvedGoniometric, LightError> {
        const LIGHT: &str = "GoniometricLight";
        let amount =
            check_amount(self.amount, LIGHT, "amount", &[Quantity::Intensity, Quantity::Power], "cd, W/sr, lm or W")?;
        let (unit_power, sampler) = match &self.profile {
            GonioProfile::Ies(ies) => {
                // Values are used as f32: a profile whose flux could exceed f32 is refused (found by fuzzing).
                if !(ies.max_candela() * 4.0 * PI64 <= f32::MAX as f64) {
                    return Err(LightError::Invalid {
                        light: LIGHT,
                        msg: format!("IES candela values up to {:e} cd are too large for f32", ies.max_candela()),
                    });
                }
                ies_sampler(ies)
            }
            GonioProfile::EqualAreaImage(image) => {
                check_image(image, LIGHT)?;
                if image.width != image.height {
                    return Err(LightError::Invalid {
                        light: LIGHT,
                        msg: format!(
                            "an equal-area profile image must be square, got {} x {}",
                            image.width, image.height
                        ),
                    });
                }
                let weights: Vec<f32> = image.pixels.iter().map(|p| p.dot(LUMINANCE_WEIGHTS)).collect();
                let sum: f64 = weights.iter().map(|&w| w as f64).sum();
                let unit_power = sum * 4.0 * PI64 / weights.len() as f64;
                (unit_power, DirectionSampler::EqualArea(PiecewiseConstant2D::new(&weights, image.width, image.height)))
            }
            GonioProfile::LatLong(image) => {
                check_image(image, LIGHT)?;
                lat_long_sampler(image)
            }
        };
        let mut intensity = Emitter::from_amount(self.spectrum.clone(), amount);
        if amount.quantity() == Quantity::Power {
            intensity = intensity.scaled(if unit_power > 0.0 { (1.0 / unit_power) as f32 } else { 0.0 });
        }
        let resolved = ResolvedGoniometric {
            position: transform.translation,
            rotation: transform.aim(),
            profile: self.profile.clone(),
            intensity,
            unit_power,
            sampler,
        };
        let phi = resolved.phi();
        if !phi.is_finite() {
            return Err(LightError::Invalid { light: LIGHT, msg: format!("power {phi} W overflows f32") });
        }
        Ok(resolved)
    }
}

/// The integral of the IES profile (lm per cd of scale) and an equal-area table of supersampled,
/// floored candela values.
fn ies_sampler(ies: &IesProfile) -> (f64, DirectionSampler) {
    let (n, k) = (IES_SAMPLING_RESOLUTION, IES_SUPERSAMPLING);
    let mut weights = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let mut sum = 0.0;
            for j in 0..k {
                for i in 0..k {
                    let p = Vec2::new(
                        (x as f32 + (i as f32 + 0.5) / k as f32) / n as f32,
                        (y as f32 + (j as f32 + 0.5) / k as f32) / n as f32,
                    );
                    sum += ies.candela_dir(equal_area_square_to_sphere(p));
                }
            }
            weights.push(sum / (k * k) as f64);
        }
    }
    let mean = weights.iter().sum::<f64>() / weights.len() as f64;
    // A profile the table cannot see at all still gets a density (uniform) so sampling stays unbiased.
    let floor = if mean > 0.0 { IES_WEIGHT_FLOOR * mean } else { 1.0 };
    let weights: Vec<f32> = weights.iter().map(|&w| w.max(floor) as f32).collect();
    (ies.integrated_flux_lm(), DirectionSampler::EqualArea(PiecewiseConstant2D::new(&weights, n, n)))
}

/// Polar angles of the top and bottom of lat-long row `y` (of `height`).
fn lat_long_row_cos(y: usize, height: usize) -> (f64, f64) {
    ((PI64 * y as f64 / height as f64).cos(), (PI64 * (y + 1) as f64 / height as f64).cos())
}

/// The integral of a lat-long image's luminance over the sphere and its sampling table.
fn lat_long_sampler(image: &Arc<RgbImage>) -> (f64, DirectionSampler) {
    let (w, h) = (image.width, image.height);
    let dphi = TAU / w as f64;
    let mut weights = Vec::with_capacity(w * h);
    let mut total = 0.0;
    for y in 0..h {
        let (c0, c1) = lat_long_row_cos(y, h);
        let omega = dphi * (c0 - c1);
        for x in 0..w {
            let v = image.luminance(x, y) as f64 * omega;
            total += v;
            weights.push(v as f32);
        }
    }
    let distribution = PiecewiseConstant2D::new(&weights, w, h);
    (total, DirectionSampler::LatLong { distribution, image: image.clone(), total })
}

/// How emission directions are drawn (module docs).
#[derive(Clone, Debug, PartialEq)]
enum DirectionSampler {
    /// Over the equal-area square: pdf_w = pdf_square / (4 pi).
    EqualArea(PiecewiseConstant2D),
    /// Over a lat-long image, weights Y_i Omega_i summing to `total`.
    LatLong { distribution: PiecewiseConstant2D, image: Arc<RgbImage>, total: f64 },
}

/// A goniometric light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedGoniometric {
    /// World-space position, metres.
    pub position: Vec3,
    /// Local-to-world rotation (unit).
    pub rotation: Quat,
    /// Relative intensity over local directions, scaled by `intensity`.
    pub profile: GonioProfile,
    /// Radiant intensity per unit of the profile, W/sr (with its photometric RGB in cd).
    pub intensity: Emitter,
    /// Integral of the profile over the sphere (profile unit x sr).
    unit_power: f64,
    sampler: DirectionSampler,
}

/// Nearest texel of an image at `uv` in [0, 1]^2.
fn nearest(image: &RgbImage, uv: Vec2) -> (usize, usize) {
    let x = ((uv.x * image.width as f32) as usize).min(image.width - 1);
    let y = ((uv.y * image.height as f32) as usize).min(image.height - 1);
    (x, y)
}

impl ResolvedGoniometric {
    /// The profile toward local direction `w` as linear RGB whose luminance is the profile value
    /// (grey for IES profiles).
    fn profile_rgb(&self, w: Vec3) -> Vec3 {
        match &self.profile {
            GonioProfile::Ies(ies) => Vec3::splat(ies.candela_dir(w) as f32),
            GonioProfile::EqualAreaImage(image) => {
                let (x, y) = nearest(image, equal_area_sphere_to_square(w));
                image.get(x, y)
            }
            GonioProfile::LatLong(image) => {
                let (x, y) = nearest(image, direction_to_lat_long(w));
                image.get(x, y)
            }
        }
    }

    /// Profile value toward world direction `w` (from the light): cd for IES files, texel
    /// luminance for images.
    pub fn profile_value(&self, w: Vec3) -> f32 {
        match &self.profile {
            GonioProfile::Ies(ies) => ies.candela_dir(self.rotation.inverse() * w) as f32,
            _ => self.profile_rgb(self.rotation.inverse() * w).dot(LUMINANCE_WEIGHTS),
        }
    }

    /// Radiant intensity toward world direction `w` (from the light), W/sr.
    pub fn intensity_toward(&self, w: Vec3) -> f32 {
        self.intensity.radiometric * self.profile_value(w)
    }

    /// Intensity toward world direction `w` in the query's colour mode.
    pub fn intensity_spectrum(&self, w: Vec3, query: ColorQuery) -> SampledSpectrum {
        let local = self.rotation.inverse() * w;
        match &self.profile {
            GonioProfile::Ies(ies) => self.intensity.eval(query).scale(ies.candela_dir(local) as f32),
            _ => self.intensity.eval_tinted(query, self.profile_rgb(local)),
        }
    }

    /// The delta direction toward the light with radiance I(-wi) / r^2; None at the light or where
    /// the profile is dark.
    pub fn sample_li(&self, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let (wi, r2) = ctx.toward(self.position)?;
        let i = self.intensity_spectrum(-wi, query);
        if i.0.iter().all(|&v| v == 0.0) {
            return None;
        }
        Some(LiSample { radiance: i.scale(1.0 / r2), wi, pdf: 1.0, p_light: self.position, n_light: Vec3::ZERO })
    }

    /// A delta light is never hit by sampled directions.
    pub fn pdf_li(&self) -> f32 {
        0.0
    }

    /// An emission direction (world, unit) with its solid-angle density, following the profile;
    /// None when the light is black.
    pub fn sample_emission_direction(&self, u: Vec2) -> Option<(Vec3, f32)> {
        if !(self.unit_power > 0.0) {
            return None;
        }
        let (local, pdf) = match &self.sampler {
            DirectionSampler::EqualArea(distribution) => {
                let (p, pdf, _) = distribution.sample(u);
                (equal_area_square_to_sphere(p), pdf / (4.0 * PI))
            }
            DirectionSampler::LatLong { distribution, image, total } => {
                let (uv, _, [ix, iy]) = distribution.sample(u);
                let h = image.height;
                // Uniform in (phi, cos theta) inside the texel: uniform over its solid angle.
                let fy = (uv.y as f64 * h as f64 - iy as f64).clamp(0.0, 1.0);
                let (c0, c1) = lat_long_row_cos(iy, h);
                let cos_theta = c0 + (c1 - c0) * fy;
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let phi = TAU * (uv.x as f64 - 0.5);
                let d = glam::DVec3::new(sin_theta * phi.cos(), cos_theta, sin_theta * phi.sin());
                (d.as_vec3(), (image.luminance(ix, iy) as f64 / total) as f32)
            }
        };
        (pdf > 0.0).then_some((self.rotation * local, pdf))
    }

    /// Solid-angle density of [`Self::sample_emission_direction`] at world direction `w` (unit).
    pub fn pdf_emission_direction(&self, w: Vec3) -> f32 {
        if !(self.unit_power > 0.0) {
            return 0.0;
        }
        let local = self.rotation.inverse() * w;
        match &self.sampler {
            DirectionSampler::EqualArea(distribution) => {
                distribution.pdf(equal_area_sphere_to_square(local)) / (4.0 * PI)
            }
            DirectionSampler::LatLong { image, total, .. } => {
                let (x, y) = nearest(image, direction_to_lat_long(local));
                (image.luminance(x, y) as f64 / total) as f32
            }
        }
    }

    /// Radiant power, W: s * integral of the profile (module docs).
    pub fn phi(&self) -> f32 {
        (self.intensity.radiometric as f64 * self.unit_power) as f32
    }

    /// Bounds for light BVHs: like a point light, emitting every way (pbrt-v4).
    pub fn bounds(&self) -> LightBounds {
        LightBounds {
            min: self.position,
            max: self.position,
            phi: self.phi(),
            w: self.rotation * Vec3::NEG_Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        }
    }
}
