//! Scenes kelvin ships, built in code: the embedded default scene and generators for benchmarks.
pub mod bench_scenes;
pub mod default_scene;
