//! Colour spaces: CIE XYZ, xyY, CIE 1976 u'v' and 1960 uv, linear sRGB (Rec. 709) and ACEScg.

use glam::{DMat3, DVec3};

/// Chromaticity of the D65 white point (CIE 015:2018, 4 digits as sRGB uses).
pub const D65_XY: [f64; 2] = [0.3127, 0.3290];
/// Chromaticity of the ACES white point (SMPTE ST 2065-1).
pub const ACES_WHITE_XY: [f64; 2] = [0.32168, 0.33767];

/// Linear sRGB (D65) to XYZ, IEC 61966-2-1 primaries (columns are the primaries' XYZ).
pub const SRGB_TO_XYZ: DMat3 = DMat3::from_cols_array(&[
    0.4124564, 0.2126729, 0.0193339, //
    0.3575761, 0.7151522, 0.1191920, //
    0.1804375, 0.0721750, 0.9503041,
]);
/// XYZ to linear sRGB (D65), the inverse of [`SRGB_TO_XYZ`].
pub const XYZ_TO_SRGB: DMat3 = DMat3::from_cols_array(&[
    3.2404542, -0.9692660, 0.0556434, //
    -1.5371385, 1.8760108, -0.2040259, //
    -0.4985314, 0.0415560, 1.0572252,
]);
/// ACES AP1 (ACEScg) to XYZ relative to the ACES white (ACES TB-2014-004).
pub const AP1_TO_XYZ: DMat3 = DMat3::from_cols_array(&[
    0.6624541811,
    0.2722287168,
    -0.0055746495, //
    0.1340042065,
    0.6740817658,
    0.0040607335, //
    0.1561876870,
    0.0536895174,
    1.0103391003,
]);

/// xy chromaticity and luminance Y from XYZ. A black XYZ maps to the D65 chromaticity.
pub fn xyz_to_xyy(xyz: DVec3) -> DVec3 {
    let s = xyz.x + xyz.y + xyz.z;
    if s.abs() < 1e-300 || !s.is_finite() {
        return DVec3::new(D65_XY[0], D65_XY[1], 0.0);
    }
    DVec3::new(xyz.x / s, xyz.y / s, xyz.y)
}

/// XYZ from xy chromaticity and luminance Y. y = 0 gives black.
pub fn xyy_to_xyz(xyy: DVec3) -> DVec3 {
    let (x, y, lum) = (xyy.x, xyy.y, xyy.z);
    if y.abs() < 1e-300 {
        return DVec3::ZERO;
    }
    DVec3::new(x * lum / y, lum, (1.0 - x - y) * lum / y)
}

/// CIE 1976 u'v' from xy.
pub fn xy_to_uv_prime([x, y]: [f64; 2]) -> [f64; 2] {
    let d = -2.0 * x + 12.0 * y + 3.0;
    [4.0 * x / d, 9.0 * y / d]
}

/// xy from CIE 1976 u'v'.
pub fn uv_prime_to_xy([u, v]: [f64; 2]) -> [f64; 2] {
    let d = 6.0 * u - 16.0 * v + 12.0;
    [9.0 * u / d, 4.0 * v / d]
}

/// CIE 1960 uv (used for CCT and Duv) from xy: u = u', v = 2/3 v'.
pub fn xy_to_uv1960(xy: [f64; 2]) -> [f64; 2] {
    let [u, v] = xy_to_uv_prime(xy);
    [u, v * 2.0 / 3.0]
}

/// xy from CIE 1960 uv.
pub fn uv1960_to_xy([u, v]: [f64; 2]) -> [f64; 2] {
    uv_prime_to_xy([u, v * 1.5])
}

/// Linear sRGB from XYZ (same white, no adaptation).
pub fn xyz_to_srgb(xyz: DVec3) -> DVec3 {
    XYZ_TO_SRGB * xyz
}

/// XYZ from linear sRGB.
pub fn srgb_to_xyz(rgb: DVec3) -> DVec3 {
    SRGB_TO_XYZ * rgb
}

/// Bradford chromatic adaptation from white `src` to white `dst` (xy chromaticities).
pub fn bradford(src: [f64; 2], dst: [f64; 2]) -> DMat3 {
    // Bradford cone response matrix (Lam 1985), rows as published.
    let m = DMat3::from_cols_array(&[0.8951, -0.7502, 0.0389, 0.2664, 1.7135, -0.0685, -0.1614, 0.0367, 1.0296]);
    let cone = |xy: [f64; 2]| m * xyy_to_xyz(DVec3::new(xy[0], xy[1], 1.0));
    let (s, d) = (cone(src), cone(dst));
    m.inverse() * DMat3::from_diagonal(d / s) * m
}

/// ACEScg (AP1 primaries) from XYZ whose white is D65, adapted to the ACES white by Bradford.
pub fn xyz_to_acescg(xyz: DVec3) -> DVec3 {
    AP1_TO_XYZ.inverse() * bradford(D65_XY, ACES_WHITE_XY) * xyz
}

/// XYZ (white D65) from ACEScg, the inverse of [`xyz_to_acescg`].
pub fn acescg_to_xyz(rgb: DVec3) -> DVec3 {
    bradford(ACES_WHITE_XY, D65_XY) * AP1_TO_XYZ * rgb
}

/// sRGB transfer function (IEC 61966-2-1) for one linear channel, clamped to [0, 1].
pub fn srgb_encode(linear: f64) -> f64 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}
