//! Scenes kelvin ships, built in code: the embedded default scene and generators for benchmarks.
pub mod default_scene;
