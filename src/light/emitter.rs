//! What a light emits: a spectrum shape with a radiometric amount, plus its photometric RGB for
//! RGB mode. Photometric inputs (lm, cd, lx, nit) are converted once here with the spectrum's
//! luminous efficacy.

use glam::Vec3;

use super::ColorQuery;
use crate::spectrum::{SampledSpectrum, Spectrum, rgb_reflectance};

/// Wavelength range of the Mallett-Yuksel basis behind [`rgb_reflectance`], nm.
const RGB_BASIS_NM: (f64, f64) = (380.0, 780.0);

/// Errors in a light's description; each names the light and the field.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LightError {
    /// An amount or a point light's radius is negative, NaN or infinite.
    #[error("{light}: {field} = {value} must be finite and >= 0")]
    BadAmount {
        /// The light's component type, such as `"PointLight"`.
        light: &'static str,
        /// The field that holds the number.
        field: &'static str,
        /// The number given.
        value: f32,
    },
    /// An area light's size is not positive and finite, as given or once scaled by its transform.
    #[error("{light}: {field} = {value} (scaled by the transform: {scaled}) must be finite and > 0")]
    BadSize {
        /// The light's component type, such as `"AreaLight"`.
        light: &'static str,
        /// The field that holds the size.
        field: &'static str,
        /// The size given.
        value: f32,
        /// The size in world space.
        scaled: f32,
    },
    /// An [`Amount`] measures a quantity this light does not accept (say, lux for a point light).
    #[error("{light}: {field} is given in {given}, expected {expected}")]
    WrongUnit {
        /// The light's component type, such as `"PointLight"`.
        light: &'static str,
        /// The field that holds the amount.
        field: &'static str,
        /// Symbol of the unit given, as [`Amount::unit`].
        given: &'static str,
        /// The units the light accepts, for the message (such as `"lx or W/m^2"`).
        expected: &'static str,
    },
    /// Any other invalid description: an angle out of range, a degenerate shape or transform, a bad
    /// texture or image, a value that overflows f32, an entity without a shape; `msg` says which.
    #[error("{light}: {msg}")]
    Invalid {
        /// The light's component type, such as `"AreaLight"`.
        light: &'static str,
        /// What is wrong.
        msg: String,
    },
}

/// How much light, in a photometric or a radiometric unit. Which units a light accepts is in its
/// component's docs (a point light takes an intensity or a power, a distant light an irradiance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Amount {
    /// Luminous power, lm.
    Lumens(f32),
    /// Radiant power, W.
    Watts(f32),
    /// Luminous intensity, cd (lm/sr).
    Candela(f32),
    /// Radiant intensity, W/sr.
    WattsPerSr(f32),
    /// Illuminance, lx (lm/m^2).
    Lux(f32),
    /// Irradiance, W/m^2.
    WattsPerM2(f32),
    /// Luminance, nit (cd/m^2).
    Nits(f32),
    /// Radiance, W/(m^2 sr).
    WattsPerM2Sr(f32),
}

/// The physical quantity an [`Amount`] measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Total emitted power: lm or W.
    Power,
    /// Power per solid angle: cd or W/sr.
    Intensity,
    /// Power arriving per area: lx or W/m^2.
    Irradiance,
    /// Power per area and solid angle: nit or W/(m^2 sr).
    Radiance,
}

