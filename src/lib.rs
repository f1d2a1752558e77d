//! kelvin: an ECS-based, data-oriented light system after the "Light Sources" chapter of
//! Physically Based Rendering.
//!
//! `src/` holds what things are (data and pure math); `systems/` holds what happens each update.
#![warn(missing_docs)]

pub mod bake;
pub mod geometry;
/// Lane kernels' plumbing (16 f32 per array, the run-time instruction-set choice): public only with the
/// `internals` feature, for the crate's own lane benchmarks and tests.
#[cfg(feature = "internals")]
#[doc(hidden)]
pub mod lanes;
#[cfg(not(feature = "internals"))]
#[allow(dead_code)]
pub(crate) mod lanes;
pub mod light;
pub mod light_sampler;
mod prefetch;
pub mod provenance;
pub mod render;
#[cfg(feature = "report")]
pub mod report;
pub mod rng;
pub mod sampling;
pub mod scene;
#[cfg(feature = "scenes")]
#[path = "../scenes/mod.rs"]
pub mod scenes;
pub mod shading;
pub mod spectrum;
#[path = "../systems/mod.rs"]
pub mod systems;

/// The vector and matrix types of kelvin's API (glam, the version kelvin is built with): an app
/// names `kelvin::math::Vec3` and never guesses which glam to depend on. Bevy's `bevy::math` types
/// are another glam version; pass them as arrays (`Vec3::from_array(v.to_array())`).
pub use glam as math;

/// The ECS kelvin's components, resources and systems live in (bevy_ecs, the version kelvin is
/// built with), for apps that run the light system without Bevy.
pub use bevy_ecs as ecs;

/// What an app that embeds the light system needs, glob-importable next to `bevy::prelude::*`: it
/// holds no name Bevy's prelude uses. kelvin's types named like Bevy's (`PointLight`, `SpotLight`,
/// `Transform`, `Mesh`, `Sphere`, `Rectangle`, `Camera`, `Material`) are reached through the
/// modules it brings in: `light::PointLight`, `geometry::Transform`, `render::material::Material`.
pub mod prelude {
    pub use crate::geometry::Disk;
    pub use crate::light::{
        Amount, AreaLight, DistantLight, GoniometricLight, ImageInfiniteLight, ProjectionLight, SunSkyLight,
        UniformInfiniteLight,
    };
    pub use crate::render::job::RenderJob;
    pub use crate::shading::{
        ColorMode, DirectLighting, LightSamplerKind, LightSelection, Restir, ReuseWeights, RunReport, Settings,
        ShadingBatch,
    };
    pub use crate::spectrum::Spectrum;
    pub use crate::systems::{LightingPlugin, LightingSet};
    pub use crate::{geometry, light, render};
}

/// The README's examples, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
