//! Silhouettes of smooth and normal-mapped meshes: where the view is below the interpolated or
//! mapped shading normal (a coarse sphere's rim, bumps that lean away from the camera), the
//! bent shading normal keeps the surface shaded. Under a uniform sky, every pixel wholly on the
//! sphere must be lit: a black texel there is a BSDF that gave up.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Mesh, Transform};
use kelvin::light::{Amount, UniformInfiniteLight};
use kelvin::render::camera::{Camera, PinholeCamera};
use kelvin::render::material::Material;
use kelvin::render::path::PathDepth;
use kelvin::render::renderer::{Integrator, RenderOptions, render};
use kelvin::rng::SplitMix64;
use kelvin::scene::image::RgbImage;
use kelvin::shading::Settings;
use kelvin::systems::LightingPlugin;

const SIZE: u32 = 64;

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A bumpy normal texture: every texel leans `tilt` from the surface normal toward a random side.
fn bumps(tilt: f32) -> RgbImage {
    let mut rng = SplitMix64::new(8);
    let pixels = (0..32 * 16)
        .map(|_| {
            let phi = std::f32::consts::TAU * rng.f32();
            let n = Vec3::new(tilt.sin() * phi.cos(), tilt.sin() * phi.sin(), tilt.cos());
            (n + Vec3::ONE) * 0.5
        })
        .collect();
    RgbImage { width: 32, height: 16, pixels }
}

/// Pixels wholly on a coarse smooth unit sphere (10 segments, 6 rings) in front of the camera,
/// and their luminances under a uniform sky of 1 nit, at 32 spp: a sharp metal whose bumps are
/// bent to reflect at grazing loses about half its samples below the horizon, so at 4 spp a few
/// pixels are dark by chance; a BSDF that gives up is dark at any spp.
fn sphere_pixels(material: Material, integrator: Integrator) -> Vec<f32> {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings::default());
    LightingPlugin::build(&mut world, &mut schedule);
    world.spawn((Mesh::uv_sphere(1.0, 10, 6), Transform::IDENTITY, material));
    world.spawn((UniformInfiniteLight { amount: Amount::Nits(1.0), ..Default::default() }, Transform::default()));
    let (camera, eye) = (Camera { yfov: 0.75 }, Transform::from_translation(Vec3::new(0.0, 0.3, 3.2)));
    let eye = eye.looking_to(-eye.translation, Vec3::Y);
    world.spawn((camera, eye));
    let opts = RenderOptions { integrator, ..RenderOptions::direct(SIZE, SIZE, 32) };
    let film = render(&mut world, &mut schedule, &opts, |_| {}).0;
    // The mesh's faces lie outside the sphere of radius cos(18 deg) cos(15 deg) = 0.918: a pixel
    // whose corner rays all meet the sphere of radius 0.9 is on the mesh throughout.
    let pinhole = PinholeCamera::new(&camera, &eye, SIZE, SIZE);
    let meets = |x, y, corner: Vec2| {
        let ray = pinhole.ray(x, y, corner);
        let b = ray.origin.dot(ray.dir);
        b * b - (ray.origin.length_squared() - 0.81) > 0.0
    };
    let corners = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
    let on = |x, y| corners.iter().all(|&c| meets(x, y, c));
    (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
        .filter(|&(x, y)| on(x, y))
        .map(|(x, y)| luminance(film.pixel(x, y)))
        .collect()
}

#[test]
fn smooth_and_normal_mapped_spheres_have_no_black_pixels_at_their_silhouettes() {
    let plain = Material { roughness: 0.5, base_color: Vec3::splat(0.8), ..Default::default() };
    let mapped = Material { normal_texture: Some(Arc::new(bumps(55f32.to_radians()))), ..plain.clone() };
    let metal = Material { metallic: 1.0, roughness: 0.2, ..mapped.clone() };
    let path = Integrator::Path(PathDepth { max_depth: 4, ..PathDepth::DEFAULT });
    let cases = [
        ("smooth", plain, Integrator::Direct),
        ("normal-mapped", mapped.clone(), Integrator::Direct),
        ("normal-mapped metal", metal, Integrator::Direct),
        ("normal-mapped, path", mapped, path),
    ];
    for (name, material, integrator) in cases {
        let pixels = sphere_pixels(material, integrator);
        let dark = pixels.iter().filter(|&&l| !(l > 0.02)).count();
        let least = pixels.iter().copied().fold(f32::INFINITY, f32::min);
        eprintln!("{name}: {} pixels on the sphere, {dark} below 0.02 nit (darkest {least:.4})", pixels.len());
        assert!(pixels.len() > 1000, "{name}: {} pixels on the sphere", pixels.len());
        assert_eq!(dark, 0, "{name}: {dark} black pixels on the sphere (darkest {least})");
    }
}
