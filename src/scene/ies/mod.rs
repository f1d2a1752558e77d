//! IES LM-63 photometric files (1986, 1991, 1995, 2002, 2019): parsing, the candela distribution with
//! its symmetries, total flux, beam angles and an equal-area image for goniometric lights.
//!
//! # Frame
//!
//! Directions are given in the light's local frame (right-handed, like the rest of kelvin):
//!
//! - **Type C** (architectural and road luminaires; what pbrt-v4 and Mitsuba read): local **-Z**, the
//!   light's forward like a spot light or a glTF light, is photometric nadir (vertical angle 0, the
//!   direction a downlight points) and +Z is the zenith (180). Horizontal angle 0 (the C0 plane, the
//!   luminaire's length in LM-63) is local **+X** and 90 is local **+Y** (counter-clockwise seen from
//!   above, as LM-63 measures type C).
//! - **Types A and B** (automotive lamps and floodlights): LM-63 does not draw these, so here is the
//!   reading used. LM-63-1995 puts the polar axis of type B along the luminaire's width and that of
//!   type A along its length, both with the 0-180 photometric plane through the luminaire's vertical
//!   axis; LM-63-2002 says the direction at H = 0, V = 0 is photometric zero for type B, H = 0, V = 90 is
//!   photometric horizontal, and that B planes share a horizontal axis. So, keeping type C's axes
//!   (length +X, width +Y, nadir -Z): the polar axis is **+Y for type B** and **+X for type A**, and
//!   both are horizontal. Horizontal angle H names a half-plane through the polar axis (turning
//!   clockwise seen from the polar axis' positive end, as LM-63 says for A and B) and vertical angle
//!   V is the latitude in that half-plane, positive toward the polar axis. H = 0, V = 0 is local -Z,
//!   the light's forward, so a floodlight aims where a spot light would:
//!   - type B: `d = (cos V sin H, sin V, -cos V cos H)`;
//!   - type A: `d = (sin V, -cos V sin H, -cos V cos H)`.
//!
//!   A and B data cover H and V in -90..90, the hemisphere around -Z; the back hemisphere is dark.
//!
//! Values are candelas with the file's candela multiplier and ballast factor applied (and, for
//! 1986/1991 files, the ballast-lamp photometric factor, as Radiance's ies2rad does). Between the
//! measured angles the distribution is bilinear in (vertical, horizontal) angle; outside the measured
//! vertical range it is zero.

mod parse;
mod profile;
mod summary;

use std::path::Path;

pub use summary::{IesSummary, plane_names};

/// Largest number of vertical or horizontal angles accepted (real files have at most a few hundred).
pub const MAX_ANGLES: usize = 100_000;

/// What can go wrong reading an IES file. Every message names the file (`what`) and, for content
/// errors, the 1-based line where reading stopped and what was expected there.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum IesError {
    /// The file could not be read.
    #[error("{what}: cannot read: {msg}")]
    Io {
        /// The file.
        what: String,
        /// The operating system's message.
        msg: String,
    },
    /// The file ends before the TILT line, or before all the numbers its counts declare.
    #[error("{what}, line {line}: the file ends early; expected {expected}")]
    Truncated {
        /// The file.
        what: String,
        /// The last line of the file.
        line: usize,
        /// What was still missing (with the declared angle counts when they are known).
        expected: String,
    },
    /// A field after the TILT line does not parse as a number.
    #[error("{what}, line {line}: expected {expected}, found '{found}'")]
    NotANumber {
        /// The file.
        what: String,
        /// 1-based line of the field.
        line: usize,
        /// The field that was expected there.
        expected: String,
        /// The text found (shortened if long).
        found: String,
    },
    /// A number is infinite or NaN.
    #[error("{what}, line {line}: expected a finite number for {expected}, found '{found}'")]
    NotFinite {
        /// The file.
        what: String,
        /// 1-based line of the number.
        line: usize,
        /// The field that was expected there.
        expected: String,
        /// The text found.
        found: String,
    },
    /// A header value is out of its allowed range: an empty `TILT=`, a units type other than 1 or 2,
    /// lumens neither positive nor -1, a candela multiplier or ballast factor not positive, or a
    /// negative tilt factor.
    #[error("{what}, line {line}: {msg}")]
    BadValue {
        /// The file.
        what: String,
        /// 1-based line of the value.
        line: usize,
        /// Which value, and what it must be.
        msg: String,
    },
    /// The photometric type is not 1 (C), 2 (B) or 3 (A).
    #[error("{what}, line {line}: unknown photometric type {found} (expected 1 = C, 2 = B or 3 = A)")]
    UnknownPhotometricType {
        /// The file.
        what: String,
        /// 1-based line of the type.
        line: usize,
        /// The number found.
        found: String,
    },
    /// A count (lamps, angles, tilt pairs, tilt geometry) is not a whole number in its range (at most
    /// [`MAX_ANGLES`] angles), or more tilt pairs are declared than numbers follow.
    #[error("{what}, line {line}: {msg}")]
    BadCount {
        /// The file.
        what: String,
        /// 1-based line of the count.
        line: usize,
        /// Which count, and what it must be.
        msg: String,
    },
    /// A list of angles does not strictly increase.
    #[error("{what}, line {line}: {which} angles must increase, but {value} follows {previous}")]
    NonMonotonic {
        /// The file.
        what: String,
        /// 1-based line of the offending angle.
        line: usize,
        /// `"vertical"`, `"horizontal"` or `"tilt"`.
        which: String,
        /// The angle before, degrees.
        previous: f64,
        /// The offending angle, degrees.
        value: f64,
    },
    /// A candela value is negative.
    #[error("{what}, line {line}: candela values must not be negative, found {value}")]
    NegativeCandela {
        /// The file.
        what: String,
        /// 1-based line of the value.
        line: usize,
        /// The value as written (cd, before the multiplier).
        value: f64,
    },
    /// The angle ranges are outside what LM-63 allows for the photometric type (e.g. type C vertical
    /// angles beyond 0..180, or horizontal ones not 0-90, 0-180, 90-270 or 0-360).
    #[error("{what}, line {line}: {msg}")]
    UnsupportedAngles {
        /// The file.
        what: String,
        /// 1-based line of the offending angle list.
        line: usize,
        /// Which range, and what is allowed.
        msg: String,
    },
    /// Numbers follow the last candela value (usually wrong angle counts).
    #[error("{what}, line {line}: found '{found}' after the last candela value; {msg}")]
    TrailingData {
        /// The file.
        what: String,
        /// 1-based line of the first extra value.
        line: usize,
        /// The first extra value (shortened if long).
        found: String,
        /// The declared counts and how many values are left over.
        msg: String,
    },
}

