//! glTF node animation end to end, on tests/data/gltf/kelvin/animated_lamp.gltf (written by
//! scripts/make_test_gltf.py, which documents its channels): a point light whose parent node
//! steps sideways and grows along a cubic spline while the light rises linearly, a shutter that
//! slides over the floor point the camera looks at, and a camera that slides along x.
//!
//! Per frame the image's luminance must equal the closed form rho/pi * I cos(theta) / d^2 at the
//! point the camera sees (zero where the shutter is in the way), computed here from the file's
//! keyframes with the interpolation formulas of the glTF spec (Appendix C). Each frame moves
//! only the animated entities: the light system refits the BVH, never rebuilds it.

mod common;

use bevy_ecs::prelude::*;
use glam::DVec3;
use kelvin::geometry::Transform;
use kelvin::render::renderer::{RenderOptions, render};
use kelvin::scene::animate::{GltfNode, pose_gltf};
use kelvin::scene::gltf::animation::Target;
use kelvin::scene::gltf::load_gltf;
use kelvin::scene::spawn::spawn_gltf;
use kelvin::systems::LightingPlugin;

use common::files::test_data;

const FILE: &str = "gltf/kelvin/animated_lamp.gltf";

/// The floor luminance the camera sees at time t (s), from the keyframes the script writes.
fn expected_luminance(t: f64) -> f64 {
    let rig_x = if t < 1.0 { 0.0 } else { 0.6 }; // STEP
    let u = (t / 2.0).clamp(0.0, 1.0);
    let rig_scale = 1.0 + 3.0 * u * u - 2.0 * u * u * u; // CUBICSPLINE, zero tangents
    let lamp_y = 1.0 + u; // LINEAR, local
    let lamp = DVec3::new(rig_x, rig_scale * lamp_y, 0.0);
    let seen = DVec3::new(0.4 * u, 0.0, 0.0);
    // The shutter (0.8 m square at y = 0.5) and where the shadow ray crosses its plane.
    let shutter_x = 3.0 - 6.0 * u;
    let cross = seen + (lamp - seen) * (0.5 / lamp.y);
    if (cross.x - shutter_x).abs() <= 0.4 && cross.z.abs() <= 0.4 {
        return 0.0;
    }
    let d = lamp - seen;
    0.5 / std::f64::consts::PI * 10.0 * d.y / d.length().powi(3)
}

fn world_of_the_file() -> (World, Schedule) {
    let scene = load_gltf(&test_data(FILE)).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let report = spawn_gltf(&mut world, &scene);
    assert_eq!((report.file, report.animations), (0, 1));
    (world, schedule)
}

#[test]
fn the_file_reads_as_five_channels_of_each_interpolation() {
    let scene = load_gltf(&test_data(FILE)).unwrap();
    let clips = &scene.animations.clips;
    assert_eq!(clips.len(), 1);
    assert_eq!(clips[0].name.as_deref(), Some("day"));
    assert_eq!(clips[0].channels.len(), 5);
    assert_eq!(clips[0].duration(), 2.0);
    let targets: Vec<Target> = clips[0].channels.iter().map(|c| c.target).collect();
    assert_eq!(
        targets,
        [Target::Translation, Target::Scale, Target::Translation, Target::Translation, Target::Translation]
    );
    // rig, lamp, shutter and camera move; the floor does not.
    let moved = scene.animations.moved_by(0);
    assert_eq!(moved.iter().filter(|&&m| m).count(), 4);
}

