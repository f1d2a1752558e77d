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
//!   distribution), the work is done in f64 and only the result is rounded; `spherical_f32` is
//!   the f32 kernel of triangle sampling, which bounds its own error and says where it cannot.

pub mod alias;
pub mod distribution;
pub mod distribution_2d;
pub mod frame;
pub mod spherical;
pub mod spherical_f32;
pub mod warp;

pub use alias::AliasTable;
pub use distribution::{Bins, PiecewiseConstant1D};
pub use distribution_2d::PiecewiseConstant2D;
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
    /// A domain bound is not finite, or min >= max (for a 2D distribution, on one of its axes).
    #[error("{what}: domain [{min}, {max}] must be finite with min < max")]
    BadDomain {
        /// The distribution being built.
        what: &'static str,
        /// Lower bound given.
        min: f32,
        /// Upper bound given.
        max: f32,
    },
    /// A 2D grid's size is 0 along an axis, or does not match the number of values.
    #[error("{what}: {len} values given for a {nu} x {nv} grid (needs {nu} * {nv} values, both at least 1)")]
    BadGrid {
        /// The distribution being built.
        what: &'static str,
        /// Number of values given.
        len: usize,
        /// Grid size along u (values per row).
        nu: usize,
        /// Grid size along v (rows).
        nv: usize,
    },
    /// A 1D function has no values.
    #[error("{what}: no values given (needs at least one)")]
    Empty {
        /// The distribution being built.
        what: &'static str,
    },
}

/// The largest f32 below 1: samples are clamped to it so that `floor(u * n) < n`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
