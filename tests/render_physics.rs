//! Rendered pixels against closed forms: photometric units end to end (Y in cd/m^2).

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Rectangle, Transform};
use kelvin::light::{Amount, DistantLight, PointLight};
use kelvin::render::camera::Camera;
use kelvin::render::material::Material;
use kelvin::render::renderer::{Integrator, RenderOptions, Strategy, render};
use kelvin::shading::{ColorMode, Settings};
use kelvin::systems::LightingPlugin;

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A Lambertian floor (albedo `rho`, specular 0) at y = 0 seen from straight above.
fn floor_scene(mode: ColorMode, rho: f32) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { color_mode: mode, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z); // local +Z -> world +Y
    world.spawn((Rectangle { half_size: Vec2::splat(50.0) }, up, Material::lambertian(Vec3::splat(rho))));
    let cam = Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Camera { yfov: 0.01 }, cam));
    (world, schedule)
}

fn centre_luminance(world: &mut World, schedule: &mut Schedule, spp: u32) -> f32 {
    let opts = RenderOptions {
        width: 5,
        height: 5,
        spp,
        strategy: Strategy::Mis,
        integrator: Integrator::Direct,
        ..Default::default()
    };
    let (film, _) = render(world, schedule, &opts, |_| {});
    luminance(film.pixel(2, 2))
}

#[test]
fn point_light_over_lambertian_floor_gives_rho_over_pi_i_over_h2() {
    let (rho, i, h) = (0.5f32, 100.0f32, 2.0f32);
    let want = rho / std::f32::consts::PI * i / (h * h);
    for mode in [ColorMode::Rgb, ColorMode::Spectral] {
        let (mut world, mut schedule) = floor_scene(mode, rho);
        world.spawn((PointLight::candela(i), Transform::from_translation(Vec3::new(0.0, h, 0.0))));
        let spp = if mode == ColorMode::Rgb { 1 } else { 4096 };
        let got = centre_luminance(&mut world, &mut schedule, spp);
        eprintln!("{mode:?}: {got} cd/m^2, expected {want}");
        let tol = if mode == ColorMode::Rgb { 1e-3 } else { 0.02 };
        assert!((got / want - 1.0).abs() < tol, "{mode:?}: {got} vs {want}");
    }
}

/// Self-shadowing, the hard case of a flat floor: every shadow ray leaves the floor, and the floor
/// never blocks it (the any-hit query ignores the flat primitive a ray leaves, in any scene). A
/// ball off to the side is tested by the same rays and changes nothing.
#[test]
fn shadow_rays_leaving_a_floor_are_not_blocked_by_it_and_a_ball_aside_changes_nothing() {
    let (mut world, mut schedule) = floor_scene(ColorMode::Rgb, 0.5);
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
    let opts = RenderOptions::direct(5, 5, 4);
    let (alone, stats) = render(&mut world, &mut schedule, &opts, |_| {});
    assert_eq!(stats.shadow_rays, stats.camera_samples);
    assert!(alone.pixel(2, 2).max_element() > 0.0, "the floor shadowed itself");
    let ball = Transform::from_translation(Vec3::new(10.0, 1.0, 10.0));
    world.spawn((kelvin::geometry::Sphere { radius: 0.5 }, ball, Material::lambertian(Vec3::ONE)));
    let (with_ball, stats) = render(&mut world, &mut schedule, &opts, |_| {});
    assert_eq!(stats.shadow_rays, stats.camera_samples);
    assert_eq!(alone.pixel(2, 2), with_ball.pixel(2, 2));
}

#[test]
fn directional_light_gives_rho_over_pi_e_cos_theta() {
    let (rho, e) = (0.8f32, 1000.0f32);
    let theta = 60f32.to_radians();
    let want = rho / std::f32::consts::PI * e * theta.cos();
    let (mut world, mut schedule) = floor_scene(ColorMode::Rgb, rho);
    let dir = Vec3::new(theta.sin(), -theta.cos(), 0.0);
    world.spawn((
        DistantLight { amount: Amount::Lux(e), ..Default::default() },
        Transform::default().looking_to(dir, Vec3::Y),
    ));
    let got = centre_luminance(&mut world, &mut schedule, 1);
    eprintln!("directional: {got} cd/m^2, expected {want}");
    assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
}

