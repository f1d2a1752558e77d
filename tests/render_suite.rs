//! The render suite (`kelvin bench render`, kelvin::report::render_bench): every scene's files are
//! in tests/data and load into a world that renders lit, with the counts the generators wrote;
//! scaling_10k.glb is the scaling scene's own layout (so it goes stale loudly if
//! `spawn_scaling_scene` changes: rerun `cargo run --release --example export_scaling_gltf`).

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{Amount, PointLight, SpotLight};
use kelvin::render::renderer::{Integrator, render};
use kelvin::report::render_bench::{SUITE, suite_options, suite_scene};
use kelvin::spectrum::Spectrum;

mod common;
use common::files::test_data;

#[test]
fn every_suite_scene_loads_and_renders_lit() {
    let data = test_data("");
    for scene in SUITE {
        test_data(scene.file);
        if let Some((map, _)) = scene.env {
            test_data(map);
        }
        let (mut world, mut schedule, report) = scene.world(&data).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        assert!(report.meshes > 0, "{}: no meshes", scene.name);
        let (film, stats) = render(&mut world, &mut schedule, &suite_options(16, 16, 1, Integrator::Direct), |_| {});
        assert_eq!(stats.camera_samples, 256);
        let sum: f32 = film.pixels().iter().map(|c| c.x + c.y + c.z).sum();
        assert!(sum.is_finite() && sum > 0.0, "{}: black or non-finite render ({sum})", scene.name);
        assert!(scene.default_spp(128, 128) == scene.spp_128 && scene.default_spp(256, 256) >= 1);
    }
}

/// The suite measures both integrators: on points (point lights only) direct lighting traces no
/// BSDF ray, while the path tracer at depth 2 continues every path that finds a surface with one;
/// at depth 1 the path tracer is direct lighting, ray for ray.
#[test]
fn the_suite_runs_the_path_tracer_too() {
    use kelvin::render::path::PathDepth;
    use kelvin::report::render_bench::{RenderBenchConfig, run_scene};
    let scene = suite_scene("points").unwrap();
    let run = |integrator| {
        let cfg = RenderBenchConfig {
            data_dir: test_data(""),
            width: 16,
            height: 16,
            spp: Some(2),
            repeat: 1,
            integrator,
            ..RenderBenchConfig::default()
        };
        run_scene(scene, &cfg).unwrap()
    };
    let depth = |d| Integrator::Path(PathDepth { max_depth: d, ..PathDepth::DEFAULT });
    let (direct, one, two) = (run(Integrator::Direct), run(depth(1)), run(depth(2)));
    assert_eq!((direct.integrator.as_str(), two.integrator.as_str()), ("direct", "path, depth 2"));
    assert_eq!((direct.bsdf_rays, one.bsdf_rays), (0, 0));
    assert_eq!(one.shadow_rays, direct.shadow_rays);
    assert!(two.bsdf_rays > 0 && two.shadow_rays > direct.shadow_rays, "{} BSDF rays", two.bsdf_rays);
}

/// The suite measures every light sampler with both integrators: `world_with` hands the choice
/// to the light system, and each sampler (all unbiased: ReSTIR with its default weights) renders
/// emissive_strength's 60 emissive triangles to the light BVH's mean brightness under the same
/// integrator, within 3% at 64 spp.
#[test]
fn the_suite_runs_every_light_sampler_to_the_same_image_mean() {
    use kelvin::render::job::{RenderJob, SamplerChoice};
    use kelvin::render::path::PathDepth;
    use kelvin::shading::Settings;
    let data = test_data("");
    let scene = suite_scene("emissive_strength").unwrap();
    let samplers =
        [SamplerChoice::Bvh, SamplerChoice::Uniform, SamplerChoice::Power, SamplerChoice::Ris, SamplerChoice::Restir];
    let path = Integrator::Path(PathDepth { max_depth: 3, ..PathDepth::DEFAULT });
    for integrator in [Integrator::Direct, path] {
        let mut means = Vec::new();
        for sampler in samplers {
            let (mut world, mut schedule, _) = scene.world_with(&data, sampler).unwrap();
            let job = RenderJob { light_sampler: sampler, ..RenderJob::default() };
            let settings = world.resource::<Settings>();
            assert_eq!((settings.light_sampler, settings.selection), (job.settings().light_sampler, job.selection()));
            let (film, _) = render(&mut world, &mut schedule, &suite_options(24, 24, 64, integrator), |_| {});
            let pixels = film.pixels();
            means.push(pixels.iter().map(|c| f64::from(c.x + c.y + c.z)).sum::<f64>() / pixels.len() as f64);
        }
        assert!(means[0] > 0.0, "{integrator:?} lit: {means:?}");
        for (k, m) in means.iter().enumerate() {
            assert!(
                (m / means[0] - 1.0).abs() < 0.03,
                "{integrator:?}, sampler {k}: mean {m} against the light BVH's {} (all: {means:?})",
                means[0]
            );
        }
    }
}

#[test]
fn generated_scenes_have_the_counts_their_generators_wrote() {
    let data = test_data("");
    let counts = |name: &str| {
        let (_, _, r) = suite_scene(name).expect("a suite scene").world(&data).expect("loads");
        (r.meshes, r.triangles, r.lights, r.cameras)
    };
    // Floor quad + the 256 x 129 UV sphere; one point light; one camera.
    assert_eq!(counts("sphere_65k"), (2, 2 + 65_536, 1, 1));
    // Floor + three boxes + three 48 x 24 spheres.
    assert_eq!(counts("env_objects"), (7, 2 + 3 * 12 + 3 * 2 * 48 * 23, 0, 1));
    // Ground quad + 1,250 instances of the 16 x 8 sphere; 10,000 lights.
    assert_eq!(counts("scaling_10k"), (1 + 1250, 2 + 1250 * 2 * 16 * 7, 10_000, 1));
}

