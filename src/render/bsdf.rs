//! The glTF metallic-roughness BSDF: Lambertian diffuse plus a GGX microfacet lobe, mixed as the
//! glTF 2.0 specification's appendix B describes (dielectric Fresnel mix, conductor Fresnel
//! tinted by the base colour). Works on 4-lane values: RGB (lanes 0-2) or 4 sampled wavelengths.
//!
//! A dielectric whose F0 is 0 (KHR_materials_specular factor 0, or KHR_materials_ior = 1) has no
//! specular lobe at all: that is how a glTF file says "pure Lambertian". (Schlick's grazing term
//! is dropped with it, since a surface of ior 1 reflects nothing.)

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};

use crate::sampling::{Frame, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::SampledSpectrum;

/// Smallest GGX alpha, to keep the distribution finite for roughness 0.
const MIN_ALPHA: f32 = 1e-3;

/// A BSDF at one surface point, in its shading frame (z = shading normal).
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    pub frame: Frame,
    /// Base colour (albedo for dielectrics, F0 for metals).
    pub base: SampledSpectrum,
    pub metallic: f32,
    /// Dielectric reflectance at normal incidence times the specular factor; 0 = no lobe.
    pub dielectric_f0: f32,
    /// GGX alpha = roughness^2.
    pub alpha: f32,
}

/// A sampled direction with its BSDF value and pdf (solid angle).
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f: SampledSpectrum,
    pub pdf: f32,
}

fn schlick(f0: f32, cos: f32) -> f32 {
    f0 + (1.0 - f0) * (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

fn ggx_d(cos_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let c2 = cos_h * cos_h;
    let d = c2 * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Height-correlated Smith visibility G / (4 cos_i cos_o) for GGX (Heitz 2014).
fn smith_v(cos_i: f32, cos_o: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = cos_i * (cos_o * cos_o * (1.0 - a2) + a2).sqrt();
    let gl = cos_o * (cos_i * cos_i * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-12)
}

impl Bsdf {
    /// A BSDF from glTF parameters; `roughness` is perceptual (alpha = roughness^2).
    pub fn new(frame: Frame, base: SampledSpectrum, metallic: f32, roughness: f32, dielectric_f0: f32) -> Self {
        let r = roughness.clamp(0.0, 1.0);
        Self {
            frame,
            base,
            metallic: metallic.clamp(0.0, 1.0),
            dielectric_f0: dielectric_f0.clamp(0.0, 1.0),
            alpha: (r * r).max(MIN_ALPHA),
        }
    }

    /// True when there is a specular lobe.
    pub fn has_specular(&self) -> bool {
        self.metallic > 0.0 || self.dielectric_f0 > 0.0
    }

    /// Probability of sampling the specular lobe.
    fn specular_probability(&self) -> f32 {
        if !self.has_specular() {
            return 0.0;
        }
        let lum = (self.base.0[0] + self.base.0[1] + self.base.0[2]) / 3.0;
        let w_spec = self.metallic + (1.0 - self.metallic) * (4.0 * self.dielectric_f0).min(1.0);
        let w_diff = (1.0 - self.metallic) * lum.max(0.0);
        if w_spec + w_diff > 0.0 { (w_spec / (w_spec + w_diff)).clamp(0.05, 0.95) } else { 0.5 }
    }

    /// BSDF value for world directions `wo` (toward the viewer) and `wi` (toward the light).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if !self.has_specular() {
            // Lambertian: only the two cosines matter (each the z of `to_local`).
            let n = self.frame.z;
            let upper = wo.dot(n) > 0.0 && wi.dot(n) > 0.0;
            return if upper { self.base.scale(FRAC_1_PI) } else { SampledSpectrum::default() };
        }
        let (o, i) = (self.frame.to_local(wo), self.frame.to_local(wi));
        self.f_local(o, i)
    }

    fn f_local(&self, o: Vec3, i: Vec3) -> SampledSpectrum {
        if o.z <= 0.0 || i.z <= 0.0 {
            return SampledSpectrum::default();
        }
        let m = self.metallic;
        if !self.has_specular() {
            return self.base.scale(FRAC_1_PI);
        }
        let h = (o + i).normalize();
        let cos_oh = o.dot(h).max(0.0);
        let fd = if self.dielectric_f0 > 0.0 { schlick(self.dielectric_f0, cos_oh) } else { 0.0 };
        let dv = ggx_d(h.z, self.alpha) * smith_v(i.z, o.z, self.alpha);
        let fresnel_tail = (1.0 - cos_oh).clamp(0.0, 1.0).powi(5);
        SampledSpectrum(std::array::from_fn(|k| {
            let base = self.base.0[k];
            let diffuse = (1.0 - m) * (1.0 - fd) * base * FRAC_1_PI;
            let metal_f = base + (1.0 - base) * fresnel_tail;
            diffuse + dv * ((1.0 - m) * fd + m * metal_f)
        }))
    }

    /// Solid-angle pdf of `sample` returning `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !self.has_specular() {
            let (cos_o, cos_i) = (wo.dot(self.frame.z), wi.dot(self.frame.z));
            return if cos_o > 0.0 && cos_i > 0.0 { cosine_hemisphere_pdf(cos_i) } else { 0.0 };
        }
        let (o, i) = (self.frame.to_local(wo), self.frame.to_local(wi));
        self.pdf_local(o, i)
    }

    fn pdf_local(&self, o: Vec3, i: Vec3) -> f32 {
        if o.z <= 0.0 || i.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability();
        let diffuse = cosine_hemisphere_pdf(i.z);
        if ps == 0.0 {
            return diffuse;
        }
        let h = (o + i).normalize();
        let spec = ggx_d(h.z, self.alpha) * h.z / (4.0 * o.dot(h).max(1e-12));
        ps * spec + (1.0 - ps) * diffuse
    }

    /// Samples a direction: the specular lobe (GGX normals, D cos(theta_h)) or the diffuse one
    /// (cosine), chosen with `u_lobe`. None below the surface or for a failed sample.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let o = self.frame.to_local(wo);
        if o.z <= 0.0 {
            return None;
        }
        let ps = self.specular_probability();
        let i = if u_lobe < ps {
            let a2 = self.alpha * self.alpha;
            let tan2 = a2 * u.x / (1.0 - u.x).max(1e-12);
            let cos_h = 1.0 / (1.0 + tan2).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let h = Vec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            2.0 * o.dot(h) * h - o
        } else {
            sample_cosine_hemisphere(u)
        };
        if i.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf_local(o, i);
        (pdf > 0.0).then(|| BsdfSample { wi: self.frame.from_local(i), f: self.f_local(o, i), pdf })
    }
}
