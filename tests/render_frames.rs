//! A frame's image does not depend on the frames rendered before it in the same process (what a
//! render farm needs to spread frames over tasks, alone, in chunks or in sequences): with the
//! render job's settings (`LightUpdates::Rebuild`) a frame rendered after another, its lights moved
//! in between as an animation moves them, is bit for bit the frame rendered in a fresh world. With
//! incremental updates (the embedding default) the refitted light BVH gives another image.

mod common;

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::PointLight;
use kelvin::render::job::{LoadedJob, RenderJob};
use kelvin::render::renderer::render_with;
use kelvin::shading::{LightUpdates, Settings};

use common::files::TempDir;
use common::gltf_doc::{Doc, floor};

/// 300 point lights in a grid over a floor, seen by kelvin's framing camera.
fn scene(dir: &TempDir) -> RenderJob {
    let mut doc = Doc::default();
    let m = doc.material(0.7, 0.0);
    doc.mesh("floor", &[floor([-4.0, 4.0], [-4.0, 4.0], 0.0, m)]);
    for k in 0..300 {
        let at = Vec3::new((k % 20) as f32 * 0.4 - 4.0, 0.3 + (k / 20) as f32 * 0.1, (k / 20) as f32 * 0.5 - 3.5);
        doc.light(serde_json::json!({ "type": "point", "intensity": 1.0 + (k % 7) as f32 }), at, [0.0, 0.0, 0.0, 1.0]);
    }
    let path = dir.join("lights.gltf");
    doc.write(&path);
    RenderJob { scene: Some(path), width: 24, height: 16, spp: 2, ..RenderJob::default() }
}

/// Moves every third light by `shift`, as an animation frame would.
fn step(world: &mut World, shift: Vec3) {
    let mut lights = world.query_filtered::<(Entity, &Transform), With<PointLight>>();
    let moved: Vec<(Entity, Transform)> = lights
        .iter(world)
        .enumerate()
        .filter(|(k, _)| k % 3 == 0)
        .map(|(_, (e, t))| (e, Transform { translation: t.translation + shift, ..*t }))
        .collect();
    for (e, t) in moved {
        *world.get_mut::<Transform>(e).unwrap() = t;
    }
}

fn image(loaded: &mut LoadedJob, job: &RenderJob) -> Vec<Vec3> {
    render_with(&mut loaded.world, &mut loaded.schedule, &job.options(), job.camera(), |_| {}).0.pixels()
}

/// Frame 2 of a sequence (after frames 0 and 1) and frame 2 alone.
fn frame_two(job: &RenderJob, updates: LightUpdates) -> (Vec<Vec3>, Vec<Vec3>) {
    let shift = Vec3::new(0.05, 0.02, -0.03);
    let mut sequence = job.load().unwrap();
    sequence.world.resource_mut::<Settings>().light_updates = updates;
    for _ in 0..2 {
        image(&mut sequence, job);
        step(&mut sequence.world, shift);
    }
    let in_sequence = image(&mut sequence, job);
    let mut fresh = job.load().unwrap();
    fresh.world.resource_mut::<Settings>().light_updates = updates;
    step(&mut fresh.world, 2.0 * shift);
    // Two steps of one shift and one of twice it place the lights alike only up to rounding: the
    // alone frame takes the sequence's transforms instead.
    let mut placed = sequence.world.query_filtered::<(&Transform, &PointLight), ()>();
    let transforms: Vec<Transform> = placed.iter(&sequence.world).map(|(t, _)| *t).collect();
    let mut targets = fresh.world.query_filtered::<&mut Transform, With<PointLight>>();
    for (t, want) in targets.iter_mut(&mut fresh.world).zip(&transforms) {
        *t.into_inner() = *want;
    }
    (in_sequence, image(&mut fresh, job))
}

#[test]
fn a_frame_is_the_same_bit_for_bit_in_a_sequence_and_alone() {
    let dir = TempDir::new("frames", "rebuild");
    let job = scene(&dir);
    assert_eq!(job.settings().light_updates, LightUpdates::Rebuild, "render jobs rebuild");
    let (in_sequence, alone) = frame_two(&job, LightUpdates::Rebuild);
    assert!(in_sequence.iter().any(|p| p.max_element() > 0.0));
    assert!(in_sequence == alone, "frame 2 differs between a sequence and a fresh world");
    // The case this guards: refits steer light choice by another tree.
    let (in_sequence, alone) = frame_two(&job, LightUpdates::Incremental);
    assert!(in_sequence != alone, "refits gave the built tree: the test no longer shows the difference");
}
