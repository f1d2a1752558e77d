//! Spot light: a point light restricted to a cone with a smooth falloff (pbrt-v4 `SpotLight`).
//!
//! Falloff: I(theta) = I * smoothstep(cos theta; cos outer, cos inner), the cubic Hermite
//! smoothstep between the cosines of the outer and inner half-angles; power
//! phi = 2 pi I ((1 - cos inner) + (cos inner - cos outer) / 2) (pbrt-v4 section 12.2.1).
//!
//! glTF (KHR_lights_punctual) gives `innerConeAngle` and `outerConeAngle` as half-angles from the
//! axis; they map one to one onto `inner_angle` and `outer_angle`. glTF only *suggests* a falloff,
//! (clamp((cos theta - cos outer) / (cos inner - cos outer), 0, 1))^2, which starts with a
//! nonzero slope at the inner cone and has zero slope at the outer one; kelvin keeps pbrt's
//! smoothstep (zero slope at both ends), so the beam edge looks slightly softer at the inner
//! angle and the power differs by a few percent for wide falloff bands.

use std::f32::consts::PI;

use bevy_ecs::component::Component;
use glam::Vec3;

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, Quantity};
use crate::geometry::Transform;
use crate::sampling::smooth_step;
use crate::spectrum::Spectrum;

/// glTF's default outer cone half-angle, pi/4.
pub const DEFAULT_OUTER_ANGLE: f32 = PI / 4.0;

/// A spot light at its entity's translation, shining along the entity's local -Z axis.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct SpotLight {
    /// On-axis intensity (cd or W/sr) or total power (lm or W, divided by the falloff's solid
    /// angle). Defaults to 800 lm.
    pub amount: Amount,
    /// Spectral shape. Defaults to D65 (white).
    pub spectrum: Spectrum,
    /// Half-angle (radians) inside which the intensity is full. Defaults to 0.
    pub inner_angle: f32,
    /// Half-angle (radians) outside which there is no light, up to pi. Defaults to pi/4.
    pub outer_angle: f32,
    /// Whether shadow rays are traced. Defaults to true.
    pub casts_shadows: bool,
}

impl Default for SpotLight {
    fn default() -> Self {
        Self {
            amount: Amount::Lumens(super::point::DEFAULT_POINT_LUMENS),
            spectrum: Spectrum::d65(),
            inner_angle: 0.0,
            outer_angle: DEFAULT_OUTER_ANGLE,
            casts_shadows: true,
        }
    }
}

/// Solid-angle factor of the falloff: phi = I * this.
fn falloff_solid_angle(cos_inner: f32, cos_outer: f32) -> f32 {
    2.0 * PI * ((1.0 - cos_inner) + (cos_inner - cos_outer) / 2.0)
}

impl SpotLight {
    /// World-space form; errors for NaN or out-of-order angles and bad amounts.
    pub fn resolve(&self, transform: &Transform) -> Result<ResolvedSpot, LightError> {
        let (inner, outer) = (self.inner_angle, self.outer_angle);
        if !(0.0 <= inner && inner <= outer && outer <= PI) {
            return Err(LightError::Invalid {
                light: "SpotLight",
                msg: format!("need 0 <= inner_angle ({inner}) <= outer_angle ({outer}) <= pi"),
            });
        }
        let (cos_inner, cos_outer) = (inner.cos(), outer.cos());
        let amount = check_amount(
            self.amount,
            "SpotLight",
            "amount",
            &[Quantity::Intensity, Quantity::Power],
            "cd, W/sr, lm or W",
        )?;
        let mut intensity = Emitter::from_amount(self.spectrum.clone(), amount);
        if amount.quantity() == Quantity::Power {
            let omega = falloff_solid_angle(cos_inner, cos_outer);
            intensity = intensity.scaled(if omega > 0.0 { 1.0 / omega } else { 0.0 });
        }
        Ok(ResolvedSpot {
            position: transform.translation,
            direction: transform.forward().normalize(),
            cos_inner,
            cos_outer,
            intensity,
        })
    }
}

