//! LM-63 text -> [`IesProfile`]: the version line, keyword lines, `TILT=`, then a stream of numbers
//! separated by spaces, commas or line breaks in any layout (LM-63-2002 section 3, "delimiter").

use super::{Grid, IesError, IesProfile, IesVersion, MAX_ANGLES, PhotometricType, Symmetry, Tilt, Units};

/// Angles within this many degrees count as equal when naming the symmetry.
const ANGLE_EPS: f64 = 1e-6;

/// One whitespace- or comma-separated field and the 1-based line it came from.
#[derive(Clone, Copy)]
struct Token<'a> {
    line: usize,
    text: &'a str,
}

/// The numeric part of the file as a cursor over tokens.
struct Tokens<'a> {
    what: &'a str,
    items: Vec<Token<'a>>,
    pos: usize,
    /// Line to blame when the file ends early.
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn remaining(&self) -> usize {
        self.items.len() - self.pos.min(self.items.len())
    }

    /// The next number; `expected` describes it for the error message.
    fn number(&mut self, expected: impl FnOnce() -> String) -> Result<(f64, usize), IesError> {
        let Some(tok) = self.items.get(self.pos).copied() else {
            return Err(IesError::Truncated { what: self.what.into(), line: self.last_line, expected: expected() });
        };
        self.pos += 1;
        match tok.text.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok((x, tok.line)),
            Ok(_) => Err(IesError::NotFinite {
                what: self.what.into(),
                line: tok.line,
                expected: expected(),
                found: tok.text.into(),
            }),
            Err(_) => Err(IesError::NotANumber {
                what: self.what.into(),
                line: tok.line,
                expected: expected(),
                found: clip(tok.text),
            }),
        }
    }

    /// The next number, which must be an integer in `lo..=hi` (1986 files may write `2.0`).
    fn integer(&mut self, expected: &str, lo: f64, hi: f64) -> Result<(u64, usize), IesError> {
        let (x, line) = self.number(|| expected.to_string())?;
        if x.fract() != 0.0 || x < lo || x > hi {
            return Err(IesError::BadCount {
                what: self.what.into(),
                line,
                msg: format!("{expected} must be a whole number in {lo}..={hi}, found {x}"),
            });
        }
        Ok((x as u64, line))
    }

    /// `n` strictly increasing angles; returns them with the lines of the first and last.
    fn angles(&mut self, n: usize, which: &str) -> Result<(Vec<f64>, [usize; 2]), IesError> {
        let mut out = Vec::with_capacity(n.min(self.remaining()));
        let mut lines = [self.last_line; 2];
        for i in 0..n {
            let (a, line) = self.number(|| format!("{which} angle {} of {n}", i + 1))?;
            if let Some(&prev) = out.last()
                && a <= prev
            {
                return Err(IesError::NonMonotonic {
                    what: self.what.into(),
                    line,
                    which: which.into(),
                    previous: prev,
                    value: a,
                });
            }
            if i == 0 {
                lines[0] = line;
            }
            lines[1] = line;
            out.push(a);
        }
        Ok((out, lines))
    }
}

/// Shortens a bad token for the error message (a binary file can have huge "tokens").
fn clip(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}...", &s[..i]),
        None => s.to_string(),
    }
}

/// Splits into lines on LF, CR LF or a lone CR (old Mac files), keeping 1-based numbering.
fn split_lines(text: &str) -> Vec<&str> {
    let mut lines = Vec::new();
    let text = text.strip_suffix('\n').unwrap_or(text);
    for l in text.split('\n') {
        let l = l.strip_suffix('\r').unwrap_or(l);
        lines.extend(l.split('\r'));
    }
    lines
}

/// The version a first line names, with a warning when it is not one of the five known tags.
fn version_of(first: &str) -> Option<(IesVersion, Option<String>)> {
    let up = first.trim().to_ascii_uppercase();
    let known = match up.as_str() {
        "IESNA91" | "IESNA:LM-63-1991" => Some(IesVersion::Lm63_1991),
        "IESNA:LM-63-1986" => Some(IesVersion::Lm63_1986),
        "IESNA:LM-63-1995" => Some(IesVersion::Lm63_1995),
        "IESNA:LM-63-2002" => Some(IesVersion::Lm63_2002),
        "IES:LM-63-2019" | "IESNA:LM-63-2019" => Some(IesVersion::Lm63_2019),
        _ => None,
    };
    if let Some(v) = known {
        return Some((v, None));
    }
    if !(up.starts_with("IESNA") || up.starts_with("IES:")) {
        return None;
    }
    let digits: String = up.chars().rev().take_while(|c| c.is_ascii_digit()).collect();
    let year: u32 = digits.chars().rev().collect::<String>().parse().unwrap_or(2002);
    let v = match year {
        ..1991 => IesVersion::Lm63_1986,
        1991..1995 => IesVersion::Lm63_1991,
        1995..2002 => IesVersion::Lm63_1995,
        2002..2019 => IesVersion::Lm63_2002,
        _ => IesVersion::Lm63_2019,
    };
    Some((v, Some(format!("unrecognised version line '{}'; read as {v}", clip(first.trim())))))
}

