//! The path tracer against closed forms: a closed emitting furnace, the white furnace under a
//! uniform sky, and depth 1 against the direct integrator on a real file.

mod common;

use bevy_ecs::prelude::*;
use common::lobe_grid::LobeGrid;
use glam::Vec3;
use kelvin::geometry::{Mesh, Sphere, Transform};
use kelvin::light::{Amount, AreaLight, UniformInfiniteLight};
use kelvin::render::bsdf::Bsdf;
use kelvin::render::camera::Camera;
use kelvin::render::material::Material;
use kelvin::render::path::PathDepth;
use kelvin::render::renderer::{Integrator, RenderOptions, render};
use kelvin::sampling::Frame;
use kelvin::shading::{ColorMode, Settings};
use kelvin::spectrum::SampledSpectrum;
use kelvin::systems::LightingPlugin;

fn luminance(c: Vec3) -> f64 {
    (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) as f64
}

/// Mean luminance over pixels and its standard error (pixels are independent estimates).
fn mean_and_error(pixels: &[Vec3]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let ys: Vec<f64> = pixels.iter().map(|&p| luminance(p)).collect();
    let mean = ys.iter().sum::<f64>() / n;
    let var = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn path(max_depth: u32) -> Integrator {
    Integrator::Path(PathDepth { max_depth, ..PathDepth::DEFAULT })
}

fn world_with(mode: ColorMode, seed: u64) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { color_mode: mode, seed, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    (world, schedule)
}

/// The camera at the centre of a closed UV sphere (radius 1) whose inside is Lambertian of
/// albedo `albedo` and emits `le` nit, wound so that its front faces point inward.
fn closed_furnace(mode: ColorMode, albedo: f32, le: f32) -> (World, Schedule) {
    let (mut world, schedule) = world_with(mode, 3);
    let sphere = Mesh::uv_sphere(1.0, 24, 12);
    let inward: Vec<u32> = sphere.indices().chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect();
    let mesh = Mesh::new(sphere.positions().to_vec(), inward).unwrap();
    let light = AreaLight { amount: Amount::Nits(le), ..Default::default() };
    world.spawn((mesh, Transform::default(), Material::lambertian(Vec3::splat(albedo)), light));
    world.spawn((Camera { yfov: 1.5 }, Transform::default().looking_to(Vec3::new(0.3, -0.2, -1.0), Vec3::Y)));
    (world, schedule)
}

fn render_pixels(world: &mut World, schedule: &mut Schedule, size: u32, spp: u32, integrator: Integrator) -> Vec<Vec3> {
    let opts = RenderOptions { width: size, height: size, spp, integrator, ..Default::default() };
    render(world, schedule, &opts, |_| {}).0.pixels()
}

/// Inside a closed furnace every path sees Le at each surface and keeps a fraction a of its
/// throughput per bounce: L = Le (1 - a^(d+1)) / (1 - a) with at most d bounces after the
/// camera's surface, Le / (1 - a) without a limit (roulette ends the paths, without bias).
#[test]
fn closed_furnace_gives_the_geometric_series_of_its_albedo_at_every_depth() {
    let le = 2.0f32;
    let cases = [
        (ColorMode::Rgb, 0.5, Some(0)),
        (ColorMode::Rgb, 0.5, Some(1)),
        (ColorMode::Rgb, 0.5, Some(3)),
        (ColorMode::Rgb, 0.3, None),
        (ColorMode::Rgb, 0.8, None),
        (ColorMode::Spectral, 0.5, Some(2)),
        (ColorMode::Spectral, 0.7, None),
    ];
    for (mode, a, depth) in cases {
        let (mut world, mut schedule) = closed_furnace(mode, a, le);
        let max_depth = depth.unwrap_or(u32::MAX);
        let spp = if mode == ColorMode::Rgb { 16 } else { 64 };
        let pixels = render_pixels(&mut world, &mut schedule, 16, spp, path(max_depth));
        let (got, error) = mean_and_error(&pixels);
        let a = a as f64;
        let want = match depth {
            Some(d) => le as f64 * (1.0 - a.powi(d as i32 + 1)) / (1.0 - a),
            None => le as f64 / (1.0 - a),
        };
        eprintln!("{mode:?} a = {a} depth {depth:?}: {got:.5} +- {error:.5}, expected {want:.5}");
        // The sphere is of triangles and the light's radiance is exact: only noise remains,
        // plus the colour conversion's rounding in spectral mode.
        let tolerance = 3.0 * error + want * if mode == ColorMode::Rgb { 1e-4 } else { 5e-3 };
        assert!((got - want).abs() < tolerance, "{mode:?} a = {a} depth {depth:?}: {got} vs {want} (+- {error})");
    }
}

/// A convex white object under a uniform sky: whatever a path does, it ends seeing the sky, so
/// every pixel is the sky's radiance times the surface's directional albedo, at any depth >= 1.
fn furnace_pixels(material: Material, max_depth: u32, mode: ColorMode) -> Vec<Vec3> {
    let (mut world, mut schedule) = world_with(mode, 5);
    world.spawn((UniformInfiniteLight { amount: Amount::Nits(3.0), ..Default::default() }, Transform::default()));
    world.spawn((Sphere { radius: 1.0 }, Transform::default(), material));
    let eye = Vec3::new(0.0, 0.0, 4.0);
    world.spawn((Camera { yfov: 0.2 }, Transform::from_translation(eye).looking_to(-eye, Vec3::Y)));
    render_pixels(&mut world, &mut schedule, 12, 32, path(max_depth))
}

#[test]
fn white_lambertian_furnace_is_the_sky_at_every_pixel_and_depth() {
    for (mode, depth) in [(ColorMode::Rgb, 1), (ColorMode::Rgb, 2), (ColorMode::Rgb, 16), (ColorMode::Spectral, 5)] {
        let pixels = furnace_pixels(Material::lambertian(Vec3::ONE), depth, mode);
        let (got, error) = mean_and_error(&pixels);
        eprintln!("{mode:?} depth {depth}: {got:.5} +- {error:.5}");
        let tolerance = 3.0 * error + if mode == ColorMode::Rgb { 1e-4 } else { 0.01 };
        assert!((got - 3.0).abs() < tolerance, "{mode:?} depth {depth}: {got} +- {error}");
        // No pixel loses or gains energy beyond noise.
        assert!(pixels.iter().all(|&p| (luminance(p) - 3.0).abs() < 1.5), "{mode:?} depth {depth}");
    }
}

/// Single-scattering GGX loses energy: a white metal reflects E(wo) = integral of f cos over the
/// hemisphere, below 1. The furnace's centre pixels (seen head-on) must show the sky times E at
/// normal incidence, integrated here from `Bsdf::f` on a grid fine about the lobe, at roughness
/// 0.1 to 1 (roughness 1 alone cannot tell alpha = roughness from alpha = roughness^2).
#[test]
fn white_ggx_furnace_loses_the_energy_its_directional_albedo_says() {
    for roughness in [0.1f32, 0.4, 0.7, 1.0] {
        let material = Material { base_color: Vec3::ONE, metallic: 1.0, roughness, ..Default::default() };
        let bsdf = Bsdf::new(Frame::from_z(Vec3::Z), SampledSpectrum([1.0; 4]), 1.0, roughness, 0.0, 1.0);
        let grid = LobeGrid::new(Vec3::Z, (4.0 * roughness as f64 * roughness as f64).min(1.0), 64, 32);
        let cells = grid.integrate_cells(8, Vec3::Z, 8, |wi| bsdf.f(Vec3::Z, wi).0[1] as f64 * wi.z.max(0.0) as f64);
        let albedo: f64 = cells.iter().sum();
        eprintln!("white GGX metal, roughness {roughness}: E(normal incidence) = {albedo:.4}");
        if roughness == 1.0 {
            // At alpha 1, D = 1/pi and V = 1/(2 (cos_i + 1)) head-on, so E = 1 - ln 2.
            assert!((albedo - (1.0 - 2f64.ln())).abs() < 1e-4, "{albedo}");
        }
        for depth in [1, 4] {
            let pixels = furnace_pixels(material.clone(), depth, ColorMode::Rgb);
            // The 2x2 centre pixels see the sphere within 0.7 degrees of head-on.
            let centre: Vec<Vec3> = [(5, 5), (5, 6), (6, 5), (6, 6)].iter().map(|&(x, y)| pixels[y * 12 + x]).collect();
            let (got, error) = mean_and_error(&centre);
            let want = 3.0 * albedo;
            eprintln!("roughness {roughness} depth {depth}: centre {got:.4} +- {error:.4}, expected {want:.4}");
            assert!(
                (got - want).abs() < 4.0 * error + 0.01 * want,
                "roughness {roughness} depth {depth}: {got} vs {want}"
            );
        }
    }
}

/// At depth 1 the path tracer does what the direct integrator does (light and BSDF samples at
/// the camera's surface), with the same random numbers: the images agree to rounding.
#[test]
fn depth_one_agrees_with_the_direct_integrator_on_the_cornell_box() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bevy/CornellBox.glb");
    let mut images = Vec::new();
    for integrator in [Integrator::Direct, path(1)] {
        let (mut world, mut schedule) = world_with(ColorMode::Rgb, 11);
        kelvin::render::scene_file::spawn_gltf_file(&mut world, std::path::Path::new(file)).unwrap();
        images.push(render_pixels(&mut world, &mut schedule, 32, 8, integrator));
    }
    let (direct, traced) = (&images[0], &images[1]);
    let (mean, _) = mean_and_error(direct);
    assert!(mean > 0.0, "the box is lit");
    for (i, (d, p)) in direct.iter().zip(traced).enumerate() {
        let diff = (*d - *p).abs().max_element();
        assert!(diff <= 1e-4 * d.max_element().max(mean as f32), "pixel {i}: direct {d} path {p}");
    }
}

