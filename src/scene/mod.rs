//! Loading: images (env maps, light images, textures) and IES photometric profiles, each with clear errors.
pub mod ies;
pub mod image;
