//! Scenes kelvin ships, built in code: the embedded default scene and generators for benchmarks
//! and reports.
pub mod bench_scenes;
pub mod color_checker;
pub mod default_scene;
pub mod many_lights;
pub mod sunlit_objects;
