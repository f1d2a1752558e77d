//! Emission spectra: Planck and Kirchhoff emitters, CIE tables and illuminants, colour spaces,
//! photometry, colour temperature and sampled wavelengths for spectral rendering.
//!
//! A [`Spectrum`] is a shape over wavelength in nm. Lights pair one with an amount (watts or a
//! photometric unit) and convert once with [`Spectrum::luminous_efficacy`].

pub mod cct;
pub mod cie;
pub mod color;
pub mod lab;
mod parse;
pub mod photometry;
pub mod planck;
pub mod sampled;
pub mod summary;
pub mod tabulated;

use std::sync::{Arc, LazyLock};

use glam::DVec3;

pub use cie::{CIE_1931, CIE_1964, Cmf};
pub use photometry::{K_M, luminous_efficacy_of};
pub use sampled::{N_SPECTRUM_SAMPLES, SampledSpectrum, SampledWavelengths};
pub use summary::SpectrumSummary;
pub use tabulated::TabulatedSpectrum;

/// What can go wrong building a spectrum. Messages say what was given and what is accepted.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SpectrumError {
    /// `range` as written in maths: "[0, 1]", "(0, 1000000000]".
    #[error("{what} = {value} is outside {range}")]
    OutOfRange {
        /// The parameter, with its unit: `"temperature (K)"`, `"emissivity"`.
        what: String,
        /// The value given.
        value: f64,
        /// The accepted range.
        range: String,
    },
    /// A table's wavelengths and values do not match in number, it has fewer than two rows, a
    /// wavelength is not positive or not increasing, or a value is not finite.
    #[error("{what}: {msg}")]
    BadTable {
        /// The table's source (a file path, a built-in name).
        what: String,
        /// What is wrong, with the row.
        msg: String,
    },
    /// A CSV row has the wrong number of fields or a field that is not a number, or there are no
    /// data rows.
    #[error("{what}, line {line}: {msg}")]
    BadCsv {
        /// The CSV's source (a file path).
        what: String,
        /// 1-based line number; 0 when the whole file is at fault (no data rows).
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A specification is not one of the accepted forms, names no known illuminant, or has a
    /// number that does not parse.
    #[error("unknown spectrum '{given}'; accepted: {accepted}")]
    Unknown {
        /// The specification given.
        given: String,
        /// The accepted forms or names.
        accepted: String,
    },
    /// A spectrum file could not be read.
    #[error("{what}: cannot read: {msg}")]
    Io {
        /// The file's path.
        what: String,
        /// The system's error message.
        msg: String,
    },
}

impl SpectrumError {
    /// `value` of `what` is outside the closed range `[lo, hi]`.
    pub fn out_of_range(what: &str, value: f64, lo: f64, hi: f64) -> Self {
        Self::OutOfRange { what: what.into(), value, range: format!("[{lo}, {hi}]") }
    }
}

/// A spectral distribution over wavelength (nm): an emitter's shape, or an emissivity.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength (CIE illuminant E when 1). Integrated over 360-830 nm.
    Constant(f64),
    /// Planck's law at a temperature (K), normalised so its peak (at Wien's lambda_max) is 1.
    Blackbody {
        /// Temperature, K.
        temperature_k: f64,
    },
    /// Kirchhoff's law with a constant emissivity in [0, 1]: a grey body, `emissivity` times the
    /// normalised blackbody.
    Graybody {
        /// Temperature, K.
        temperature_k: f64,
        /// Emissivity at every wavelength, in [0, 1].
        emissivity: f64,
    },
    /// Kirchhoff's law with a tabulated emissivity (0 outside its table) times the normalised
    /// blackbody.
    Emitter {
        /// Temperature, K.
        temperature_k: f64,
        /// Emissivity over wavelength (nm), clamped to [0, 1] where evaluated.
        emissivity: Arc<TabulatedSpectrum>,
    },
    /// CIE illuminant A from its defining formula, 300-830 nm, 100 at 560 nm.
    IlluminantA,
    /// A table, linearly interpolated (CIE illuminants, daylight, measured data).
    Tabulated(Arc<TabulatedSpectrum>),
    /// An emitter whose colour is a linear-sRGB triple: the Mallett-Yuksel (2019) basis spectra
    /// weighted by `rgb`, times the D65 illuminant normalised to 1 at 560 nm, so (1, 1, 1) is D65.
    Rgb {
        /// Linear-sRGB weights of the red, green and blue basis spectra.
        rgb: [f64; 3],
    },
}

/// Range over which analytic, unbounded spectra (constants) are integrated: the CMF range.
const CONSTANT_RANGE_NM: (f64, f64) = (cie::CMF_MIN_NM, cie::CMF_MAX_NM);

impl Spectrum {
    /// A normalised blackbody; errors for T outside (0, 1e9] K or NaN.
    pub fn blackbody(temperature_k: f64) -> Result<Self, SpectrumError> {
        check_temperature(temperature_k)?;
        Ok(Self::Blackbody { temperature_k })
    }

