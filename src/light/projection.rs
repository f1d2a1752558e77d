//! Projection light: a point light that shines an image through a perspective frustum, like a
//! slide projector (pbrt-v4 `ProjectionLight`, section 12.2.2).
//!
//! # Geometry
//!
//! The light sits at its entity's translation and looks along its local -Z axis. The image covers
//! the window [-sx, sx] x [-sy, sy] of the plane z = -1 in the light's local frame: row 0 along +Y,
//! column 0 along -X, so someone standing behind the projector sees the picture upright and
//! unmirrored on a wall. `fov` is the full angle spanned by the image's shorter side (pbrt-v4's
//! convention): the shorter half-extent is tan(fov / 2) and the longer one that times the aspect
//! ratio. Directions outside the window get nothing.
//!
//! # Intensity and power
//!
//! Toward a direction through texel c (linear RGB) the intensity is I = s * c, where s is the
//! intensity of a texel (1, 1, 1) (the light's `amount`). Texels are looked up nearest, so each
//! projects as a sharp-edged rectangle and the power has a closed form. pbrt-v4 writes
//! Phi = integral over the screen of I cos^3 theta dA (on a plane at unit distance
//! dw = cos^3 theta dA, i.e. I / distance^3); over one texel that integral is the solid angle
//! Omega_i of the texel's rectangle, so Phi = s * sum_i Y(c_i) Omega_i, with Y the Rec. 709
//! luminance (exact for grey texels; for coloured texels it is the photometric power divided by
//! the base spectrum's efficacy). Omega of [x0, x1] x [y0, y1] on the plane at unit distance is
//! F(x1, y1) - F(x0, y1) - F(x1, y0) + F(x0, y0) with F(x, y) = atan(x y / sqrt(1 + x^2 + y^2)),
//! the solid angle of a rectangle seen from above one corner (R. J. Mathar, "Solid angle of a
//! rectangular plate", 2014), F being odd in x and y.
//!
//! # Sampling
//!
//! Emission directions are drawn from a `PiecewiseConstant2D` over the image's (u, v) square with
//! texel weights Y(c_i) Omega_i (pbrt-v4 weights by cos^3 theta at the texel centre; the exact
//! solid angle makes each texel's probability its share of the power), uniformly over the texel's
//! rectangle on the plane. The density converts from the plane to solid angle as in pbrt-v4
//! section 12.2.2: pdf_w = pdf_uv / (A cos^3 theta), A = 4 sx sy the window's area.

use std::f32::consts::FRAC_PI_2;
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{DVec2, Quat, Vec2, Vec3};

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, Quantity};
use crate::geometry::Transform;
use crate::sampling::PiecewiseConstant2D;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage};
use crate::spectrum::{SampledSpectrum, Spectrum};

/// pbrt-v4's default field of view for projection lights: 90 degrees.
pub const DEFAULT_PROJECTION_FOV: f32 = FRAC_PI_2;

/// A light that projects `image` from its entity's translation along the entity's local -Z axis.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct ProjectionLight {
    /// The projected picture, linear RGB (finite, non-negative texels).
    pub image: Arc<RgbImage>,
    /// Full field of view of the image's shorter side, radians, in (0, pi). Defaults to pi/2.
    pub fov: f32,
    /// Intensity of a texel (1, 1, 1) (cd or W/sr), or the light's total power (lm or W), which
    /// sets that intensity through the closed-form power (see the module docs). Defaults to 1 cd,
    /// so texel values read as candela.
    pub amount: Amount,
    /// Spectral shape of a white texel; texels tint it (see [`Emitter::eval_tinted`]). Defaults
    /// to D65.
    pub spectrum: Spectrum,
    /// Whether shadow rays are traced for this light. Defaults to true.
    pub casts_shadows: bool,
}

impl ProjectionLight {
    /// A white projector of `image` with field of view `fov` (radians, shorter side); texel
    /// values are candela.
    pub fn new(image: Arc<RgbImage>, fov: f32) -> Self {
        Self { image, fov, amount: Amount::Candela(1.0), spectrum: Spectrum::d65(), casts_shadows: true }
    }

