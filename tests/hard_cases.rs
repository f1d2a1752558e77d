//! Hard cases, one named test each: every output is finite, and matches the analytic value where
//! one exists.

use std::f32::consts::PI;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Rectangle, Transform};
use kelvin::light::*;
use kelvin::scene::image::RgbImage;
use kelvin::shading::{DirectLighting, LightSamplerKind, RunReport, SceneBounds, Settings, ShadingBatch};
use kelvin::spectrum::{SampledWavelengths, Spectrum};
use kelvin::systems::LightingPlugin;

fn us(n: usize) -> impl Iterator<Item = Vec2> {
    let mut s = 0x1234_5678u64;
    (0..n).map(move |_| {
        s = kelvin::rng::mix64(s);
        Vec2::new((s >> 40) as f32 / 16_777_216.0, ((s >> 8) & 0xff_ffff) as f32 / 16_777_216.0)
    })
}

/// Mean and standard error of L cos / pdf over `n` light samples (irradiance), asserting every
/// sample is finite.
fn irradiance_stats(light: &ResolvedArea, ctx: &LightSampleContext, n: usize) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0, 0.0);
    for u in us(n) {
        if let Some(s) = light.sample_li(ctx, u, ColorQuery::Rgb) {
            assert!(s.radiance.is_finite() && s.pdf.is_finite() && s.pdf > 0.0 && s.wi.is_finite(), "{s:?}");
            assert!(light.pdf_li(ctx, s.wi).is_finite());
            let v = (s.radiance.0[1] * s.wi.dot(ctx.n).max(0.0) / s.pdf) as f64;
            sum += v;
            sum2 += v * v;
        }
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}

fn irradiance(light: &ResolvedArea, ctx: &LightSampleContext, n: usize) -> f64 {
    irradiance_stats(light, ctx, n).0
}

/// Lambert's formula: irradiance at the origin (normal `n`) from a polygon of radiance `l`.
fn lambert_polygon(vertices: &[Vec3], n: Vec3, l: f64) -> f64 {
    let k = vertices.len();
    (0..k)
        .map(|i| {
            let (a, b) = (vertices[i].as_dvec3().normalize(), vertices[(i + 1) % k].as_dvec3().normalize());
            let c = a.cross(b);
            a.angle_between(b) * n.as_dvec3().dot(c.normalize())
        })
        .sum::<f64>()
        .abs()
        * l
        / 2.0
}

fn sphere_light(r: f32) -> ResolvedArea {
    let l = AreaLight { amount: Amount::Nits(100.0), two_sided: true, ..Default::default() };
    l.resolve_sphere(r, &Transform::default()).unwrap()
}

#[test]
fn hard_case_sphere_light_shading_point_on_inside_and_just_outside() {
    let r = 2.0f32;
    let light = sphere_light(r);
    // Inside (centre and halfway), on the surface, and outside at 1e-7 r and 1e-3 r.
    for d in [0.0, 0.5 * r, r, r * (1.0 + 1e-7), r * (1.0 + 1e-3), 3.0 * r] {
        let p = Vec3::new(0.0, d, 0.0);
        let ctx = LightSampleContext::on_surface(p, Vec3::Y);
        let e = irradiance(&light, &ctx, 20_000);
        assert!(e.is_finite(), "d = {d}: {e}");
        if d > r * 1.0001 {
            // Outside, facing away from the centre: the normal points away, so nothing arrives.
            assert!(e < 1e-6, "d = {d}: facing away yet E = {e}");
        }
        let facing = LightSampleContext::on_surface(p + Vec3::Y * 0.0, Vec3::NEG_Y);
        let e_in = irradiance(&light, &facing, 20_000);
        if d >= 3.0 * r {
            let want = PI as f64 * 100.0 * ((r / d) as f64).powi(2);
            assert!((e_in / want - 1.0).abs() < 0.02, "d = {d}: {e_in} vs {want}");
        }
        assert!(e_in.is_finite());
    }
}

#[test]
fn hard_case_triangle_solid_angle_extremes_1e8_sr_and_near_2pi() {
    let l = AreaLight { amount: Amount::Nits(10.0), two_sided: true, ..Default::default() };
    // Tiny: a 1e-4 m triangle 1 m away (~5e-9 sr).
    let tiny = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(1e-4, 1.0, 0.0), Vec3::new(0.0, 1.0, 1e-4)];
    // Huge: a 10 m triangle 1 cm above the point (about 6.27 sr, near 2 pi).
    let huge = [Vec3::new(-10.0, 1e-2, -10.0), Vec3::new(10.0, 1e-2, -10.0), Vec3::new(0.0, 1e-2, 10.0)];
    for (name, tri) in [("tiny", tiny), ("huge", huge)] {
        let mesh = l.resolve_mesh(&tri, &[], &[0, 1, 2], &Transform::default()).unwrap();
        let light = &mesh.triangles[0];
        let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
        let (e, se) = irradiance_stats(light, &ctx, 200_000);
        let want = lambert_polygon(&tri, Vec3::Y, 10.0);
        eprintln!("{name}: E = {e:.6e} +- {se:.1e}, Lambert {want:.6e}");
        assert!(e.is_finite() && (e - want).abs() <= 4.0 * se + 1e-4 * want, "{name}: {e} +- {se} vs {want}");
    }
}

