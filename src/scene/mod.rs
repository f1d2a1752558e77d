//! Loading: images (env maps, light images, textures).
pub mod image;
