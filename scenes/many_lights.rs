//! A many-lights scene for the accuracy report: a square of point and spot lights of mixed
//! power and colour temperature over a ground with sphere occluders, seen from above at an angle.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::geometry::{Rectangle, Sphere, Transform};
use crate::light::{Amount, PointLight, SpotLight};
use crate::render::camera::Camera;
use crate::render::material::Material;
use crate::rng::mix64;
use crate::spectrum::Spectrum;

/// Distance between neighbouring lights, m.
const SPACING: f32 = 2.0;

/// Uniform in [0, 1) from a counter (splitmix64).
fn uniform(seed: u64, i: u64) -> f32 {
    (mix64(seed ^ mix64(i)) >> 40) as f32 / (1u32 << 24) as f32
}

/// Spawns `n` lights (every third a downward spot, the rest point lights; 100-3000 lm,
/// log-uniform; 2700-6500 K blackbodies) jittered on a grid 1.5-4 m above a grey ground, one
/// sphere occluder per 8 lights, and a camera. Deterministic in `seed`.
pub fn spawn_many_lights(world: &mut World, n: usize, seed: u64) {
    let side = (n.max(1) as f32).sqrt().ceil() as usize;
    let half = 0.5 * SPACING * side as f32;
    let mut k = 0u64;
    let mut next = || {
        k += 1;
        uniform(seed, k)
    };
    for i in 0..n {
        let (gx, gz) = ((i % side) as f32, (i / side) as f32);
        let p = Vec3::new(-half + (gx + next()) * SPACING, 1.5 + 2.5 * next(), -half + (gz + next()) * SPACING);
        let lumens = 100.0 * 30f32.powf(next());
        let spectrum = Spectrum::blackbody(2700.0 + 3800.0 * next() as f64).expect("valid temperature");
        if i % 3 == 2 {
            let spot = SpotLight {
                amount: Amount::Lumens(lumens),
                spectrum,
                inner_angle: 25f32.to_radians(),
                outer_angle: 40f32.to_radians(),
                ..Default::default()
            };
            world.spawn((spot, Transform::from_translation(p).looking_to(Vec3::NEG_Y, Vec3::Z)));
        } else {
            world.spawn((
                PointLight { amount: Amount::Lumens(lumens), spectrum, ..Default::default() },
                Transform::from_translation(p),
            ));
        }
    }
    let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z); // a Rectangle's front (+Z) to +Y
    world.spawn((Rectangle { half_size: Vec2::splat(half + 10.0) }, up, Material::lambertian(Vec3::splat(0.5))));
    for _ in 0..(n / 8).max(1) {
        let r = 0.3 + 0.7 * next();
        let c = Vec3::new(-half + 2.0 * half * next(), r, -half + 2.0 * half * next());
        let albedo = Vec3::new(0.3 + 0.5 * next(), 0.3 + 0.5 * next(), 0.3 + 0.5 * next());
        world.spawn((Sphere { radius: r }, Transform::from_translation(c), Material::lambertian(albedo)));
    }
    let eye = Vec3::new(0.0, 0.9 * half, 1.3 * half);
    world.spawn((
        Camera { yfov: 50f32.to_radians() },
        Transform::from_translation(eye).looking_to(Vec3::new(0.0, 0.0, -0.1 * half) - eye, Vec3::Y),
    ));
}
