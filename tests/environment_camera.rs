//! The environment camera renders a lat-long radiance map of a scene, and that map lights another
//! scene as an image infinite light with the same irradiance.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Rectangle, Transform};
use kelvin::light::{ImageInfiniteLight, UniformInfiniteLight};
use kelvin::render::material::Material;
use kelvin::render::renderer::{RenderOptions, render_environment};
use kelvin::shading::{DirectLighting, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;

#[test]
fn environment_map_of_sky_over_floor_relights_a_point_with_pi_l() {
    let (l, rho) = (100.0f32, 0.5f32);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    world.spawn(UniformInfiniteLight::nits(l));
    let floor = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Rectangle { half_size: Vec2::splat(1e4) }, floor, Material::lambertian(Vec3::splat(rho))));
    let opts = RenderOptions::direct(64, 32, 64);
    let (map, _) = render_environment(&mut world, &mut schedule, Vec3::Y, &opts);
    let y = |p: Vec3| 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
    // Rows fully above the horizon see the sky; rows fully below see the lit floor (rho L).
    let row_mean = |r: usize| (0..map.width).map(|x| y(map.pixels[r * map.width + x])).sum::<f32>() / map.width as f32;
    assert!((row_mean(2) / l - 1.0).abs() < 1e-3, "sky row: {}", row_mean(2));
    let floor_row = row_mean(map.height - 3);
    assert!((floor_row / (rho * l) - 1.0).abs() < 0.02, "floor row: {floor_row} vs {}", rho * l);

    // Relight: a point facing up under the map gets the sky's irradiance, pi L.
    let mut relit = World::new();
    let mut schedule2 = Schedule::default();
    relit.insert_resource(Settings { samples_per_point: 4096, mis: false, ..Default::default() });
    LightingPlugin::build(&mut relit, &mut schedule2);
    relit.spawn((ImageInfiniteLight::new(Arc::new(map)), Transform::IDENTITY));
    relit.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    schedule2.run(&mut relit);
    let out = relit.resource::<DirectLighting>();
    let e: f32 = out
        .entries(0)
        .map(|k| y(Vec3::from_slice(&out.radiance[k].0[..3])) * out.wi[k].y.max(0.0) / out.pdf[k])
        .sum::<f32>();
    let want = std::f32::consts::PI * l;
    assert!((e / want - 1.0).abs() < 0.03, "irradiance {e} vs pi L = {want}");
}
