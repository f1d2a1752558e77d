//! kelvin: an ECS-based, data-oriented light system after the "Light Sources" chapter of
//! Physically Based Rendering.
//!
//! `src/` holds what things are (data and pure math); `systems/` holds what happens each update.
pub mod geometry;
pub mod light;
pub mod report;
pub mod sampling;
pub mod spectrum;
