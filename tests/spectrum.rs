//! Emission spectra against published values: Stefan-Boltzmann, Wien, CIE chromaticities,
//! luminous efficacy, and the hard cases of Planck's law.

use std::sync::Arc;

use kelvin::spectrum::planck::{
    STEFAN_BOLTZMANN, blackbody_exitance, kirchhoff, planck, planck_normalized, wien_peak_nm,
};
use kelvin::spectrum::{Spectrum, TabulatedSpectrum, color};

/// Simpson's rule on a log-spaced grid from 1 nm to 1 mm (integrand in per-nm units).
fn integrate_1nm_to_1mm(f: impl Fn(f64) -> f64) -> f64 {
    let n = 200_000; // even
    let (a, b) = (1.0f64.ln(), 1e6f64.ln());
    let h = (b - a) / n as f64;
    let g = |s: f64| {
        let l = s.exp();
        f(l) * l // d(lambda) = lambda d(ln lambda)
    };
    let inner: f64 = (1..n).map(|i| g(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
    h / 3.0 * (g(a) + g(b) + inner)
}

#[test]
fn pi_times_planck_integrates_to_sigma_t4() {
    for t in [300.0, 2856.0, 6500.0, 1e5] {
        let m = std::f64::consts::PI * integrate_1nm_to_1mm(|l| planck(l, t));
        let rel = (m / (STEFAN_BOLTZMANN * t.powi(4)) - 1.0).abs();
        eprintln!(
            "T = {t} K: integral pi B = {m:.6e} W/m^2, sigma T^4 = {:.6e}, rel err {rel:.2e}",
            blackbody_exitance(t)
        );
        assert!(rel < 1e-4, "T = {t}: relative error {rel}");
    }
}

#[test]
fn normalized_blackbody_peaks_at_wien_wavelength_with_value_one() {
    for t in [1000.0, 2856.0, 6500.0, 20000.0] {
        let peak = wien_peak_nm(t);
        assert!((planck_normalized(peak, t) - 1.0).abs() < 1e-12);
        // The discrete maximum on a 0.01% grid lands next to b/T.
        let grid = (0..20001).map(|i| peak * (0.9 + 0.2 * i as f64 / 20000.0));
        let best = grid.max_by(|a, b| planck(*a, t).total_cmp(&planck(*b, t))).unwrap();
        assert!((best / peak - 1.0).abs() < 2e-5, "T = {t}: numerical peak {best} vs b/T {peak}");
        assert!(planck_normalized(peak * 1.01, t) < 1.0 && planck_normalized(peak * 0.99, t) < 1.0);
    }
}

#[test]
fn cie_illuminant_chromaticities_match_published_values() {
    // CIE 015:2018 Table 11.1 / CIE 15:2004 Table T.8 (2-degree observer).
    let published = [
        ("A", 0.44757, 0.40745),
        ("D50", 0.34567, 0.35850),
        ("D65", 0.31272, 0.32903),
        ("F2", 0.37208, 0.37529),
        ("F7", 0.31292, 0.32933),
        ("F11", 0.38052, 0.37713),
    ];
    for (name, x, y) in published {
        let [cx, cy] = Spectrum::illuminant(name).unwrap().xy();
        let err = (cx - x).abs().max((cy - y).abs());
        eprintln!("{name}: xy = ({cx:.5}, {cy:.5}), published ({x}, {y}), max error {err:.1e}");
        assert!(err < 2e-4, "{name}: ({cx}, {cy}) vs ({x}, {y})");
    }
}

#[test]
fn every_named_illuminant_loads_with_a_plausible_chromaticity() {
    for name in kelvin::spectrum::cie::ILLUMINANT_NAMES {
        let s = Spectrum::illuminant(name).unwrap();
        let [x, y] = s.xy();
        assert!((0.25..0.5).contains(&x) && (0.25..0.45).contains(&y), "{name}: xy ({x}, {y})");
        assert!(s.luminous_efficacy() > 100.0, "{name}");
    }
    assert!(Spectrum::illuminant("FL11").unwrap() == Spectrum::illuminant("f11").unwrap());
    let err = Spectrum::illuminant("D66").unwrap_err().to_string();
    assert!(err.contains("D65") && err.contains("LED-B1"), "error lists what is accepted: {err}");
}

#[test]
fn daylight_series_matches_the_tabulated_d_illuminants() {
    // D50, D55, D75 are generated from the basis at 5003, 5503, 7504 K (CIE 015:2018 note 4.1.2).
    for (name, cct) in [("D50", 5003.0), ("D55", 5503.0), ("D65", 6504.0), ("D75", 7504.0)] {
        let table = Spectrum::illuminant(name).unwrap().xy();
        let generated = Spectrum::daylight(cct).unwrap().xy();
        let err = (table[0] - generated[0]).abs().max((table[1] - generated[1]).abs());
        assert!(err < 1e-4, "{name}: {table:?} vs generated {generated:?}");
    }
    assert!(Spectrum::daylight(3999.0).is_err() && Spectrum::daylight(25001.0).is_err());
}

#[test]
fn monochromatic_555nm_has_efficacy_683_lm_per_w() {
    // A 0.2 nm wide triangle around 555 nm approximates a line.
    let s = TabulatedSpectrum::new(vec![554.9, 555.0, 555.1], vec![0.0, 1.0, 0.0], "line").unwrap();
    let s = Spectrum::Tabulated(Arc::new(s));
    let xyz = s.xyz_integral(&kelvin::spectrum::CIE_1931);
    // The 1 nm summation sees the line at one sample: compare the efficacy of V(555) directly too.
    let k = 683.0 * kelvin::spectrum::cie::luminous_efficiency(555.0);
    eprintln!("K(555 nm) = {k:.3} lm/W; line XYZ {xyz:?}");
    assert!((k / 683.0 - 1.0).abs() < 1e-3);
    let flat =
        Spectrum::Tabulated(Arc::new(TabulatedSpectrum::new(vec![550.0, 560.0], vec![1.0, 1.0], "band").unwrap()));
    let kb = flat.luminous_efficacy();
    assert!((kb / 683.0 - 1.0).abs() < 5e-3, "550-560 nm band: {kb} lm/W");
}

#[test]
fn blackbody_efficacy_peaks_near_6600k_at_about_95_lm_per_w() {
    let temps: Vec<f64> = (20..=200).map(|i| i as f64 * 50.0).collect();
    let (t_best, k_best) = temps
        .iter()
        .map(|&t| (t, Spectrum::blackbody(t).unwrap().luminous_efficacy()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    eprintln!("blackbody efficacy peaks at {t_best} K with {k_best:.2} lm/W");
    assert!((6300.0..=6900.0).contains(&t_best), "peak at {t_best} K");
    assert!((94.0..=96.5).contains(&k_best), "peak efficacy {k_best}");
    // Illuminant A (2856 K) is about 15 lm/W over all wavelengths.
    let ka = Spectrum::blackbody(2856.0).unwrap().luminous_efficacy();
    assert!((14.0..17.0).contains(&ka), "2856 K: {ka}");
}

#[test]
fn graybody_follows_kirchhoff_and_keeps_the_blackbody_colour() {
    let bb = Spectrum::blackbody(3000.0).unwrap();
    let gb = Spectrum::graybody(3000.0, 0.3).unwrap();
    assert!((gb.eval(600.0) - 0.3 * bb.eval(600.0)).abs() < 1e-15);
    assert!((gb.luminous_efficacy() - bb.luminous_efficacy()).abs() < 1e-9);
    assert!((kirchhoff(600.0, 3000.0, 0.3) - 0.3 * planck(600.0, 3000.0)).abs() < 1e-6 * planck(600.0, 3000.0));
    assert!(Spectrum::graybody(3000.0, 1.5).is_err());
}

#[test]
fn colour_space_round_trips() {
    let xyz = glam::DVec3::new(0.4, 0.5, 0.3);
    let back = color::xyy_to_xyz(color::xyz_to_xyy(xyz));
    assert!((back - xyz).length() < 1e-12);
    assert!((color::srgb_to_xyz(color::xyz_to_srgb(xyz)) - xyz).length() < 1e-6);
    assert!((color::acescg_to_xyz(color::xyz_to_acescg(xyz)) - xyz).length() < 1e-9);
    let uv = color::xy_to_uv_prime([0.3127, 0.329]);
    let xy = color::uv_prime_to_xy(uv);
    assert!((xy[0] - 0.3127).abs() < 1e-12 && (xy[1] - 0.329).abs() < 1e-12);
    // D65 white maps to equal sRGB and to equal ACEScg components.
    let white = color::xyy_to_xyz(glam::DVec3::new(0.3127, 0.3290, 1.0));
    let rgb = color::xyz_to_srgb(white);
    assert!((rgb - glam::DVec3::ONE).abs().max_element() < 1e-3, "{rgb}");
    let ap1 = color::xyz_to_acescg(white);
    assert!((ap1 - glam::DVec3::ONE).abs().max_element() < 1e-3, "{ap1}");
}

#[test]
fn rgb_derived_spectrum_reproduces_its_colour() {
    let white = Spectrum::Rgb { rgb: [1.0, 1.0, 1.0] };
    let d65 = Spectrum::d65().xy();
    let xy = white.xy();
    assert!((xy[0] - d65[0]).abs() < 2e-3 && (xy[1] - d65[1]).abs() < 2e-3, "{xy:?} vs {d65:?}");
    for rgb in [[1.0, 0.0, 0.0], [0.2, 0.7, 0.1], [0.1, 0.2, 0.9]] {
        let got = Spectrum::Rgb { rgb }.srgb_normalized();
        let want = glam::DVec3::from_array(rgb);
        let want = want / color::srgb_to_xyz(want).y;
        assert!((got - want).abs().max_element() < 0.03, "{rgb:?}: {got} vs {want}");
    }
}

// ---- hard cases: finite results or clear errors, never NaN/Inf ----

#[test]
fn hard_case_zero_and_tiny_temperatures() {
    for t in [0.0, 1e-3, -5.0] {
        for l in [1.0, 555.0, 1e6] {
            let b = planck(l, t);
            assert!(b.is_finite() && b >= 0.0, "planck({l}, {t}) = {b}");
            assert!(planck_normalized(l, t).is_finite());
        }
    }
    assert_eq!(planck(555.0, 0.0), 0.0);
    assert!(Spectrum::blackbody(0.0).is_err() && Spectrum::blackbody(-1.0).is_err());
    let s = Spectrum::blackbody(1e-3).unwrap();
    assert!(s.eval(555.0).is_finite() && s.luminous_efficacy().is_finite());
}

#[test]
fn hard_case_extreme_temperatures_1k_and_1e9k() {
    for t in [1.0, 1e9] {
        for l in [1.0, 10.0, 555.0, 1e4, 1e6] {
            let b = planck(l, t);
            assert!(b.is_finite() && b >= 0.0, "planck({l} nm, {t} K) = {b}");
            let n = planck_normalized(l, t);
            assert!(n.is_finite() && (0.0..=1.0 + 1e-12).contains(&n), "normalised({l}, {t}) = {n}");
        }
        let s = Spectrum::blackbody(t).unwrap();
        let summary = kelvin::spectrum::SpectrumSummary::of(&s);
        assert!(summary.efficacy_lm_per_w.is_finite());
        assert!(summary.xyz.iter().chain(&summary.xy).all(|v| v.is_finite()), "{summary:?}");
    }
    assert!(Spectrum::blackbody(1.1e9).is_err());
}

#[test]
fn hard_case_wavelength_extremes_1nm_and_1mm() {
    for t in [300.0, 6500.0, 1e5] {
        for l in [1.0, 1e6] {
            let b = planck(l, t);
            assert!(b.is_finite() && b >= 0.0, "planck({l}, {t}) = {b}");
        }
    }
    assert!(planck(1e6, 300.0) > 0.0, "the far infrared of a room-temperature body is not zero");
}

#[test]
fn hard_case_negative_and_nan_inputs() {
    for (l, t) in
        [(f64::NAN, 300.0), (500.0, f64::NAN), (-500.0, 300.0), (f64::INFINITY, 300.0), (500.0, f64::INFINITY)]
    {
        assert_eq!(planck(l, t), 0.0, "planck({l}, {t})");
        assert_eq!(planck_normalized(l, t), 0.0);
    }
    assert!(Spectrum::blackbody(f64::NAN).is_err());
    assert!(Spectrum::graybody(300.0, f64::NAN).is_err());
    assert!(Spectrum::daylight(f64::NAN).is_err());
    assert!(kirchhoff(500.0, 3000.0, f64::NAN) == 0.0);
    assert!(TabulatedSpectrum::new(vec![400.0, 500.0], vec![1.0, f64::NAN], "nan").is_err());
    assert!(TabulatedSpectrum::new(vec![500.0, 400.0], vec![1.0, 1.0], "order").is_err());
    let e = TabulatedSpectrum::parse_csv("nm,value\n400,1\n500,abc\n", "my.csv").unwrap_err().to_string();
    assert!(e.contains("my.csv") && e.contains("line 3") && e.contains("abc"), "{e}");
}
