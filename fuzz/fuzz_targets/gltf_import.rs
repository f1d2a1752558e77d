//! glTF import to light table: bytes -> `load_gltf_from_bytes` -> `spawn_gltf` into a World with the
//! `LightingPlugin` -> one schedule run (BVH, light sync, sampler, sampling and shadow rays for two points).
//! A load error is fine; a panic, or a scene breaking `GltfScene`'s documented invariants, is a crash.
#![no_main]

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::scene::gltf::{GltfScene, load_gltf_from_bytes};
use kelvin::scene::spawn::spawn_gltf;
use kelvin::shading::ShadingBatch;
use kelvin::systems::LightingPlugin;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // No base directory: external buffers are errors and external images warnings, so the input is all there is.
    let Ok(scene) = load_gltf_from_bytes(data, None, "fuzz.glb") else { return };
    check_invariants(&scene);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    spawn_gltf(&mut world, &scene);
    let mut batch = world.resource_mut::<ShadingBatch>();
    batch.push(Vec3::ZERO, Vec3::Y, 0, 0);
    batch.push(Vec3::new(0.5, 1.0, -2.0), Vec3::NEG_Z, 1, 0);
    schedule.run(&mut world);
});

/// What the `GltfScene` docs promise about a loaded scene.
fn check_invariants(scene: &GltfScene) {
    for mesh in &scene.meshes {
        for p in &mesh.primitives {
            assert!(!p.indices.is_empty() && p.indices.len() % 3 == 0, "indices: {}", p.indices.len());
            assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()), "index out of range");
            assert!(p.positions.iter().all(|v| v.is_finite()), "non-finite position");
            if let Some(n) = &p.normals {
                assert!(n.len() == p.positions.len() && n.iter().all(|v| v.is_finite()), "bad normals");
            }
            if let Some(uv) = &p.uvs {
                assert_eq!(uv.len(), p.positions.len(), "bad uvs");
            }
            assert!(p.material.is_none_or(|m| m < scene.materials.len()), "material out of range");
        }
    }
    assert!(scene.instances.iter().all(|i| i.mesh < scene.meshes.len()), "instance mesh out of range");
    for m in &scene.materials {
        for t in [m.base_color_texture, m.metallic_roughness_texture, m.emissive_texture].into_iter().flatten() {
            assert!(t < scene.textures.len(), "texture out of range");
        }
        assert!(m.emissive.is_finite() && m.emissive.cmpge(Vec3::ZERO).all(), "emissive {:?}", m.emissive);
    }
    for l in &scene.lights {
        assert!(l.intensity.is_finite() && l.intensity >= 0.0, "light intensity {}", l.intensity);
        assert!(l.color.is_finite() && l.color.cmpge(Vec3::ZERO).all(), "light colour {:?}", l.color);
    }
    for c in &scene.cameras {
        assert!(c.yfov > 0.0 && c.yfov < std::f32::consts::PI && c.znear > 0.0, "camera {c:?}");
    }
}
