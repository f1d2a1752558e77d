//! The sun's disc of the sun-and-sky light: Hosek-Wilkie 2013 radiance with limb darkening,
//! photometric RGB as a polynomial in the limb cosine, sampled uniformly in its cone.

use std::f32::consts::PI;

use glam::{DVec3, Vec2, Vec3};

use super::hosek::{self, SunModel};
use crate::light::ColorQuery;
use crate::light::distant::SUN_ANGULAR_DIAMETER;
use crate::sampling::{Frame, sample_uniform_cone_sin2};
use crate::spectrum::SampledSpectrum;
use crate::spectrum::cie::CIE_1931;
use crate::spectrum::color::XYZ_TO_SRGB;
use crate::spectrum::photometry::K_M;

/// The sun's disc: Hosek-Wilkie radiance with limb darkening, sampled uniformly in its cone.
#[derive(Clone, Debug, PartialEq)]
pub struct SunDisc {
    /// Spectral radiance and limb darkening for the sun's elevation and the turbidity.
    pub model: SunModel,
    /// Unit direction toward the disc's centre.
    pub dir: Vec3,
    /// sin^2 and 1 - cos of the disc's angular radius.
    pub sin2_radius: f32,
    /// 1 - cos of the disc's angular radius (see `sin2_radius`).
    pub one_minus_cos: f32,
    /// Radiance factor keeping the illuminance of a sun of [`SUN_ANGULAR_DIAMETER`].
    pub size_factor: f32,
    /// Photometric linear sRGB radiance (nit) as a polynomial in the limb cosine mu:
    /// L(mu) = sum_k `rgb_limb[k]` mu^k (size factor included, `scale` not).
    pub rgb_limb: [Vec3; 6],
    /// Normal illuminance (lx) and irradiance (W/m^2) of the disc, before `scale`.
    pub illuminance: f64,
    /// Normal irradiance of the disc, W/m^2, before `scale` (see `illuminance`).
    pub irradiance: f64,
}

impl SunDisc {
    pub(super) fn new(model: SunModel, dir: Vec3, diameter: f32) -> Self {
        let r = 0.5 * diameter as f64;
        let omega = |r: f64| 4.0 * PI as f64 * (0.5 * r).sin().powi(2);
        let size_factor = omega(0.5 * SUN_ANGULAR_DIAMETER as f64) / omega(r);
        // Per power of mu: the integral of centre(lambda) c_k(lambda) cmf(lambda) over 360-830 nm.
        let mut xyz = [DVec3::ZERO; 6];
        let mut watts = [0.0f64; 6];
        for nm in 360..=830usize {
            let cmf = DVec3::from_array(CIE_1931.at_nm(nm));
            for k in 0..6 {
                let v = limb_term(&model, nm as f32, k);
                xyz[k] += cmf * v;
                watts[k] += v;
            }
        }
        let rgb_limb = xyz.map(|c| (XYZ_TO_SRGB * c * K_M * size_factor).as_vec3());
        // Over the disc, mu^k averages to 2 / (k + 2) (small-disc limit: area element 2 mu dmu).
        let mean = |k: usize| 2.0 / (k as f64 + 2.0);
        let solid_angle = omega(r);
        let illuminance = (0..6).map(|k| xyz[k].y * K_M * mean(k)).sum::<f64>() * solid_angle * size_factor;
        let irradiance = (0..6).map(|k| watts[k] * mean(k)).sum::<f64>() * solid_angle * size_factor;
        Self {
            model,
            dir,
            sin2_radius: r.sin().powi(2) as f32,
            one_minus_cos: (2.0 * (0.5 * r).sin().powi(2)) as f32,
            size_factor: size_factor as f32,
            rgb_limb,
            illuminance,
            irradiance,
        }
    }

    /// Solid angle of the disc, sr.
    pub fn solid_angle(&self) -> f32 {
        2.0 * PI * self.one_minus_cos
    }

    /// sin^2 of the angle between unit `wi` and the disc's centre, None outside the disc (or
    /// behind). f64 cross product as [`crate::light::ResolvedDistant`]; the 1e-4 margin covers the
    /// f32 rounding of sampled directions at the rim.
    fn sin2_in_disc(&self, wi: Vec3) -> Option<f64> {
        let (w, d) = (wi.as_dvec3().normalize(), self.dir.as_dvec3());
        let s2 = w.cross(d).length_squared();
        (w.dot(d) > 0.0 && s2 <= self.sin2_radius as f64 * (1.0 + 1e-4)).then_some(s2)
    }

    /// The limb cosine at sin^2 `s2` from the centre.
    fn mu(&self, s2: f64) -> f32 {
        (1.0 - s2 / self.sin2_radius as f64).max(0.0).sqrt() as f32
    }

    pub(super) fn sample(&self, u: Vec2) -> Vec3 {
        Frame::from_z(self.dir).from_local(sample_uniform_cone_sin2(u, self.sin2_radius)).normalize()
    }

    pub(super) fn pdf(&self, wi: Vec3) -> f32 {
        if self.sin2_in_disc(wi).is_some() { 1.0 / self.solid_angle() } else { 0.0 }
    }

    /// Radiance toward `wi` (zero outside the disc), before `scale`.
    pub(super) fn le(&self, wi: Vec3, query: ColorQuery) -> Option<SampledSpectrum> {
        let mu = self.mu(self.sin2_in_disc(wi)?);
        Some(match query {
            ColorQuery::Rgb => {
                // A low sun is redder than sRGB's gamut: its negative blue is clipped.
                let c = self.rgb_limb.iter().rev().fold(Vec3::ZERO, |acc, &c| acc * mu + c).max(Vec3::ZERO);
                SampledSpectrum([c.x, c.y, c.z, 0.0])
            }
            ColorQuery::Spectral(w) => SampledSpectrum(w.lambda.map(|l| self.model.spectral(l, mu) * self.size_factor)),
        })
    }
}

/// centre(lambda) times the mu^k coefficient of limb darkening at `lambda`: the k-th term of
/// [`SunModel::spectral`].
fn limb_term(model: &SunModel, lambda: f32, k: usize) -> f64 {
    let (i, f) = hosek::wavelength_cell(lambda);
    let lerp = |a: f32, b: f32| (a + f * (b - a)) as f64;
    lerp(model.radiance[i], model.radiance[i + 1]) * lerp(model.limb[i][k], model.limb[i + 1][k])
}
