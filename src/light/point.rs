//! Point light: an isotropic emitter at a single point (pbrt-v4 `PointLight`).

use std::f32::consts::PI;

use bevy_ecs::component::Component;
use glam::Vec3;

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, Quantity};
use crate::geometry::Transform;
use crate::spectrum::Spectrum;

/// Default luminous power of a point light: 800 lm, about a 60 W incandescent bulb.
pub const DEFAULT_POINT_LUMENS: f32 = 800.0;

/// An isotropic point light at its entity's `Transform` translation.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct PointLight {
    /// Intensity (cd or W/sr) or total power (lm or W; I = power / 4 pi). Defaults to 800 lm.
    pub amount: Amount,
    /// Spectral shape; its chromaticity is the light's colour. Defaults to D65 (white).
    pub spectrum: Spectrum,
    /// Radius in metres. 0 (the default) is a true point; a positive radius makes the light a
    /// sphere area light of the same power and intensity far away (radiance I / (pi r^2)).
    pub radius: f32,
    /// Whether shadow rays are traced for this light. Defaults to true.
    pub casts_shadows: bool,
}

impl Default for PointLight {
    fn default() -> Self {
        Self {
            amount: Amount::Lumens(DEFAULT_POINT_LUMENS),
            spectrum: Spectrum::d65(),
            radius: 0.0,
            casts_shadows: true,
        }
    }
}

impl PointLight {
    /// A white point light of `candela` cd.
    pub fn candela(candela: f32) -> Self {
        Self { amount: Amount::Candela(candela), ..Default::default() }
    }

    /// The radiant intensity emitter (W/sr) this light describes.
    pub fn intensity(&self) -> Result<Emitter, LightError> {
        let amount = check_amount(
            self.amount,
            "PointLight",
            "amount",
            &[Quantity::Intensity, Quantity::Power],
            "cd, W/sr, lm or W",
        )?;
        let e = Emitter::from_amount(self.spectrum.clone(), amount);
        Ok(if amount.quantity() == Quantity::Power { e.scaled(1.0 / (4.0 * PI)) } else { e })
    }

    /// World-space form for sampling. (A positive radius is resolved as a sphere area light by
    /// the area-light code; this is the point form.)
    pub fn resolve(&self, transform: &Transform) -> Result<ResolvedPoint, LightError> {
        if !(self.radius >= 0.0 && self.radius.is_finite()) {
            return Err(LightError::BadAmount { light: "PointLight", field: "radius", value: self.radius });
        }
        Ok(ResolvedPoint { position: transform.translation, intensity: self.intensity()? })
    }
}

/// A point light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedPoint {
    pub position: Vec3,
    /// Radiant intensity, W/sr (with its photometric RGB in cd).
    pub intensity: Emitter,
}

impl ResolvedPoint {
    /// The delta direction toward the light with radiance I / r^2; None at the light's position.
    pub fn sample_li(&self, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let d = self.position - ctx.p;
        let r2 = d.length_squared();
        if !(r2 > 0.0) || !r2.is_finite() {
            return None;
        }
        Some(LiSample {
            radiance: self.intensity.eval(query).scale(1.0 / r2),
            wi: d / r2.sqrt(),
            pdf: 1.0,
            p_light: self.position,
            n_light: Vec3::ZERO,
        })
    }

    /// A delta light is never hit by sampled directions.
    pub fn pdf_li(&self) -> f32 {
        0.0
    }

    /// Radiant power, W: 4 pi I.
    pub fn phi(&self) -> f32 {
        4.0 * PI * self.intensity.radiometric
    }

    /// Bounds for light BVHs: a point emitting in every direction.
    pub fn bounds(&self) -> LightBounds {
        LightBounds {
            min: self.position,
            max: self.position,
            phi: self.phi(),
            w: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        }
    }
}
