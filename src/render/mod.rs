//! Rendering: film and image output.
pub mod film_io;