/// A Lambertian floor meeting a Lambertian wall at a right angle, both of albedo a and "infinite",
/// under a uniform sky of radiance L: every point of either plane sees half its cosine-weighted
/// hemisphere as sky and half as the other plane, so radiance is uniform and each bounce adds a
/// factor a/2: L_d = L * sum_{k=1..d} (a/2)^k, and a L / (2 - a) without a limit. The hard case is
/// light that reaches a surface only by bouncing (the half of the wall's hemisphere facing the
/// floor) in an open scene, at every depth, and the direct integrator as depth 1.
#[test]
fn a_floor_and_wall_under_a_uniform_sky_give_the_series_of_half_their_albedo() {
    let sky = 3.0f32;
    // Planes 2000 across, seen within 2 units of the corner: the sky beyond their edges is
    // ~1e-3 of the cosine weight.
    let s = 1000.0f32;
    let floor = Mesh::new(
        vec![Vec3::new(0.0, 0.0, -s), Vec3::new(0.0, 0.0, s), Vec3::new(s, 0.0, s), Vec3::new(s, 0.0, -s)],
        vec![0, 1, 2, 0, 2, 3],
    )
    .unwrap();
    let wall = Mesh::new(
        vec![Vec3::new(0.0, 0.0, -s), Vec3::new(0.0, s, -s), Vec3::new(0.0, s, s), Vec3::new(0.0, 0.0, s)],
        vec![0, 1, 2, 0, 2, 3],
    )
    .unwrap();
    for (a, integrator, bounces) in [
        (0.8f32, Integrator::Direct, Some(1)),
        (0.8, path(1), Some(1)),
        (0.8, path(2), Some(2)),
        (0.5, path(4), Some(4)),
        (0.8, path(u32::MAX), None),
    ] {
        let (mut world, mut schedule) = world_with(ColorMode::Rgb, 9);
        world.spawn((UniformInfiniteLight { amount: Amount::Nits(sky), ..Default::default() }, Transform::default()));
        for mesh in [floor.clone(), wall.clone()] {
            world.spawn((mesh, Transform::default(), Material::lambertian(Vec3::splat(a))));
        }
        let eye = Vec3::new(2.0, 1.0, 0.0);
        world.spawn((
            Camera { yfov: 0.6 },
            Transform::from_translation(eye).looking_to(Vec3::new(-1.0, -1.0, 0.0), Vec3::Y),
        ));
        let pixels = render_pixels(&mut world, &mut schedule, 16, 32, integrator);
        let (got, error) = mean_and_error(&pixels);
        let (h, l) = (a as f64 / 2.0, sky as f64);
        let want = match bounces {
            Some(d) => l * h * (1.0 - h.powi(d)) / (1.0 - h),
            None => l * h / (1.0 - h),
        };
        eprintln!("a = {a} {integrator:?}: {got:.5} +- {error:.5}, expected {want:.5}");
        assert!((got - want).abs() < 3.0 * error + 4e-3 * want, "a = {a} {integrator:?}: {got} vs {want} (+- {error})");
    }
}

