//! The candela distribution: symmetry unfolding, bilinear interpolation, directions in the light's
//! local frame (see the module docs of [`super`]), total flux, beam and field angles, and the
//! equal-area image a goniometric light samples.

use std::f64::consts::{FRAC_PI_4, TAU};

use glam::{DVec3, Vec3};

use super::{Grid, IesProfile, PhotometricType, Symmetry};

/// Samples around a great circle when measuring beam and field angles (0.05 degree steps).
const SPREAD_SAMPLES: usize = 7200;

impl IesProfile {
    /// Intensity in cd at the file's own angles, in degrees: for type C vertical angle gamma from nadir
    /// and horizontal angle C; for types A/B V and H. Any angle is accepted: it is wrapped onto the
    /// sphere, unfolded by the file's symmetry and bilinearly interpolated; unmeasured directions give 0.
    pub fn candela(&self, vertical_deg: f64, horizontal_deg: f64) -> f64 {
        self.grid.eval(vertical_deg, horizontal_deg)
    }

    /// Intensity in cd toward `local`, a direction in the light's local frame (need not be
    /// normalised; zero or non-finite vectors give 0).
    pub fn candela_dir(&self, local: Vec3) -> f64 {
        self.grid.eval_dir(local.as_dvec3())
    }

    /// The unit direction in the light's local frame for the file's angles (degrees); the inverse of
    /// what [`IesProfile::candela_dir`] does.
    pub fn direction(&self, vertical_deg: f64, horizontal_deg: f64) -> Vec3 {
        let (sv, cv) = vertical_deg.to_radians().sin_cos();
        let (sh, ch) = horizontal_deg.to_radians().sin_cos();
        let d = match self.grid.kind {
            PhotometricType::C => DVec3::new(sv * ch, sv * sh, -cv),
            PhotometricType::B => DVec3::new(cv * sh, sv, -cv * ch),
            PhotometricType::A => DVec3::new(sv, -cv * sh, -cv * ch),
        };
        d.as_vec3()
    }

    /// Largest candela value of the grid.
    pub fn max_candela(&self) -> f64 {
        self.grid.cd.iter().copied().fold(0.0, f64::max)
    }

    /// Total luminous flux in lm: the integral of the bilinear interpolant over the sphere, exactly
    /// (each cell's sine-weighted integral in closed form), with the symmetry's copies counted.
    pub fn integrated_flux_lm(&self) -> f64 {
        self.grid.flux()
    }

    /// Intensity along the great circle through nadir (local -Z) and the local direction at
    /// `azimuth_deg` around Z (0: the local XZ plane, type C's C0-C180 plane; 90: the YZ plane):
    /// `steps + 1` points (theta in degrees from -180 to 180, cd), positive theta on the azimuth side.
    pub fn plane_curve(&self, azimuth_deg: f64, steps: usize) -> Vec<(f64, f64)> {
        let steps = steps.max(1);
        (0..=steps)
            .map(|k| {
                let theta = -180.0 + 360.0 * k as f64 / steps as f64;
                (theta, self.grid.eval_dir(plane_direction(azimuth_deg, theta)))
            })
            .collect()
    }

    /// Full angle in degrees of the lobe around the brightest direction of the great circle of
    /// [`IesProfile::plane_curve`] where the intensity stays at or above `fraction` of that circle's
    /// maximum (the IES/NEMA convention; CIE uses the centre-beam intensity instead). None when the
    /// circle is dark or the intensity never falls below `fraction` of its maximum.
    pub fn spread_angle_deg(&self, azimuth_deg: f64, fraction: f64) -> Option<f64> {
        let n = SPREAD_SAMPLES;
        let step = 360.0 / n as f64;
        let values: Vec<f64> =
            (0..n).map(|k| self.grid.eval_dir(plane_direction(azimuth_deg, k as f64 * step))).collect();
        let (peak, max) =
            values.iter().copied().enumerate().fold((0, 0.0), |a, (k, x)| if x > a.1 { (k, x) } else { a });
        if max <= 0.0 {
            return None;
        }
        let threshold = fraction * max;
        // Walks from the peak one way until the intensity drops below the threshold.
        let half_width = |dir: isize| -> Option<f64> {
            let at = |s: usize| values[(peak as isize + dir * s as isize).rem_euclid(n as isize) as usize];
            (1..n).find(|&s| at(s) < threshold).map(|s| {
                let (a, b) = (at(s - 1), at(s));
                (s as f64 - 1.0 + (a - threshold) / (a - b)) * step
            })
        };
        Some(half_width(1)? + half_width(-1)?)
    }

