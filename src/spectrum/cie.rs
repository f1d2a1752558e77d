//! CIE data compiled into the binary: colour-matching functions, the D-series basis and the
//! standard illuminants. Tables come from `data/` (see `data/generate.py` for their source).

use std::sync::{Arc, LazyLock};

use super::SpectrumError;
use super::tabulated::{TabulatedSpectrum, parse_csv_columns};

/// Shortest wavelength of the CIE colour-matching tables, nm.
pub const CMF_MIN_NM: f64 = 360.0;
/// Longest wavelength of the CIE colour-matching tables, nm.
pub const CMF_MAX_NM: f64 = 830.0;

/// Colour-matching functions x-bar, y-bar, z-bar at 1 nm steps from 360 nm to 830 nm.
pub struct Cmf {
    xyz: Vec<[f64; 3]>,
    /// Integral of y-bar, nm (about 106.857 for the 1931 observer).
    pub y_integral: f64,
}

impl Cmf {
    fn from_csv(text: &str, what: &str) -> Self {
        let rows = parse_csv_columns(text, 4, what).expect("compiled-in CMF table is valid");
        debug_assert_eq!(rows.len(), 471);
        let xyz: Vec<[f64; 3]> = rows.iter().map(|r| [r[1], r[2], r[3]]).collect();
        let y_integral = xyz.iter().map(|v| v[1]).sum();
        Self { xyz, y_integral }
    }

    /// (x-bar, y-bar, z-bar) at `lambda_nm`, linearly interpolated, 0 outside 360-830 nm.
    pub fn eval(&self, lambda_nm: f64) -> [f64; 3] {
        if !(CMF_MIN_NM..=CMF_MAX_NM).contains(&lambda_nm) {
            return [0.0; 3];
        }
        let f = lambda_nm - CMF_MIN_NM;
        let i = (f as usize).min(self.xyz.len() - 2);
        let t = f - i as f64;
        let (a, b) = (self.xyz[i], self.xyz[i + 1]);
        [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * t)
    }

    /// Table row at an integer wavelength (360..=830).
    pub fn at_nm(&self, nm: usize) -> [f64; 3] {
        self.xyz[nm - CMF_MIN_NM as usize]
    }
}

/// The CIE 1931 2-degree standard observer (CIE 015:2018).
pub static CIE_1931: LazyLock<Cmf> =
    LazyLock::new(|| Cmf::from_csv(include_str!("data/cie1931_2deg.csv"), "cie1931_2deg.csv"));
/// The CIE 1964 10-degree standard observer (CIE 015:2018).
pub static CIE_1964: LazyLock<Cmf> =
    LazyLock::new(|| Cmf::from_csv(include_str!("data/cie1964_10deg.csv"), "cie1964_10deg.csv"));

/// Photopic luminous efficiency V(lambda): the 1931 y-bar, which the CIE defined equal to it.
pub fn luminous_efficiency(lambda_nm: f64) -> f64 {
    CIE_1931.eval(lambda_nm)[1]
}

/// The D-series basis S0, S1, S2, 300-830 nm at 5 nm (CIE 015:2018 Table 6).
struct DaylightBasis {
    s: [TabulatedSpectrum; 3],
}

static D_BASIS: LazyLock<DaylightBasis> = LazyLock::new(|| {
    let rows = parse_csv_columns(include_str!("data/cie_d_basis.csv"), 4, "cie_d_basis.csv").expect("valid table");
    let nm: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let s = [1, 2, 3].map(|k| {
        TabulatedSpectrum::new(nm.clone(), rows.iter().map(|r| r[k]).collect(), "cie_d_basis.csv").expect("valid")
    });
    DaylightBasis { s }
});

/// Chromaticity of CIE daylight at correlated colour temperature `cct_k` (CIE 015:2018 eq. 4.7,
/// 4.8), defined for 4000 K to 25000 K.
pub fn daylight_xy(cct_k: f64) -> Result<[f64; 2], SpectrumError> {
    if !(4000.0..=25000.0).contains(&cct_k) {
        return Err(SpectrumError::out_of_range("daylight CCT (K)", cct_k, 4000.0, 25000.0));
    }
    let t = cct_k;
    let x = if t <= 7000.0 {
        -4.6070e9 / t.powi(3) + 2.9678e6 / t.powi(2) + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t.powi(3) + 1.9018e6 / t.powi(2) + 0.24748e3 / t + 0.237040
    };
    Ok([x, -3.000 * x * x + 2.870 * x - 0.275])
}

