//! Shared by the light tests: Monte Carlo statistics and their assertion, and
//! the area-light fixtures. Each test binary uses part of it.
#![allow(dead_code)]

pub mod area;
pub mod chi_square;
pub mod files;
pub mod gltf_doc;
pub mod lobe_grid;
pub mod room_files;

use kelvin::light::ColorQuery;
use kelvin::spectrum::SampledSpectrum;

/// Running mean and standard error.
#[derive(Default)]
pub struct Stats {
    pub n: f64,
    sum: f64,
    sum2: f64,
}

impl Stats {
    pub fn add(&mut self, x: f64) {
        self.n += 1.0;
        self.sum += x;
        self.sum2 += x * x;
    }
    pub fn mean(&self) -> f64 {
        self.sum / self.n
    }
    pub fn sigma(&self) -> f64 {
        let m = self.mean();
        ((self.sum2 / self.n - m * m).max(0.0) / self.n).sqrt()
    }
    /// Asserts |mean - expected| <= 3 sigma + abs_tol and prints the errors.
    pub fn check(&self, name: &str, expected: f64, abs_tol: f64) {
        let (m, s) = (self.mean(), self.sigma());
        let rel = (m - expected).abs() / expected.abs().max(1e-300);
        eprintln!("{name}: estimate {m:.6e} vs {expected:.6e}, rel err {rel:.2e}, sigma/expected {:.2e}", s / expected);
        assert!((m - expected).abs() <= 3.0 * s + abs_tol, "{name}: {m} vs {expected} (3 sigma = {})", 3.0 * s);
    }
}

pub const RGB: ColorQuery<'static> = ColorQuery::Rgb;

/// Rec. 709 luminance of an RGB-mode result.
pub fn lum(s: SampledSpectrum) -> f64 {
    0.2126 * s.0[0] as f64 + 0.7152 * s.0[1] as f64 + 0.0722 * s.0[2] as f64
}

/// Asserts |measured - expected| <= 3 sigma (+ a 1e-5 relative floor for f32 rounding when the
/// estimator has next to no variance) and prints the relative error.
pub fn assert_mc(name: &str, s: &Stats, expected: f64) {
    let (m, sigma) = (s.mean(), s.sigma());
    let rel = (m - expected).abs() / expected.abs().max(1e-30);
    eprintln!(
        "{name}: measured {m:.6e}, expected {expected:.6e}, rel err {rel:.2e}, 3 sigma rel {:.2e}",
        3.0 * sigma / expected.abs().max(1e-30)
    );
    assert!((m - expected).abs() <= 3.0 * sigma + 1e-5 * expected.abs(), "{name}: {m} vs {expected} (sigma {sigma})");
}
