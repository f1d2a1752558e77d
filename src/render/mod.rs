//! Rendering: camera, materials and BSDFs, the direct-lighting renderer, film and image output.
pub mod bsdf;
pub mod camera;
mod camera_pass;
pub mod film;
pub mod film_io;
pub mod material;
pub mod renderer;
pub mod scene_file;
mod shade_lanes;
pub mod tiles;
