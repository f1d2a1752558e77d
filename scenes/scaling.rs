//! The many-lights scaling scene: N lights at a constant density over a ground plane with sphere
//! occluders, so a larger N means a larger world (a city at night, a stadium complex), which is
//! where choosing lights well matters: from any point only the nearby lights count.
//!
//! Area lights are not in the scene yet (`AreaLight` is not on this branch): half the lights are
//! point lights, half downward spot lights.

use std::f32::consts::PI;

use bevy_ecs::prelude::*;
use glam::{Quat, Vec2, Vec3};

use super::scene_rng;
use crate::geometry::{Rectangle, Sphere, Transform};
use crate::light::{Amount, LightSampleContext, PointLight, SpotLight};
use crate::rng::SplitMix64;
use crate::spectrum::Spectrum;

/// Mean distance between neighbouring lights, m: one light per `LIGHT_SPACING^2` of ground.
pub const LIGHT_SPACING: f32 = 3.0;
/// Lights hang this high above the ground, m.
const HEIGHT: (f32, f32) = (2.0, 6.0);
/// Luminous power range, lm (log-uniform): from a porch lamp to a street light.
const LUMENS: (f32, f32) = (200.0, 5000.0);
/// Colour temperatures of the lights, K.
const CCT_K: [f64; 6] = [2700.0, 3000.0, 3500.0, 4000.0, 5000.0, 6500.0];
/// One occluder per this many lights, up to `MAX_OCCLUDERS`.
const LIGHTS_PER_OCCLUDER: usize = 8;
const MAX_OCCLUDERS: usize = 20_000;

/// What [`spawn_scaling_scene`] made.
#[derive(Clone, Debug)]
pub struct ScalingScene {
    /// Half the side of the lit square (centred on the origin, in the XZ plane), m.
    pub half_extent: f32,
    /// The light entities (point lights first, then spot lights).
    pub lights: Vec<Entity>,
    /// The ground rectangle.
    pub ground: Entity,
    /// Number of sphere occluders.
    pub occluders: usize,
}

impl ScalingScene {
    /// `count` points on the ground (normal +Y), uniform over the central 80% of the lit square.
    pub fn ground_points(&self, count: usize, seed: u64) -> Vec<LightSampleContext> {
        let mut rng = scene_rng(seed ^ 0x9_0123);
        let h = 0.8 * self.half_extent;
        (0..count)
            .map(|_| LightSampleContext::on_surface(Vec3::new(rng.range(-h, h), 0.0, rng.range(-h, h)), Vec3::Y))
            .collect()
    }
}

/// Spawns `n` lights (half point, half spot), a ground plane and sphere occluders into `world`,
/// deterministically from `seed`. The lit square grows with `n` (constant light density).
pub fn spawn_scaling_scene(world: &mut World, n: usize, seed: u64) -> ScalingScene {
    let mut rng = scene_rng(seed);
    let half_extent = 0.5 * LIGHT_SPACING * (n.max(1) as f32).sqrt();
    let position = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(-half_extent, half_extent),
            rng.range(HEIGHT.0, HEIGHT.1),
            rng.range(-half_extent, half_extent),
        )
    };
    // The colour temperatures lamps are sold in (a handful, as in real scenes).
    let warm_to_daylight = |rng: &mut SplitMix64| {
        let t = CCT_K[(rng.next_u64() % CCT_K.len() as u64) as usize];
        Spectrum::Blackbody { temperature_k: t }
    };

    let n_points = n.div_ceil(2);
    let points: Vec<(PointLight, Transform)> = (0..n_points)
        .map(|_| {
            let light = PointLight {
                amount: Amount::Lumens(rng.log_range(LUMENS.0, LUMENS.1)),
                spectrum: warm_to_daylight(&mut rng),
                ..Default::default()
            };
            (light, Transform::from_translation(position(&mut rng)))
        })
        .collect();
    let spots: Vec<(SpotLight, Transform)> = (n_points..n)
        .map(|_| {
            let outer = rng.range(25.0, 60.0).to_radians();
            let light = SpotLight {
                amount: Amount::Lumens(rng.log_range(LUMENS.0, LUMENS.1)),
                spectrum: warm_to_daylight(&mut rng),
                inner_angle: outer * rng.range(0.5, 0.9),
                outer_angle: outer,
                ..Default::default()
            };
            // Downward, tilted by up to 30 degrees.
            let (tilt, turn) = (rng.range(0.0, 30.0).to_radians(), rng.range(0.0, 2.0 * PI));
            let dir = Quat::from_rotation_y(turn) * Quat::from_rotation_x(tilt) * Vec3::NEG_Y;
            (light, Transform::from_translation(position(&mut rng)).looking_to(dir, Vec3::Z))
        })
        .collect();
    let mut lights: Vec<Entity> = world.spawn_batch(points).collect();
    lights.extend(world.spawn_batch(spots));

    // The ground: a rectangle whose front (+Z) faces +Y, a little larger than the lit square.
    let ground_transform =
        Transform { rotation: Quat::from_rotation_x(-PI / 2.0), ..Transform::from_translation(Vec3::ZERO) };
    let ground = world.spawn((Rectangle::from_size(Vec2::splat(2.0 * half_extent + 20.0)), ground_transform)).id();

    let occluders = (n / LIGHTS_PER_OCCLUDER).clamp(1, MAX_OCCLUDERS);
    let spheres: Vec<(Sphere, Transform)> = (0..occluders)
        .map(|_| {
            let r = rng.range(0.3, 1.5);
            let p = Vec3::new(rng.range(-half_extent, half_extent), r, rng.range(-half_extent, half_extent));
            (Sphere { radius: r }, Transform::from_translation(p))
        })
        .collect();
    world.spawn_batch(spheres);

    ScalingScene { half_extent, lights, ground, occluders }
}
