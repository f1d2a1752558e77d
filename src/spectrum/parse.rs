//! Spectrum specifications as the CLI and scene files write them.

use std::sync::Arc;

use super::{Spectrum, SpectrumError, TabulatedSpectrum, cie};

/// What [`Spectrum::parse`] accepts, for error messages.
pub const SPEC_FORMS: &str = "blackbody:<K>, graybody:<K>:<emissivity>, illuminant:<name>, daylight:<K> (4000-25000), \
    or a CSV file of nm,value rows";

impl Spectrum {
    /// Parses `blackbody:<K>`, `graybody:<K>:<emissivity>`, `illuminant:<name>`, `daylight:<K>`,
    /// or a path to a CSV file of `nm,value` rows.
    pub fn parse(spec: &str) -> Result<Self, SpectrumError> {
        let number = |s: &str, what: &str| {
            s.trim().parse::<f64>().map_err(|_| SpectrumError::Unknown {
                given: spec.to_string(),
                accepted: format!("{what} must be a number; forms: {SPEC_FORMS}"),
            })
        };
        let (kind, rest) = spec.split_once(':').unwrap_or((spec, ""));
        match kind.to_ascii_lowercase().as_str() {
            "blackbody" => Self::blackbody(number(rest, "temperature")?),
            "graybody" | "greybody" => {
                let (t, eps) = rest.split_once(':').ok_or_else(|| SpectrumError::Unknown {
                    given: spec.to_string(),
                    accepted: "graybody:<K>:<emissivity>".into(),
                })?;
                Self::graybody(number(t, "temperature")?, number(eps, "emissivity")?)
            }
            "illuminant" => Self::illuminant(rest),
            "daylight" => Self::daylight(number(rest, "temperature")?),
            _ if spec.to_ascii_lowercase().ends_with(".csv") => Self::from_csv_file(std::path::Path::new(spec)),
            _ => Err(SpectrumError::Unknown {
                given: spec.to_string(),
                accepted: format!("{SPEC_FORMS}; illuminants: {}", cie::ILLUMINANT_NAMES.join(", ")),
            }),
        }
    }

    /// Reads a CSV file of `nm,value` rows (a header row and `#` comments are allowed).
    pub fn from_csv_file(path: &std::path::Path) -> Result<Self, SpectrumError> {
        let what = path.display().to_string();
        let text =
            std::fs::read_to_string(path).map_err(|e| SpectrumError::Io { what: what.clone(), msg: e.to_string() })?;
        Ok(Self::Tabulated(Arc::new(TabulatedSpectrum::parse_csv(&text, &what)?)))
    }
}
