//! Projection and goniometric lights: closed-form power against Monte Carlo integrals of I(w)
//! over the sphere, sample pdfs against pdf functions, pdfs integrating to 1, delta-light
//! irradiance, IES flux, and hard cases.
//!
//! Monte Carlo estimates use 64 independent jittered 128 x 128 grids (2^20 samples); the standard
//! error comes from the spread of the 64 grid means, so "3 sigma" is an honest bound.
//!
//! Files: `common` (RNG, estimators, checks), `projection`, `goniometric`.

#[path = "lights_projection_gonio/common.rs"]
mod common;
#[allow(dead_code)]
#[path = "common/files.rs"]
mod files;
#[path = "lights_projection_gonio/goniometric.rs"]
mod goniometric;
#[path = "lights_projection_gonio/projection.rs"]
mod projection;
