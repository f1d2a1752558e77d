//! Objects on a ground plane under an environment map (a real sky with its sun): the scene of the
//! accuracy report's env-table knob.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::geometry::{Rectangle, Sphere, Transform};
use crate::light::ImageInfiniteLight;
use crate::render::camera::Camera;
use crate::render::material::Material;
use crate::scene::image::RgbImage;

/// Spawns a grey ground, a back wall, three spheres (white plastic, blue diffuse, rough gold), a
/// camera, and `image` as an environment light whose texel (1, 1, 1) is `nits` cd/m^2.
/// Returns the light's entity (its `table_max_width` is the report's knob).
pub fn spawn_sunlit_objects(world: &mut World, image: Arc<RgbImage>, nits: f32) -> Entity {
    let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z); // a Rectangle's front (+Z) to +Y
    world.spawn((Rectangle { half_size: Vec2::splat(10.0) }, up, Material::lambertian(Vec3::splat(0.4))));
    world.spawn((
        Rectangle { half_size: Vec2::new(2.5, 1.0) },
        Transform::from_translation(Vec3::new(0.0, 1.0, -1.5)),
        Material::lambertian(Vec3::splat(0.6)),
    ));
    world.spawn((Sphere { radius: 0.5 }, Transform::from_translation(Vec3::new(-0.8, 0.5, 0.0)), Material::default()));
    world.spawn((
        Sphere { radius: 0.25 },
        Transform::from_translation(Vec3::new(0.15, 0.25, 0.9)),
        Material::lambertian(Vec3::new(0.05, 0.15, 0.6)),
    ));
    let gold =
        Material { base_color: Vec3::new(1.0, 0.78, 0.34), metallic: 1.0, roughness: 0.35, ..Default::default() };
    world.spawn((Sphere { radius: 0.4 }, Transform::from_translation(Vec3::new(0.7, 0.4, 0.2)), gold));
    let eye = Vec3::new(0.0, 1.4, 4.0);
    world.spawn((
        Camera { yfov: 40f32.to_radians() },
        Transform::from_translation(eye).looking_to(Vec3::new(0.0, 0.5, 0.0) - eye, Vec3::Y),
    ));
    let mut light = ImageInfiniteLight::new(image);
    light.scale = nits;
    world.spawn((light, Transform::IDENTITY)).id()
}
