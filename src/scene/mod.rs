//! Loading: images (env maps, light images, textures) and glTF scenes.
pub mod gltf;
pub mod image;
