//! The real glTF scenes in tests/data/gltf (origins in tests/data/SOURCES.md), checked against
//! what each file says:
//!
//! - the light table holds exactly the file's lights: every KHR_lights_punctual light a node
//!   instances (one table entity each) and every emissive primitive (one area-light entity, one
//!   row per triangle);
//! - each render is finite, lit where the file's lights face geometry, and gets the same light
//!   from one light sample chosen by the light BVH as from a sample of every light;
//! - at chosen points, the irradiance the light system delivers (all-lights mode, one entry per
//!   light, shadows on) equals the closed form E = sum over visible lights of
//!   I cos(theta) / d^2 (times kelvin's smoothstep spot falloff, src/light/spot.rs), or
//!   E_lux cos(theta) for directional lights, from the light data written in the file's JSON;
//!   for the Cornell box's emissive quad, Lambert's polygon formula.
//!
//! Units: glTF punctual intensities are candela (point, spot) and lux (directional); kelvin
//! takes a light's luminous amount as the intensity times its colour's Rec. 709 luminance
//! (src/scene/spawn.rs), and its RGB mode is photometric, so the luminance of an entry's radiance
//! is cd/m^2 and the irradiance below is lux.
//!
//! The validator's deliberately invalid files are only spawned (they must not panic).

mod common;
#[path = "render_gltf/irradiance.rs"]
mod irradiance;

use bevy_ecs::prelude::*;
use kelvin::light::LightTable;
use kelvin::render::renderer::{RenderOptions, render};
use kelvin::scene::gltf::load_gltf;
use kelvin::scene::spawn::{SpawnReport, spawn_gltf};
use kelvin::shading::{LightSelection, Settings};
use kelvin::systems::LightingPlugin;

use common::files::test_data;
use irradiance::lum_rgb;

/// What a file holds, counted from its JSON (KHR_lights_punctual `lights` instanced by nodes of
/// the default scene; primitives whose material has a nonzero `emissiveFactor`).
struct Expected {
    file: &'static str,
    points: usize,
    spots: usize,
    directional: usize,
    /// Emissive primitives (each one area-light entity).
    emissive_meshes: usize,
    /// Their triangles (each one area-light row): index count / 3.
    emissive_triangles: usize,
    /// Whether the lights face geometry the camera sees (so the render must not be black).
    lit: bool,
}

const fn scene(
    file: &'static str,
    points: usize,
    spots: usize,
    directional: usize,
    emissive_meshes: usize,
    emissive_triangles: usize,
) -> Expected {
    Expected { file, points, spots, directional, emissive_meshes, emissive_triangles, lit: true }
}

const SCENES: &[Expected] = &[
    // No KHR_lights_punctual; node 0 "Light" has the one emissive primitive (material 0
    // "Emitter_Light_temp", emissive (1, 1, 1) x strength 100): a quad of 6 indices.
    scene("bevy/CornellBox.glb", 0, 0, 0, 1, 2),
    // 1 directional light "Sun" (68300 lx, colour (1, 0.9895, 0.8705)) on node 0 "Sun".
    scene("bevy/VolumetricFogExample.glb", 0, 0, 1, 0, 0),
    // 1 directional light "Sun" (2049 lx) on node 6 "Sun"; nothing emissive.
    scene("bevy/MixedLightingExample/MixedLightingExample.gltf", 0, 0, 1, 0, 0),
    // No punctual lights; 5 emissive cubes (nodes Cube1/2/4/8/16, materials Emit1..Emit16,
    // emissive (0.1, 0.5, 0.9) x strength 1..16), 36 indices each. Material 1 (the backdrop)
    // does not emit.
    scene("renderling/EmissiveStrengthTest.glb", 0, 0, 0, 5, 60),
    // 4 spot lights (54351 cd each) on nodes 0-3, all at (0, 1, 0), and no meshes at all: the
    // camera sees nothing, so the render is black (the lights are checked in free space below).
    Expected { lit: false, ..scene("renderling/four_spotlights.glb", 0, 4, 0, 0, 0) },
    // 1 directional light "Light" (1366 lx, colour (0.557, 0.646, 1)) on node 6.
    scene("renderling/light_tiling_test.glb", 0, 0, 1, 0, 0),
    // 1 directional light "Light" (6830 lx) on node 1, plus the two emissive "LightCone"
    // cylinders (nodes 6 and 7, material 4, emissive (0, 0.318, 1) x 10), 372 indices each.
    scene("renderling/shadow_mapping_sanity.gltf", 0, 0, 1, 2, 248),
    // 1 directional light "Light" (68300 lx) on node 0 (the file's orthographic camera is
    // skipped with a warning, so the render frames the scene).
    scene("renderling/cheetah_cone.glb", 0, 0, 1, 0, 0),
    // 1 spot light "Light" (54351 cd) on node 0.
    scene("renderling/spot_one.glb", 0, 1, 0, 0, 0),
    // 2 spot lights "Light", "Light.001" (54351 cd) on nodes 1 and 3.
    scene("renderling/shadow_mapping_spots.glb", 0, 2, 0, 0, 0),
    // 2 narrow spot lights "Light", "Light.001" (54351 cd, outer cone 0.091 rad) on nodes 1 and 3.
    scene("renderling/spot_lights.glb", 0, 2, 0, 0, 0),
    // 1 point light "Light" (5435 cd) on node 1.
    scene("renderling/shadow_mapping_point.glb", 1, 0, 0, 0, 0),
    // 4 point lights "Point" .. "Point.003" (2174 cd) on nodes 11-14.
    scene("renderling/shadow_mapping_points.glb", 4, 0, 0, 0, 0),
    // No punctual lights; the one triangle (3 indices) of node 0 "Plane" is emissive (1, 1, 1).
    scene("kajiya/emissive_triangle/triangle.glb", 0, 0, 0, 1, 1),
];

