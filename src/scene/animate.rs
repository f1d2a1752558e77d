//! Playing a glTF file's node animations in a world: posing a frame sets the `Transform` of the
//! entities whose nodes the clip moves, and of no other, so the light system's next update
//! re-syncs only those lights and refits the scene BVH instead of rebuilding it.

use bevy_ecs::prelude::*;
use glam::Affine3A;

use super::gltf::animation::SceneAnimations;
use crate::geometry::Transform;

/// The node trees and animations of the glTF files spawned into the world, in spawn order
/// (`SpawnReport::file` indexes them).
#[derive(Resource, Clone, Debug, Default)]
pub struct GltfAnimations {
    /// One entry per spawned file.
    pub files: Vec<SceneAnimations>,
}

/// The glTF node an entity was spawned from.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct GltfNode {
    /// Index into [`GltfAnimations::files`].
    pub file: usize,
    /// Index of the node in that file's glTF `nodes`.
    pub node: usize,
    /// The inverse of the node's rest transform where the entity's data holds it (a mesh's
    /// vertices are stored in world space at rest, so its `Transform` is the change since
    /// then); the identity for lights and cameras, whose `Transform` is the node's. `None` when
    /// the rest transform cannot be inverted (a zero scale): such a mesh cannot be moved.
    pub rest_inverse: Option<Affine3A>,
}

/// What posing a frame changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseReport {
    /// Entities whose `Transform` changed.
    pub moved: usize,
    /// Entities the clip moves that kept their transform (a held keyframe).
    pub unchanged: usize,
    /// Meshes the clip moves whose rest transform is singular; they stay at rest.
    pub frozen: usize,
}

/// Poses clip `clip` of spawned file `file` at time `t` (s): every entity of that file at a node
/// the clip moves gets the node's transform at `t`. Errors name a file or clip that does not
/// exist.
pub fn pose_gltf(world: &mut World, file: usize, clip: usize, t: f32) -> Result<PoseReport, String> {
    let animations = world.get_resource::<GltfAnimations>().ok_or("no glTF file was spawned in this world")?;
    let scene = animations.files.get(file).ok_or_else(|| format!("no spawned glTF file {file}"))?;
    if clip >= scene.clips.len() {
        return Err(format!("animation {clip} does not exist ({} in the file)", scene.clips.len()));
    }
    let moved = scene.moved_by(clip);
    let pose = scene.pose(clip, t);
    let mut report = PoseReport::default();
    let mut query = world.query::<(&GltfNode, &mut Transform)>();
    for (node, mut transform) in query.iter_mut(world) {
        if node.file != file || !moved.get(node.node).copied().unwrap_or(false) {
            continue;
        }
        let Some(rest_inverse) = node.rest_inverse else {
            report.frozen += 1;
            continue;
        };
        if transform.set_if_neq(Transform::from_affine(pose[node.node] * rest_inverse)) {
            report.moved += 1;
        } else {
            report.unchanged += 1;
        }
    }
    Ok(report)
}