/// A spot light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedSpot {
    /// World-space position, metres.
    pub position: Vec3,
    /// Unit axis the light shines along.
    pub direction: Vec3,
    /// Cosine of the inner half-angle, inside which the intensity is full.
    pub cos_inner: f32,
    /// Cosine of the outer half-angle, outside which there is no light.
    pub cos_outer: f32,
    /// On-axis radiant intensity, W/sr.
    pub intensity: Emitter,
}

impl ResolvedSpot {
    /// Relative intensity toward world direction `w` (from the light, unit): the smoothstep
    /// falloff. With inner == outer it is a hard step.
    pub fn falloff(&self, w: Vec3) -> f32 {
        smooth_step(w.dot(self.direction), self.cos_outer, self.cos_inner)
    }

    /// The delta direction toward the light; None when the point is outside the cone or at the
    /// light.
    pub fn sample_li(&self, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let cone = (self.direction, self.cos_outer, self.cos_inner);
        sample_li_at(self.position, cone, || self.intensity.eval(query), ctx)
    }

    /// A delta light is never hit by sampled directions.
    pub fn pdf_li(&self) -> f32 {
        0.0
    }

    /// Radiant power, W.
    pub fn phi(&self) -> f32 {
        self.intensity.radiometric * falloff_solid_angle(self.cos_inner, self.cos_outer)
    }

    /// Bounds for light BVHs (pbrt-v4: theta_o = inner angle, theta_e = outer - inner).
    pub fn bounds(&self) -> LightBounds {
        let theta_e = self.cos_outer.clamp(-1.0, 1.0).acos() - self.cos_inner.clamp(-1.0, 1.0).acos();
        LightBounds {
            min: self.position,
            max: self.position,
            phi: self.phi(),
            w: self.direction,
            cos_theta_o: self.cos_inner,
            cos_theta_e: theta_e.cos(),
            two_sided: false,
        }
    }
}

/// Spot lights as columns (the `LightTable` block).
#[derive(Clone, Debug, Default)]
pub struct SpotColumns {
    /// World-space positions, metres.
    pub position: Vec<Vec3>,
    /// Unit axes the lights shine along.
    pub direction: Vec<Vec3>,
    /// Cosines of the inner half-angles (full intensity inside).
    pub cos_inner: Vec<f32>,
    /// Cosines of the outer half-angles (no light outside).
    pub cos_outer: Vec<f32>,
    /// Photometric linear sRGB on-axis intensity, cd.
    pub rgb: Vec<Vec3>,
    /// Spectral shape, for spectral mode.
    pub spectrum: Vec<Spectrum>,
    /// Multiplies `spectrum` to give the on-axis intensity, W/(sr nm).
    pub scale: Vec<f32>,
    /// On-axis radiant intensity, W/sr.
    pub radiometric: Vec<f32>,
    /// Whether shadow rays are traced for each light.
    pub casts_shadows: Vec<bool>,
    /// The entity each light belongs to.
    pub owner: Vec<bevy_ecs::entity::Entity>,
}

impl SpotColumns {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// True with no lights.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// The resolved light at `row`.
    pub fn get(&self, row: usize) -> ResolvedSpot {
        let intensity = Emitter {
            spectrum: self.spectrum[row].clone(),
            scale: self.scale[row],
            rgb: self.rgb[row],
            radiometric: self.radiometric[row],
        };
        ResolvedSpot {
            position: self.position[row],
            direction: self.direction[row],
            cos_inner: self.cos_inner[row],
            cos_outer: self.cos_outer[row],
            intensity,
        }
    }

    /// Sample_Li of the light at `row` straight from the columns.
    #[inline]
    pub fn sample_li(&self, row: usize, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let cone = (self.direction[row], self.cos_outer[row], self.cos_inner[row]);
        let intensity = || query.intensity_column(self.rgb[row], &self.spectrum[row], self.scale[row]);
        sample_li_at(self.position[row], cone, intensity, ctx)
    }

