//! Integration tests of `kelvin::sampling`: every warp's pdf against its Jacobian, pdfs
//! integrating to 1, inverses, spherical triangles and rectangles (tiny, ordinary, near 2 pi sr)
//! against Monte Carlo and closed forms, and chi-square tests of distributions and alias tables.

#[path = "sampling/common.rs"]
mod common;
#[path = "sampling/distributions.rs"]
mod distributions;
#[path = "sampling/spherical.rs"]
mod spherical;
#[path = "sampling/warps.rs"]
mod warps;
