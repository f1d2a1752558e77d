//! Infinite lights: radiance arriving from every direction at infinity (pbrt-v4 section 12.5).
//!
//! - [`UniformInfiniteLight`]: the same radiance from every direction (an overcast sky, an
//!   ambient term that still casts shadows).
//! - [`ImageInfiniteLight`]: radiance from a lat-long (equirectangular) environment map, sampled
//!   by its luminance with the tables in [`tables`].
//! - [`SunSkyLight`]: a physical sun and sky (Hosek-Wilkie), the sky sampled from a generated
//!   table, the sun on its cone ([`sunsky`]).
//!
//! Both are preprocessed with the scene's bounding sphere: sample points are placed beyond it and
//! power is the flux through its cross-section, phi = pi R^2 * integral of L over the sphere.

mod image;
pub mod sunsky;
pub mod tables;

use std::f32::consts::PI;

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightError, LightFlags, LightSampleContext, Quantity, SceneSphere};
use crate::sampling::{
    Frame, cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_sphere, uniform_sphere_pdf,
};
use crate::spectrum::{SampledSpectrum, Spectrum};

pub use image::{ImageInfiniteLight, ResolvedImageInfinite};
pub use sunsky::{ResolvedSunSky, SunPosition, SunSkyLight};
pub use tables::{EnvLookup, EnvMapTables, EnvTableOptions};

/// Default sky luminance, nit: 10 000 / pi, so a horizontal surface under the whole sky receives
/// 10 000 lx (E = pi L), the same as [`super::distant::DEFAULT_DISTANT_LUX`].
pub const DEFAULT_SKY_NITS: f32 = 10_000.0 / PI;

/// Uniform radiance from every direction.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct UniformInfiniteLight {
    /// Radiance (nit or W/(m^2 sr)). Defaults to [`DEFAULT_SKY_NITS`].
    pub amount: Amount,
    /// Spectral shape. Defaults to D65 (white).
    pub spectrum: Spectrum,
}

impl Default for UniformInfiniteLight {
    fn default() -> Self {
        Self { amount: Amount::Nits(DEFAULT_SKY_NITS), spectrum: Spectrum::d65() }
    }
}

impl UniformInfiniteLight {
    /// A white sky of `nits` cd/m^2.
    pub fn nits(nits: f32) -> Self {
        Self { amount: Amount::Nits(nits), ..Default::default() }
    }

    /// World-space form; `scene` is the scene's bounding sphere (the preprocess step).
    pub fn resolve(&self, scene: SceneSphere) -> Result<ResolvedUniformInfinite, LightError> {
        let amount =
            check_amount(self.amount, "UniformInfiniteLight", "amount", &[Quantity::Radiance], "nit or W/(m^2 sr)")?;
        Ok(ResolvedUniformInfinite { radiance: Emitter::from_amount(self.spectrum.clone(), amount), scene })
    }
}

/// A uniform infinite light, ready to sample.
///
/// Sampling: cosine-weighted about the context's normal (the shading normal if set, else the
/// geometric one) when there is one, uniform over the sphere otherwise. pbrt-v4 samples the
/// uniform sphere; for a constant radiance the cosine density makes the irradiance estimate
/// exact (zero variance) on a surface. The price: directions behind the surface are never
/// sampled, so a transmissive BSDF must get its back-side light from BSDF sampling (MIS), or be
/// shaded with a context without normal. `pdf_li` follows the same rule.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedUniformInfinite {
    /// Radiance, W/(m^2 sr) (with its photometric RGB in nit).
    pub radiance: Emitter,
    /// Bounds of the scene, used to place sample points beyond it and to compute the power.
    pub scene: SceneSphere,
}

/// The unit normal the context samples around, or zero for "no surface".
fn sampling_normal(ctx: &LightSampleContext) -> Vec3 {
    let n = if ctx.ns != Vec3::ZERO { ctx.ns } else { ctx.n };
    n.normalize_or_zero()
}

/// Distance to a point beyond the scene's bounding sphere along any direction from `p`.
pub(crate) fn far_distance(scene: SceneSphere, p: Vec3) -> f32 {
    2.0 * scene.radius + (p - scene.center).length()
}

impl ResolvedUniformInfinite {
    /// Infinite: seen by escaping rays, never a delta.
    pub fn flags(&self) -> LightFlags {
        LightFlags::INFINITE
    }

    /// A direction toward the sky (see the type's docs for the density); None only if the
    /// sample falls exactly on the horizon of a surface.
    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let n = sampling_normal(ctx);
        let wi = if n == Vec3::ZERO {
            sample_uniform_sphere(u)
        } else {
            Frame::from_z(n).from_local(sample_cosine_hemisphere(u)).normalize()
        };
        let pdf = self.pdf_li(ctx, wi);
        if !(pdf > 0.0) {
            return None;
        }
        let p_light = ctx.p + wi * far_distance(self.scene, ctx.p);
        Some(LiSample { radiance: self.radiance.eval(query), wi, pdf, p_light, n_light: Vec3::ZERO })
    }

    /// Solid-angle density of [`Self::sample_li`] choosing `wi` (unit): cos / pi above the
    /// context's surface (0 below), 1 / (4 pi) without a surface.
    pub fn pdf_li(&self, ctx: &LightSampleContext, wi: Vec3) -> f32 {
        let n = sampling_normal(ctx);
        if n == Vec3::ZERO { uniform_sphere_pdf() } else { cosine_hemisphere_pdf(n.dot(wi)) }
    }

    /// Radiance along an escaping ray of any direction.
    pub fn le(&self, _wi: Vec3, query: ColorQuery) -> SampledSpectrum {
        self.radiance.eval(query)
    }

    /// Power through the scene's bounding disc, W: pi R^2 * 4 pi L = 4 pi^2 R^2 L (pbrt-v4
    /// `UniformInfiniteLight::Phi`).
    pub fn phi(&self) -> f32 {
        4.0 * PI * PI * self.scene.radius * self.scene.radius * self.radiance.radiometric
    }
}
