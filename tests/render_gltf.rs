//! Every real glTF scene in ../shared/data/gltf (except the validator's deliberately invalid
//! files) loads, spawns and renders to finite pixels; emissive surfaces and punctual lights reach
//! the light table.

use std::path::Path;

use bevy_ecs::prelude::*;
use kelvin::light::LightTable;
use kelvin::render::renderer::{RenderOptions, Strategy, render};
use kelvin::scene::gltf::load_gltf;
use kelvin::scene::spawn::spawn_gltf;
use kelvin::systems::LightingPlugin;

/// (file, minimum number of lights expected in the light table).
const SCENES: &[(&str, usize)] = &[
    ("bevy/CornellBox.glb", 1),
    ("bevy/VolumetricFogExample.glb", 1),
    ("bevy/MixedLightingExample/MixedLightingExample.gltf", 1),
    ("renderling/EmissiveStrengthTest.glb", 1),
    ("renderling/four_spotlights.glb", 4),
    ("renderling/light_tiling_test.glb", 1),
    ("renderling/shadow_mapping_sanity.gltf", 1),
    ("renderling/cheetah_cone.glb", 0),
    ("renderling/spot_one.glb", 1),
    ("renderling/shadow_mapping_spots.glb", 1),
    ("renderling/spot_lights.glb", 1),
    ("renderling/shadow_mapping_point.glb", 1),
    ("renderling/shadow_mapping_points.glb", 1),
    ("kajiya/emissive_triangle/triangle.glb", 1),
];

#[test]
fn every_real_gltf_scene_renders() {
    let root = Path::new("../shared/data/gltf");
    if !root.is_dir() {
        eprintln!("skipping: {} not found", root.display());
        return;
    }
    for &(file, min_lights) in SCENES {
        let path = root.join(file);
        let scene = load_gltf(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let mut world = World::new();
        let mut schedule = Schedule::default();
        LightingPlugin::build(&mut world, &mut schedule);
        let report = spawn_gltf(&mut world, &scene);
        let (film, stats) = render(
            &mut world,
            &mut schedule,
            &RenderOptions { width: 24, height: 16, spp: 2, strategy: Strategy::Mis },
            |_| {},
        );
        let lights = world.resource::<LightTable>().entity_count();
        eprintln!(
            "{file}: {} meshes, {} triangles, {} emissive, {} lights spawned, {lights} in the table, {} warnings, {:.3} s",
            report.meshes,
            report.triangles,
            report.emissive_meshes,
            report.lights,
            report.warnings.len(),
            stats.seconds
        );
        assert!(film.pixels().iter().all(|p| p.is_finite() && p.min_element() >= 0.0), "{file}: non-finite pixel");
        assert!(lights >= min_lights, "{file}: {lights} lights, expected at least {min_lights}");
    }
}

#[test]
fn the_validator_files_spawn_without_panicking() {
    let root = Path::new("../shared/data/gltf/khronos-validator");
    if !root.is_dir() {
        eprintln!("skipping: {} not found", root.display());
        return;
    }
    let mut stack = vec![root.to_path_buf()];
    let mut n = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "gltf") {
                if let Ok(scene) = load_gltf(&path) {
                    let mut world = World::new();
                    let mut schedule = Schedule::default();
                    LightingPlugin::build(&mut world, &mut schedule);
                    spawn_gltf(&mut world, &scene);
                    schedule.run(&mut world);
                    n += 1;
                }
            }
        }
    }
    assert!(n >= 20, "{n} validator files spawned");
}
