//! Rendering: materials and BSDFs, film and image output.
pub mod bsdf;
pub mod film_io;
pub mod material;