/// CIE daylight SPD at `cct_k` from the S0 + M1 S1 + M2 S2 basis (300-830 nm at 5 nm), normalised
/// to 100 at 560 nm as the CIE tabulates it.
pub fn daylight(cct_k: f64) -> Result<TabulatedSpectrum, SpectrumError> {
    let [x, y] = daylight_xy(cct_k)?;
    // CIE 015:2018 eq. 4.9; M1 and M2 rounded to three decimals as the CIE does.
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    let m1 = ((-1.3515 - 1.7703 * x + 5.9114 * y) / m * 1000.0).round() / 1000.0;
    let m2 = ((0.0300 - 31.4424 * x + 30.0717 * y) / m * 1000.0).round() / 1000.0;
    let b = &D_BASIS.s;
    let nm = b[0].wavelengths().to_vec();
    let raw: Vec<f64> =
        (0..nm.len()).map(|i| b[0].values()[i] + m1 * b[1].values()[i] + m2 * b[2].values()[i]).collect();
    let s = TabulatedSpectrum::new(nm.clone(), raw, "daylight")?;
    let at560 = s.eval(560.0);
    TabulatedSpectrum::new(nm, s.values().iter().map(|v| v * 100.0 / at560).collect(), "daylight")
}

/// CIE standard illuminant A at `lambda_nm` from its defining formula (CIE 015:2018 eq. 4.1):
/// a 2856 K Planckian radiator with c2 = 1.435e-2 m K, normalised to 100 at 560 nm.
pub fn illuminant_a(lambda_nm: f64) -> f64 {
    if !(300.0..=830.0).contains(&lambda_nm) {
        return 0.0;
    }
    let c: f64 = 1.435e7 / 2848.0; // c2 / T in nm, with the 1968 c2 that fixes T = 2848 K
    100.0 * (560.0 / lambda_nm).powi(5) * (c / 560.0).exp_m1() / (c / lambda_nm).exp_m1()
}

/// Names accepted by [`Spectrum::illuminant`](crate::spectrum::Spectrum::illuminant), for help and error messages.
pub const ILLUMINANT_NAMES: &[&str] = &[
    "A", "B", "C", "D50", "D55", "D65", "D75", "E", "F1", "F2", "F3", "F4", "F5", "F6", "F7", "F8", "F9", "F10", "F11",
    "F12", "LED-B1", "LED-B2", "LED-B3", "LED-B4", "LED-B5", "LED-BH1", "LED-RGB1", "LED-V1", "LED-V2",
];

macro_rules! tables {
    ($($name:literal),* $(,)?) => {
        fn illuminant_csv(name: &str) -> Option<&'static str> {
            match name {
                $($name => Some(include_str!(concat!("data/illuminant_", $name, ".csv"))),)*
                _ => None,
            }
        }
    };
}
tables!(
    "B", "C", "D50", "D55", "D65", "D75", "F1", "F2", "F3", "F4", "F5", "F6", "F7", "F8", "F9", "F10", "F11", "F12",
    "LED-B1", "LED-B2", "LED-B3", "LED-B4", "LED-B5", "LED-BH1", "LED-RGB1", "LED-V1", "LED-V2",
);

/// The tabulated CIE illuminant called `name` (case-insensitive, "FL11" is accepted for "F11").
/// A and E are analytic: use [`super::Spectrum::illuminant`] for every name.
pub fn tabulated_illuminant(name: &str) -> Option<Arc<TabulatedSpectrum>> {
    static CACHE: LazyLock<std::sync::Mutex<Vec<(String, Arc<TabulatedSpectrum>)>>> = LazyLock::new(Default::default);
    let key = canonical_illuminant_name(name)?;
    let csv = illuminant_csv(key)?;
    let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, t)) = cache.iter().find(|(k, _)| k == key) {
        return Some(t.clone());
    }
    let table = Arc::new(TabulatedSpectrum::parse_csv(csv, key).expect("compiled-in illuminant table is valid"));
    cache.push((key.to_string(), table.clone()));
    Some(table)
}

/// Maps user spellings ("d65", "FL2", "led-b1") to the entry of [`ILLUMINANT_NAMES`].
pub fn canonical_illuminant_name(name: &str) -> Option<&'static str> {
    let upper = name.trim().to_ascii_uppercase();
    let upper = upper.strip_prefix("FL").map(|rest| format!("F{rest}")).unwrap_or(upper);
    ILLUMINANT_NAMES.iter().copied().find(|n| *n == upper)
}