    /// Beam angle in degrees: the full angle in the C0-C180 plane (local XZ) where the intensity is
    /// at least 50% of the maximum in that plane. See [`IesProfile::spread_angle_deg`].
    pub fn beam_angle_deg(&self) -> Option<f64> {
        self.spread_angle_deg(0.0, 0.5)
    }

    /// Field angle in degrees: as [`IesProfile::beam_angle_deg`] at 10% of the maximum.
    pub fn field_angle_deg(&self) -> Option<f64> {
        self.spread_angle_deg(0.0, 0.1)
    }

    /// `resolution`^2 intensities (cd), row-major, on the Clarberg equal-area octahedral square:
    /// pixel (i, j) at index `j * resolution + i` holds the candela toward
    /// `equal_area_square_to_sphere((i + 0.5) / resolution, (j + 0.5) / resolution)` in the light's
    /// local frame. Every pixel covers the same solid angle, 4 pi / resolution^2 sr. Empty when
    /// resolution^2 overflows.
    pub fn to_equal_area_image(&self, resolution: usize) -> Vec<f32> {
        let Some(pixels) = resolution.checked_mul(resolution) else { return Vec::new() };
        let inv = 1.0 / resolution as f64;
        let mut image = Vec::with_capacity(pixels);
        for j in 0..resolution {
            for i in 0..resolution {
                let d = equal_area_square_to_sphere((i as f64 + 0.5) * inv, (j as f64 + 0.5) * inv);
                image.push(self.grid.eval_dir(d) as f32);
            }
        }
        image
    }
}

/// Direction at `theta_deg` from nadir toward azimuth `azimuth_deg` (negative theta: the other side).
fn plane_direction(azimuth_deg: f64, theta_deg: f64) -> DVec3 {
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    DVec3::new(st * ca, st * sa, -ct)
}

/// Clarberg's equal-area map from the unit square to the sphere (Clarberg 2008, "Fast Equal-Area
/// Mapping of the (Hemi)Sphere using SIMD"; pbrt-v4 section 3.8.3): the centre is +Z, the corners -Z.
// TODO: switch to `crate::sampling::equal_area_square_to_sphere` once src/sampling/warp.rs lands.
fn equal_area_square_to_sphere(u: f64, v: f64) -> DVec3 {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    // Signed distance from the diamond |a| + |b| = 1: positive inside (upper hemisphere).
    let signed = 1.0 - (a.abs() + b.abs());
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 1.0 } else { (b.abs() - a.abs()) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(phi.cos().copysign(a) * s, phi.sin().copysign(b) * s, z)
}

/// Weights (wa, wb) with `integral over [x0, x1] of sin x * lerp(fa, fb) dx = wa fa + wb fb` (radians):
/// the closed-form sine-weighted integral of a linear function, by parts.
fn sin_lerp_weights(x0: f64, x1: f64) -> (f64, f64) {
    let dx = x1 - x0;
    if dx <= 0.0 {
        return (0.0, 0.0);
    }
    let mean_cos = (x1.sin() - x0.sin()) / dx;
    (x0.cos() - mean_cos, mean_cos - x1.cos())
}

