//! Loading: glTF scenes, environment maps, light images and textures, and IES photometric profiles,
//! each with clear errors; spawning a glTF scene as entities, and playing its node animations.
pub mod animate;
mod exr_decode;
pub mod gltf;
pub mod ies;
pub mod image;
pub mod spawn;
