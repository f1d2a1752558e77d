//! CIELAB (CIE 1976 L*a*b*) and the CIEDE2000 colour difference.
//!
//! CIELAB follows CIE 015:2018 section 8.2.1 (the cube root with its linear segment below
//! (6/29)^3). CIEDE2000 follows Sharma, Wu and Dalal, "The CIEDE2000 color-difference formula:
//! implementation notes, supplementary test data, and mathematical observations", Color Research
//! and Application 30(1), 2005, equations (1)-(22), with kL = kC = kH = 1. The unit test checks
//! pairs of their Table 1.

use glam::DVec3;

use super::color::{D65_XY, xyy_to_xyz};

/// The D65 white point as XYZ with Y = 1 (from the chromaticity sRGB uses).
pub fn d65_white() -> DVec3 {
    xyy_to_xyz(DVec3::new(D65_XY[0], D65_XY[1], 1.0))
}

/// CIE 1976 L*a*b* of `xyz` relative to the reference white `white` (same units as `xyz`).
pub fn xyz_to_lab(xyz: DVec3, white: DVec3) -> DVec3 {
    const DELTA: f64 = 6.0 / 29.0;
    let f = |t: f64| if t > DELTA * DELTA * DELTA { t.cbrt() } else { t / (3.0 * DELTA * DELTA) + 4.0 / 29.0 };
    let (fx, fy, fz) = (f(xyz.x / white.x), f(xyz.y / white.y), f(xyz.z / white.z));
    DVec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

/// The CIEDE2000 difference between two L*a*b* colours (kL = kC = kH = 1).
pub fn ciede2000(lab1: DVec3, lab2: DVec3) -> f64 {
    let deg = |r: f64| r.to_degrees();
    let rad = |d: f64| d.to_radians();
    let (l1, a1, b1) = (lab1.x, lab1.y, lab1.z);
    let (l2, a2, b2) = (lab2.x, lab2.y, lab2.z);
    // (2)-(5): a* rescaled by G, which depends on the mean chroma.
    let c_mean = 0.5 * (a1.hypot(b1) + a2.hypot(b2));
    let c7 = c_mean.powi(7);
    let g = 0.5 * (1.0 - (c7 / (c7 + 25f64.powi(7))).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = (a1p.hypot(b1), a2p.hypot(b2));
    // (7): hue angle in degrees in [0, 360); 0 for achromatic colours.
    let hue = |a: f64, b: f64| if a == 0.0 && b == 0.0 { 0.0 } else { deg(b.atan2(a)).rem_euclid(360.0) };
    let (h1p, h2p) = (hue(a1p, b1), hue(a2p, b2));
    // (8)-(10): differences; the hue difference takes the short way round.
    let dl = l2 - l1;
    let dc = c2p - c1p;
    let dh = if c1p * c2p == 0.0 {
        0.0
    } else if (h2p - h1p).abs() <= 180.0 {
        h2p - h1p
    } else if h2p - h1p > 180.0 {
        h2p - h1p - 360.0
    } else {
        h2p - h1p + 360.0
    };
    let dhh = 2.0 * (c1p * c2p).sqrt() * (0.5 * rad(dh)).sin();
    // (12)-(14): means; the mean hue also takes the short way round.
    let l_mean = 0.5 * (l1 + l2);
    let c_mean_p = 0.5 * (c1p + c2p);
    let h_mean = if c1p * c2p == 0.0 {
        h1p + h2p
    } else if (h1p - h2p).abs() <= 180.0 {
        0.5 * (h1p + h2p)
    } else if h1p + h2p < 360.0 {
        0.5 * (h1p + h2p + 360.0)
    } else {
        0.5 * (h1p + h2p - 360.0)
    };
    // (15)-(21): weighting functions and the rotation term.
    let t =
        1.0 - 0.17 * rad(h_mean - 30.0).cos() + 0.24 * rad(2.0 * h_mean).cos() + 0.32 * rad(3.0 * h_mean + 6.0).cos()
            - 0.20 * rad(4.0 * h_mean - 63.0).cos();
    let d_theta = 30.0 * (-((h_mean - 275.0) / 25.0).powi(2)).exp();
    let cp7 = c_mean_p.powi(7);
    let r_c = 2.0 * (cp7 / (cp7 + 25f64.powi(7))).sqrt();
    let l50 = (l_mean - 50.0).powi(2);
    let s_l = 1.0 + 0.015 * l50 / (20.0 + l50).sqrt();
    let s_c = 1.0 + 0.045 * c_mean_p;
    let s_h = 1.0 + 0.015 * c_mean_p * t;
    let r_t = -(2.0 * rad(d_theta)).sin() * r_c;
    let (tl, tc, th) = (dl / s_l, dc / s_c, dhh / s_h);
    (tl * tl + tc * tc + th * th + r_t * tc * th).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pairs of Sharma, Wu, Dalal (2005), Table 1: (L1, a1, b1), (L2, a2, b2), Delta E00. They
    /// cover the hue wrap-around, the mean-hue cases and achromatic colours.
    const SHARMA_2005: [([f64; 3], [f64; 3], f64); 14] = [
        ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
        ([50.0, -1.3802, -84.2814], [50.0, 0.0, -82.7485], 1.0000),
        ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
        ([50.0, 2.4900, -0.0010], [50.0, -2.4900, 0.0009], 7.1792),
        ([50.0, 2.4900, -0.0010], [50.0, -2.4900, 0.0011], 7.2195),
        ([50.0, -0.0010, 2.4900], [50.0, 0.0009, -2.4900], 4.8045),
        ([50.0, -0.0010, 2.4900], [50.0, 0.0011, -2.4900], 4.7461),
        ([50.0, 2.5, 0.0], [50.0, 0.0, -2.5], 4.3065),
        ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
        ([50.0, 2.5, 0.0], [56.0, -27.0, -3.0], 31.9030),
        ([60.2574, -34.0099, 36.2677], [60.4626, -34.1751, 39.4387], 1.2644),
        ([22.7233, 20.0904, -46.6940], [23.0331, 14.9730, -42.5619], 2.0373),
        ([90.9257, -0.5406, -0.9208], [88.6381, -0.8985, -0.7239], 1.5381),
        ([2.0776, 0.0795, -1.1350], [0.9033, -0.0636, -0.5514], 0.9082),
    ];

    #[test]
    fn ciede2000_matches_sharma_wu_dalal_table_1() {
        for (i, (a, b, want)) in SHARMA_2005.iter().enumerate() {
            let (a, b) = (DVec3::from_array(*a), DVec3::from_array(*b));
            let got = ciede2000(a, b);
            assert!((got - want).abs() < 5e-5, "pair {i}: {got:.5} vs {want}");
            assert!((ciede2000(b, a) - got).abs() < 1e-9, "pair {i} is not symmetric");
            assert_eq!(ciede2000(a, a), 0.0);
        }
    }

    #[test]
    fn lab_of_the_white_is_100_0_0_and_of_18_percent_grey_is_about_49_5() {
        let w = d65_white();
        let lab = xyz_to_lab(w, w);
        assert!((lab - DVec3::new(100.0, 0.0, 0.0)).abs().max_element() < 1e-9, "{lab}");
        // L* of Y = 0.18 (CIE 015:2018 formula): 116 * 0.18^(1/3) - 16 = 49.496.
        let grey = xyz_to_lab(0.18 * w, w);
        assert!((grey.x - 49.496).abs() < 1e-3 && grey.y.abs() < 1e-9 && grey.z.abs() < 1e-9, "{grey}");
    }
}