    /// World-space form for sampling; errors for a bad field of view, amount or image.
    pub fn resolve(&self, transform: &Transform) -> Result<ResolvedProjection, LightError> {
        const LIGHT: &str = "ProjectionLight";
        if !(self.fov > 0.0 && self.fov < std::f32::consts::PI) {
            return Err(LightError::Invalid {
                light: LIGHT,
                msg: format!("fov = {} rad must lie strictly between 0 and pi", self.fov),
            });
        }
        check_image(&self.image, LIGHT)?;
        let amount =
            check_amount(self.amount, LIGHT, "amount", &[Quantity::Intensity, Quantity::Power], "cd, W/sr, lm or W")?;

        let (width, height) = (self.image.width, self.image.height);
        let tan_half = (self.fov as f64 / 2.0).tan();
        let aspect = width as f64 / height as f64;
        let half = if aspect >= 1.0 {
            DVec2::new(tan_half * aspect, tan_half)
        } else {
            DVec2::new(tan_half, tan_half / aspect)
        };
        // Texel solid angles from the same (f32) window that lookups and sampling use.
        let half = half.as_vec2().as_dvec2();

        // Texel weights Y * Omega; their sum is the power per unit of s.
        let mut weights = Vec::with_capacity(width * height);
        let mut unit_power = 0.0f64;
        for y in 0..height {
            for x in 0..width {
                let omega = texel_solid_angle(half, x, y, width, height);
                let w = self.image.luminance(x, y) as f64 * omega;
                unit_power += w;
                weights.push(w as f32);
            }
        }

        let mut intensity = Emitter::from_amount(self.spectrum.clone(), amount);
        if amount.quantity() == Quantity::Power {
            intensity = intensity.scaled(if unit_power > 0.0 { (1.0 / unit_power) as f32 } else { 0.0 });
        }
        Ok(ResolvedProjection {
            position: transform.translation,
            rotation: transform.aim(),
            image: self.image.clone(),
            half_extent: half.as_vec2(),
            intensity,
            unit_power,
            distribution: PiecewiseConstant2D::new(&weights, width, height),
        })
    }
}

/// Checks an image can be a light: pixel count matches its size, every texel finite and >= 0.
pub(crate) fn check_image(image: &RgbImage, light: &'static str) -> Result<(), LightError> {
    if image.width == 0 || image.height == 0 || image.pixels.len() != image.width * image.height {
        return Err(LightError::Invalid {
            light,
            msg: format!(
                "image has {} pixels for a {} x {} size (needs at least 1 x 1)",
                image.pixels.len(),
                image.width,
                image.height
            ),
        });
    }
    if let Some(i) = image.pixels.iter().position(|p| !(p.is_finite() && p.cmpge(Vec3::ZERO).all())) {
        let p = image.pixels[i];
        return Err(LightError::Invalid {
            light,
            msg: format!(
                "image pixel (x {}, y {}) = ({}, {}, {}) must be finite and >= 0",
                i % image.width,
                i / image.width,
                p.x,
                p.y,
                p.z
            ),
        });
    }
    Ok(())
}

/// Solid angle (sr) of texel (x, y)'s rectangle on the plane at unit distance (module docs).
fn texel_solid_angle(half: DVec2, x: usize, y: usize, width: usize, height: usize) -> f64 {
    let f = |a: f64, b: f64| (a * b / (1.0 + a * a + b * b).sqrt()).atan();
    let x0 = half.x * (2.0 * x as f64 / width as f64 - 1.0);
    let x1 = half.x * (2.0 * (x + 1) as f64 / width as f64 - 1.0);
    let y0 = half.y * (1.0 - 2.0 * (y + 1) as f64 / height as f64);
    let y1 = half.y * (1.0 - 2.0 * y as f64 / height as f64);
    (f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)).max(0.0)
}

/// A projection light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedProjection {
    /// World-space position, metres.
    pub position: Vec3,
    /// Local-to-world rotation (unit); the light looks along local -Z.
    pub rotation: Quat,
    /// The projected picture, linear RGB, scaled by `intensity`.
    pub image: Arc<RgbImage>,
    /// Half-width and half-height (sx, sy) of the image window on the plane z = -1.
    pub half_extent: Vec2,
    /// Radiant intensity of a texel (1, 1, 1), W/sr (with its photometric RGB in cd).
    pub intensity: Emitter,
    /// sum_i Y(c_i) Omega_i, sr: the power per W/sr of `intensity`.
    unit_power: f64,
    /// Over the image's (u, v) square, texel weights Y * Omega.
    distribution: PiecewiseConstant2D,
}

