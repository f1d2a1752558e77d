//! Light choice on a normal-mapped floor under many low lights: the light BVH's efficiency
//! (1 / (relMSE x seconds)) against a converged render of the same scene, to compare how it ranks
//! clusters (by the geometric or the shading normal) at equal time. The floor's normal map leans
//! every normal up to 50 degrees in bumps; 2,000 point lights sit 0.3-1.5 m over it.
//! `cargo run --release --example light_ranking [spp] [reference_spp]` (defaults 16, 2048);
//! prints one line per render with spp, seconds, relMSE and efficiency.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Mesh, Transform};
use kelvin::light::PointLight;
use kelvin::render::camera::Camera;
use kelvin::render::material::Material;
use kelvin::render::renderer::{RenderOptions, render};
use kelvin::rng::SplitMix64;
use kelvin::scene::image::RgbImage;
use kelvin::systems::LightingPlugin;

const SIZE: u32 = 96;

/// A tangent-space normal map of round bumps: normals lean up to 50 degrees from +Z.
fn bump_map(n: usize) -> RgbImage {
    let cells = 8.0;
    let pixels = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            let (u, v) = ((x / n as f32 * cells).fract() - 0.5, (y / n as f32 * cells).fract() - 0.5);
            let lean = 50f32.to_radians() * (2.0 * (u * u + v * v).sqrt()).min(1.0);
            let dir = Vec2::new(u, v).normalize_or_zero();
            let normal = Vec3::new(dir.x * lean.sin(), dir.y * lean.sin(), lean.cos());
            (normal + Vec3::ONE) * 0.5
        })
        .collect();
    RgbImage { width: n, height: n, pixels }
}

fn scene() -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let corners = [(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)];
    let positions = corners.iter().map(|&(x, z)| Vec3::new(x, 0.0, z)).collect();
    let uvs = corners.iter().map(|&(x, z)| Vec2::new(x / 8.0 + 0.5, z / 8.0 + 0.5)).collect();
    let mesh = Mesh::new(positions, vec![0, 2, 1, 0, 3, 2]).unwrap().with_uvs(uvs).unwrap();
    let material = Material { normal_texture: Some(Arc::new(bump_map(256))), ..Material::lambertian(Vec3::splat(0.7)) };
    world.spawn((mesh, Transform::IDENTITY, material));
    let mut rng = SplitMix64::new(7);
    for _ in 0..2000 {
        let p = Vec3::new(rng.f32() * 8.0 - 4.0, 0.3 + 1.2 * rng.f32(), rng.f32() * 8.0 - 4.0);
        world.spawn((PointLight::candela(0.2 + rng.f32()), Transform::from_translation(p)));
    }
    let eye = Vec3::new(0.0, 6.0, 0.01);
    world.spawn((Camera { yfov: 1.0 }, Transform::from_translation(eye).looking_to(-eye, Vec3::Y)));
    (world, schedule)
}

fn main() {
    let args: Vec<u32> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let (spp, reference_spp) = (args.first().copied().unwrap_or(16), args.get(1).copied().unwrap_or(2048));
    let (mut world, mut schedule) = scene();
    let reference =
        render(&mut world, &mut schedule, &RenderOptions::direct(SIZE, SIZE, reference_spp), |_| {}).0.pixels();
    for seed in 1..=5 {
        world.resource_mut::<kelvin::shading::Settings>().seed = seed;
        let (film, stats) = render(&mut world, &mut schedule, &RenderOptions::direct(SIZE, SIZE, spp), |_| {});
        let (mut err, mut norm) = (0.0f64, 0.0f64);
        for (a, b) in film.pixels().iter().zip(&reference) {
            err += f64::from((*a - *b).length_squared());
            norm += f64::from(b.length_squared());
        }
        let rel_mse = err / norm;
        println!(
            "spp {spp} seconds {:.4} relMSE {rel_mse:.4e} efficiency {:.4e}",
            stats.seconds,
            1.0 / (rel_mse * stats.seconds)
        );
    }
}
