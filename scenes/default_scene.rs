//! The default scene, compiled into the binary: a Cornell-style room open toward the camera,
//! lit at once by a ceiling area light, a spot light, a 2200 K blackbody point light and a sky.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::geometry::{Rectangle, Sphere, Transform};
use crate::light::{Amount, AreaLight, PointLight, SpotLight, UniformInfiniteLight};
use crate::render::camera::Camera;
use crate::render::material::Material;
use crate::spectrum::Spectrum;

/// Albedos of the classic Cornell box walls.
const WHITE: Vec3 = Vec3::new(0.73, 0.73, 0.73);
const RED: Vec3 = Vec3::new(0.63, 0.065, 0.05);
const GREEN: Vec3 = Vec3::new(0.14, 0.45, 0.091);

/// A rectangle of half size `half` at `centre` whose front side faces `normal`.
fn wall(centre: Vec3, normal: Vec3, half: Vec2) -> (Rectangle, Transform) {
    let up = if normal.y.abs() > 0.9 { Vec3::Z } else { Vec3::Y };
    (Rectangle { half_size: half }, Transform::from_translation(centre).looking_to(-normal, up))
}

/// Spawns the default scene: a 2 m room (x and z in [-1, 1], y in [0, 2]) with its front open.
pub fn spawn_default_scene(world: &mut World) {
    let half = Vec2::splat(1.0);
    world.spawn((wall(Vec3::ZERO, Vec3::Y, half), Material::lambertian(WHITE)));
    world.spawn((wall(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, half), Material::lambertian(WHITE)));
    world.spawn((wall(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, half), Material::lambertian(WHITE)));
    world.spawn((wall(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, half), Material::lambertian(RED)));
    world.spawn((wall(Vec3::new(1.0, 1.0, 0.0), Vec3::NEG_X, half), Material::lambertian(GREEN)));

    // Objects: a white plastic sphere and a rough gold one.
    world.spawn((
        Sphere { radius: 0.35 },
        Transform::from_translation(Vec3::new(-0.4, 0.35, -0.3)),
        Material::default(),
    ));
    let gold = Material { base_color: Vec3::new(1.0, 0.78, 0.34), metallic: 1.0, roughness: 0.3, ..Default::default() };
    world.spawn((Sphere { radius: 0.3 }, Transform::from_translation(Vec3::new(0.45, 0.3, 0.15)), gold));

    // Ceiling panel: 0.5 m square, 3000 nit, D65.
    let (panel, panel_t) = wall(Vec3::new(0.0, 1.99, 0.0), Vec3::NEG_Y, Vec2::splat(0.25));
    world.spawn((
        panel,
        panel_t,
        AreaLight { amount: Amount::Nits(3000.0), ..Default::default() },
        Material::lambertian(WHITE),
    ));

    // A warm spot on the white sphere, a 2200 K "candle" bulb near the floor, and the sky.
    let spot_at = Vec3::new(0.85, 1.85, 0.7);
    let spot = SpotLight {
        amount: Amount::Lumens(400.0),
        spectrum: Spectrum::blackbody(3500.0).expect("valid temperature"),
        inner_angle: 10f32.to_radians(),
        outer_angle: 18f32.to_radians(),
        ..Default::default()
    };
    world
        .spawn((spot, Transform::from_translation(spot_at).looking_to(Vec3::new(-0.4, 0.35, -0.3) - spot_at, Vec3::Y)));
    let bulb = PointLight {
        amount: Amount::Lumens(60.0),
        spectrum: Spectrum::blackbody(2200.0).expect("valid"),
        ..Default::default()
    };
    world.spawn((bulb, Transform::from_translation(Vec3::new(-0.6, 0.25, 0.5))));
    world.spawn(UniformInfiniteLight {
        amount: Amount::Nits(150.0),
        spectrum: Spectrum::daylight(6500.0).expect("valid"),
    });

    let eye = Vec3::new(0.0, 1.0, 3.6);
    world.spawn((
        Camera { yfov: 38f32.to_radians() },
        Transform::from_translation(eye).looking_to(Vec3::new(0.0, 0.95, 0.0) - eye, Vec3::Y),
    ));
}