#[test]
fn every_frame_shows_the_closed_form_of_its_pose() {
    let (mut world, mut schedule) = world_of_the_file();
    let opts = RenderOptions::direct(8, 8, 4);
    let mut lit = 0;
    // 4 fps over the clip, and past its end (the last keyframes hold).
    for frame in 0..=10 {
        let t = frame as f64 / 4.0;
        let posed = pose_gltf(&mut world, 0, 0, t as f32).unwrap();
        let (film, stats) = render(&mut world, &mut schedule, &opts, |_| {});
        let pixels = film.pixels();
        let mean: f64 = pixels.iter().map(|c| (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) as f64).sum::<f64>()
            / pixels.len() as f64;
        let want = expected_luminance(t);
        if want == 0.0 {
            assert!(mean < 1e-6, "frame {frame}: the shutter should shadow the point, got {mean}");
        } else {
            lit += 1;
            assert!((mean / want - 1.0).abs() < 2e-3, "frame {frame} (t = {t}): {mean} against {want}");
        }
        if frame > 0 {
            // The lamp, the shutter and the camera moved (past the end nothing does).
            assert_eq!(posed.moved, if frame <= 8 { 3 } else { 0 }, "frame {frame}: {posed:?}");
            let report = &stats.report;
            assert_eq!(report.runs("bvh_refit") > 0, frame <= 8, "frame {frame}:\n{report}");
            assert!(
                report.line("update_scene_bvh", true).is_none_or(|l| !l.last_why.contains("added")),
                "frame {frame}: a rebuild\n{report}"
            );
        }
    }
    assert_eq!(lit, 10, "only frame 4 is shadowed");
}

/// Hard case: posing the rest time of a clip whose first keyframes are the rest pose moves a
/// mesh back to where it was baked, so its transform is (nearly) the identity again.
#[test]
fn posing_the_first_keyframe_puts_meshes_back_at_rest() {
    let (mut world, _) = world_of_the_file();
    pose_gltf(&mut world, 0, 0, 1.3).unwrap();
    pose_gltf(&mut world, 0, 0, 0.0).unwrap();
    let mut query = world.query::<(&GltfNode, &Transform, Option<&kelvin::geometry::Mesh>)>();
    let meshes: Vec<Transform> = query.iter(&world).filter(|(_, _, m)| m.is_some()).map(|(_, t, _)| *t).collect();
    assert_eq!(meshes.len(), 2);
    for t in meshes {
        assert!(t.translation.length() < 1e-6 && t.scale.abs_diff_eq(glam::Vec3::ONE, 1e-6), "{t:?}");
    }
}

#[test]
fn posing_what_does_not_exist_is_an_error_that_says_so() {
    let (mut world, _) = world_of_the_file();
    assert!(pose_gltf(&mut world, 0, 1, 0.0).unwrap_err().contains("animation 1 does not exist"));
    assert!(pose_gltf(&mut world, 3, 0, 0.0).unwrap_err().contains("no spawned glTF file 3"));
    let mut empty = World::new();
    assert!(pose_gltf(&mut empty, 0, 0, 0.0).unwrap_err().contains("no glTF file"));
}

/// Bad channels (too few values for CUBICSPLINE, a missing node, an unknown interpolation,
/// morph weights) are dropped, each with a warning at its JSON pointer; the good channels and
/// the rest of the scene load.
#[test]
fn bad_channels_are_dropped_with_a_warning_and_the_rest_loads() {
    let path = test_data(FILE);
    let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let animation = &mut json["animations"][0];
    animation["samplers"][0]["interpolation"] = "CUBICSPLINE".into();
    animation["channels"][2]["target"]["node"] = 99.into();
    animation["samplers"][3]["interpolation"] = "BOGUS".into();
    animation["channels"][4]["target"]["path"] = "weights".into();
    let bytes = serde_json::to_vec(&json).unwrap();
    let scene = kelvin::scene::gltf::load_gltf_from_bytes(&bytes, None, "bad.gltf").unwrap();
    let warnings = scene.warnings.join("\n");
    for (channel, says) in
        [(0, "3 each needed"), (2, "node 99 does not exist"), (3, "invalid interpolation"), (4, "weights")]
    {
        let pointer = format!("bad.gltf: /animations/0/channels/{channel}: ");
        assert!(scene.warnings.iter().any(|w| w.starts_with(&pointer) && w.contains(says)), "{channel}: {warnings}");
    }
    assert_eq!(scene.animations.clips[0].channels.len(), 1, "{warnings}");
    assert_eq!((scene.instances.len(), scene.lights.len(), scene.cameras.len()), (2, 1, 1));
}