/// Mean and standard error of the centre pixel's luminance over renders with different seeds.
fn centre_stats(
    world: &mut World,
    schedule: &mut Schedule,
    renders: u64,
    spp: u32,
    size: u32,
    strategy: Strategy,
) -> (f64, f64) {
    let opts = RenderOptions {
        width: size,
        height: size,
        spp,
        strategy,
        integrator: Integrator::Direct,
        ..Default::default()
    };
    let values: Vec<f64> = (0..renders)
        .map(|seed| {
            world.resource_mut::<Settings>().seed = seed;
            let (film, _) = render(world, schedule, &opts, |_| {});
            luminance(film.pixel(size / 2, size / 2)) as f64
        })
        .collect();
    let mean = values.iter().sum::<f64>() / renders as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (renders as f64 - 1.0);
    (mean, (var / renders as f64).sqrt())
}

#[test]
fn furnace_lambertian_sphere_under_uniform_sky_renders_albedo_times_l() {
    use kelvin::geometry::Sphere;
    use kelvin::light::UniformInfiniteLight;
    let (albedo, l) = (0.5f32, 100.0f32);
    let runs = [
        (ColorMode::Rgb, Strategy::Mis),
        (ColorMode::Spectral, Strategy::Mis),
        (ColorMode::Rgb, Strategy::LightOnly),
        (ColorMode::Rgb, Strategy::BsdfOnly),
    ];
    for (mode, strategy) in runs {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings { color_mode: mode, ..Default::default() });
        LightingPlugin::build(&mut world, &mut schedule);
        world.spawn((Sphere { radius: 1.0 }, Transform::default(), Material::lambertian(Vec3::splat(albedo))));
        world.spawn(UniformInfiniteLight::nits(l));
        let cam = Transform::from_translation(Vec3::new(0.0, 0.0, 5.0)).looking_to(Vec3::NEG_Z, Vec3::Y);
        world.spawn((Camera { yfov: 0.3 }, cam));
        let (mean, se) = centre_stats(&mut world, &mut schedule, 16, 16, 3, strategy);
        let want = (albedo * l) as f64;
        eprintln!("furnace {mode:?} {strategy:?}: {mean:.4} +- {se:.4} (want {want})");
        assert!((mean - want).abs() <= 3.0 * se + 1e-3 * want, "{mode:?} {strategy:?}: {mean} +- {se} vs {want}");
    }
}

/// The accuracy report's knobs that must not change a delta light's answer: BSDF-only keeps the
/// light samples of delta lights, f64 light math and a sane fixed shadow offset agree with f32 and
/// the error-bound offset.
#[test]
fn point_light_answer_is_the_same_under_strategy_precision_and_offset_knobs() {
    use kelvin::geometry::ShadowOffset;
    use kelvin::shading::LightPrecision;
    let (rho, i, h) = (0.5f32, 100.0f32, 2.0f32);
    let want = rho / std::f32::consts::PI * i / (h * h);
    let (mut world, mut schedule) = floor_scene(ColorMode::Rgb, rho);
    world.spawn((PointLight::candela(i), Transform::from_translation(Vec3::new(0.0, h, 0.0))));
    for (strategy, precision, offset) in [
        (Strategy::BsdfOnly, LightPrecision::F32, ShadowOffset::ErrorBound),
        (Strategy::LightOnly, LightPrecision::F64, ShadowOffset::ErrorBound),
        (Strategy::Mis, LightPrecision::F32, ShadowOffset::FixedEpsilon(1e-3)),
    ] {
        {
            let mut s = world.resource_mut::<Settings>();
            (s.light_precision, s.shadow_offset) = (precision, offset);
        }
        let opts = RenderOptions {
            width: 5,
            height: 5,
            spp: 1,
            strategy,
            integrator: Integrator::Direct,
            ..Default::default()
        };
        let (film, _) = render(&mut world, &mut schedule, &opts, |_| {});
        let got = luminance(film.pixel(2, 2));
        assert!((got / want - 1.0).abs() < 1e-3, "{strategy:?} {precision:?} {offset:?}: {got} vs {want}");
    }
}

/// View factor from a differential area to a parallel rectangle centred above it (a x b at
/// height h): four corner rectangles (Howell's catalogue, configuration B-3).
fn view_factor_centered(a: f64, b: f64, h: f64) -> f64 {
    let corner = |x: f64, y: f64| {
        let (x, y) = (x / h, y / h);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    };
    4.0 * corner(a / 2.0, b / 2.0)
}

