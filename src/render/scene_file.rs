//! A scene file in a world, as `kelvin render` loads one: a glTF file's entities (`scene::gltf`
//! then `scene::spawn`) and an optional lat-long environment map as an image infinite light.
//! The CLI and the render suite (`report::render_bench`) both go through here, so they render
//! the same world from the same file.

use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;

use crate::geometry::Transform;
use crate::light::ImageInfiniteLight;
use crate::scene::gltf::GltfError;
use crate::scene::image::ImageError;
use crate::scene::spawn::SpawnReport;

/// Loads the glTF file at `path` (.gltf or .glb) and spawns its meshes, lights and cameras into
/// `world`. The report's warnings include the loader's.
pub fn spawn_gltf_file(world: &mut World, path: &Path) -> Result<SpawnReport, GltfError> {
    let scene = crate::scene::gltf::load_gltf(path)?;
    Ok(crate::scene::spawn::spawn_gltf(world, &scene))
}

/// Loads the lat-long map at `path` (.exr or .hdr) and spawns it at the identity transform as an
/// `ImageInfiniteLight` of scale `intensity` (the luminance, nit, of a texel of value 1).
/// Returns the loader's warnings.
pub fn spawn_env_map(world: &mut World, path: &Path, intensity: f32) -> Result<Vec<String>, ImageError> {
    spawn_env_map_recorded(world, path, intensity).map(|(warnings, _)| warnings)
}

/// [`spawn_env_map`], with the record of the file's bytes as read.
pub fn spawn_env_map_recorded(
    world: &mut World,
    path: &Path,
    intensity: f32,
) -> Result<(Vec<String>, crate::provenance::InputFile), ImageError> {
    let (loaded, read) = crate::scene::image::load_image_recorded(path)?;
    let mut light = ImageInfiniteLight::new(Arc::new(loaded.image));
    light.scale = intensity;
    world.spawn((light, Transform::IDENTITY));
    Ok((loaded.warnings, read))
}
