//! Point light: an isotropic emitter at a single point (pbrt-v4 `PointLight`).

use std::f32::consts::PI;

use bevy_ecs::component::Component;
use glam::Vec3;

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, Quantity};
use crate::geometry::Transform;
use crate::lanes::{F32x16, Mask16, U32x16, Vec3x16};
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
    /// World-space position, metres.
    pub position: Vec3,
    /// Radiant intensity, W/sr (with its photometric RGB in cd).
    pub intensity: Emitter,
}

impl ResolvedPoint {
    /// The delta direction toward the light with radiance I / r^2; None at the light's position.
    pub fn sample_li(&self, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        sample_li_at(self.position, || self.intensity.eval(query), ctx)
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

/// Point Sample_Li, f32: the delta direction from `ctx` toward a light at `position` with
/// radiance I / r^2 (`intensity`: I in the query's colour mode); None at the light's position.
/// The one scalar form (`PointColumns::sample_li_rgb_lanes` is its lane kernel,
/// `PointColumns::sample_li_f64` its f64 reference).
#[inline(always)]
fn sample_li_at(
    position: Vec3,
    intensity: impl FnOnce() -> crate::spectrum::SampledSpectrum,
    ctx: &LightSampleContext,
) -> Option<LiSample> {
    let (wi, r2) = ctx.toward(position)?;
    Some(LiSample { radiance: intensity().scale(1.0 / r2), wi, pdf: 1.0, p_light: position, n_light: Vec3::ZERO })
}

/// Point lights as columns (the `LightTable` block): what the batch paths read.
#[derive(Clone, Debug, Default)]
pub struct PointColumns {
    /// World-space positions, metres.
    pub position: Vec<Vec3>,
    /// Photometric linear sRGB intensity, cd.
    pub rgb: Vec<Vec3>,
    /// Spectral shape and its scale (W/(sr nm) per unit), for spectral mode.
    pub spectrum: Vec<crate::spectrum::Spectrum>,
    /// Multiplies `spectrum` to give W/(sr nm).
    pub scale: Vec<f32>,
    /// Radiant intensity, W/sr.
    pub radiometric: Vec<f32>,
    /// Whether shadow rays are traced for each light.
    pub casts_shadows: Vec<bool>,
    /// The entity each light belongs to.
    pub owner: Vec<bevy_ecs::entity::Entity>,
}

impl PointColumns {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// True with no lights.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// The resolved light at `row`.
    pub fn get(&self, row: usize) -> ResolvedPoint {
        let intensity = Emitter {
            spectrum: self.spectrum[row].clone(),
            scale: self.scale[row],
            rgb: self.rgb[row],
            radiometric: self.radiometric[row],
        };
        ResolvedPoint { position: self.position[row], intensity }
    }

    /// Sample_Li of the light at `row` without building a `ResolvedPoint`.
    #[inline]
    pub fn sample_li(&self, row: usize, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let intensity = || query.intensity_column(self.rgb[row], &self.spectrum[row], self.scale[row]);
        sample_li_at(self.position[row], intensity, ctx)
    }

    /// [`Self::sample_li`] with the vector to the light, r^2 and 1/r^2 in f64 (the precision knob
    /// of the accuracy report); positions and results stay f32.
    pub fn sample_li_f64(&self, row: usize, ctx: &LightSampleContext, query: ColorQuery) -> Option<LiSample> {
        let (wi, r2) = ctx.toward_f64(self.position[row])?;
        let inv_r2 = (1.0 / r2) as f32;
        let radiance = query.intensity_column(self.rgb[row], &self.spectrum[row], self.scale[row]).scale(inv_r2);
        Some(LiSample { radiance, wi: wi.as_vec3(), pdf: 1.0, p_light: self.position[row], n_light: Vec3::ZERO })
    }

    /// Radiant power of the light at `row`, W.
    pub fn phi(&self, row: usize) -> f32 {
        4.0 * PI * self.radiometric[row]
    }
}

impl crate::light::table::Block for PointColumns {
    type Row = ResolvedPoint;
    fn len(&self) -> usize {
        self.position.len()
    }
    fn push(&mut self, owner: bevy_ecs::entity::Entity, r: ResolvedPoint, casts_shadows: bool) {
        self.position.push(r.position);
        self.rgb.push(r.intensity.rgb);
        self.scale.push(r.intensity.scale);
        self.radiometric.push(r.intensity.radiometric);
        self.spectrum.push(r.intensity.spectrum);
        self.casts_shadows.push(casts_shadows);
        self.owner.push(owner);
    }
    fn set(&mut self, i: usize, r: ResolvedPoint, casts_shadows: bool) {
        self.position[i] = r.position;
        self.rgb[i] = r.intensity.rgb;
        self.scale[i] = r.intensity.scale;
        self.radiometric[i] = r.intensity.radiometric;
        self.spectrum[i] = r.intensity.spectrum;
        self.casts_shadows[i] = casts_shadows;
    }
    fn swap_remove(&mut self, i: usize) {
        self.position.swap_remove(i);
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

/// Sample_Li of `LANES` points toward point lights in RGB mode.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct PointLanes {
    /// Light position.
    pub target: Vec3x16,
    /// Unit direction toward the light.
    pub wi: Vec3x16,
    /// Photometric RGB I / r^2.
    pub radiance: Vec3x16,
    /// Unset where `sample_li` has no sample (the point is at the light, or r^2 overflows) or
    /// its radiance is not finite.
    pub valid: Mask16,
}

impl PointLanes {
    /// Lane `l` as the `LiSample` that `sample_li` gives (pdf 1, no light normal); None where
    /// it has no sample.
    #[inline(always)]
    pub fn li_sample(&self, l: usize) -> Option<LiSample> {
        let r = self.radiance.lane(l);
        self.valid.test(l).then(|| LiSample {
            radiance: crate::spectrum::SampledSpectrum([r.x, r.y, r.z, 0.0]),
            wi: self.wi.lane(l),
            pdf: 1.0,
            p_light: self.target.lane(l),
            n_light: Vec3::ZERO,
        })
    }
}

impl PointColumns {
    /// [`Self::sample_li`] in RGB mode for `LANES` points at once, bit for bit: lane `l` samples
    /// light `rows[l]` from `p[l]`. Every row must be a valid row.
    #[inline(always)]
    pub fn sample_li_rgb_lanes(&self, rows: U32x16, p: &Vec3x16) -> PointLanes {
        // The operations of `LightSampleContext::toward` and `Self::sample_li`, in order.
        let (target, rgb) = if rows.is_uniform() {
            // One light for every lane (a one-light scene, or neighbours that chose alike): whole
            // lanes of one value, without the per-lane stores a gather makes.
            let row = rows.0[0] as usize;
            (Vec3x16::splat(self.position[row]), Vec3x16::splat(self.rgb[row]))
        } else {
            (Vec3x16::gather(&self.position, rows), Vec3x16::gather(&self.rgb, rows))
        };
        let d = target - *p;
        let r2 = d.length_squared();
        let (inv_r, inv_r2) = (1.0 / r2.sqrt(), 1.0 / r2);
        let wi = d * inv_r;
        let radiance = rgb * inv_r2;
        let valid = r2.gt(F32x16::ZERO) & r2.is_finite() & inv_r2.is_finite() & radiance.is_finite();
        PointLanes { target, wi, radiance, valid }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::table::Block;
    use crate::rng::SplitMix64;

    /// The lane kernel gives the scalar f32 Sample_Li bit for bit (failed samples as invalid
    /// lanes), the resolved form gives it too, and the f64 reference agrees with it to f32
    /// rounding. Hard cases: a point at a light, one 1e-30 m from it (r^2 underflows), one 1e30 m
    /// away (r^2 overflows).
    #[test]
    fn lane_kernel_scalar_and_f64_reference_agree() {
        let mut rng = SplitMix64::new(9);
        let mut points = PointColumns::default();
        let placeholder = bevy_ecs::entity::Entity::PLACEHOLDER;
        for i in 0..3 {
            let at = Transform::from_translation(Vec3::new(i as f32, 2.0, -1.0));
            let light = PointLight { amount: Amount::Candela(100.0 * (i + 1) as f32), ..Default::default() };
            points.push(placeholder, light.resolve(&at).unwrap(), true);
        }
        let mut compared = 0;
        for block in 0..40 {
            let mut p = Vec3x16::ZERO;
            let mut rows = U32x16::splat(0);
            for l in 0..crate::lanes::LANES {
                let x = Vec3::new(rng.range(-5.0, 5.0), rng.range(-1.0, 3.0), rng.range(-5.0, 5.0));
                let x = match (block, l) {
                    (0, 0) => points.position[0],
                    (0, 1) => points.position[1] + Vec3::new(0.0, 1e-30, 0.0),
                    (0, 2) => Vec3::new(1e30, 0.0, 0.0),
                    _ => x,
                };
                p.set_lane(l, x);
                rows.0[l] = if block % 2 == 0 { 1 } else { rng.below(3) as u32 };
            }
            let lanes = crate::lanes::widest(|| points.sample_li_rgb_lanes(rows, &p));
            for l in 0..crate::lanes::LANES {
                let (row, ctx) = (rows.0[l] as usize, LightSampleContext::at(p.lane(l)));
                let scalar = points.sample_li(row, &ctx, ColorQuery::Rgb).filter(|s| s.radiance.is_finite());
                assert_eq!(
                    points.get(row).sample_li(&ctx, ColorQuery::Rgb),
                    points.sample_li(row, &ctx, ColorQuery::Rgb)
                );
                let Some(s) = scalar else {
                    assert!(!lanes.valid.test(l), "block {block}, lane {l}");
                    continue;
                };
                assert!(lanes.valid.test(l));
                let lane = |c: &Vec3x16| c.lane(l).to_array().map(f32::to_bits);
                assert_eq!(lane(&lanes.wi), s.wi.to_array().map(f32::to_bits));
                assert_eq!(lane(&lanes.radiance), [0, 1, 2].map(|c| s.radiance.0[c].to_bits()));
                assert_eq!(lane(&lanes.target), s.p_light.to_array().map(f32::to_bits));
                let f64 = points.sample_li_f64(row, &ctx, ColorQuery::Rgb).unwrap();
                for c in 0..3 {
                    let (a, b) = (s.radiance.0[c], f64.radiance.0[c]);
                    assert!((a - b).abs() <= 4e-7 * b.abs(), "radiance {a} against {b}");
                }
                assert!((s.wi - f64.wi).abs().max_element() <= 1e-6, "{} against {}", s.wi, f64.wi);
                compared += 1;
            }
        }
        assert!(compared > 600);
    }
}