#[test]
fn rectangle_area_light_matches_the_view_factor() {
    use kelvin::light::AreaLight;
    let (rho, l, h, a, b) = (0.6f32, 500.0f32, 1.0f32, 1.2f32, 0.8f32);
    let want = (rho * l) as f64 * view_factor_centered(a as f64, b as f64, h as f64);
    let (mut world, mut schedule) = floor_scene(ColorMode::Rgb, rho);
    let down = Transform::from_translation(Vec3::new(0.0, h, 0.0)).looking_to(Vec3::Y, Vec3::Z); // front -> -Y
    world.spawn((
        Rectangle { half_size: Vec2::new(a / 2.0, b / 2.0) },
        down,
        AreaLight { amount: Amount::Nits(l), ..Default::default() },
    ));
    // The camera sits below the emitter, looking down at the floor's centre.
    let mut cams = world.query_filtered::<&mut Transform, With<Camera>>();
    for mut t in cams.iter_mut(&mut world) {
        t.translation.y = 0.5;
    }
    let (mean, se) = centre_stats(&mut world, &mut schedule, 16, 16, 3, Strategy::Mis);
    eprintln!("rectangle light: {mean:.4} +- {se:.4} cd/m^2, view factor gives {want:.4}");
    assert!((mean - want).abs() <= 3.0 * se + 2e-3 * want, "{mean} +- {se} vs {want}");
}

/// `Settings::samples_per_point` = k light samples per point, combined by MIS with the one BSDF
/// sample: each entry's pdf carries k, so the pixel is the closed form at any k (it was k times
/// too bright: the renderer summed k entries of the one-sample density). A point light (exact at
/// any spp), a disk area light above (E = pi L r^2 / (h^2 + r^2)) and an image light whose
/// rows are two levels (E = sum over rows of pi L (sin^2 theta1 - sin^2 theta0); its
/// MIS-compensated table samples only the bright rows, so the BSDF weights must match).
#[test]
fn light_samples_per_point_keep_direct_light_at_the_closed_form() {
    use kelvin::geometry::Disk;
    use kelvin::light::{AreaLight, ImageInfiniteLight};
    use kelvin::scene::image::RgbImage;
    use std::f64::consts::PI;
    let rho = 0.5f32;
    let (height, rows) = (8usize, [40.0f32, 40.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
    let image_e: f64 = (0..height / 2)
        .map(|y| {
            let (t0, t1) = (PI * y as f64 / height as f64, PI * (y + 1) as f64 / height as f64);
            PI * rows[y] as f64 * (t1.sin().powi(2) - t0.sin().powi(2))
        })
        .sum();
    let (disk_l, r, h) = (300.0f32, 0.5f64, 2.0f64);
    let cases: [(&str, f64); 3] =
        [("point", 100.0 / (2.0 * 2.0)), ("disk", PI * disk_l as f64 * r * r / (h * h + r * r)), ("image", image_e)];
    for (name, e) in cases {
        let want = rho as f64 / PI * e;
        for k in [1, 2, 4] {
            let (mut world, mut schedule) = floor_scene(ColorMode::Rgb, rho);
            world.resource_mut::<Settings>().samples_per_point = k;
            match name {
                "point" => {
                    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
                }
                "disk" => {
                    let down = Transform::from_translation(Vec3::new(0.0, h as f32, 0.0)).looking_to(Vec3::Y, Vec3::Z);
                    world.spawn((
                        Disk { radius: r as f32, inner_radius: 0.0 },
                        down,
                        AreaLight { amount: Amount::Nits(disk_l), ..Default::default() },
                    ));
                }
                _ => {
                    let pixels = (0..height).flat_map(|y| [Vec3::splat(rows[y]); 16]).collect();
                    let image = RgbImage { width: 16, height, pixels };
                    world.spawn((ImageInfiniteLight::new(std::sync::Arc::new(image)), Transform::IDENTITY));
                }
            }
            let (mean, se) = centre_stats(&mut world, &mut schedule, 8, 256, 3, Strategy::Mis);
            eprintln!("{name} k={k}: {mean:.4} +- {se:.4} cd/m^2, closed form {want:.4}");
            assert!((mean - want).abs() <= 3.0 * se + 2e-3 * want, "{name} k={k}: {mean} +- {se} vs {want}");
        }
    }
}
