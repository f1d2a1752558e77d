//! Rendering: camera, materials and BSDFs, the direct-lighting and path-tracing renderer, film and image output.
pub mod bsdf;
pub mod camera;
mod camera_pass;
pub mod film;
pub mod film_io;
pub mod job;
pub mod material;
mod normal_map;
pub mod partial;
pub mod path;
mod png_text;
pub mod renderer;
pub mod scene_file;
mod shade;
mod shade_lanes;
pub(crate) mod surface_paths;
pub mod tiles;