    /// [`Self::sample_li`] with the vector to the light, r^2, the cone cosine and 1/r^2 in f64
    /// (the precision knob of the accuracy report); positions and results stay f32.
    pub fn sample_li_f64(&self, row: usize, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let (wi, r2) = ctx.toward_f64(self.position[row])?;
        let cos = -wi.dot(self.direction[row].as_dvec3());
        let f = smooth_step(cos as f32, self.cos_outer[row], self.cos_inner[row]);
        if f <= 0.0 {
            return None;
        }
        let s = (f as f64 / r2) as f32;
        let radiance = query.intensity_column(self.rgb[row], &self.spectrum[row], self.scale[row]).scale(s);
        Some(LiSample { radiance, wi: wi.as_vec3(), pdf: 1.0, p_light: self.position[row], n_light: Vec3::ZERO })
    }

    /// Radiant power of the light at `row`, W.
    pub fn phi(&self, row: usize) -> f32 {
        self.radiometric[row] * falloff_solid_angle(self.cos_inner[row], self.cos_outer[row])
    }
}

impl crate::light::table::Block for SpotColumns {
    type Row = ResolvedSpot;
    fn len(&self) -> usize {
        self.position.len()
    }
    fn push(&mut self, owner: bevy_ecs::entity::Entity, r: ResolvedSpot, casts_shadows: bool) {
        self.position.push(r.position);
        self.direction.push(r.direction);
        self.cos_inner.push(r.cos_inner);
        self.cos_outer.push(r.cos_outer);
        self.rgb.push(r.intensity.rgb);
        self.scale.push(r.intensity.scale);
        self.radiometric.push(r.intensity.radiometric);
        self.spectrum.push(r.intensity.spectrum);
        self.casts_shadows.push(casts_shadows);
        self.owner.push(owner);
    }
    fn set(&mut self, i: usize, r: ResolvedSpot, casts_shadows: bool) {
        self.position[i] = r.position;
        self.direction[i] = r.direction;
        self.cos_inner[i] = r.cos_inner;
        self.cos_outer[i] = r.cos_outer;
        self.rgb[i] = r.intensity.rgb;
        self.scale[i] = r.intensity.scale;
        self.radiometric[i] = r.intensity.radiometric;
        self.spectrum[i] = r.intensity.spectrum;
        self.casts_shadows[i] = casts_shadows;
    }
    fn swap_remove(&mut self, i: usize) {
        self.position.swap_remove(i);
        self.direction.swap_remove(i);
        self.cos_inner.swap_remove(i);
        self.cos_outer.swap_remove(i);
        self.rgb.swap_remove(i);
        self.scale.swap_remove(i);
        self.radiometric.swap_remove(i);
        self.spectrum.swap_remove(i);
        self.casts_shadows.swap_remove(i);
        self.owner.swap_remove(i);
    }
    fn owner(&self, i: usize) -> bevy_ecs::entity::Entity {
        self.owner[i]
    }
}

/// Spot Sample_Li, f32: the delta direction from `ctx` toward a light at `position` with radiance
/// I falloff / r^2, the falloff a smoothstep of the cosine to the axis between the cone's
/// (`direction`, `cos_outer`, `cos_inner`); None outside the cone or at the light. The one f32
/// form (`SpotColumns::sample_li_f64` is its f64 reference).
#[inline(always)]
fn sample_li_at(
    position: Vec3,
    (direction, cos_outer, cos_inner): (Vec3, f32, f32),
    intensity: impl FnOnce() -> crate::spectrum::SampledSpectrum,
    ctx: &LightSampleContext,
) -> Option<LiSample> {
    let (wi, r2) = ctx.toward(position)?;
    let f = smooth_step(-wi.dot(direction), cos_outer, cos_inner);
    if f <= 0.0 {
        return None;
    }
    Some(LiSample { radiance: intensity().scale(f / r2), wi, pdf: 1.0, p_light: position, n_light: Vec3::ZERO })
}