/// Index `i` and fraction `t` with `x = lerp(axis[i], axis[i + 1], t)`, or None outside the axis.
fn locate(axis: &[f64], x: f64) -> Option<(usize, f64)> {
    let (first, last) = (*axis.first()?, *axis.last()?);
    const EPS: f64 = 1e-9;
    if !(x >= first - EPS && x <= last + EPS) || axis.len() < 2 {
        return None;
    }
    let i = axis.partition_point(|&a| a <= x).clamp(1, axis.len() - 1) - 1;
    let (a, b) = (axis[i], axis[i + 1]);
    Some((i, ((x - a) / (b - a)).clamp(0.0, 1.0)))
}

impl Grid {
    fn value(&self, h: usize, v: usize) -> f64 {
        self.cd.get(h * self.v_deg.len() + v).copied().unwrap_or(0.0)
    }

    /// Candela at any (vertical, horizontal) pair in the file's convention, degrees.
    fn eval(&self, vertical_deg: f64, horizontal_deg: f64) -> f64 {
        if !(vertical_deg.is_finite() && horizontal_deg.is_finite()) {
            return 0.0;
        }
        let (v, h) = match self.kind {
            PhotometricType::C => unfold_c(self.symmetry, vertical_deg, horizontal_deg),
            PhotometricType::A | PhotometricType::B => unfold_ab(self.symmetry, vertical_deg, horizontal_deg),
        };
        let Some((vi, vt)) = locate(&self.v_deg, v) else { return 0.0 };
        let column = |hi: usize| self.value(hi, vi) * (1.0 - vt) + self.value(hi, vi + 1) * vt;
        if self.symmetry == Symmetry::Rotational {
            return column(0);
        }
        if let Some((hi, ht)) = locate(&self.h_deg, h) {
            return column(hi) * (1.0 - ht) + column(hi + 1) * ht;
        }
        // Type C full data ending before 360: interpolate from the last angle back to 0 (= 360).
        let last = self.h_deg.len() - 1;
        let gap = 360.0 - self.h_deg[last];
        if self.kind == PhotometricType::C && self.symmetry == Symmetry::Full && h > self.h_deg[last] && gap > 0.0 {
            let t = ((h - self.h_deg[last]) / gap).clamp(0.0, 1.0);
            return column(last) * (1.0 - t) + column(0) * t;
        }
        0.0
    }

    /// Candela toward `d` in the light's local frame.
    fn eval_dir(&self, d: DVec3) -> f64 {
        let len = d.length();
        if !(len > 0.0 && len.is_finite()) {
            return 0.0;
        }
        let d = d / len;
        let (v, h) = match self.kind {
            PhotometricType::C => (d.x.hypot(d.y).atan2(-d.z), d.y.atan2(d.x)),
            PhotometricType::B => (d.y.atan2(d.x.hypot(d.z)), d.x.atan2(-d.z)),
            PhotometricType::A => (d.x.atan2(d.y.hypot(d.z)), (-d.y).atan2(-d.z)),
        };
        self.eval(v.to_degrees(), h.to_degrees())
    }

