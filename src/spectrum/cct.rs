//! Correlated colour temperature: CCT -> xy on the Planckian and daylight loci, and xy or a
//! spectrum -> (CCT, Duv) by Ohno's (2013) combined triangular / parabolic method on a fine
//! Planckian table (0.1% steps, 1000 K to 100000 K). Measured accuracy: see tests/spectrum_cct.rs.

use std::sync::LazyLock;

use glam::DVec3;

use super::{CIE_1931, Spectrum, SpectrumError, color, planck};

/// Lowest and highest temperature of the Planckian table, K.
pub const CCT_RANGE_K: (f64, f64) = (1000.0, 100_000.0);
const TABLE_RATIO: f64 = 1.001;

/// xy of a blackbody at `t_k` (CIE 1931 2-degree observer, 1 nm integration 360-830 nm).
pub fn planckian_xy(t_k: f64) -> [f64; 2] {
    let xyz: DVec3 =
        (360..=830usize).map(|nm| DVec3::from_array(CIE_1931.at_nm(nm)) * planck::planck(nm as f64, t_k)).sum();
    let v = color::xyz_to_xyy(xyz);
    [v.x, v.y]
}

/// xy on the CIE daylight locus at `t_k` (4000-25000 K).
pub fn daylight_xy(t_k: f64) -> Result<[f64; 2], SpectrumError> {
    super::cie::daylight_xy(t_k)
}

struct PlanckTable {
    t: Vec<f64>,
    uv: Vec<[f64; 2]>,
}

static TABLE: LazyLock<PlanckTable> = LazyLock::new(|| {
    let mut t = Vec::new();
    // One percent of margin on both sides so the ends of the stated range have neighbours.
    let mut k = CCT_RANGE_K.0 / 1.01;
    while k <= CCT_RANGE_K.1 * 1.01 {
        t.push(k);
        k *= TABLE_RATIO;
    }
    let uv = t.iter().map(|&k| color::xy_to_uv1960(planckian_xy(k))).collect();
    PlanckTable { t, uv }
});

/// Correlated colour temperature (K) and Duv (signed distance from the Planckian locus in CIE
/// 1960 uv, positive above it) of a chromaticity, by Ohno 2013.
pub fn cct_duv_from_xy(xy: [f64; 2]) -> Result<(f64, f64), SpectrumError> {
    let [u, v] = color::xy_to_uv1960(xy);
    if !(u.is_finite() && v.is_finite()) {
        return Err(SpectrumError::out_of_range("chromaticity x", xy[0], 0.0, 1.0));
    }
    let tab = &*TABLE;
    let dist = |i: usize| ((u - tab.uv[i][0]).powi(2) + (v - tab.uv[i][1]).powi(2)).sqrt();
    let m = (0..tab.t.len()).min_by(|&a, &b| dist(a).total_cmp(&dist(b))).expect("table is not empty");
    if m == 0 || m + 1 == tab.t.len() {
        let t = tab.t[m];
        return Err(SpectrumError::out_of_range("CCT (K)", t, CCT_RANGE_K.0, CCT_RANGE_K.1));
    }
    let (p, n) = (m - 1, m + 1);
    let (dp, dm, dn) = (dist(p), dist(m), dist(n));
    let (tp, tm, tn) = (tab.t[p], tab.t[m], tab.t[n]);
    // Triangular solution (Ohno 2013, eqs. 4-7).
    let l = ((tab.uv[n][0] - tab.uv[p][0]).powi(2) + (tab.uv[n][1] - tab.uv[p][1]).powi(2)).sqrt();
    let x = (dp * dp - dn * dn + l * l) / (2.0 * l);
    let t_tri = tp + (tn - tp) * x / l;
    let v_tx = tab.uv[p][1] + (tab.uv[n][1] - tab.uv[p][1]) * x / l;
    let sign = if v - v_tx >= 0.0 { 1.0 } else { -1.0 };
    let duv_tri = (dp * dp - x * x).max(0.0).sqrt() * sign;
    if duv_tri.abs() < 0.002 {
        return in_range((t_tri, duv_tri));
    }
    // Parabolic solution (Ohno 2013, eqs. 8-12) away from the locus.
    let big_x = (tn - tm) * (tp - tn) * (tm - tp);
    let a = (tp * (dn - dm) + tm * (dp - dn) + tn * (dm - dp)) / big_x;
    let b = -(tp * tp * (dn - dm) + tm * tm * (dp - dn) + tn * tn * (dm - dp)) / big_x;
    let c = -(dp * (tn - tm) * tm * tn + dm * (tp - tn) * tp * tn + dn * (tm - tp) * tp * tm) / big_x;
    let t = -b / (2.0 * a);
    in_range((t, sign * (a * t * t + b * t + c)))
}

fn in_range((t, duv): (f64, f64)) -> Result<(f64, f64), SpectrumError> {
    if (CCT_RANGE_K.0 * (1.0 - 1e-9)..=CCT_RANGE_K.1 * (1.0 + 1e-9)).contains(&t) {
        Ok((t, duv))
    } else {
        Err(SpectrumError::out_of_range("CCT (K)", t, CCT_RANGE_K.0, CCT_RANGE_K.1))
    }
}

/// CCT (K) and Duv of a spectrum's colour.
pub fn cct_duv(spectrum: &Spectrum) -> Result<(f64, f64), SpectrumError> {
    cct_duv_from_xy(spectrum.xy())
}
