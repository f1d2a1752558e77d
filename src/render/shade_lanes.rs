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
use crate::lanes::{self, LANES};
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
        let mut f_up = [[0.0f32; LANES]; 3];
        let (material, instance) =
            (&self.columns.material[first..first + LANES], &self.columns.instance[first..first + LANES]);
        if material.iter().all(|&m| m == material[0]) && instance.iter().all(|&i| i == instance[0]) {
            let Some(base) = self.lambertian_base(material[0], instance[0]) else { return false };
            for c in 0..3 {
                f_up[c] = [base[c] * FRAC_1_PI; LANES];
            }
        } else {
            let (mut surface_of_base, mut base) = ((u32::MAX, u32::MAX), [0.0f32; 3]);
            for l in 0..LANES {
                if (material[l], instance[l]) != surface_of_base {
                    let Some(b) = self.lambertian_base(material[l], instance[l]) else { return false };
                    (surface_of_base, base) = ((material[l], instance[l]), b);
                }
                for c in 0..3 {
                    f_up[c][l] = base[c] * FRAC_1_PI;
                }
            }
        }
        // Point j's entries must be `e0 + (j - first) k ..` for a k shared by the block.
        let offsets = &self.lighting.offsets[first..=first + LANES];
        let (e0, k) = (offsets[0] as usize, (offsets[1] - offsets[0]) as usize);
        if offsets.iter().enumerate().any(|(l, &o)| o as usize != e0 + l * k) {
            return false;
        }
        let mut sum = [[0.0f32; LANES]; 3];
        // A literal stride of 1 lets LLVM load the common case's columns as contiguous runs.
        if k == 1 {
            self.add_entry_lanes(first, e0, 1, &f_up, &mut sum);
        } else {
            for slot in 0..k {
                self.add_entry_lanes(first, e0 + slot, k, &f_up, &mut sum);
            }
        }
        for (l, o) in out.iter_mut().enumerate() {
            *o = Vec3::new(sum[0][l], sum[1][l], sum[2][l]);
        }
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
        if self.lights_of_instance.get(instance as usize).is_some_and(|rows| !rows.is_empty()) {
            return None;
        }
        Some([bsdf.base.0[0], bsdf.base.0[1], bsdf.base.0[2]])
    }

    /// Adds to `sum` the light of entry `e + l stride` at camera sample `first + l` for every lane
    /// l, as `ShadeContext::shade` would. Loops over the lanes without branches (selects, `&`,
    /// both sides computed), so that they vectorise.
    #[inline(always)]
    fn add_entry_lanes(
        &self,
        first: usize,
        e: usize,
        stride: usize,
        f_up: &[[f32; LANES]; 3],
        sum: &mut [[f32; LANES]; 3],
    ) {
        let lighting = self.lighting;
        let mis = self.strategy == Strategy::Mis;
        // The other strategies weigh every light sample alike, whatever its pdfs.
        let fixed_weight = self.strategy.light_weight(1.0, 1.0);
        let dir = self.columns.dir.each_ref().map(|c| lanes::block(c, first));
        let shading_normal = &self.batch.shading_normal[first..first + LANES];
        // Slices of a length known at compile time for a literal stride: no bounds checks in the loop.
        let span = e..e + (LANES - 1) * stride + 1;
        let (wi, pdf, delta, radiance) = (
            &lighting.wi[span.clone()],
            &lighting.pdf[span.clone()],
            &lighting.delta[span.clone()],
            &lighting.radiance[span],
        );
        // One step per loop over the lanes: as one loop of whole entries, LLVM vectorised the
        // first eight lanes and left the other eight scalar.
        let (mut wo, mut wi_l, mut li) = ([[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3]);
        let (mut pdf_l, mut delta_l) = ([0.0f32; LANES], [false; LANES]);
        for l in 0..LANES {
            let e = l * stride;
            let r = radiance[e];
            for a in 0..3 {
                (wo[a][l], li[a][l]) = (-dir[a][l], r.0[a]);
            }
            (pdf_l[l], delta_l[l]) = (pdf[e], delta[e]);
        }
        // Runs of whole blocks, read as such (see `lanes::columns`).
        let ns = lanes::columns(lanes::block(shading_normal, 0));
        if stride == 1 {
            wi_l = lanes::columns(lanes::block(wi, 0));
        } else {
            for l in 0..LANES {
                let w = wi[l * stride];
                (wi_l[0][l], wi_l[1][l], wi_l[2][l]) = (w.x, w.y, w.z);
            }
        }
        // Selects as bit masks (all ones or zero): selects on arrays of bools stayed scalar.
        let (mut upper, mut s, mut counts) = ([0u32; LANES], [0.0f32; LANES], [0u32; LANES]);
        for l in 0..LANES {
            // `Bsdf::f` and `Bsdf::pdf` without a specular lobe: the frame's z is `ns`.
            let cos_o = (wo[0][l] * ns[0][l]) + (wo[1][l] * ns[1][l]) + (wo[2][l] * ns[2][l]);
            let cos_i = (wi_l[0][l] * ns[0][l]) + (wi_l[1][l] * ns[1][l]) + (wi_l[2][l] * ns[2][l]);
            let is_upper = (cos_o > 0.0) & (cos_i > 0.0);
            upper[l] = 0u32.wrapping_sub(is_upper as u32);
            let bsdf_pdf = if is_upper { cosine_hemisphere_pdf(cos_i) } else { 0.0 };
            let pdf = pdf_l[l];
            let light_weight = if mis { power_heuristic(pdf, bsdf_pdf) } else { fixed_weight };
            let w = if delta_l[l] { 1.0 } else { light_weight };
            s[l] = cos_i.abs() * w / pdf;
            // `shade` skips entries with pdf <= 0 and weight 0 (NaN goes on, as there).
            counts[l] = 0u32.wrapping_sub((((pdf > 0.0) | pdf.is_nan()) & (w != 0.0)) as u32);
        }
        for c in 0..3 {
            for l in 0..LANES {
                let f = f32::from_bits(f_up[c][l].to_bits() & upper[l]);
                let added = sum[c][l] + f * li[c][l] * s[l];
                sum[c][l] = f32::from_bits((added.to_bits() & counts[l]) | (sum[c][l].to_bits() & !counts[l]));
            }
        }
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
