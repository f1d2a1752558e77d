//! The colorimetric and photometric summary of a spectrum that `kelvin spectrum` prints.

use serde::Serialize;

use super::{Spectrum, cct, color, planck};

/// XYZ (Y = 100), chromaticities, colour temperature, efficacy and, for black and grey bodies,
/// exitance and peak wavelength.
#[derive(Clone, Debug, Serialize)]
pub struct SpectrumSummary {
    /// CIE 1931 XYZ normalised to Y = 100.
    pub xyz: [f64; 3],
    /// CIE 1931 xy chromaticity.
    pub xy: [f64; 2],
    /// CIE 1976 u'v' chromaticity.
    pub uv: [f64; 2],
    /// Linear sRGB (D65) with luminance Y = 1; may be negative outside the sRGB gamut.
    pub srgb_linear: [f64; 3],
    /// Correlated colour temperature, K (Ohno 2013); absent outside 1000-100000 K.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cct_k: Option<f64>,
    /// Distance from the Planckian locus in CIE 1960 uv, positive above it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duv: Option<f64>,
    /// Luminous efficacy of radiation, lm/W.
    pub efficacy_lm_per_w: f64,
    /// Radiant exitance of the (un-normalised) emitter, W/m^2: eps sigma T^4.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exitance_w_per_m2: Option<f64>,
    /// Wien's peak wavelength, nm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_max_nm: Option<f64>,
}

impl SpectrumSummary {
    /// Computes the summary of `spectrum`.
    pub fn of(spectrum: &Spectrum) -> Self {
        let xyz = spectrum.xyz_relative();
        let xy = spectrum.xy();
        let (cct_k, duv) = match cct::cct_duv_from_xy(xy) {
            Ok((t, d)) => (Some(t), Some(d)),
            Err(_) => (None, None),
        };
        let (exitance, lambda_max) = match spectrum {
            Spectrum::Blackbody { temperature_k: t } => {
                (Some(planck::blackbody_exitance(*t)), Some(planck::wien_peak_nm(*t)))
            }
            Spectrum::Graybody { temperature_k: t, emissivity } => {
                (Some(emissivity * planck::blackbody_exitance(*t)), Some(planck::wien_peak_nm(*t)))
            }
            _ => (None, None),
        };
        Self {
            xyz: xyz.to_array(),
            xy,
            uv: color::xy_to_uv_prime(xy),
            srgb_linear: color::xyz_to_srgb(xyz / 100.0).to_array(),
            cct_k,
            duv,
            efficacy_lm_per_w: spectrum.luminous_efficacy(),
            exitance_w_per_m2: exitance,
            lambda_max_nm: lambda_max,
        }
    }
}

impl std::fmt::Display for SpectrumSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.xyz;
        writeln!(f, "XYZ (Y=100)        {x:.4} {y:.4} {z:.4}")?;
        writeln!(f, "xy                 {:.5} {:.5}", self.xy[0], self.xy[1])?;
        writeln!(f, "u'v'               {:.5} {:.5}", self.uv[0], self.uv[1])?;
        let [r, g, b] = self.srgb_linear;
        writeln!(f, "linear sRGB (Y=1)  {r:.5} {g:.5} {b:.5}")?;
        match (self.cct_k, self.duv) {
            (Some(t), Some(d)) => writeln!(f, "CCT                {t:.1} K   Duv {d:+.5}")?,
            _ => writeln!(f, "CCT                outside 1000-100000 K")?,
        }
        writeln!(f, "luminous efficacy  {:.3} lm/W", self.efficacy_lm_per_w)?;
        if let Some(m) = self.exitance_w_per_m2 {
            writeln!(f, "radiant exitance   {m:.6e} W/m^2")?;
        }
        if let Some(l) = self.lambda_max_nm {
            writeln!(f, "lambda_max         {l:.3} nm")?;
        }
        Ok(())
    }
}