/// `TILT=...` -> the value after '=', if the line is a tilt line.
fn tilt_value(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let head = t.get(..4)?;
    if !head.eq_ignore_ascii_case("TILT") {
        return None;
    }
    t[4..].trim_start().strip_prefix('=').map(str::trim)
}

pub(super) fn parse(text: &str, what: &str) -> Result<IesProfile, IesError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines = split_lines(text);
    let mut warnings = Vec::new();

    // Version line (absent in 1986 files, whose first line is already label text).
    let (version, mut header_start) = match lines.first().and_then(|l| version_of(l)) {
        Some((v, warning)) => {
            warnings.extend(warning);
            (v, 1)
        }
        None => (IesVersion::Lm63_1986, 0),
    };

    // Keyword (or free label) lines up to TILT=.
    let mut keywords: Vec<(String, String)> = Vec::new();
    let tilt_line = loop {
        let Some(line) = lines.get(header_start) else {
            return Err(IesError::Truncated {
                what: what.into(),
                line: lines.len().max(1),
                expected: "a TILT=NONE, TILT=INCLUDE or TILT=<file> line after the header".into(),
            });
        };
        if tilt_value(line).is_some() {
            break header_start;
        }
        let t = line.trim();
        if let Some(rest) = t.strip_prefix('[')
            && let Some((key, value)) = rest.split_once(']')
        {
            let (key, value) = (key.trim(), value.trim());
            match keywords.last_mut() {
                Some((_, prev)) if key.eq_ignore_ascii_case("MORE") => {
                    prev.push('\n');
                    prev.push_str(value);
                }
                _ => keywords.push((key.to_string(), value.to_string())),
            }
        } else if !t.is_empty() {
            if version >= IesVersion::Lm63_1991 {
                warnings.push(format!("line {}: header line without a [KEYWORD]", header_start + 1));
            }
            keywords.push((String::new(), t.to_string()));
        }
        header_start += 1;
    };
    let tilt_text = tilt_value(lines[tilt_line]).unwrap_or_default();

    // Everything after the TILT line is numbers.
    let mut items = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(tilt_line + 1) {
        let fields = line.split(|c: char| c.is_whitespace() || c == ',');
        // A trailing DOS end-of-file byte is not data.
        let fields = fields.map(|f| f.trim_matches('\u{1a}')).filter(|f| !f.is_empty());
        items.extend(fields.map(|text| Token { line: i + 1, text }));
    }
    let mut tok = Tokens { what, items, pos: 0, last_line: lines.len().max(1) };

    let tilt = if tilt_text.eq_ignore_ascii_case("NONE") {
        Tilt::None
    } else if tilt_text.eq_ignore_ascii_case("INCLUDE") {
        read_tilt(&mut tok)?
    } else if tilt_text.is_empty() {
        return Err(IesError::BadValue {
            what: what.into(),
            line: tilt_line + 1,
            msg: "TILT= needs NONE, INCLUDE or a file name".into(),
        });
    } else {
        warnings.push(format!("tilt file '{tilt_text}' is not read; the candela values are used as measured"));
        Tilt::File(tilt_text.to_string())
    };

    let (lamps, _) = tok.integer("number of lamps", 1.0, 1e6)?;
    let (lumens, lumens_line) = tok.number(|| "lumens per lamp".into())?;
    let (multiplier, mult_line) = tok.number(|| "candela multiplier".into())?;
    let (n_v, counts_line) = tok.integer("number of vertical angles", 2.0, MAX_ANGLES as f64)?;
    let (n_h, _) = tok.integer("number of horizontal angles", 1.0, MAX_ANGLES as f64)?;
    let (ptype, ptype_line) = tok.number(|| "photometric type (1, 2 or 3)".into())?;
    let kind = match ptype {
        1.0 => PhotometricType::C,
        2.0 => PhotometricType::B,
        3.0 => PhotometricType::A,
        _ => {
            return Err(IesError::UnknownPhotometricType {
                what: what.into(),
                line: ptype_line,
                found: ptype.to_string(),
            });
        }
    };
    let (units_code, units_line) = tok.number(|| "units type (1 feet, 2 metres)".into())?;
    let units = match units_code {
        1.0 => Units::Feet,
        2.0 => Units::Metres,
        _ => {
            let msg = format!("units type must be 1 (feet) or 2 (metres), found {units_code}");
            return Err(IesError::BadValue { what: what.into(), line: units_line, msg });
        }
    };
    let to_m = if units == Units::Feet { 0.3048 } else { 1.0 };
    let width = tok.number(|| "luminous opening width".into())?.0 * to_m;
    let length = tok.number(|| "luminous opening length".into())?.0 * to_m;
    let height = tok.number(|| "luminous opening height".into())?.0 * to_m;
    let (ballast_factor, ballast_line) = tok.number(|| "ballast factor".into())?;
    let (bl_factor, bl_line) = tok.number(|| "ballast-lamp photometric factor / future use".into())?;
    let (input_watts, _) = tok.number(|| "input watts".into())?;

    let lumens_per_lamp = if (lumens + 1.0).abs() < 1e-9 {
        None
    } else if lumens > 0.0 {
        Some(lumens)
    } else {
        let msg = format!("lumens per lamp must be positive, or -1 for absolute photometry; found {lumens}");
        return Err(IesError::BadValue { what: what.into(), line: lumens_line, msg });
    };
    let positive = |x: f64, line: usize, name: &str| {
        if x > 0.0 {
            Ok(x)
        } else {
            Err(IesError::BadValue { what: what.into(), line, msg: format!("{name} must be positive, found {x}") })
        }
    };
    let multiplier = positive(multiplier, mult_line, "candela multiplier")?;
    let ballast_factor = positive(ballast_factor, ballast_line, "ballast factor")?;
    // The ballast-lamp photometric factor exists only in the 1986 and 1991 formats (as in ies2rad).
    let mut scale = multiplier * ballast_factor;
    if version <= IesVersion::Lm63_1991 {
        if bl_factor > 0.0 {
            scale *= bl_factor;
        } else {
            warnings.push(format!("line {bl_line}: ballast-lamp photometric factor {bl_factor} ignored"));
        }
    }

    let (n_v, n_h) = (n_v as usize, n_h as usize);
    let counts = format!("the counts on line {counts_line} declare {n_v} vertical x {n_h} horizontal angles");
    // A file that ends early usually has wrong counts: say what they were.
    let with_counts = |e: IesError| match e {
        IesError::Truncated { what, line, expected } => {
            IesError::Truncated { what, line, expected: format!("{expected}; {counts}") }
        }
        e => e,
    };
    let (v_deg, v_lines) = tok.angles(n_v, "vertical").map_err(with_counts)?;
    let (h_deg, h_lines) = tok.angles(n_h, "horizontal").map_err(with_counts)?;
    let total = n_v * n_h; // both <= MAX_ANGLES, so no overflow
    let mut cd = Vec::with_capacity(total.min(tok.remaining()));
    for &h in &h_deg {
        for &v in &v_deg {
            let describe = || format!("candela value {} of {total} (H {h}, V {v})", cd.len() + 1);
            let (c, line) = tok.number(describe).map_err(with_counts)?;
            if c < 0.0 {
                return Err(IesError::NegativeCandela { what: what.into(), line, value: c });
            }
            cd.push(c * scale);
        }
    }
    if let Some(extra) = tok.items.get(tok.pos) {
        let msg = format!("{counts}, and {} more values follow", tok.remaining());
        return Err(IesError::TrailingData { what: what.into(), line: extra.line, found: clip(extra.text), msg });
    }

    let symmetry = classify(kind, &v_deg, &h_deg, v_lines, h_lines, what, &mut warnings)?;
    Ok(IesProfile {
        version,
        keywords,
        tilt,
        lamps: lamps as u32,
        lumens_per_lamp,
        multiplier,
        ballast_factor,
        ballast_lamp_factor_or_generation: bl_factor,
        input_watts,
        units,
        opening_m: [width, length, height],
        warnings,
        grid: Grid { kind, symmetry, v_deg, h_deg, cd },
    })
}

