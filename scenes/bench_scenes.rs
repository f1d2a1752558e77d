//! Small scenes for benchmarks and reports.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::geometry::{Rectangle, Transform};
use crate::light::PointLight;
use crate::render::camera::Camera;
use crate::render::material::Material;

/// A 100 cd white point light 2 m above a 20 m Lambertian floor (albedo 0.5, specular 0), seen
/// from above at an angle: the scene of the renderer's throughput target.
pub fn spawn_point_over_plane(world: &mut World) {
    let floor = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z); // front (+Z) turned to +Y
    world.spawn((Rectangle { half_size: Vec2::splat(10.0) }, floor, Material::lambertian(Vec3::splat(0.5))));
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
    let eye = Vec3::new(0.0, 3.0, 4.0);
    world.spawn((Camera { yfov: 50f32.to_radians() }, Transform::from_translation(eye).looking_to(-eye, Vec3::Y)));
}
