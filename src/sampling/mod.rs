//! Sampling maths: warps from the unit square to shapes and directions, each beside its pdf;
//! solid-angle sampling of spherical triangles and rectangles; piecewise-constant 1D/2D
//! distributions; and Vose alias tables. Pure maths over glam: no ECS, no scene types.
//!
//! Conventions:
//! - Local frames are z-up; a [`Frame`] carries directions between one and world space.
//! - Every `sample_x` has a pdf function `x_pdf` and, where it helps tests and MIS, an
//!   `invert_x_sample` back to the unit square. Pdfs of directions are per steradian, of points
//!   per unit area (or length) of the domain named.
//! - Sample inputs `u` are uniform in [0, 1); a 1 is tolerated and clamped where it matters.
//! - Where cancellation would eat an f32 (tiny cones and spherical polygons, sun-like peaks in a
//!   distribution), the work is done in f64 and only the result is rounded.

pub mod alias;
pub mod distribution;
pub mod frame;
pub mod spherical;
pub mod warp;

pub use alias::AliasTable;
pub use distribution::{PiecewiseConstant1D, PiecewiseConstant2D};
pub use frame::Frame;
pub use spherical::{
    invert_spherical_rectangle_sample, invert_spherical_triangle_sample, sample_spherical_rectangle,
    sample_spherical_triangle, spherical_rectangle_solid_angle, spherical_triangle_area, triangle_solid_angle,
};
pub use warp::*;

/// What can go wrong building a distribution from data. Messages say what was given and what is
/// accepted.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SamplingError {
    #[error("{what}: domain [{min}, {max}] must be finite with min < max")]
    BadDomain { what: &'static str, min: f32, max: f32 },
    #[error("{what}: {len} values given for a {nu} x {nv} grid (needs {nu} * {nv} values, both at least 1)")]
    BadGrid { what: &'static str, len: usize, nu: usize, nv: usize },
    #[error("{what}: no values given (needs at least one)")]
    Empty { what: &'static str },
}

/// The largest f32 below 1: samples are clamped to it so that `floor(u * n) < n`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Helpers shared by the unit tests: a deterministic RNG.
#[cfg(test)]
pub(crate) mod test_util {
    use glam::Vec2;

    /// SplitMix64 (Steele, Lea, Flood 2014): tiny, deterministic, good enough for tests.
    pub struct Rng(u64);

    impl Rng {
        pub fn new(seed: u64) -> Self {
            Self(seed)
        }
        pub fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        /// Uniform in [0, 1) on the 2^-24 grid, like a renderer's f32 samples.
        pub fn uniform(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
        }
        pub fn uniform2(&mut self) -> Vec2 {
            Vec2::new(self.uniform(), self.uniform())
        }
        pub fn uniform_f64(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
        }
    }
}