    /// A grey body (Kirchhoff's law with constant emissivity in [0, 1]).
    pub fn graybody(temperature_k: f64, emissivity: f64) -> Result<Self, SpectrumError> {
        check_temperature(temperature_k)?;
        if !(0.0..=1.0).contains(&emissivity) {
            return Err(SpectrumError::out_of_range("emissivity", emissivity, 0.0, 1.0));
        }
        Ok(Self::Graybody { temperature_k, emissivity })
    }

    /// The CIE standard illuminant called `name` (see [`cie::ILLUMINANT_NAMES`]).
    pub fn illuminant(name: &str) -> Result<Self, SpectrumError> {
        match cie::canonical_illuminant_name(name) {
            Some("A") => Ok(Self::IlluminantA),
            Some("E") => Ok(Self::Constant(1.0)),
            Some(key) => Ok(Self::Tabulated(cie::tabulated_illuminant(key).expect("every listed table exists"))),
            None => Err(SpectrumError::Unknown {
                given: name.to_string(),
                accepted: format!("illuminant:<{}>", cie::ILLUMINANT_NAMES.join("|")),
            }),
        }
    }

    /// CIE daylight at a correlated colour temperature in 4000-25000 K.
    pub fn daylight(cct_k: f64) -> Result<Self, SpectrumError> {
        Ok(Self::Tabulated(Arc::new(cie::daylight(cct_k)?)))
    }

    /// The D65 illuminant (the white of linear sRGB).
    pub fn d65() -> Self {
        Self::illuminant("D65").expect("D65 is compiled in")
    }

    /// Value at `lambda_nm`.
    pub fn eval(&self, lambda_nm: f64) -> f64 {
        match self {
            Self::Constant(c) => *c,
            Self::Blackbody { temperature_k } => planck::planck_normalized(lambda_nm, *temperature_k),
            Self::Graybody { temperature_k, emissivity } => {
                emissivity * planck::planck_normalized(lambda_nm, *temperature_k)
            }
            Self::Emitter { temperature_k, emissivity } => {
                emissivity.eval(lambda_nm).clamp(0.0, 1.0) * planck::planck_normalized(lambda_nm, *temperature_k)
            }
            Self::IlluminantA => cie::illuminant_a(lambda_nm),
            Self::Tabulated(t) => t.eval(lambda_nm),
            Self::Rgb { rgb } => rgb_illuminant(*rgb, lambda_nm),
        }
    }

    /// Wavelength range (nm) outside which the spectrum is zero, or None if it extends over all
    /// wavelengths (blackbodies, constants).
    pub fn support_nm(&self) -> Option<(f64, f64)> {
        match self {
            Self::Constant(_) | Self::Blackbody { .. } | Self::Graybody { .. } => None,
            Self::Emitter { emissivity: t, .. } | Self::Tabulated(t) => Some((t.min_nm(), t.max_nm())),
            Self::IlluminantA => Some((300.0, 830.0)),
            Self::Rgb { .. } => Some((RGB_BASIS.min_nm(), RGB_BASIS.max_nm())),
        }
    }

    /// Integral over wavelength, in (value x nm): over all wavelengths for blackbodies (closed
    /// form, sigma T^4 / pi), over the table's range for tables, over 360-830 nm for constants.
    pub fn integral(&self) -> f64 {
        match self {
            Self::Constant(c) => c * (CONSTANT_RANGE_NM.1 - CONSTANT_RANGE_NM.0),
            Self::Blackbody { temperature_k: t } => blackbody_integral_normalized(*t),
            Self::Graybody { temperature_k: t, emissivity } => emissivity * blackbody_integral_normalized(*t),
            Self::Tabulated(t) => t.integrate_weighted(|_| 1.0),
            Self::Emitter { emissivity: t, .. } => trapezoid(t.min_nm(), t.max_nm(), t.wavelengths(), |l| self.eval(l)),
            _ => {
                let (lo, hi) = self.support_nm().expect("bounded");
                trapezoid(lo, hi, &[], |l| self.eval(l))
            }
        }
    }

    /// Tristimulus integral (integral of S times x-bar, y-bar, z-bar), in (value x nm): trapezoid
    /// rule on the 1 nm grid over 360-830 nm plus the spectrum's own table samples, so tables are
    /// linearly interpolated; this reproduces the CIE's published chromaticities (F11 to 1e-5).
    pub fn xyz_integral(&self, cmf: &Cmf) -> DVec3 {
        let (lo, hi) = self.support_nm().unwrap_or(CONSTANT_RANGE_NM);
        let (lo, hi) = (lo.max(cie::CMF_MIN_NM), hi.min(cie::CMF_MAX_NM));
        let table = match self {
            Self::Tabulated(t) | Self::Emitter { emissivity: t, .. } => t.wavelengths(),
            _ => &[],
        };
        trapezoid(lo, hi, table, |l| DVec3::from_array(cmf.eval(l)) * self.eval(l))
    }

