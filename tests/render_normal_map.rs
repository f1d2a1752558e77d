//! Normal textures: a floor whose map tilts every normal shades as a floor of that tilt under a
//! slanted distant light (rho / pi * E * cos(angle between them)), whichever way its uvs run; and
//! a real file's normal map on uvs of zero area is read and leaves the picture as it is.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use kelvin::geometry::{Mesh, Transform};
use kelvin::light::{Amount, DistantLight};
use kelvin::render::camera::Camera;
use kelvin::render::material::Material;
use kelvin::render::renderer::{RenderOptions, render};
use kelvin::scene::image::RgbImage;
use kelvin::shading::Settings;
use kelvin::systems::LightingPlugin;

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The centre pixel of a 4 m floor at y = 0 (front +Y) whose uvs map u along `u_axis`, with a
/// normal map of one texel tilting normals by `tilt` toward +v, seen from above, lit by `e` lux
/// arriving from `slant` off the vertical on the +v side. `mirrored` runs v the other way (a
/// left-handed uv layout): the tilt then follows the new +v.
fn floor_luminance(rho: f32, e: f32, tilt: f32, slant: f32, u_axis: Vec3, mirrored: bool) -> f32 {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings::default());
    LightingPlugin::build(&mut world, &mut schedule);
    let v_axis = Vec3::Y.cross(u_axis) * if mirrored { -1.0 } else { 1.0 };
    let corners = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)];
    let positions: Vec<Vec3> = corners.iter().map(|&(u, v)| u_axis * u + v_axis * v).collect();
    let uvs: Vec<Vec2> = corners.iter().map(|&(u, v)| Vec2::new(u / 4.0 + 0.5, v / 4.0 + 0.5)).collect();
    // Wound so that the front faces +Y whatever the uv layout.
    let front_up = (positions[1] - positions[0]).cross(positions[2] - positions[0]).y > 0.0;
    let indices = if front_up { vec![0, 1, 2, 0, 2, 3] } else { vec![0, 2, 1, 0, 3, 2] };
    let mesh = Mesh::new(positions, indices).unwrap().with_uvs(uvs).unwrap();
    let n = Vec3::new(0.0, tilt.sin(), tilt.cos());
    let texel = (n + Vec3::ONE) * 0.5;
    let map = RgbImage { width: 1, height: 1, pixels: vec![texel] };
    let material = Material { normal_texture: Some(Arc::new(map)), ..Material::lambertian(Vec3::splat(rho)) };
    world.spawn((mesh, Transform::default(), material));
    world.spawn((
        DistantLight { amount: Amount::Lux(e), ..Default::default() },
        Transform::default().looking_to(-(v_axis * slant.sin() + Vec3::Y * slant.cos()), u_axis),
    ));
    let cam = Transform::from_translation(Vec3::new(0.0, 3.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Camera { yfov: 0.01 }, cam));
    let (film, _) = render(&mut world, &mut schedule, &RenderOptions::direct(5, 5, 1), |_| {});
    luminance(film.pixel(2, 2))
}

#[test]
fn a_tilting_normal_map_shades_a_floor_as_the_tilted_normal_whichever_way_its_uvs_run() {
    let (rho, e, slant) = (0.5f32, 1000.0f32, 50f32.to_radians());
    let cases = [(40.0f32, Vec3::X, false), (25.0, Vec3::Z, false), (40.0, Vec3::X, true), (-30.0, Vec3::NEG_Z, true)];
    for (tilt_deg, u_axis, mirrored) in cases {
        let tilt = tilt_deg.to_radians();
        // Tilted toward the light: the angle between them is slant - tilt (slant + tilt if the
        // frame's handedness were wrong).
        let want = rho / std::f32::consts::PI * e * (slant - tilt).cos();
        let got = floor_luminance(rho, e, tilt, slant, u_axis, mirrored);
        eprintln!("tilt {tilt_deg} deg, u along {u_axis}, mirrored {mirrored}: {got} vs {want}");
        // The 1x1 map's texel is stored in f32, so the tilt is exact to rounding.
        assert!((got / want - 1.0).abs() < 1e-3, "{tilt_deg} deg: {got} vs {want}");
    }
    // A flat map (0.5, 0.5, 1) leaves the floor as it is.
    let flat = floor_luminance(rho, e, 0.0, slant, Vec3::X, false);
    assert!((flat / (rho / std::f32::consts::PI * e * slant.cos()) - 1.0).abs() < 1e-3, "{flat}");
}

/// VolumetricFogExample.glb's cube has a normalTexture, but every vertex has the same uv: there
/// is no tangent frame, so the hard case is that the interpolated normals stay, unchanged.
#[test]
fn a_normal_map_on_uvs_of_zero_area_is_read_and_leaves_the_normals_as_they_are() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf/bevy/VolumetricFogExample.glb");
    let mut images = Vec::new();
    for keep in [true, false] {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings::default());
        LightingPlugin::build(&mut world, &mut schedule);
        kelvin::render::scene_file::spawn_gltf_file(&mut world, std::path::Path::new(file)).unwrap();
        let mut q = world.query::<&mut Material>();
        let maps = q.iter(&world).filter(|m| m.normal_texture.is_some()).count();
        assert!(maps >= 1, "the file's normalTexture is read");
        if !keep {
            for mut m in q.iter_mut(&mut world) {
                m.normal_texture = None;
            }
        }
        // A uniform sky besides the file's sun, so that every side of the cube is lit.
        world.spawn((kelvin::light::UniformInfiniteLight::default(), Transform::default()));
        images.push(render(&mut world, &mut schedule, &RenderOptions::direct(32, 24, 2), |_| {}).0.pixels());
    }
    let lit = images[0].iter().filter(|p| p.max_element() > 0.0).count();
    assert!(lit > 10 && images[0].iter().all(|p| p.is_finite()), "{lit} lit pixels");
    assert!(images[0] == images[1], "a map without a tangent frame changed the picture");
}