/// A loaded, spawned scene with the light system built.
struct Loaded {
    world: World,
    schedule: Schedule,
    report: SpawnReport,
}

fn load(file: &str) -> Loaded {
    let path = test_data("gltf").join(file);
    let scene = load_gltf(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let report = spawn_gltf(&mut world, &scene);
    Loaded { world, schedule, report }
}

#[test]
fn every_real_gltf_scene_has_exactly_its_lights_in_the_table() {
    for e in SCENES {
        let Loaded { mut world, mut schedule, report } = load(e.file);
        schedule.run(&mut world);
        let table = world.resource::<LightTable>();
        let punctual = e.points + e.spots + e.directional;
        let got = (
            table.points().len(),
            table.spots().len(),
            table.distant().items.len(),
            table.area().items.len(),
            report.lights,
            report.emissive_meshes,
            table.entity_count(),
        );
        eprintln!(
            "{}: (points, spots, distant, area rows, report.lights, report.emissive, entities) = {got:?}",
            e.file
        );
        let want = (
            e.points,
            e.spots,
            e.directional,
            e.emissive_triangles,
            punctual,
            e.emissive_meshes,
            punctual + e.emissive_meshes,
        );
        assert_eq!(
            got, want,
            "{}: (points, spots, distant, area rows, report.lights, report.emissive_meshes, entities)",
            e.file
        );
        // And no rows of other kinds (projection, goniometric, infinite lights).
        assert_eq!(table.len(), e.points + e.spots + e.directional + e.emissive_triangles, "{}", e.file);
    }
}

/// Each real scene renders finite, non-negative pixels, and the light its one-sample light choice
/// (the light BVH's pmf) delivers equals what lighting every light with its own sample delivers:
/// the mean of the per-pixel difference is zero within its noise. A wrong pmf, a light the BVH
/// never picks or a light counted twice moves the difference; the scenes with many emitters
/// (EmissiveStrengthTest's 60 triangles, shadow_mapping_sanity's 248 and its sun,
/// shadow_mapping_points' 4 points) are the hard cases.
#[test]
fn every_real_gltf_scene_gets_the_same_light_from_one_sampled_light_as_from_all() {
    for e in SCENES {
        let mut images = Vec::new();
        for selection in [LightSelection::OneSampled, LightSelection::All] {
            let Loaded { mut world, mut schedule, report } = load(e.file);
            world.insert_resource(Settings { selection, ..Default::default() });
            let (film, stats) = render(&mut world, &mut schedule, &RenderOptions::direct(24, 16, 16), |_| {});
            let pixels = film.pixels();
            assert!(
                pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0),
                "{}: non-finite or negative pixel",
                e.file
            );
            eprintln!(
                "{}: {} meshes, {} triangles, {selection:?} {:.3} s",
                e.file, report.meshes, report.triangles, stats.seconds
            );
            images.push((pixels.iter().map(|p| lum_rgb(*p)).collect::<Vec<f64>>(), report.meshes));
        }
        let ((one, meshes), (all, _)) = (&images[0], &images[1]);
        let n = one.len() as f64;
        let diff: Vec<f64> = one.iter().zip(all).map(|(a, b)| a - b).collect();
        let mean_diff = diff.iter().sum::<f64>() / n;
        let error = (diff.iter().map(|d| (d - mean_diff).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let mean = all.iter().sum::<f64>() / n;
        eprintln!("{}: mean Y {mean:.4} cd/m^2, one-sampled - all {mean_diff:.5} +- {error:.5}", e.file);
        if e.lit {
            assert!(mean > 0.0, "{}: black render", e.file);
            assert!(
                mean_diff.abs() < 4.0 * error + 1e-4 * mean,
                "{}: one-sampled - all = {mean_diff} +- {error}",
                e.file
            );
        } else {
            // four_spotlights.glb has no mesh: every camera ray escapes and spots are not seen.
            assert_eq!(*meshes, 0, "{}", e.file);
            assert!(one.iter().chain(all).all(|&y| y == 0.0), "{}: a render without geometry shows light", e.file);
        }
    }
}

/// The emissive triangle of kajiya's triangle.glb (emissive (1, 1, 1), double-sided, nothing to
/// reflect its light back): a pixel wholly on it sees L = 1 cd/m^2 and no more.
#[test]
fn kajiya_emissive_triangle_pixels_see_its_radiance() {
    let Loaded { mut world, mut schedule, .. } = load("kajiya/emissive_triangle/triangle.glb");
    let opts = RenderOptions::direct(24, 16, 2);
    let (film, _) = render(&mut world, &mut schedule, &opts, |_| {});
    let max = film.pixels().iter().map(|p| lum_rgb(*p)).fold(0.0, f64::max);
    eprintln!("triangle.glb: brightest pixel Y {max:.6} (expected 1)");
    assert!((max - 1.0).abs() < 1e-4, "brightest pixel Y {max}, expected 1 (the emissive factor)");
}

#[test]
fn the_validator_files_spawn_without_panicking() {
    let root = test_data("gltf/khronos-validator");
    let mut stack = vec![root.to_path_buf()];
    let mut n = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "gltf")
                && let Ok(scene) = load_gltf(&path)
            {
                let mut world = World::new();
                let mut schedule = Schedule::default();
                LightingPlugin::build(&mut world, &mut schedule);
                spawn_gltf(&mut world, &scene);
                schedule.run(&mut world);
                n += 1;
            }
        }
    }
    assert!(n >= 20, "{n} validator files spawned");
}