/// Position bits, for matching lights of two worlds whatever their order.
fn key(t: &Transform) -> [u32; 3] {
    t.translation.to_array().map(f32::to_bits)
}

#[test]
fn scaling_10k_glb_is_the_scaling_scene() {
    let data = test_data("");
    let (mut file, _, _) = suite_scene("scaling_10k").unwrap().world(&data).unwrap();
    let mut generated = World::new();
    let scene = kelvin::scenes::spawn_scaling_scene(&mut generated, 10_000, 1);
    assert_eq!(scene.lights.len(), 10_000);

    // The colour a light renders with in RGB mode; glTF's RGB colour comes back through kelvin's RGB
    // illuminant spectrum, within about 1e-3 of the blackbody's (2700 K red).
    let colour = |s: &Spectrum| s.srgb_normalized().as_vec3();
    // Within 1e-4: the file's colours were normalised with Rec. 709's 4-digit luminance weights, the
    // loader weighs them with the sRGB matrix's Y row (0.2126729, ...), 3e-5 apart on these colours.
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * b.abs().max(1.0);
    let mut points: Vec<_> =
        file.query::<(&PointLight, &Transform)>().iter(&file).map(|(l, t)| (key(t), l.clone())).collect();
    let mut spots: Vec<_> =
        file.query::<(&SpotLight, &Transform)>().iter(&file).map(|(l, t)| (key(t), l.clone(), *t)).collect();
    points.sort_by_key(|p| p.0);
    spots.sort_by_key(|s| s.0);
    let mut gen_points: Vec<_> =
        generated.query::<(&PointLight, &Transform)>().iter(&generated).map(|(l, t)| (key(t), l.clone())).collect();
    let mut gen_spots: Vec<_> =
        generated.query::<(&SpotLight, &Transform)>().iter(&generated).map(|(l, t)| (key(t), l.clone(), *t)).collect();
    gen_points.sort_by_key(|p| p.0);
    gen_spots.sort_by_key(|s| s.0);
    assert_eq!((points.len(), spots.len()), (gen_points.len(), gen_spots.len()));

    for ((k, l), (gk, g)) in points.iter().zip(&gen_points) {
        assert_eq!(k, gk, "point light positions");
        let (Amount::Candela(cd), Amount::Lumens(lm)) = (l.amount, g.amount) else { panic!("amounts") };
        assert!(close(cd, lm / (4.0 * std::f32::consts::PI)), "{cd} cd for {lm} lm");
        let (a, b) = (colour(&l.spectrum), colour(&g.spectrum));
        assert!(a.abs_diff_eq(b, 3e-3), "colour {a} against {b}");
    }
    for ((k, l, t), (gk, g, gt)) in spots.iter().zip(&gen_spots) {
        assert_eq!(k, gk, "spot light positions");
        assert_eq!((l.inner_angle, l.outer_angle), (g.inner_angle, g.outer_angle));
        assert!(t.forward().abs_diff_eq(gt.forward(), 1e-6), "spot directions");
        let (ci, co) = (g.inner_angle.cos(), g.outer_angle.cos());
        let omega = 2.0 * std::f32::consts::PI * ((1.0 - ci) + (ci - co) / 2.0);
        let (Amount::Candela(cd), Amount::Lumens(lm)) = (l.amount, g.amount) else { panic!("amounts") };
        assert!(close(cd, lm / omega), "{cd} cd for {lm} lm");
        let (a, b) = (colour(&l.spectrum), colour(&g.spectrum));
        assert!(a.abs_diff_eq(b, 3e-3), "colour {a} against {b}");
    }
    // The ground and the spheres: each mesh's world bounds are a generated shape's (the 16 x 8 sphere
    // reaches its radius exactly along each axis).
    let bounds = |m: &kelvin::geometry::Mesh| {
        let p = m.positions();
        p.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
    };
    let mut q = file.query::<&kelvin::geometry::Mesh>();
    let mut balls: Vec<(Vec3, Vec3)> = Vec::new();
    for m in q.iter(&file) {
        let (lo, hi) = bounds(m);
        if m.triangle_count() == 2 {
            let half = scene.half_extent + 10.0;
            assert!(
                lo.abs_diff_eq(Vec3::new(-half, 0.0, -half), 1e-3) && hi.abs_diff_eq(Vec3::new(half, 0.0, half), 1e-3)
            );
        } else {
            balls.push((0.5 * (lo + hi), 0.5 * (hi - lo)));
        }
    }
    let mut gen_balls: Vec<(Vec3, Vec3)> = generated
        .query::<(&kelvin::geometry::Sphere, &Transform)>()
        .iter(&generated)
        .map(|(s, t)| (t.translation, Vec3::splat(s.radius)))
        .collect();
    let order = |v: &mut Vec<(Vec3, Vec3)>| v.sort_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.z.total_cmp(&b.0.z)));
    order(&mut balls);
    order(&mut gen_balls);
    assert_eq!(balls.len(), gen_balls.len());
    for (b, g) in balls.iter().zip(&gen_balls) {
        assert!(b.0.abs_diff_eq(g.0, 1e-4) && b.1.abs_diff_eq(g.1, 1e-5), "sphere {b:?} against {g:?}");
    }
}