impl IesError {
    /// The 1-based line the error points at (None for I/O errors).
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Io { .. } => None,
            Self::Truncated { line, .. }
            | Self::NotANumber { line, .. }
            | Self::NotFinite { line, .. }
            | Self::BadValue { line, .. }
            | Self::UnknownPhotometricType { line, .. }
            | Self::BadCount { line, .. }
            | Self::NonMonotonic { line, .. }
            | Self::NegativeCandela { line, .. }
            | Self::UnsupportedAngles { line, .. }
            | Self::TrailingData { line, .. } => Some(*line),
        }
    }
}

/// Which revision of LM-63 the file follows, from its first line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum IesVersion {
    /// No version line: free-form label lines up to `TILT=`.
    Lm63_1986,
    /// `IESNA91`.
    Lm63_1991,
    /// `IESNA:LM-63-1995`.
    Lm63_1995,
    /// `IESNA:LM-63-2002`.
    Lm63_2002,
    /// `IES:LM-63-2019`.
    Lm63_2019,
}

impl std::fmt::Display for IesVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Lm63_1986 => "LM-63-1986",
            Self::Lm63_1991 => "LM-63-1991",
            Self::Lm63_1995 => "LM-63-1995",
            Self::Lm63_2002 => "LM-63-2002",
            Self::Lm63_2019 => "LM-63-2019",
        })
    }
}

/// The goniometer's coordinate system (LM-63 photometric type 1, 2 or 3); see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotometricType {
    /// Type 1: vertical polar axis, vertical angle from nadir, horizontal angle around it.
    C,
    /// Type 2 (floodlights): horizontal polar axis along the luminaire's width.
    B,
    /// Type 3 (automotive): horizontal polar axis along the luminaire's length.
    A,
}

impl std::fmt::Display for PhotometricType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::C => "C",
            Self::B => "B",
            Self::A => "A",
        })
    }
}

/// Which part of the sphere the file measures and how the rest follows from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// Type C, one horizontal angle: the same in every C plane.
    Rotational,
    /// Type C, horizontal 0-90: mirrored about the C0-C180 and C90-C270 planes.
    Quadrant,
    /// Type C, horizontal 0-180: mirrored about the C0-C180 plane.
    BilateralC0C180,
    /// Type C, horizontal 90-270: mirrored about the C90-C270 plane.
    BilateralC90C270,
    /// No symmetry: type C horizontal 0-360, or types A/B with H and V both from -90.
    Full,
    /// Types A/B, H from 0: mirrored to negative H (laterally symmetric).
    Lateral,
    /// Types A/B, V from 0: mirrored to negative V.
    Vertical,
    /// Types A/B, H and V both from 0: mirrored in both.
    LateralAndVertical,
}

impl std::fmt::Display for Symmetry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Rotational => "rotational (one C plane)",
            Self::Quadrant => "quadrant (C0-C90)",
            Self::BilateralC0C180 => "bilateral about C0-C180",
            Self::BilateralC90C270 => "bilateral about C90-C270",
            Self::Full => "none (full sphere data)",
            Self::Lateral => "lateral (H mirrored)",
            Self::Vertical => "vertical (V mirrored)",
            Self::LateralAndVertical => "lateral and vertical (H and V mirrored)",
        })
    }
}