    /// Exact integral of the bilinear interpolant over the sphere (lm), copies included.
    fn flux(&self) -> f64 {
        // Type C's vertical angle is a polar angle (weight sin); A/B's V is a latitude, and
        // cos V = sin(V + 90), so shift it by 90 degrees and use the same weights.
        let offset = if self.kind == PhotometricType::C { 0.0 } else { 90.0 };
        let weights: Vec<(f64, f64)> = self
            .v_deg
            .windows(2)
            .map(|w| sin_lerp_weights((w[0] + offset).to_radians(), (w[1] + offset).to_radians()))
            .collect();
        // Integral over the vertical angle of each horizontal angle's column.
        let column = |hi: usize| -> f64 {
            weights.iter().enumerate().map(|(vi, (wa, wb))| wa * self.value(hi, vi) + wb * self.value(hi, vi + 1)).sum()
        };
        if self.symmetry == Symmetry::Rotational {
            return TAU * column(0);
        }
        let columns: Vec<f64> = (0..self.h_deg.len()).map(column).collect();
        let mut sum: f64 = self
            .h_deg
            .windows(2)
            .zip(columns.windows(2))
            .map(|(h, c)| (h[1] - h[0]).to_radians() * 0.5 * (c[0] + c[1]))
            .sum();
        let last = self.h_deg.len() - 1;
        if self.kind == PhotometricType::C && self.symmetry == Symmetry::Full && self.h_deg[last] < 360.0 {
            sum += (360.0 - self.h_deg[last]).to_radians() * 0.5 * (columns[last] + columns[0]);
        }
        let copies = match self.symmetry {
            Symmetry::Quadrant | Symmetry::LateralAndVertical => 4.0,
            Symmetry::BilateralC0C180 | Symmetry::BilateralC90C270 | Symmetry::Lateral | Symmetry::Vertical => 2.0,
            Symmetry::Full | Symmetry::Rotational => 1.0,
        };
        copies * sum
    }
}

/// Type C: wraps (gamma, C) onto gamma in [0, 180], C in [0, 360), then folds C into the measured range.
fn unfold_c(symmetry: Symmetry, gamma: f64, c: f64) -> (f64, f64) {
    let mut g = gamma.rem_euclid(360.0);
    let mut c = c;
    if g > 180.0 {
        g = 360.0 - g;
        c += 180.0;
    }
    let c = c.rem_euclid(360.0);
    let c = match symmetry {
        Symmetry::Quadrant => {
            let c = if c > 180.0 { 360.0 - c } else { c };
            if c > 90.0 { 180.0 - c } else { c }
        }
        Symmetry::BilateralC0C180 => {
            if c > 180.0 {
                360.0 - c
            } else {
                c
            }
        }
        // Mirror about the 90-270 line: C -> 180 - C.
        Symmetry::BilateralC90C270 => {
            if c < 90.0 {
                180.0 - c
            } else if c > 270.0 {
                540.0 - c
            } else {
                c
            }
        }
        _ => c,
    };
    (g, c)
}

/// Types A/B: wraps (V, H) onto V in [-90, 90], H in [-180, 180), then mirrors the symmetric halves.
fn unfold_ab(symmetry: Symmetry, v: f64, h: f64) -> (f64, f64) {
    let mut v = (v + 90.0).rem_euclid(360.0) - 90.0;
    let mut h = h;
    if v > 90.0 {
        // Past the pole: the same latitude on the opposite half-plane.
        v = 180.0 - v;
        h += 180.0;
    }
    let h = (h + 180.0).rem_euclid(360.0) - 180.0;
    match symmetry {
        Symmetry::Lateral => (v, h.abs()),
        Symmetry::Vertical => (v.abs(), h),
        Symmetry::LateralAndVertical => (v.abs(), h.abs()),
        _ => (v, h),
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn sin_weights_integrate_linear_functions_exactly() {
        // integral_0^{pi/2} sin x dx = 1; integral_0^{pi/2} x sin x dx = 1.
        let (wa, wb) = sin_lerp_weights(0.0, PI / 2.0);
        assert!((wa + wb - 1.0).abs() < 1e-12);
        assert!((wb * PI / 2.0 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn equal_area_map_is_unit_and_covers_poles() {
        assert!((equal_area_square_to_sphere(0.5, 0.5) - DVec3::Z).length() < 1e-12);
        assert!((equal_area_square_to_sphere(0.0, 0.0) + DVec3::Z).length() < 1e-12);
        for k in 0..100 {
            let (u, v) = ((k as f64 * 0.618_034).fract(), (k as f64 * 0.414_214).fract());
            assert!((equal_area_square_to_sphere(u, v).length() - 1.0).abs() < 1e-12);
        }
    }
}