impl Amount {
    /// The number, whatever the unit.
    pub fn value(self) -> f32 {
        match self {
            Self::Lumens(v) | Self::Watts(v) | Self::Candela(v) | Self::WattsPerSr(v) => v,
            Self::Lux(v) | Self::WattsPerM2(v) | Self::Nits(v) | Self::WattsPerM2Sr(v) => v,
        }
    }
    /// What is measured.
    pub fn quantity(self) -> Quantity {
        match self {
            Self::Lumens(_) | Self::Watts(_) => Quantity::Power,
            Self::Candela(_) | Self::WattsPerSr(_) => Quantity::Intensity,
            Self::Lux(_) | Self::WattsPerM2(_) => Quantity::Irradiance,
            Self::Nits(_) | Self::WattsPerM2Sr(_) => Quantity::Radiance,
        }
    }
    /// True for lm, cd, lx and nit.
    pub fn is_photometric(self) -> bool {
        matches!(self, Self::Lumens(_) | Self::Candela(_) | Self::Lux(_) | Self::Nits(_))
    }
    /// The unit's symbol, for messages.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Lumens(_) => "lm",
            Self::Watts(_) => "W",
            Self::Candela(_) => "cd",
            Self::WattsPerSr(_) => "W/sr",
            Self::Lux(_) => "lx",
            Self::WattsPerM2(_) => "W/m^2",
            Self::Nits(_) => "nit",
            Self::WattsPerM2Sr(_) => "W/(m^2 sr)",
        }
    }
    /// The radiometric value (W, W/sr, W/m^2, W/(m^2 sr)) for a spectrum of the given efficacy.
    pub fn radiometric(self, efficacy_lm_per_w: f64) -> f32 {
        if self.is_photometric() {
            crate::spectrum::photometry::radiometric(self.value() as f64, efficacy_lm_per_w) as f32
        } else {
            self.value()
        }
    }
    /// Checks the number is finite and non-negative.
    pub fn validate(self, light: &'static str, field: &'static str) -> Result<Self, LightError> {
        let v = self.value();
        if v.is_finite() && v >= 0.0 { Ok(self) } else { Err(LightError::BadAmount { light, field, value: v }) }
    }
}

/// A radiometric quantity Q (W, W/sr, W/m^2 or W/(m^2 sr), integrated over wavelength) with the
/// spectral shape S: Q(lambda) = `scale` * S(lambda) per nm. `rgb` is the same light as
/// photometric linear sRGB (lm, cd, lx or nit per channel; its Y is the photometric amount).
#[derive(Clone, Debug, PartialEq)]
pub struct Emitter {
    /// Spectral shape S; only its shape matters, `scale` sets the amount.
    pub spectrum: Spectrum,
    /// Multiplies `spectrum.eval(lambda)` to give the quantity per nm.
    pub scale: f32,
    /// Photometric linear sRGB.
    pub rgb: Vec3,
    /// The radiometric quantity integrated over wavelength.
    pub radiometric: f32,
}

impl Emitter {
    /// An emitter of radiometric total `radiometric` with shape `spectrum`.
    pub fn new(spectrum: Spectrum, radiometric: f32) -> Self {
        let SpectrumFacts { integral, efficacy, srgb } = SpectrumFacts::of(&spectrum);
        let scale = if integral > 0.0 { (radiometric as f64 / integral) as f32 } else { 0.0 };
        let rgb = srgb * (radiometric as f64 * efficacy);
        Self { spectrum, scale, rgb: rgb.as_vec3(), radiometric }
    }

    /// An emitter from an amount in any unit of the same quantity.
    pub fn from_amount(spectrum: Spectrum, amount: Amount) -> Self {
        let k = SpectrumFacts::of(&spectrum).efficacy;
        Self::new(spectrum, amount.radiometric(k))
    }

    /// A black emitter.
    pub fn black() -> Self {
        Self { spectrum: Spectrum::Constant(0.0), scale: 0.0, rgb: Vec3::ZERO, radiometric: 0.0 }
    }

    /// The same emitter with its amount multiplied by `s`.
    pub fn scaled(&self, s: f32) -> Self {
        Self {
            spectrum: self.spectrum.clone(),
            scale: self.scale * s,
            rgb: self.rgb * s,
            radiometric: self.radiometric * s,
        }
    }

    /// The emitted quantity in the query's colour mode.
    pub fn eval(&self, query: ColorQuery) -> SampledSpectrum {
        match query {
            ColorQuery::Rgb => SampledSpectrum([self.rgb.x, self.rgb.y, self.rgb.z, 0.0]),
            ColorQuery::Spectral(w) => w.eval(&self.spectrum).scale(self.scale),
        }
    }

