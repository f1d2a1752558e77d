//! The RGB sky model over `LANES` directions of one lat-long row: the sky image's kernel. It is
//! the second copy of [`SkyModel::rgb_nits_in_row`] (the reference, evaluated per ray), with the
//! same operations in the same order, except that e^x and atan2 are the lane polynomials of
//! [`crate::lanes::math`]; the tests bound the difference.

use glam::Vec3;

use super::hosek::{RgbRow, SkyModel};
use crate::lanes::{F32x16, Vec3x16, math};

impl SkyModel {
    /// [`Self::rgb_nits_in_row`] toward the `LANES` directions (sin theta cos phi, cos theta,
    /// sin theta sin phi) of a row whose factors `row` are, for unit `sun`: lane columns r, g, b.
    #[inline(always)]
    pub(crate) fn rgb_nits_lanes(
        &self,
        row: &RgbRow,
        (sin_t, cos_t): (f32, f32),
        cos_phi: &F32x16,
        sin_phi: &F32x16,
        sun: Vec3,
    ) -> Vec3x16 {
        let mut rgb = Vec3x16::ZERO;
        if !(cos_t > 0.0) {
            return rgb;
        }
        // The direction, cos gamma and |w x sun| as glam's dot, cross and length compute them.
        let w = Vec3x16 { x: sin_t * *cos_phi, y: F32x16::splat(cos_t), z: sin_t * *sin_phi };
        let sun_lanes = Vec3x16::splat(sun);
        let cos_g = w.dot(sun_lanes).map(|v| v.clamp(-1.0, 1.0));
        let gamma = math::atan2_pos(w.cross(sun_lanes).length(), cos_g);
        for ch in 0..3 {
            let [_, _, c, d, e, f, g, i, h] = self.rgb[ch].params;
            let glow = math::exp(e * gamma);
            // ChannelConfig::circumsolar, term for term.
            let x = (1.0 + h * h) - 2.0 * h * cos_g;
            let mie = (1.0 + cos_g * cos_g) / (x * x.sqrt());
            let v = row.dome[ch] * (c + d * glow + f * cos_g * cos_g + g * mie + i * row.sqrt_cos_theta);
            rgb[ch] = v.max(F32x16::ZERO);
        }
        rgb
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::{self, LANES, Level};

    /// The magnitude of F L_M 683's sum of terms in channel `ch` toward `w` (the scalar's angles,
    /// f64): what rounding in the sum is relative to. C + D e^(E gamma) cancels where C ~ -D and E
    /// ~ 0 (the blue channel of a low sun: C = -37.3, D = 37.6), so a relative error of the result
    /// alone would blame the kernel for the scalar model's own cancellation.
    fn magnitude(sky: &SkyModel, row: &RgbRow, ch: usize, w: Vec3, sun: Vec3) -> f64 {
        let cg = w.dot(sun).clamp(-1.0, 1.0);
        let gamma = w.cross(sun).length().atan2(cg) as f64;
        let [_, _, c, d, e, f, g, i, h] = sky.rgb[ch].params.map(f64::from);
        let cg = cg as f64;
        let mie = (1.0 + cg * cg) / (1.0 + h * h - 2.0 * h * cg).powf(1.5);
        let terms = [c, d * (e * gamma).exp(), f * cg * cg, g * mie, i * row.sqrt_cos_theta as f64];
        row.dome[ch] as f64 * terms.iter().map(|t| t.abs()).sum::<f64>()
    }

    /// The kernel against the scalar model over every upper-hemisphere texel of a `width` x
    /// `width / 2` image (directions as the sky image makes them) and the row through the sun, at
    /// every instruction-set level the CPU has: the worst error relative to the texel's largest
    /// channel, and relative to the channel's magnitude (see `magnitude`).
    fn worst_error(sky: &SkyModel, sun: Vec3, width: usize) -> (f64, f64) {
        let height = width / 2;
        let phi = |x: usize| std::f32::consts::TAU * ((x as f32 + 0.5) / width as f32 - 0.5);
        let cos_phi: Vec<f32> = (0..width).map(|x| phi(x).cos()).collect();
        let sin_phi: Vec<f32> = (0..width).map(|x| phi(x).sin()).collect();
        let (mut of_max, mut of_terms, mut compared) = (0.0f64, 0.0f64, 0usize);
        let mut rows: Vec<(f32, f32)> =
            (0..height / 2).map(|y| (std::f32::consts::PI * (y as f32 + 0.5) / height as f32).sin_cos()).collect();
        // The sun's own zenith angle: lanes at and next to gamma = 0.
        rows.push((sun.y.clamp(-1.0, 1.0).acos().sin(), sun.y));
        for &level in Level::ALL {
            let ran = lanes::at_level(
                level,
                #[inline(always)]
                || {
                    for &(sin_t, cos_t) in &rows {
                        let row = sky.rgb_row(cos_t);
                        for k in 0..width / LANES {
                            let b = k * LANES;
                            let mut out = [Vec3::NAN; LANES];
                            let (c, s) = (F32x16::load(&cos_phi, b), F32x16::load(&sin_phi, b));
                            sky.rgb_nits_lanes(&row, (sin_t, cos_t), &c, &s, sun).store_vec3s(&mut out);
                            for l in 0..LANES {
                                let w = Vec3::new(sin_t * c[l], cos_t, sin_t * s[l]);
                                let want = sky.rgb_nits_in_row(&row, w, sun).as_dvec3();
                                let err = (out[l].as_dvec3() - want).abs();
                                let top = want.max_element();
                                assert!(out[l].is_finite(), "{level:?} {w}: {}", out[l]);
                                if top == 0.0 {
                                    assert_eq!(out[l], Vec3::ZERO, "{level:?} {w}: black in the model");
                                    continue;
                                }
                                compared += 1;
                                of_max = of_max.max(err.max_element() / top);
                                for ch in 0..3 {
                                    of_terms = of_terms.max(err[ch] / magnitude(sky, &row, ch, w, sun));
                                }
                            }
                        }
                    }
                },
            );
            assert!(ran.is_some() || level != lanes::level(), "the level in use ran");
        }
        assert!(compared >= width * height / 2, "{compared} texels compared");
        (of_max, of_terms)
    }

    /// Error bounds: 8 f32 ulps (1e-6) of the magnitude of the terms summed, and 1e-4 of the
    /// texel's largest channel (what tests/lights_sunsky_hard.rs allows the image against the
    /// model); measured 3.1e-5 there, from the cancellation `magnitude` describes.
    #[test]
    fn the_lane_sky_equals_the_scalar_model_within_8_ulps_of_its_terms() {
        let mut worst = (0.0f64, 0.0f64);
        // Sun at the horizon (elevation 0), low, mid, high and at the zenith; turbidity 1..10.
        for elevation_deg in [0.0f32, 0.5, 3.0, 15.0, 45.0, 80.0, 90.0] {
            for turbidity in 1..=10 {
                for albedo in [0.0, 0.3, 1.0] {
                    let e = elevation_deg.to_radians();
                    // Azimuth on a column centre of the 256-wide grid (x = 37), so a lane sits on the sun.
                    let phi = std::f32::consts::TAU * ((37.0 + 0.5) / 256.0 - 0.5);
                    let sun = Vec3::new(e.cos() * phi.cos(), e.sin(), e.cos() * phi.sin()).normalize();
                    let sky = SkyModel::new(e, turbidity as f32, albedo);
                    let (a, b) = worst_error(&sky, sun, 256);
                    worst = (worst.0.max(a), worst.1.max(b));
                }
            }
        }
        eprintln!("lane sky vs scalar: worst {:e} of the largest channel, {:e} of the terms", worst.0, worst.1);
        assert!(worst.0 <= 1e-4 && worst.1 <= 1e-6, "{worst:?}");
    }
}