/// A time budget renders passes of `spp` samples until it is spent, each pass drawing the next
/// samples of every pixel: the picture is the one-pass render at the total spp, bit for bit.
#[test]
fn time_budget_renders_passes_equal_to_one_render_at_their_total_spp() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bevy/CornellBox.glb");
    let render_with = |spp: u32, budget: Option<std::time::Duration>| {
        let (mut world, mut schedule) = world_with(ColorMode::Rgb, 2);
        kelvin::render::scene_file::spawn_gltf_file(&mut world, std::path::Path::new(file)).unwrap();
        let opts = RenderOptions { width: 12, height: 10, spp, time_budget: budget, ..Default::default() };
        let (film, stats) = render(&mut world, &mut schedule, &opts, |_| {});
        (film.pixels(), stats.spp)
    };
    let (passes, total) = render_with(2, Some(std::time::Duration::from_millis(300)));
    assert!(total >= 4 && total.is_multiple_of(2), "{total} spp in passes of 2");
    let (once, spp) = render_with(u32::try_from(total).unwrap(), None);
    assert_eq!(spp, total);
    let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    let lit = once.iter().filter(|p| p.max_element() > 0.0).count();
    assert!(lit > once.len() / 4, "the box is lit: {lit} of {} pixels", once.len());
    assert_eq!(bits(&passes), bits(&once), "{total} spp");
}