    /// XYZ scaled so that Y = 100 (the CIE's relative colorimetry; 2-degree observer).
    pub fn xyz_relative(&self) -> DVec3 {
        let xyz = self.xyz_integral(&CIE_1931);
        if xyz.y > 0.0 { xyz * (100.0 / xyz.y) } else { DVec3::ZERO }
    }

    /// xy chromaticity (2-degree observer).
    pub fn xy(&self) -> [f64; 2] {
        let v = color::xyz_to_xyy(self.xyz_integral(&CIE_1931));
        [v.x, v.y]
    }

    /// Luminous efficacy of radiation, lm/W: 683 * integral(V S) / integral(S).
    pub fn luminous_efficacy(&self) -> f64 {
        luminous_efficacy_of(self.xyz_integral(&CIE_1931).y, self.integral())
    }

    /// Linear sRGB (Rec. 709, D65) of the spectrum's colour, scaled so its luminance Y is 1.
    pub fn srgb_normalized(&self) -> DVec3 {
        color::xyz_to_srgb(self.xyz_relative() / 100.0)
    }
}

fn check_temperature(t: f64) -> Result<(), SpectrumError> {
    if t > 0.0 && t <= 1e9 {
        Ok(())
    } else {
        Err(SpectrumError::OutOfRange { what: "temperature (K)".into(), value: t, range: "(0, 1000000000]".into() })
    }
}

/// Integral over all wavelengths of the peak-normalised blackbody, nm.
fn blackbody_integral_normalized(t_k: f64) -> f64 {
    let peak = planck::planck(planck::wien_peak_nm(t_k), t_k);
    if peak > 0.0 { planck::blackbody_radiance_total(t_k) / peak } else { 0.0 }
}

/// Trapezoid rule over [lo, hi] with nodes at every integer nm, at `extra` nodes inside the range
/// (a table's samples) and at both ends.
fn trapezoid<T>(lo: f64, hi: f64, extra: &[f64], f: impl Fn(f64) -> T) -> T
where
    T: Copy + Default + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    if !(hi > lo) {
        return T::default();
    }
    let mut nodes: Vec<f64> = (lo.ceil() as i64..=hi.floor() as i64).map(|n| n as f64).collect();
    nodes.extend(extra.iter().copied().filter(|l| (lo..=hi).contains(l)));
    nodes.extend([lo, hi]);
    nodes.sort_by(f64::total_cmp);
    nodes.dedup();
    let values: Vec<T> = nodes.iter().map(|&l| f(l)).collect();
    let mut sum = T::default();
    for i in 1..nodes.len() {
        let w = 0.5 * (nodes[i] - nodes[i - 1]);
        sum = sum + (values[i - 1] + values[i]) * w;
    }
    sum
}

/// The Mallett-Yuksel sRGB basis, 380-780 nm at 5 nm (columns r, g, b).
struct RgbBasis {
    rgb: [TabulatedSpectrum; 3],
}

impl RgbBasis {
    fn min_nm(&self) -> f64 {
        self.rgb[0].min_nm()
    }
    fn max_nm(&self) -> f64 {
        self.rgb[0].max_nm()
    }
}

static RGB_BASIS: LazyLock<RgbBasis> = LazyLock::new(|| {
    let text = include_str!("data/srgb_basis_mallett2019.csv");
    let rows = tabulated::parse_csv_columns(text, 4, "srgb_basis_mallett2019.csv").expect("valid table");
    let nm: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let rgb = [1, 2, 3]
        .map(|k| TabulatedSpectrum::new(nm.clone(), rows.iter().map(|r| r[k]).collect(), "rgb basis").expect("valid"));
    RgbBasis { rgb }
});

static D65_UNIT: LazyLock<Arc<TabulatedSpectrum>> = LazyLock::new(|| {
    let d65 = cie::tabulated_illuminant("D65").expect("compiled in");
    let s = 1.0 / d65.eval(560.0);
    Arc::new(
        TabulatedSpectrum::new(d65.wavelengths().to_vec(), d65.values().iter().map(|v| v * s).collect(), "D65")
            .expect("valid"),
    )
});

/// The reflectance spectrum of a linear-sRGB albedo at `lambda_nm` (Mallett & Yuksel 2019: the
/// basis sums to 1, so (1, 1, 1) is a perfect white and values stay in [0, 1] for albedos in it).
pub fn rgb_reflectance(rgb: [f64; 3], lambda_nm: f64) -> f64 {
    let b = &RGB_BASIS.rgb;
    rgb[0] * b[0].eval(lambda_nm) + rgb[1] * b[1].eval(lambda_nm) + rgb[2] * b[2].eval(lambda_nm)
}

fn rgb_illuminant(rgb: [f64; 3], lambda_nm: f64) -> f64 {
    rgb_reflectance(rgb, lambda_nm) * D65_UNIT.eval(lambda_nm)
}
