//! The shading pass for [`LANES`] camera samples at once, in the common case: every sample hit a
//! surface that emits nothing, of an untextured material without a specular lobe (Lambertian),
//! and colours are RGB. The caller checks that no BSDF rays are traced. Same operations in the
//! same order as `ShadeContext::shade`, so the pixels are the same bit for bit; other blocks are
//! shaded one sample at a time.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use super::camera_pass::SampleSurface;
use super::renderer::{Strategy, power_heuristic};
use super::shade::ShadeContext;
use crate::lanes::{self, F32x16, LANES, Mask16, Vec3x16};
use crate::sampling::cosine_hemisphere_pdf;

impl ShadeContext<'_> {
    /// Shades camera samples `first..first + out.len()` into `out` (RGB) if they are `LANES`
    /// samples of the common case (see the module docs); returns whether it did.
    #[inline(always)]
    pub(super) fn shade_lanes(&self, first: usize, out: &mut [Vec3]) -> bool {
        if out.len() != LANES {
            return false;
        }
        // Base colour / pi (the Lambertian f above the surface) per lane. Neighbouring samples
        // usually share a surface, so its checks run once per run of equal (material, instance),
        // and a block of one surface fills whole lanes.
        let mut f_up = Vec3x16::ZERO;
        let (material, instance) =
            (&self.columns.material[first..first + LANES], &self.columns.instance[first..first + LANES]);
        if material.iter().all(|&m| m == material[0]) && instance.iter().all(|&i| i == instance[0]) {
            let Some(base) = self.lambertian_base(material[0], instance[0]) else { return false };
            f_up = Vec3x16::splat(Vec3::from(base) * FRAC_1_PI);
        } else {
            let (mut surface_of_base, mut base) = ((u32::MAX, u32::MAX), [0.0f32; 3]);
            for l in 0..LANES {
                if (material[l], instance[l]) != surface_of_base {
                    let Some(b) = self.lambertian_base(material[l], instance[l]) else { return false };
                    (surface_of_base, base) = ((material[l], instance[l]), b);
                }
                f_up.set_lane(l, Vec3::from(base) * FRAC_1_PI);
            }
        }
        // Point j's entries must be `e0 + (j - first) k ..` for a k shared by the block.
        let offsets = &self.lighting.offsets[first..=first + LANES];
        let (e0, k) = (offsets[0] as usize, (offsets[1] - offsets[0]) as usize);
        if offsets.iter().enumerate().any(|(l, &o)| o as usize != e0 + l * k) {
            return false;
        }
        let mut sum = Vec3x16::ZERO;
        // A literal stride of 1 lets LLVM load the common case's columns as contiguous runs.
        if k == 1 {
            self.add_entry_lanes(first, e0, 1, &f_up, &mut sum);
        } else {
            for slot in 0..k {
                self.add_entry_lanes(first, e0 + slot, k, &f_up, &mut sum);
            }
        }
        sum.store_vec3s(lanes::block_mut(out, 0));
        true
    }

    /// The base colour of a camera sample's surface (its `material` and `instance` columns) if it
    /// is of the common case: hit, not emitting, of an untextured material without a specular lobe.
    #[inline(always)]
    fn lambertian_base(&self, material: u32, instance: u32) -> Option<[f32; 3]> {
        if instance == SampleSurface::ESCAPED.instance {
            return None;
        }
        let bsdf = match self.uniform_bsdfs.get(material as usize) {
            Some(Some(b)) if !b.has_specular() => b,
            _ => return None,
        };
        if self.may_emit(instance) {
            return None;
        }
        Some([bsdf.base.0[0], bsdf.base.0[1], bsdf.base.0[2]])
    }

    /// Adds to `sum` the light of entry `e + l stride` at camera sample `first + l` for every lane
    /// l, as `ShadeContext::shade` would. Loops over the lanes without branches (selects, `&`,
    /// both sides computed), so that they vectorise.
    #[inline(always)]
    fn add_entry_lanes(&self, first: usize, e: usize, stride: usize, f_up: &Vec3x16, sum: &mut Vec3x16) {
        let lighting = self.lighting;
        let mis = self.strategy == Strategy::Mis;
        // The other strategies weigh every light sample alike, whatever its pdfs.
        let fixed_weight = self.strategy.light_weight(1.0, 1.0);
        let [dx, dy, dz] = self.columns.dir.each_ref().map(|c| F32x16::load(c, first));
        let wo = -Vec3x16 { x: dx, y: dy, z: dz };
        // Slices of a length known at compile time for a literal stride: no bounds checks in the loop.
        let span = e..e + (LANES - 1) * stride + 1;
        let (wi, pdf, delta, radiance) = (
            &lighting.wi[span.clone()],
            &lighting.pdf[span.clone()],
            &lighting.delta[span.clone()],
            &lighting.radiance[span],
        );
        let (mut li, mut pdf_l, mut delta_l) = (Vec3x16::ZERO, F32x16::ZERO, [false; LANES]);
        for l in 0..LANES {
            let e = l * stride;
            let r = radiance[e];
            (li.x[l], li.y[l], li.z[l]) = (r.0[0], r.0[1], r.0[2]);
            (pdf_l[l], delta_l[l]) = (pdf[e], delta[e]);
        }
        // Runs of whole blocks, read as such (see `Vec3x16::from_vec3s`).
        let ns = Vec3x16::load(&self.batch.shading_normal, first);
        let wi_l = if stride == 1 {
            Vec3x16::load(wi, 0)
        } else {
            let mut w = Vec3x16::ZERO;
            for l in 0..LANES {
                w.set_lane(l, wi[l * stride]);
            }
            w
        };
        let zero = F32x16::ZERO;
        // `Bsdf::f` and `Bsdf::pdf` without a specular lobe: the frame's z is `ns`.
        let (cos_o, cos_i) = (wo.dot(ns), wi_l.dot(ns));
        let upper = cos_o.gt(zero) & cos_i.gt(zero);
        let bsdf_pdf = F32x16::select(upper, cos_i.map(cosine_hemisphere_pdf), zero);
        let light_weight = if mis { pdf_l.zip(bsdf_pdf, power_heuristic) } else { F32x16::splat(fixed_weight) };
        let w = F32x16::select(Mask16::from_bools(delta_l), F32x16::ONE, light_weight);
        let s = cos_i.abs() * w / pdf_l;
        // `shade` skips entries with pdf <= 0 and weight 0 (NaN goes on, as there).
        let counts = (pdf_l.gt(zero) | pdf_l.is_nan()) & w.ne(zero);
        let f = Vec3x16::select(upper, *f_up, Vec3x16::ZERO);
        *sum = Vec3x16::select(counts, *sum + f * li * s, *sum);
    }
}

