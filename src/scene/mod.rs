//! Loading: glTF scenes, environment maps, light images and textures, and IES photometric profiles,
//! each with clear errors.
pub mod gltf;
pub mod ies;
pub mod image;
pub mod spawn;
