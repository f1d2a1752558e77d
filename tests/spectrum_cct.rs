//! Colour temperature: the Planckian round trip and the CIE illuminants' published CCTs.

use kelvin::spectrum::Spectrum;
use kelvin::spectrum::cct::{cct_duv, cct_duv_from_xy, planckian_xy};

#[test]
fn blackbody_cct_round_trips_within_0_1_percent() {
    let mut worst: f64 = 0.0;
    for i in 0..=190 {
        let t = 1000.0 + 100.0 * i as f64; // 1000..20000 K
        let (cct, duv) = cct_duv(&Spectrum::blackbody(t).unwrap()).unwrap();
        let rel = (cct / t - 1.0).abs();
        worst = worst.max(rel);
        assert!(rel < 1e-3, "T = {t}: CCT {cct}");
        assert!(duv.abs() < 1e-5, "T = {t}: Duv {duv}");
    }
    eprintln!("worst blackbody CCT round-trip error, 1000-20000 K: {worst:.2e}");
}

#[test]
fn published_ccts_of_cie_illuminants() {
    // CIE 015:2018 Table 11.1: D65 6504 K, A 2856 K, D50 5003 K, F11 4000 K.
    for (name, want, tol) in [("D65", 6504.0, 5.0), ("A", 2856.0, 2.0), ("D50", 5003.0, 5.0), ("F11", 4000.0, 15.0)] {
        let (cct, duv) = cct_duv(&Spectrum::illuminant(name).unwrap()).unwrap();
        eprintln!("{name}: CCT {cct:.1} K, Duv {duv:+.5}");
        assert!((cct - want).abs() < tol, "{name}: {cct} vs {want}");
    }
}

#[test]
fn duv_sign_and_parabolic_branch_off_the_locus() {
    // Points 0.01 above and below the 4000 K locus point, along the uv normal direction.
    let xy = planckian_xy(4000.0);
    let [u, v] = kelvin::spectrum::color::xy_to_uv1960(xy);
    let [u2, v2] = kelvin::spectrum::color::xy_to_uv1960(planckian_xy(4010.0));
    let (du, dv) = (u2 - u, v2 - v);
    let len = (du * du + dv * dv).sqrt();
    let normal = [-dv / len, du / len]; // rotated 90 degrees
    for (sign, s) in [(1.0, "above"), (-1.0, "below")] {
        let p = [u + sign * 0.01 * normal[0], v + sign * 0.01 * normal[1]];
        let (cct, duv) = cct_duv_from_xy(kelvin::spectrum::color::uv1960_to_xy(p)).unwrap();
        assert!((duv.abs() - 0.01).abs() < 2e-4, "{s}: Duv {duv}");
        assert!((cct - 4000.0).abs() < 20.0, "{s}: CCT {cct}");
        assert!(duv.signum() == if normal[1] * sign > 0.0 { 1.0 } else { -1.0 }, "{s}: Duv {duv}");
    }
}

#[test]
fn cct_out_of_range_is_an_error_not_nan() {
    assert!(cct_duv_from_xy([0.7, 0.29]).is_err(), "a deep red far below 1000 K");
    assert!(cct_duv_from_xy([f64::NAN, 0.3]).is_err());
}
