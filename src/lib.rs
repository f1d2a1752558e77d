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

/// The README's examples, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
