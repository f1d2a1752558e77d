//! A room lit by a ceiling panel of many emissive triangles (an LED panel with a pattern of
//! bright, dim and dark cells), the "real scene" of the many-lights benchmark.
//!
//! Stand-in until `AreaLight` and the glTF importer reach this branch: each emissive triangle is
//! a downward spot light at its centroid (inner angle 0, outer pi/2, so power pi I), whose
//! on-axis intensity L A (cd) and power pi L A match a one-sided Lambertian triangle of
//! luminance L and area A; the smoothstep falloff 3c^2 - 2c^3 replaces the cosine c. The panel
//! mesh itself is in the scene as geometry, the spots 1 mm below it.

use std::f32::consts::PI;

use bevy_ecs::prelude::*;
use glam::{Quat, Vec2, Vec3};

use super::scene_rng;
use crate::geometry::{Mesh, Rectangle, Sphere, Transform};
use crate::light::{Amount, LightSampleContext, SpotLight};
use crate::rng::SplitMix64;
use crate::spectrum::Spectrum;

/// Room size (x, y, z), m; the floor is y = 0.
const ROOM: Vec3 = Vec3::new(10.0, 3.0, 10.0);
/// The panel covers this square of the ceiling, m.
const PANEL_SIZE: f32 = 6.0;
/// Luminance of a bright cell, nit.
const PANEL_NITS: f32 = 2000.0;

/// What [`spawn_emissive_panel_room`] made.
#[derive(Clone, Debug)]
pub struct PanelScene {
    /// One spot light per emissive triangle (dark cells included, with zero power).
    pub lights: Vec<Entity>,
    /// The panel mesh entity.
    pub panel: Entity,
    /// Number of emissive triangles.
    pub triangles: usize,
}

impl PanelScene {
    /// `count` points on the floor (normal +Y), uniform over the room.
    pub fn floor_points(&self, count: usize, seed: u64) -> Vec<LightSampleContext> {
        let mut rng = scene_rng(seed ^ 0x7a_11e1);
        let h = 0.5 * ROOM.x * 0.95;
        (0..count)
            .map(|_| LightSampleContext::on_surface(Vec3::new(rng.range(-h, h), 0.0, rng.range(-h, h)), Vec3::Y))
            .collect()
    }
}

/// Relative luminance of the cell (i, j) of `tiles` x `tiles`: concentric bands of full, half and
/// no light, with a few random dark cells.
fn cell_pattern(i: usize, j: usize, tiles: usize, rng: &mut SplitMix64) -> f32 {
    let c = (tiles as f32 - 1.0) / 2.0;
    let ring = (i as f32 - c).abs().max((j as f32 - c).abs()) as usize;
    let band = [1.0, 0.5, 0.0, 0.5][ring % 4];
    if rng.f32() < 0.05 { 0.0 } else { band }
}

/// Spawns a walled room with a ceiling panel of `2 tiles^2` emissive triangles (facing down)
/// and a few sphere occluders, deterministically from `seed`.
pub fn spawn_emissive_panel_room(world: &mut World, tiles: usize, seed: u64) -> PanelScene {
    let tiles = tiles.max(1);
    let mut rng = scene_rng(seed);
    let y = ROOM.y - 0.05;
    let step = PANEL_SIZE / tiles as f32;
    let corner =
        |i: usize, j: usize| Vec3::new(-0.5 * PANEL_SIZE + i as f32 * step, y, -0.5 * PANEL_SIZE + j as f32 * step);
    let mut triangles = Vec::with_capacity(2 * tiles * tiles);
    let mut spots = Vec::with_capacity(2 * tiles * tiles);
    for i in 0..tiles {
        for j in 0..tiles {
            let level = cell_pattern(i, j, tiles, &mut rng);
            let (a, b, c, d) = (corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1));
            // Counter-clockwise seen from below: the front faces -Y.
            for tri in [[a, b, c], [a, c, d]] {
                let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
                let centroid = (tri[0] + tri[1] + tri[2]) / 3.0 - Vec3::Y * 1e-3;
                let spot = SpotLight {
                    amount: Amount::Lumens(PI * PANEL_NITS * level * area),
                    spectrum: Spectrum::Blackbody { temperature_k: 4000.0 },
                    inner_angle: 0.0,
                    outer_angle: PI / 2.0,
                    casts_shadows: true,
                };
                spots.push((spot, Transform::from_translation(centroid).looking_to(Vec3::NEG_Y, Vec3::Z)));
                triangles.push(tri);
            }
        }
    }
    let n = triangles.len();
    let mesh = Mesh::from_triangles(&triangles).expect("panel triangles are finite");
    let panel = world.spawn((mesh, Transform::IDENTITY)).id();
    let lights: Vec<Entity> = world.spawn_batch(spots).collect();

    // Floor (+Y), ceiling (-Y) and four walls facing in; rectangles face local +Z.
    let half = 0.5 * ROOM;
    let walls = [
        (Vec3::ZERO, Quat::from_rotation_x(-PI / 2.0), Vec2::new(ROOM.x, ROOM.z)),
        (Vec3::new(0.0, ROOM.y, 0.0), Quat::from_rotation_x(PI / 2.0), Vec2::new(ROOM.x, ROOM.z)),
        (Vec3::new(0.0, half.y, -half.z), Quat::IDENTITY, Vec2::new(ROOM.x, ROOM.y)),
        (Vec3::new(0.0, half.y, half.z), Quat::from_rotation_y(PI), Vec2::new(ROOM.x, ROOM.y)),
        (Vec3::new(-half.x, half.y, 0.0), Quat::from_rotation_y(PI / 2.0), Vec2::new(ROOM.z, ROOM.y)),
        (Vec3::new(half.x, half.y, 0.0), Quat::from_rotation_y(-PI / 2.0), Vec2::new(ROOM.z, ROOM.y)),
    ];
    for (p, rotation, size) in walls {
        world.spawn((Rectangle::from_size(size), Transform { rotation, ..Transform::from_translation(p) }));
    }
    for _ in 0..6 {
        let r = rng.range(0.3, 0.6);
        let p = Vec3::new(rng.range(-3.5, 3.5), r, rng.range(-3.5, 3.5));
        world.spawn((Sphere { radius: r }, Transform::from_translation(p)));
    }
    PanelScene { lights, panel, triangles: n }
}