#[test]
fn hard_case_degenerate_emissive_triangles_are_skipped() {
    let l = AreaLight::default();
    let p = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::ZERO, Vec3::Y, Vec3::Z];
    // Triangle 0: collinear; triangle 1: repeated vertex; triangle 2: a real one.
    let m = l.resolve_mesh(&p, &[], &[0, 1, 2, 3, 3, 4, 3, 4, 5], &Transform::default()).unwrap();
    assert_eq!(m.triangles.len(), 1);
    assert_eq!(m.skipped_degenerate, 2);
    assert_eq!(m.primitives, vec![2]);
    assert!(m.triangles[0].phi().is_finite() && m.triangles[0].phi() > 0.0);
}

#[test]
fn hard_case_grazing_angle_cos_1e_7() {
    let point = PointLight::candela(100.0).resolve(&Transform::from_translation(Vec3::new(1.0, 1e-7, 0.0))).unwrap();
    let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
    let s = point.sample_li(&ctx, ColorQuery::Rgb).unwrap();
    let e = s.radiance.0[1] * s.wi.dot(ctx.n);
    assert!(e.is_finite() && (e / 1e-5 - 1.0).abs() < 1e-2, "I cos / r^2 = 100 * 1e-7: {e}");
    let rect = AreaLight { amount: Amount::Nits(1.0), two_sided: true, ..Default::default() };
    let up = Transform::from_translation(Vec3::new(5.0, 1e-7, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
    let light = rect.resolve_rectangle(1.0, 1.0, &up).unwrap();
    assert!(irradiance(&light, &ctx, 10_000).is_finite());
}

#[test]
fn hard_case_spot_inner_equals_outer_outer_90_and_180_degrees() {
    let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
    for (inner, outer) in [(0.3, 0.3), (0.0, PI / 2.0), (0.5, PI)] {
        let spot =
            SpotLight { amount: Amount::Lumens(1000.0), inner_angle: inner, outer_angle: outer, ..Default::default() };
        let r = spot.resolve(&Transform::from_translation(Vec3::Y * 2.0).looking_to(Vec3::NEG_Y, Vec3::Z)).unwrap();
        assert!(r.phi().is_finite() && r.phi() > 0.0, "{inner} {outer}");
        let s = r.sample_li(&ctx, ColorQuery::Rgb).unwrap();
        assert!(s.radiance.is_finite() && s.radiance.0[1] > 0.0);
        // Behind the light, 14 degrees off its back axis: zero unless the cone covers it.
        let behind =
            r.sample_li(&LightSampleContext::on_surface(Vec3::new(0.5, 4.0, 0.0), Vec3::NEG_Y), ColorQuery::Rgb);
        assert_eq!(behind.is_some(), outer == PI, "{inner} {outer}");
    }
}

#[test]
fn hard_case_blackbody_emitters_at_1k_and_1e9k() {
    let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
    for t in [1.0, 1e9] {
        let light = PointLight {
            amount: Amount::Watts(100.0),
            spectrum: Spectrum::blackbody(t).unwrap(),
            ..Default::default()
        };
        let r = light.resolve(&Transform::from_translation(Vec3::Y)).unwrap();
        assert!(r.phi().is_finite() && r.intensity.rgb.is_finite(), "{t} K");
        let w = SampledWavelengths::sample_visible(0.3);
        let s = r.sample_li(&ctx, ColorQuery::Spectral(&w)).unwrap();
        assert!(s.radiance.is_finite(), "{t} K: {:?}", s.radiance);
        // 1 K emits nothing visible; lumens of it are zero, not NaN.
        let lum = PointLight {
            amount: Amount::Lumens(100.0),
            spectrum: Spectrum::blackbody(t).unwrap(),
            ..Default::default()
        };
        assert!(lum.resolve(&Transform::default()).unwrap().phi().is_finite());
    }
}

fn env_light(image: RgbImage) -> Option<ResolvedImageInfinite> {
    let light = ImageInfiniteLight::new(Arc::new(image));
    light.resolve(&Transform::default(), SceneSphere::default()).ok()
}

#[test]
fn hard_case_environment_maps_zero_single_hot_pixel_and_tiny() {
    let ctx = LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y);
    let zeros = RgbImage { width: 8, height: 4, pixels: vec![Vec3::ZERO; 32] };
    let mut hot = vec![Vec3::splat(1e-3); 64 * 32];
    hot[10 * 64 + 20] = Vec3::splat(1e9);
    let hot = RgbImage { width: 64, height: 32, pixels: hot };
    let one = RgbImage { width: 1, height: 1, pixels: vec![Vec3::ONE] };
    let row = RgbImage { width: 7, height: 1, pixels: vec![Vec3::ONE; 7] };
    let col = RgbImage { width: 1, height: 5, pixels: vec![Vec3::ONE; 5] };
    for (name, img) in [("zeros", zeros), ("hot", hot), ("1x1", one), ("7x1", row), ("1x5", col)] {
        let light = env_light(img).unwrap_or_else(|| panic!("{name} resolves"));
        assert!(light.phi().is_finite(), "{name}");
        for u in us(2000) {
            if let Some(s) = light.sample_li(&ctx, u, ColorQuery::Rgb) {
                assert!(s.radiance.is_finite() && s.pdf.is_finite() && s.pdf > 0.0, "{name}");
                assert!(light.pdf_li(s.wi).is_finite());
            } else {
                assert_eq!(name, "zeros", "only the black map has nothing to sample");
            }
        }
    }
}

#[test]
fn hard_case_nan_inf_negative_env_pixels_error_or_clamp() {
    let dir = std::env::temp_dir().join(format!("kelvin-hard-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, v) in [("nan", f32::NAN), ("inf", f32::INFINITY), ("neg", -1.0)] {
        let mut px = vec![Vec3::ONE; 16];
        px[5] = Vec3::new(v, 0.5, 0.5);
        let path = dir.join(format!("{name}.exr"));
        kelvin::render::film_io::write_exr(&path, 4, 4, &px).unwrap();
        match kelvin::scene::image::load_image(&path) {
            Err(e) => {
                assert!(name != "neg", "negative pixels are clamped, not rejected");
                assert!(e.to_string().contains(&format!("{name}.exr")), "error names the file: {e}");
            }
            Ok(loaded) => {
                assert_eq!(name, "neg", "NaN and Inf are rejected (as pbrt-v4 does)");
                assert!(!loaded.warnings.is_empty() && loaded.image.pixels.iter().all(|p| p.min_element() >= 0.0));
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn hard_case_far_from_the_origin_at_1e5() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let origin = Vec3::new(1e5, 1e5, -1e5);
    let floor = Transform::from_translation(origin).looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Rectangle { half_size: Vec2::splat(100.0) }, floor));
    world.spawn((PointLight::candela(100.0), Transform::from_translation(origin + Vec3::new(3.0, 2.0, 1.0))));
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        for i in 0..64 {
            let p = origin + Vec3::new(i as f32 * 0.37 - 12.0, 0.0, i as f32 * 0.11 - 3.0);
            batch.push(p, Vec3::Y, i, 0);
        }
    }
    schedule.run(&mut world);
    let out = world.resource::<DirectLighting>();
    assert!(out.radiance.iter().all(|r| r.is_finite()));
    assert!(out.occluded.iter().all(|&o| !o), "no point on the floor shadows itself at 1e5");
}

#[test]
fn hard_case_zero_power_lights_in_every_sampler() {
    for kind in [LightSamplerKind::Uniform, LightSamplerKind::Power, LightSamplerKind::Bvh] {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings { light_sampler: kind, ..Default::default() });
        LightingPlugin::build(&mut world, &mut schedule);
        world.spawn((PointLight::candela(0.0), Transform::from_translation(Vec3::Y)));
        world.spawn((
            SpotLight { amount: Amount::Lumens(0.0), ..Default::default() },
            Transform::from_translation(Vec3::Y),
        ));
        world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
        schedule.run(&mut world);
        let out = world.resource::<DirectLighting>();
        assert!(out.radiance.iter().all(|r| r.is_finite() && r.0.iter().all(|&v| v == 0.0)), "{kind:?}");
        assert!(out.pdf.iter().all(|p| p.is_finite()), "{kind:?}");
        if kind != LightSamplerKind::Uniform {
            assert!(out.pdf.iter().all(|&p| p == 0.0), "{kind:?}: zero-power lights are never chosen");
        }
        // One light with power among zero-power ones: only it is chosen.
        world.spawn((PointLight::candela(10.0), Transform::from_translation(Vec3::Y * 2.0)));
        schedule.run(&mut world);
        let out = world.resource::<DirectLighting>();
        assert!(out.radiance.iter().all(|r| r.is_finite()));
    }
}

#[test]
fn hard_case_empty_ecs_after_every_light_is_removed() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let lights: Vec<Entity> = (0..10)
        .map(|i| {
            world.spawn((PointLight::candela(i as f32), Transform::from_translation(Vec3::Y * (i + 1) as f32))).id()
        })
        .collect();
    world.spawn(UniformInfiniteLight::nits(10.0));
    world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    schedule.run(&mut world);
    for e in lights {
        world.despawn(e);
    }
    let sky: Vec<Entity> = world.query_filtered::<Entity, With<UniformInfiniteLight>>().iter(&world).collect();
    for e in sky {
        world.despawn(e);
    }
    schedule.run(&mut world);
    assert!(world.resource::<LightTable>().is_empty());
    assert!(world.resource::<DirectLighting>().radiance.iter().all(|r| r.0 == [0.0; 4]));
    assert!(!world.resource::<RunReport>().ran("sample_direct_lighting"));
    let _ = world.resource::<SceneBounds>();
}
