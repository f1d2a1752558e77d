//! Distant light: parallel light from one direction (pbrt-v4 `DistantLight`), optionally with an
//! angular diameter, which turns it into a uniformly bright disc in the sky (a sun) sampled
//! uniformly in its cone.

use std::f32::consts::PI;

use bevy_ecs::component::Component;
use glam::Vec3;

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightError, LightFlags, LightSampleContext, Quantity, SceneSphere};
use crate::geometry::Transform;
use crate::sampling::{Frame, sample_uniform_cone_sin2};
use crate::spectrum::Spectrum;

/// Default illuminance: 10 000 lx, full daylight in shade (Bevy's `AMBIENT_DAYLIGHT`).
pub const DEFAULT_DISTANT_LUX: f32 = 10_000.0;
/// The sun's mean angular diameter seen from Earth, radians (0.533 degrees).
pub const SUN_ANGULAR_DIAMETER: f32 = 0.009_3;

/// Light arriving from far away along the entity's local -Z axis (glTF's directional light).
#[derive(Component, Clone, Debug, PartialEq)]
pub struct DistantLight {
    /// Illuminance on a surface facing the light (lx or W/m^2). Defaults to 10 000 lx.
    pub amount: Amount,
    /// Spectral shape. Defaults to D65 (white).
    pub spectrum: Spectrum,
    /// Full apparent diameter of the source, radians. 0 (the default) is a delta direction;
    /// [`SUN_ANGULAR_DIAMETER`] gives the sun.
    pub angular_diameter: f32,
    /// Whether shadow rays are traced. Defaults to true.
    pub casts_shadows: bool,
}

impl Default for DistantLight {
    fn default() -> Self {
        Self {
            amount: Amount::Lux(DEFAULT_DISTANT_LUX),
            spectrum: Spectrum::d65(),
            angular_diameter: 0.0,
            casts_shadows: true,
        }
    }
}

impl DistantLight {
    /// World-space form; `scene` is the scene's bounding sphere (the preprocess step).
    pub fn resolve(&self, transform: &Transform, scene: SceneSphere) -> Result<ResolvedDistant, LightError> {
        let amount = check_amount(self.amount, "DistantLight", "amount", &[Quantity::Irradiance], "lx or W/m^2")?;
        let d = self.angular_diameter;
        if !(0.0..PI).contains(&d) {
            return Err(LightError::Invalid {
                light: "DistantLight",
                msg: format!("angular_diameter {d} must be in [0, pi) radians"),
            });
        }
        let half = 0.5 * d;
        let sin2 = half.sin().powi(2);
        Ok(ResolvedDistant {
            to_light: -transform.forward().normalize(),
            irradiance: Emitter::from_amount(self.spectrum.clone(), amount),
            sin2_half_angle: sin2,
            // 1 - cos(a) = 2 sin^2(a/2), exact for tiny discs.
            one_minus_cos: 2.0 * (0.5 * half).sin().powi(2),
            scene,
        })
    }
}

/// A distant light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedDistant {
    /// Unit direction from any point toward the light.
    pub to_light: Vec3,
    /// Irradiance on a surface facing the light, W/m^2.
    pub irradiance: Emitter,
    /// sin^2 of the half-angle of the source disc; 0 for a delta direction.
    pub sin2_half_angle: f32,
    /// 1 - cos of the half-angle.
    pub one_minus_cos: f32,
    /// Bounds of the scene, used to place sample points beyond it and to compute the power.
    pub scene: SceneSphere,
}

impl ResolvedDistant {
    /// Delta-direction light, or infinite (seen by escaping rays) when it has an angular size.
    pub fn flags(&self) -> LightFlags {
        if self.is_delta() { LightFlags::DELTA_DIRECTION } else { LightFlags::INFINITE }
    }

    /// True without an angular diameter.
    pub fn is_delta(&self) -> bool {
        self.one_minus_cos <= 0.0
    }

    /// Solid angle of the disc, sr.
    pub fn solid_angle(&self) -> f32 {
        2.0 * PI * self.one_minus_cos
    }

    /// Radiance of the disc, E / (pi sin^2 a), so its irradiance at normal incidence is E.
    fn disc_radiance(&self, query: ColorQuery) -> super::SampledSpectrum {
        self.irradiance.eval(query).scale(1.0 / (PI * self.sin2_half_angle))
    }

    /// A direction toward the light: the delta direction (radiance E), or a uniform direction in
    /// the disc's cone.
    pub fn sample_li(&self, ctx: &LightSampleContext, u: glam::Vec2, query: ColorQuery) -> Option<LiSample> {
        let far = 2.0 * self.scene.radius + (ctx.p - self.scene.center).length();
        if self.is_delta() {
            let radiance = self.irradiance.eval(query);
            return Some(LiSample {
                radiance,
                wi: self.to_light,
                pdf: 1.0,
                p_light: ctx.p + self.to_light * far,
                n_light: -self.to_light,
            });
        }
        let wi = Frame::from_z(self.to_light).from_local(sample_uniform_cone_sin2(u, self.sin2_half_angle)).normalize();
        Some(LiSample {
            radiance: self.disc_radiance(query),
            wi,
            pdf: 1.0 / self.solid_angle(),
            p_light: ctx.p + wi * far,
            n_light: -wi,
        })
    }

    /// Solid-angle density of sampling `wi`: 0 for the delta form or outside the disc.
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        if self.is_delta() || !self.in_disc(wi) { 0.0 } else { 1.0 / self.solid_angle() }
    }

    /// Radiance seen along an escaping ray with direction `wi` (zero outside the disc).
    pub fn le(&self, wi: Vec3, query: ColorQuery) -> super::SampledSpectrum {
        if self.is_delta() || !self.in_disc(wi) { Default::default() } else { self.disc_radiance(query) }
    }

    fn in_disc(&self, wi: Vec3) -> bool {
        // sin^2 from a cross product keeps its digits for a sun-sized disc, where 1 - cos in f32
        // does not; the 1e-4 margin covers the f32 rounding of sampled directions at the rim.
        let (w, d) = (wi.as_dvec3().normalize(), self.to_light.as_dvec3());
        w.dot(d) > 0.0 && w.cross(d).length_squared() <= self.sin2_half_angle as f64 * (1.0 + 1e-4)
    }

    /// Power through the scene's bounding disc, W: E pi R^2.
    pub fn phi(&self) -> f32 {
        self.irradiance.radiometric * PI * self.scene.radius * self.scene.radius
    }
}
