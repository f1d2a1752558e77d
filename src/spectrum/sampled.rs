//! A few wavelengths per path for spectral rendering (hero-wavelength style), importance-sampled
//! over the visible range, and their conversion to XYZ.

use glam::Vec3;

use super::{CIE_1931, K_M, Spectrum};

/// Wavelengths carried per sample.
pub const N_SPECTRUM_SAMPLES: usize = 4;
/// Visible range that wavelengths are sampled in, nm.
pub const VISIBLE_NM: (f32, f32) = (360.0, 830.0);

/// `N_SPECTRUM_SAMPLES` wavelengths (nm) and the pdf (1/nm) each was drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    /// The wavelengths, nm.
    pub lambda: [f32; N_SPECTRUM_SAMPLES],
    /// Density each wavelength was drawn with, 1/nm.
    pub pdf: [f32; N_SPECTRUM_SAMPLES],
}

/// Values of a spectrum at the `SampledWavelengths` of the same sample.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SampledSpectrum(pub [f32; N_SPECTRUM_SAMPLES]);

/// Draws a wavelength from pbrt-v4's visible-light density p(l) ~ 1/cosh^2(0.0072 (l - 538)),
/// which follows the sum of the CMFs, truncated to 360-830 nm.
pub fn sample_visible_wavelength(u: f32) -> f32 {
    538.0 - 138.888_89 * (0.856_910_6 - 1.827_502 * u).atanh()
}

/// Density of [`sample_visible_wavelength`], 1/nm; 0 outside 360-830 nm.
// The normalisation as pbrt-v4 prints it (VisibleWavelengthsPDF).
#[allow(clippy::excessive_precision)]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(VISIBLE_NM.0..=VISIBLE_NM.1).contains(&lambda) {
        return 0.0;
    }
    0.003_939_804_2 / (0.0072 * (lambda - 538.0)).cosh().powi(2)
}

impl SampledWavelengths {
    /// Stratified hero sampling: one uniform `u` picks the first wavelength's stratum offset, the
    /// others are shifted by 1/N in sample space.
    pub fn sample_visible(u: f32) -> Self {
        let mut lambda = [0.0; N_SPECTRUM_SAMPLES];
        let mut pdf = [0.0; N_SPECTRUM_SAMPLES];
        for i in 0..N_SPECTRUM_SAMPLES {
            let up = (u + i as f32 / N_SPECTRUM_SAMPLES as f32).fract();
            lambda[i] = sample_visible_wavelength(up);
            pdf[i] = visible_wavelength_pdf(lambda[i]);
        }
        Self { lambda, pdf }
    }

    /// Evaluates `spectrum` at these wavelengths.
    pub fn eval(&self, spectrum: &Spectrum) -> SampledSpectrum {
        SampledSpectrum(self.lambda.map(|l| spectrum.eval(l as f64) as f32))
    }

    /// Photometric XYZ (Y in cd/m^2 when `radiance` is spectral radiance in W/(m^2 sr nm)):
    /// the Monte Carlo estimate of 683 * integral(L cmf) over these wavelengths.
    pub fn to_xyz(&self, radiance: SampledSpectrum) -> Vec3 {
        let mut xyz = Vec3::ZERO;
        for i in 0..N_SPECTRUM_SAMPLES {
            if self.pdf[i] > 0.0 {
                let cmf = CIE_1931.eval(self.lambda[i] as f64).map(|c| c as f32);
                xyz += Vec3::from_array(cmf) * (radiance.0[i] / self.pdf[i]);
            }
        }
        xyz * (K_M as f32 / N_SPECTRUM_SAMPLES as f32)
    }
}

// Named `mul` and `add` rather than operator impls, so hot loops read as the lane arithmetic they are.
#[allow(clippy::should_implement_trait)]
impl SampledSpectrum {
    /// The same value at every wavelength.
    pub const fn splat(v: f32) -> Self {
        Self([v; N_SPECTRUM_SAMPLES])
    }
    /// Component-wise product.
    pub fn mul(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        // Lanes spelled out: `array::from_fn` was left as a loop in hot paths.
        Self([a[0] * b[0], a[1] * b[1], a[2] * b[2], a[3] * b[3]])
    }
    /// Multiplied by a scalar.
    pub fn scale(self, s: f32) -> Self {
        let a = self.0;
        Self([a[0] * s, a[1] * s, a[2] * s, a[3] * s])
    }
    /// Component-wise sum.
    pub fn add(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        Self([a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]])
    }
    /// True when every value is finite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
}
