//! Helpers shared by the infinite-light tests: running Monte Carlo
//! statistics, and small constructors.
#![allow(dead_code)]

use std::sync::Arc;

use glam::{Quat, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{ImageInfiniteLight, LightSampleContext, ResolvedImageInfinite, SceneSphere};
use kelvin::scene::image::{LUMINANCE_WEIGHTS, RgbImage};
use kelvin::spectrum::SampledSpectrum;

pub use crate::common::Stats;

/// Photometric Y of an RGB-mode radiance.
pub fn y_of(s: SampledSpectrum) -> f64 {
    Vec3::new(s.0[0], s.0[1], s.0[2]).dot(LUMINANCE_WEIGHTS) as f64
}

pub fn rel_diff(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(f32::MIN_POSITIVE)
}

pub fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> Vec3) -> Arc<RgbImage> {
    Arc::new(RgbImage { width: w, height: h, pixels: (0..w * h).map(|i| f(i % w, i / w)).collect() })
}

/// A smooth sky with a soft bright spot: a gradient plus a Gaussian blob, no zeros.
pub fn test_sky(w: usize, h: usize) -> Arc<RgbImage> {
    image(w, h, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        let blob = 20.0 * (-((u - 0.3).powi(2) + (v - 0.35).powi(2)) / 0.004).exp();
        Vec3::new(0.3 + u, 0.5 + 0.5 * v, 1.0 - 0.5 * v) + Vec3::splat(blob)
    })
}

pub fn resolve(light: &ImageInfiniteLight, rotation: Quat) -> ResolvedImageInfinite {
    let t = Transform { rotation, ..Transform::IDENTITY };
    light.resolve(&t, SceneSphere { center: Vec3::new(1.0, 2.0, 3.0), radius: 5.0 }).expect("valid light")
}

pub fn tilted() -> Quat {
    Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.2)
}

pub fn surface_ctx() -> LightSampleContext {
    LightSampleContext::on_surface(Vec3::new(0.5, 0.2, -0.3), Vec3::new(0.3, 0.9, -0.2).normalize())
}
