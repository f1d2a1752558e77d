//! kelvin: an ECS-based, data-oriented light system after the "Light Sources" chapter of
//! Physically Based Rendering.
//!
//! `src/` holds what things are (data and pure math); `systems/` holds what happens each update.
pub mod geometry;
pub mod lanes;
pub mod light;
pub mod light_sampler;
mod prefetch;
pub mod render;
#[cfg(feature = "report")]
pub mod report;
pub mod rng;
pub mod sampling;
pub mod scene;
#[path = "../scenes/mod.rs"]
pub mod scenes;
pub mod shading;
pub mod spectrum;
#[path = "../systems/mod.rs"]
pub mod systems;

/// What an app that embeds the light system needs: the light and geometry components, their
/// `Transform`, the `Settings`, the batch it fills and the results it reads, and the plugin.
pub mod prelude {
    pub use crate::geometry::{Disk, Mesh, Rectangle, Sphere, Transform};
    pub use crate::light::{
        Amount, AreaLight, DistantLight, GoniometricLight, ImageInfiniteLight, PointLight, ProjectionLight, SpotLight,
        UniformInfiniteLight,
    };
    pub use crate::shading::{ColorMode, DirectLighting, LightSamplerKind, RunReport, Settings, ShadingBatch};
    pub use crate::spectrum::Spectrum;
    pub use crate::systems::{LightingPlugin, LightingSet};
}

/// The README's examples, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
