//! What `kelvin ies` prints about a profile: header, type, symmetry, lumens, peak and beam angles.

use serde::Serialize;

use super::{IesProfile, PhotometricType, Tilt};

/// Summary of an [`IesProfile`], printable as a table (Display) or as one JSON object (serde).
#[derive(Clone, Debug, Serialize)]
pub struct IesSummary {
    /// LM-63 revision, e.g. "LM-63-2002".
    pub version: String,
    /// `[KEYWORD] value` pairs in file order (`[MORE]` joined with newlines).
    pub keywords: Vec<(String, String)>,
    /// "A", "B" or "C".
    pub photometric_type: String,
    /// The symmetry case, in words.
    pub symmetry: String,
    /// "none", "include" or the tilt file's name.
    pub tilt: String,
    /// Number of vertical angles measured.
    pub vertical_angles: usize,
    /// Number of horizontal angles measured.
    pub horizontal_angles: usize,
    /// Measured vertical and horizontal ranges, degrees: [first, last].
    pub vertical_range_deg: [f64; 2],
    /// Horizontal range, degrees: [first, last].
    pub horizontal_range_deg: [f64; 2],
    /// Number of lamps.
    pub lamps: u32,
    /// None for absolute photometry.
    pub lumens_per_lamp: Option<f64>,
    /// Lamps x lumens per lamp (bare lamps, for relative photometry).
    pub stated_lumens: Option<f64>,
    /// Flux of the distribution integrated over the sphere, lm.
    pub integrated_lumens: f64,
    /// Integrated / stated lumens (luminaire efficiency for relative photometry).
    pub integrated_over_stated: Option<f64>,
    /// Peak intensity of the grid, cd (multiplier and ballast factor applied).
    pub max_candela: f64,
    /// The planes of the beam and field angles, local XZ then local YZ, each named in the file's
    /// own angles ([`plane_names`]): C0-C180 and C90-C270 for type C; for types A and B, whose
    /// horizontal angles are not C-planes, the plane V = 0 (swept in H) and H = 0 (swept in V).
    pub angle_planes: [&'static str; 2],
    /// Beam (50%) full angle in the local XZ plane (`angle_planes[0]`; C0-C180 for type C), degrees.
    pub beam_angle_deg: Option<f64>,
    /// Field (10%) full angle in the local XZ plane (`angle_planes[0]`), degrees.
    pub field_angle_deg: Option<f64>,
    /// Beam (50%) full angle in the local YZ plane (`angle_planes[1]`; C90-C270 for type C; the
    /// key keeps its type C name), degrees.
    pub beam_angle_c90_deg: Option<f64>,
    /// Field (10%) full angle in the local YZ plane (`angle_planes[1]`), degrees.
    pub field_angle_c90_deg: Option<f64>,
    /// Input power stated in the file, W.
    pub input_watts: f64,
    /// What the parser noticed but read anyway.
    pub warnings: Vec<String>,
}

impl IesSummary {
    /// Computes the summary of `profile`.
    pub fn of(profile: &IesProfile) -> Self {
        let integrated = profile.integrated_flux_lm();
        let stated = profile.stated_lumens();
        let range = |a: &[f64]| [a.first().copied().unwrap_or(0.0), a.last().copied().unwrap_or(0.0)];
        Self {
            version: profile.version.to_string(),
            keywords: profile.keywords.clone(),
            photometric_type: profile.photometric_type().to_string(),
            symmetry: profile.symmetry().to_string(),
            tilt: match &profile.tilt {
                Tilt::None => "none".into(),
                Tilt::Include { .. } => "include".into(),
                Tilt::File(f) => f.clone(),
            },
            vertical_angles: profile.vertical_angles_deg().len(),
            horizontal_angles: profile.horizontal_angles_deg().len(),
            vertical_range_deg: range(profile.vertical_angles_deg()),
            horizontal_range_deg: range(profile.horizontal_angles_deg()),
            lamps: profile.lamps,
            lumens_per_lamp: profile.lumens_per_lamp,
            stated_lumens: stated,
            integrated_lumens: integrated,
            integrated_over_stated: stated.map(|s| integrated / s),
            max_candela: profile.max_candela(),
            angle_planes: plane_names(profile.photometric_type()),
            beam_angle_deg: profile.beam_angle_deg(),
            field_angle_deg: profile.field_angle_deg(),
            beam_angle_c90_deg: profile.spread_angle_deg(90.0, 0.5),
            field_angle_c90_deg: profile.spread_angle_deg(90.0, 0.1),
            input_watts: profile.input_watts,
            warnings: profile.warnings.clone(),
        }
    }
}

/// Names of the local XZ and YZ planes in the file's own angles.
pub fn plane_names(kind: PhotometricType) -> [&'static str; 2] {
    match kind {
        PhotometricType::C => ["C0-C180", "C90-C270"],
        PhotometricType::B => ["V = 0 (H sweep)", "H = 0 (V sweep)"],
        PhotometricType::A => ["H = 0 (V sweep)", "V = 0 (H sweep)"],
    }
}

impl std::fmt::Display for IesSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let angle = |a: Option<f64>| a.map_or("-".to_string(), |a| format!("{a:.1} deg"));
        writeln!(f, "version            {}", self.version)?;
        for (key, value) in &self.keywords {
            let mut lines = value.lines();
            let label = if key.is_empty() { String::new() } else { format!("[{key}]") };
            writeln!(f, "  {label:<17}{}", lines.next().unwrap_or(""))?;
            for more in lines {
                writeln!(f, "  {:<17}{more}", "[MORE]")?;
            }
        }
        writeln!(f, "photometric type   {}", self.photometric_type)?;
        writeln!(f, "symmetry           {}", self.symmetry)?;
        writeln!(f, "tilt               {}", self.tilt)?;
        let [v0, v1] = self.vertical_range_deg;
        let [h0, h1] = self.horizontal_range_deg;
        writeln!(f, "vertical angles    {} ({v0} to {v1} deg)", self.vertical_angles)?;
        writeln!(f, "horizontal angles  {} ({h0} to {h1} deg)", self.horizontal_angles)?;
        match (self.lumens_per_lamp, self.stated_lumens) {
            (Some(l), Some(s)) => writeln!(f, "stated lumens      {s:.1} lm ({} x {l} lm)", self.lamps)?,
            _ => writeln!(f, "stated lumens      absolute photometry (-1)")?,
        }
        write!(f, "integrated lumens  {:.1} lm", self.integrated_lumens)?;
        match self.integrated_over_stated {
            Some(r) => writeln!(f, " ({:.1}% of stated)", 100.0 * r)?,
            None => writeln!(f)?,
        }
        writeln!(f, "max candela        {:.1} cd", self.max_candela)?;
        let [xz, yz] = self.angle_planes;
        writeln!(
            f,
            "beam angle (50%)   {} (XZ / {xz}), {} (YZ / {yz})",
            angle(self.beam_angle_deg),
            angle(self.beam_angle_c90_deg)
        )?;
        writeln!(
            f,
            "field angle (10%)  {} (XZ / {xz}), {} (YZ / {yz})",
            angle(self.field_angle_deg),
            angle(self.field_angle_c90_deg)
        )?;
        writeln!(f, "input watts        {}", self.input_watts)?;
        for w in &self.warnings {
            writeln!(f, "warning            {w}")?;
        }
        Ok(())
    }
}