/// Units of the luminous opening's width, length and height in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    /// Units type 1; converted to metres on reading.
    Feet,
    /// Units type 2.
    Metres,
}

/// Lamp output versus tilt (metal-halide lamps), from the `TILT=` line.
#[derive(Clone, Debug, PartialEq)]
pub enum Tilt {
    /// `TILT=NONE`: output does not depend on how the luminaire is tilted.
    None,
    /// `TILT=INCLUDE`: the table follows in the file.
    Include {
        /// Lamp-to-luminaire geometry: 1 vertical base up or down, 2 horizontal and stays so when tilted
        /// along the 0-180 plane, 3 horizontal and tilts with the luminaire.
        geometry: u8,
        /// Tilt angles, degrees, increasing.
        angles_deg: Vec<f64>,
        /// Output multiplying factor at each angle.
        factors: Vec<f64>,
    },
    /// `TILT=<file>`: a separate tilt file, which is not read (see [`IesProfile::warnings`]).
    File(String),
}

/// The measured grid after validation: angles in degrees, strictly increasing; candela in cd,
/// horizontal-major (`cd[h * v_deg.len() + v]`), all finite and non-negative.
#[derive(Clone, Debug, PartialEq)]
struct Grid {
    kind: PhotometricType,
    symmetry: Symmetry,
    v_deg: Vec<f64>,
    h_deg: Vec<f64>,
    cd: Vec<f64>,
}

/// A parsed IES file: header, lamp data and the candela distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct IesProfile {
    /// LM-63 revision from the first line.
    pub version: IesVersion,
    /// `[KEYWORD] value` lines in file order; `[MORE]` lines are joined to the previous value with a
    /// newline. 1986-style free-text label lines appear with an empty keyword.
    pub keywords: Vec<(String, String)>,
    /// The `TILT=` section.
    pub tilt: Tilt,
    /// Number of lamps.
    pub lamps: u32,
    /// Rated lumens per lamp; None for absolute photometry (`-1` in the file).
    pub lumens_per_lamp: Option<f64>,
    /// Candela multiplier from the file (already applied to the candela values).
    pub multiplier: f64,
    /// Ballast factor from the file (already applied to the candela values).
    pub ballast_factor: f64,
    /// The field after the ballast factor: ballast-lamp photometric factor (1986/1991, applied when
    /// positive), "future use" (1995/2002) or file generation type (2019), as written.
    pub ballast_lamp_factor_or_generation: f64,
    /// Input watts of the luminaire.
    pub input_watts: f64,
    /// Units of the luminous opening in the file.
    pub units: Units,
    /// Luminous opening width, length and height in metres (signs encode shapes in LM-63).
    pub opening_m: [f64; 3],
    /// Things that were accepted but are worth knowing (unread tilt file, odd angle ranges, ...).
    pub warnings: Vec<String>,
    grid: Grid,
}

impl IesProfile {
    /// Reads and parses an IES file; bytes that are not UTF-8 (Latin-1 keywords) are replaced.
    pub fn from_file(path: &Path) -> Result<Self, IesError> {
        let what = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| IesError::Io { what: what.clone(), msg: e.to_string() })?;
        Self::parse(&String::from_utf8_lossy(&bytes), &what)
    }

    /// Parses the text of an IES file; `what` names it in errors (a path, or "test file").
    pub fn parse(text: &str, what: &str) -> Result<Self, IesError> {
        parse::parse(text, what)
    }

    /// Goniometer coordinate system of the data.
    pub fn photometric_type(&self) -> PhotometricType {
        self.grid.kind
    }

    /// Which symmetry the measured angles imply.
    pub fn symmetry(&self) -> Symmetry {
        self.grid.symmetry
    }

    /// Measured vertical angles, degrees, increasing.
    pub fn vertical_angles_deg(&self) -> &[f64] {
        &self.grid.v_deg
    }

    /// Measured horizontal angles, degrees, increasing.
    pub fn horizontal_angles_deg(&self) -> &[f64] {
        &self.grid.h_deg
    }

    /// Candela values (multipliers applied), horizontal-major: index `h * vertical count + v`.
    pub fn candela_grid(&self) -> &[f64] {
        &self.grid.cd
    }

    /// Lamp lumens the file states (lamps x lumens per lamp); None for absolute photometry. For
    /// relative photometry this is the bare lamps' output, so a luminaire that absorbs light emits
    /// less (see [`IesProfile::integrated_flux_lm`]).
    pub fn stated_lumens(&self) -> Option<f64> {
        self.lumens_per_lamp.map(|l| l * f64::from(self.lamps))
    }

    /// Value of the first keyword named `key` (case-insensitive), if any.
    pub fn keyword(&self, key: &str) -> Option<&str> {
        self.keywords.iter().find(|(k, _)| k.eq_ignore_ascii_case(key)).map(|(_, v)| v.as_str())
    }
}
