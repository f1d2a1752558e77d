//! Spectra given as (wavelength, value) tables, linearly interpolated, zero outside their range.

use super::SpectrumError;

/// A spectrum sampled at increasing wavelengths (nm), linearly interpolated between samples and
/// zero outside `[first, last]`. Invariant: `nm` is strictly increasing, same length as `values`,
/// at least two entries, every value finite.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedSpectrum {
    nm: Vec<f64>,
    values: Vec<f64>,
    /// Some(step) when the samples are evenly spaced, for O(1) lookup.
    step: Option<f64>,
}

impl TabulatedSpectrum {
    /// Builds a table, checking the invariants above; `what` names the source in errors.
    pub fn new(nm: Vec<f64>, values: Vec<f64>, what: &str) -> Result<Self, SpectrumError> {
        let bad = |msg: String| SpectrumError::BadTable { what: what.to_string(), msg };
        if nm.len() != values.len() {
            return Err(bad(format!("{} wavelengths but {} values", nm.len(), values.len())));
        }
        if nm.len() < 2 {
            return Err(bad("needs at least two rows".into()));
        }
        for (i, (&l, &v)) in nm.iter().zip(&values).enumerate() {
            if !l.is_finite() || l <= 0.0 {
                return Err(bad(format!("row {}: wavelength {l} is not a positive number", i + 1)));
            }
            if !v.is_finite() {
                return Err(bad(format!("row {}: value {v} is not finite", i + 1)));
            }
            if i > 0 && l <= nm[i - 1] {
                return Err(bad(format!("row {}: wavelengths must increase ({} after {})", i + 1, l, nm[i - 1])));
            }
        }
        let step0 = nm[1] - nm[0];
        let even = nm.windows(2).all(|w| ((w[1] - w[0]) - step0).abs() <= 1e-9 * step0.max(1.0));
        Ok(Self { nm, values, step: even.then_some(step0) })
    }

    /// Parses CSV text of `nm,value` rows. Lines starting with `#` and a header row whose first
    /// field is not a number are skipped. Errors name `what` and the 1-based line.
    pub fn parse_csv(text: &str, what: &str) -> Result<Self, SpectrumError> {
        let rows = parse_csv_columns(text, 2, what)?;
        let (nm, values) = rows.into_iter().map(|r| (r[0], r[1])).unzip();
        Self::new(nm, values, what)
    }

    /// Shortest wavelength, nm.
    pub fn min_nm(&self) -> f64 {
        self.nm[0]
    }
    /// Longest wavelength, nm.
    pub fn max_nm(&self) -> f64 {
        *self.nm.last().unwrap()
    }
    /// The sample wavelengths, nm.
    pub fn wavelengths(&self) -> &[f64] {
        &self.nm
    }
    /// The sample values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Largest value in the table.
    pub fn max_value(&self) -> f64 {
        self.values.iter().copied().fold(f64::MIN, f64::max)
    }

    /// Value at `lambda_nm`: linear interpolation, 0 outside the table.
    pub fn eval(&self, lambda_nm: f64) -> f64 {
        let (lo, hi) = (self.min_nm(), self.max_nm());
        if !(lambda_nm >= lo && lambda_nm <= hi) {
            return 0.0;
        }
        let i = match self.step {
            Some(step) => (((lambda_nm - lo) / step) as usize).min(self.nm.len() - 2),
            None => self.nm.partition_point(|&l| l <= lambda_nm).clamp(1, self.nm.len() - 1) - 1,
        };
        let (l0, l1) = (self.nm[i], self.nm[i + 1]);
        let t = ((lambda_nm - l0) / (l1 - l0)).clamp(0.0, 1.0);
        self.values[i] * (1.0 - t) + self.values[i + 1] * t
    }

    /// Integral of `self(lambda) * weight(lambda)` over the table's range by the trapezoid rule on
    /// its own samples: the CIE's summation practice for tabulated spectra.
    pub fn integrate_weighted(&self, weight: impl Fn(f64) -> f64) -> f64 {
        let n = self.nm.len();
        (0..n)
            .map(|i| {
                let left = if i > 0 { self.nm[i] - self.nm[i - 1] } else { 0.0 };
                let right = if i + 1 < n { self.nm[i + 1] - self.nm[i] } else { 0.0 };
                self.values[i] * weight(self.nm[i]) * 0.5 * (left + right)
            })
            .sum()
    }
}

/// Parses CSV text into rows of exactly `columns` numbers. Comment lines (`#`) and blank lines
/// are skipped, as is a first data line that does not start with a number (a header).
pub(crate) fn parse_csv_columns(text: &str, columns: usize, what: &str) -> Result<Vec<Vec<f64>>, SpectrumError> {
    let mut rows = Vec::new();
    let mut seen_data = false;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split([',', ';', '\t']).map(str::trim).collect();
        if !seen_data && fields[0].parse::<f64>().is_err() {
            seen_data = true; // a header row
            continue;
        }
        seen_data = true;
        let bad = |msg: String| SpectrumError::BadCsv { what: what.to_string(), line: i + 1, msg };
        if fields.len() != columns {
            return Err(bad(format!("expected {columns} comma-separated numbers, found {} fields", fields.len())));
        }
        let row = fields
            .iter()
            .map(|f| f.parse::<f64>().map_err(|_| bad(format!("'{f}' is not a number"))))
            .collect::<Result<Vec<_>, _>>()?;
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(SpectrumError::BadCsv { what: what.to_string(), line: 0, msg: "no data rows".into() });
    }
    Ok(rows)
}