/// Tests turn the lane kernels (shading, and the camera pass's block writes) off to compare them
/// with one-at-a-time code.
#[cfg(test)]
static OFF_FOR_TESTS: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a test has turned the lane kernels off (never outside tests).
pub(super) fn turned_off() -> bool {
    #[cfg(test)]
    return OFF_FOR_TESTS.load(std::sync::atomic::Ordering::Relaxed);
    #[cfg(not(test))]
    false
}

#[cfg(test)]
mod tests {
    use bevy_ecs::prelude::*;
    use glam::{Vec2, Vec3};

    use crate::geometry::{Rectangle, Transform};
    use crate::light::{DistantLight, PointLight, SpotLight};
    use crate::render::camera::Camera;
    use crate::render::material::Material;
    use crate::render::renderer::{Integrator, RenderOptions, Strategy, render};
    use crate::shading::{LightSamplerKind, Settings};
    use crate::systems::LightingPlugin;

    /// Pixels of a scene that mixes lane blocks with one-at-a-time ones: a Lambertian floor and a
    /// glossy wall seen from behind (it has a specular lobe, and its normals are flipped), sky
    /// above the horizon (escaped rays), two light samples per point, a point light, a spot
    /// light, and a distant light from below the floor. Lights are chosen uniformly: the power
    /// sampler would choose the distant light, which the floor blocks, nearly every time.
    fn pixels(strategy: Strategy) -> Vec<Vec3> {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        let light_sampler = LightSamplerKind::Uniform;
        world.insert_resource(Settings { samples_per_point: 2, light_sampler, ..Default::default() });
        LightingPlugin::build(&mut world, &mut schedule);
        let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
        world.spawn((Rectangle { half_size: Vec2::splat(5.0) }, up, Material::lambertian(Vec3::new(0.5, 0.3, 0.8))));
        let wall = Transform::from_translation(Vec3::new(1.5, 1.0, -2.0)).looking_to(Vec3::Z, Vec3::Y);
        world.spawn((Rectangle { half_size: Vec2::splat(2.0) }, wall, Material::default()));
        world.spawn((PointLight::candela(50.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
        let spot = Transform::from_translation(Vec3::new(-1.0, 3.0, 1.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
        world.spawn((SpotLight::default(), spot));
        world.spawn((DistantLight::default(), Transform::default().looking_to(Vec3::Y, Vec3::Z)));
        let eye = Vec3::new(0.0, 1.5, 5.0);
        world.spawn((Camera { yfov: 1.2 }, Transform::from_translation(eye).looking_to(-eye, Vec3::Y)));
        let opts = RenderOptions {
            width: 24,
            height: 16,
            spp: 4,
            strategy,
            integrator: Integrator::Direct,
            ..Default::default()
        };
        render(&mut world, &mut schedule, &opts, |_| {}).0.pixels()
    }

    #[test]
    fn lane_shading_matches_one_at_a_time_bit_for_bit() {
        use std::sync::atomic::Ordering::Relaxed;
        for strategy in [Strategy::Mis, Strategy::LightOnly] {
            let lanes = pixels(strategy);
            super::OFF_FOR_TESTS.store(true, Relaxed);
            let one_at_a_time = pixels(strategy);
            super::OFF_FOR_TESTS.store(false, Relaxed);
            // Most of the floor and the wall are lit.
            let lit = lanes.iter().filter(|p| p.length() > 0.0).count();
            assert!(lit > lanes.len() / 3 && lanes.iter().all(|p| p.is_finite()), "{lit} lit pixels");
            let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&lanes), bits(&one_at_a_time), "{strategy:?}");
        }
    }

    /// The lane path against the closed form, not only against the one-at-a-time path: a point
    /// light of I cd at height h over a Lambertian floor gives rho/pi I/h^2 in every pixel it
    /// lights straight down, at k = 1, 2 and 4 light samples per point (each entry's pdf carries k).
    #[test]
    fn lane_shading_meets_the_closed_form_at_any_samples_per_point() {
        let (rho, i, h) = (0.5f32, 100.0f32, 2.0f32);
        let want = rho / std::f32::consts::PI * i / (h * h);
        for k in [1, 2, 4] {
            let mut world = World::new();
            let mut schedule = Schedule::default();
            world.insert_resource(Settings { samples_per_point: k, ..Default::default() });
            LightingPlugin::build(&mut world, &mut schedule);
            let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
            world.spawn((Rectangle { half_size: Vec2::splat(50.0) }, up, Material::lambertian(Vec3::splat(rho))));
            world.spawn((PointLight::candela(i), Transform::from_translation(Vec3::new(0.0, h, 0.0))));
            let cam = Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
            world.spawn((Camera { yfov: 0.01 }, cam));
            let opts = RenderOptions { integrator: Integrator::Direct, ..RenderOptions::direct(5, 5, 16) };
            let c = render(&mut world, &mut schedule, &opts, |_| {}).0.pixel(2, 2);
            let got = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
            assert!((got / want - 1.0).abs() < 1e-3, "k = {k}: {got} vs {want}");
        }
    }
}