impl ResolvedProjection {
    /// Where the world direction `w` crosses the image, as (u, v) in [0, 1]^2 (v = 0 at the top),
    /// with its cos theta to the axis; None outside the window. In f64, so that narrow fields of
    /// view keep their texels apart.
    fn window_uv(&self, w: Vec3) -> Option<(DVec2, f64)> {
        let local = self.rotation.as_dquat().inverse() * w.as_dvec3();
        if !(local.z < 0.0) {
            return None;
        }
        let p = DVec2::new(local.x, local.y) / -local.z;
        let half = self.half_extent.as_dvec2();
        let uv = DVec2::new(0.5 * (1.0 + p.x / half.x), 0.5 * (1.0 - p.y / half.y));
        let inside = uv.cmpge(DVec2::ZERO).all() && uv.cmple(DVec2::ONE).all();
        inside.then(|| (uv, -local.z / local.length()))
    }

    /// The texel (linear RGB) seen along the world direction `w` from the light (unit); zero
    /// outside the frustum.
    pub fn texel(&self, w: Vec3) -> Vec3 {
        let Some((uv, _)) = self.window_uv(w) else { return Vec3::ZERO };
        let x = ((uv.x * self.image.width as f64) as usize).min(self.image.width - 1);
        let y = ((uv.y * self.image.height as f64) as usize).min(self.image.height - 1);
        self.image.get(x, y)
    }

    /// Radiant intensity toward world direction `w` (unit, from the light), W/sr: the
    /// luminance-weighted scalar whose integral is [`Self::phi`].
    pub fn intensity_toward(&self, w: Vec3) -> f32 {
        self.intensity.radiometric * self.texel(w).dot(LUMINANCE_WEIGHTS)
    }

    /// Intensity toward world direction `w` in the query's colour mode.
    pub fn intensity_spectrum(&self, w: Vec3, query: ColorQuery) -> SampledSpectrum {
        self.intensity.eval_tinted(query, self.texel(w))
    }

    /// The delta direction toward the light with radiance I / r^2; None at the light, outside the
    /// frustum or through a black texel.
    pub fn sample_li(&self, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let (wi, r2) = ctx.toward(self.position)?;
        let tint = self.texel(-wi);
        if tint == Vec3::ZERO {
            return None;
        }
        let radiance = self.intensity.eval_tinted(query, tint).scale(1.0 / r2);
        Some(LiSample { radiance, wi, pdf: 1.0, p_light: self.position, n_light: Vec3::ZERO })
    }

    /// A delta light is never hit by sampled directions.
    pub fn pdf_li(&self) -> f32 {
        0.0
    }

    /// An emission direction (world, unit) with its solid-angle density, importance-sampled by
    /// texel power; None when the light is black.
    pub fn sample_direction(&self, u: Vec2) -> Option<(Vec3, f32)> {
        if !(self.unit_power > 0.0) {
            return None;
        }
        let (uv, pdf_uv, _) = self.distribution.sample(u);
        if !(pdf_uv > 0.0) {
            return None;
        }
        let half = self.half_extent.as_dvec2();
        let p = glam::DVec3::new(half.x * (2.0 * uv.x as f64 - 1.0), half.y * (1.0 - 2.0 * uv.y as f64), -1.0);
        let len = p.length();
        // dw = cos^3 theta dA, cos theta = 1 / |p|; the window has area 4 sx sy (pbrt-v4 12.2.2).
        let pdf = pdf_uv as f64 * len * len * len / (4.0 * half.x * half.y);
        Some(((self.rotation.as_dquat() * (p / len)).as_vec3(), pdf as f32))
    }

    /// Solid-angle density of [`Self::sample_direction`] at world direction `w` (unit).
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        if !(self.unit_power > 0.0) {
            return 0.0;
        }
        let Some((uv, cos)) = self.window_uv(w) else { return 0.0 };
        let half = self.half_extent.as_dvec2();
        (self.distribution.pdf(uv.as_vec2()) as f64 / (4.0 * half.x * half.y * cos * cos * cos)) as f32
    }

    /// Radiant power, W: s * sum_i Y(c_i) Omega_i (module docs).
    pub fn phi(&self) -> f32 {
        (self.intensity.radiometric as f64 * self.unit_power) as f32
    }

    /// Bounds for light BVHs (pbrt-v4: the frustum's corner sets theta_o, theta_e = 0).
    pub fn bounds(&self) -> LightBounds {
        let corner = self.half_extent.as_dvec2();
        let cos_corner = 1.0 / (1.0 + corner.length_squared()).sqrt();
        LightBounds {
            min: self.position,
            max: self.position,
            phi: self.phi(),
            w: self.rotation * Vec3::NEG_Z,
            cos_theta_o: cos_corner as f32,
            cos_theta_e: 1.0,
            two_sided: false,
        }
    }
}