/// `TILT=INCLUDE`: lamp-to-luminaire geometry, pair count, angles, multiplying factors.
fn read_tilt(tok: &mut Tokens) -> Result<Tilt, IesError> {
    let (geometry, _) = tok.integer("tilt lamp-to-luminaire geometry (1, 2 or 3)", 1.0, 3.0)?;
    let (n, line) = tok.integer("number of tilt angles", 1.0, MAX_ANGLES as f64)?;
    let n = n as usize;
    if 2 * n > tok.remaining() {
        let msg = format!("declares {n} tilt angles but only {} numbers follow", tok.remaining());
        return Err(IesError::BadCount { what: tok.what.into(), line, msg });
    }
    let (angles_deg, _) = tok.angles(n, "tilt")?;
    let mut factors = Vec::with_capacity(n);
    for i in 0..n {
        let (f, line) = tok.number(|| format!("tilt multiplying factor {} of {n}", i + 1))?;
        if f < 0.0 {
            let msg = format!("tilt multiplying factors must not be negative, found {f}");
            return Err(IesError::BadValue { what: tok.what.into(), line, msg });
        }
        factors.push(f);
    }
    Ok(Tilt::Include { geometry: geometry as u8, angles_deg, factors })
}

/// Names the symmetry the angle ranges imply, or says which range LM-63 does not allow.
fn classify(
    kind: PhotometricType,
    v: &[f64],
    h: &[f64],
    v_lines: [usize; 2],
    h_lines: [usize; 2],
    what: &str,
    warnings: &mut Vec<String>,
) -> Result<Symmetry, IesError> {
    let (v0, vn, h0, hn) = (v[0], v[v.len() - 1], h[0], h[h.len() - 1]);
    let near = |a: f64, b: f64| (a - b).abs() < ANGLE_EPS;
    let bad = |line: usize, msg: String| Err(IesError::UnsupportedAngles { what: what.into(), line, msg });
    match kind {
        PhotometricType::C => {
            if v0 < -ANGLE_EPS || vn > 180.0 + ANGLE_EPS {
                return bad(v_lines[0], format!("type C vertical angles must lie in 0..180, found {v0}..{vn}"));
            }
            if h.len() == 1 {
                if !near(h0, 0.0) {
                    warnings.push(format!("single horizontal angle {h0} (expected 0); read as rotationally symmetric"));
                }
                return Ok(Symmetry::Rotational);
            }
            let symmetry = if near(h0, 0.0) && near(hn, 90.0) {
                Symmetry::Quadrant
            } else if near(h0, 0.0) && near(hn, 180.0) {
                Symmetry::BilateralC0C180
            } else if near(h0, 90.0) && near(hn, 270.0) {
                Symmetry::BilateralC90C270
            } else if near(h0, 0.0) && hn > 180.0 && hn <= 360.0 + ANGLE_EPS {
                if !near(hn, 360.0) {
                    warnings.push(format!("horizontal angles end at {hn}, not 360; {hn}..360 is interpolated to 0"));
                }
                Symmetry::Full
            } else {
                let msg = format!("type C horizontal angles must run 0-90, 0-180, 90-270 or 0-360, found {h0}-{hn}");
                return bad(h_lines[1], msg);
            };
            Ok(symmetry)
        }
        PhotometricType::A | PhotometricType::B => {
            if v0 < -90.0 - ANGLE_EPS || vn > 90.0 + ANGLE_EPS {
                return bad(v_lines[0], format!("type {kind} vertical angles must lie in -90..90, found {v0}..{vn}"));
            }
            if h.len() < 2 || h0 < -180.0 - ANGLE_EPS || hn > 180.0 + ANGLE_EPS {
                let msg = format!("type {kind} needs at least two horizontal angles in -180..180, found {h0}..{hn}");
                return bad(h_lines[0], msg);
            }
            if !(near(h0, 0.0) || near(h0, -90.0)) || !near(hn, 90.0) || !(near(v0, 0.0) || near(v0, -90.0)) {
                warnings
                    .push(format!("LM-63 expects H and V to run -90 (or 0) to 90; found H {h0}..{hn}, V {v0}..{vn}"));
            }
            Ok(match (h0 >= -ANGLE_EPS, v0 >= -ANGLE_EPS) {
                (false, false) => Symmetry::Full,
                (true, false) => Symmetry::Lateral,
                (false, true) => Symmetry::Vertical,
                (true, true) => Symmetry::LateralAndVertical,
            })
        }
    }
}