    /// The emitted quantity tinted by a linear-sRGB texture value: multiplied per channel in RGB
    /// mode, by the tint's reflectance spectrum (Mallett-Yuksel basis) in spectral mode.
    pub fn eval_tinted(&self, query: ColorQuery, tint: Vec3) -> SampledSpectrum {
        match query {
            ColorQuery::Rgb => {
                let c = self.rgb * tint;
                SampledSpectrum([c.x, c.y, c.z, 0.0])
            }
            ColorQuery::Spectral(w) => {
                let t = [tint.x as f64, tint.y as f64, tint.z as f64];
                SampledSpectrum(std::array::from_fn(|i| {
                    let l = w.lambda[i] as f64;
                    // The basis ends at 380-780 nm (zero beyond); hold its end values so a white tint
                    // keeps every sampled wavelength (360-830 nm).
                    let tint = rgb_reflectance(t, l.clamp(RGB_BASIS_NM.0, RGB_BASIS_NM.1));
                    (self.spectrum.eval(l) * tint) as f32 * self.scale
                }))
            }
        }
    }

    /// Luminance-like weight of the emitter (photometric Y), for importance.
    pub fn luminous(&self) -> f32 {
        self.rgb.dot(crate::scene::image::LUMINANCE_WEIGHTS)
    }
}

/// What converting a spectrum needs: its integral, efficacy and normalised sRGB. Computing them
/// integrates over ~500 wavelengths, so they are memoised: lights that move or change their
/// amount but not their spectrum (the common case in a game loop) reuse them.
#[derive(Clone, Copy)]
struct SpectrumFacts {
    integral: f64,
    efficacy: f64,
    srgb: glam::DVec3,
}

impl SpectrumFacts {
    fn of(spectrum: &Spectrum) -> Self {
        use std::collections::HashMap;
        use std::sync::{LazyLock, Mutex};
        // Keyed by the spectrum's parameters; tables by the address of their Arc, which the cache
        // keeps alive so the address cannot be reused.
        static CACHE: LazyLock<Mutex<HashMap<Vec<u64>, (Spectrum, SpectrumFacts)>>> = LazyLock::new(Default::default);
        const MAX_ENTRIES: usize = 4096;
        let key = spectrum_key(spectrum);
        if let Some((_, facts)) = CACHE.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return *facts;
        }
        let facts = Self {
            integral: spectrum.integral(),
            efficacy: spectrum.luminous_efficacy(),
            srgb: spectrum.srgb_normalized(),
        };
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= MAX_ENTRIES {
            cache.clear();
        }
        cache.insert(key, (spectrum.clone(), facts));
        facts
    }
}

fn spectrum_key(s: &Spectrum) -> Vec<u64> {
    match s {
        Spectrum::Constant(c) => vec![0, c.to_bits()],
        Spectrum::Blackbody { temperature_k } => vec![1, temperature_k.to_bits()],
        Spectrum::Graybody { temperature_k, emissivity } => vec![2, temperature_k.to_bits(), emissivity.to_bits()],
        Spectrum::Emitter { temperature_k, emissivity } => {
            vec![3, temperature_k.to_bits(), std::sync::Arc::as_ptr(emissivity) as u64]
        }
        Spectrum::IlluminantA => vec![4],
        Spectrum::Tabulated(t) => vec![5, std::sync::Arc::as_ptr(t) as u64],
        Spectrum::Rgb { rgb } => vec![6, rgb[0].to_bits(), rgb[1].to_bits(), rgb[2].to_bits()],
    }
}

/// Checks a user-facing amount has the expected quantity and a valid value.
pub fn check_amount(
    amount: Amount,
    light: &'static str,
    field: &'static str,
    allowed: &[Quantity],
    expected: &'static str,
) -> Result<Amount, LightError> {
    if !allowed.contains(&amount.quantity()) {
        return Err(LightError::WrongUnit { light, field, given: amount.unit(), expected });
    }
    amount.validate(light, field)
}
