//! The glTF metallic-roughness BSDF: Lambertian diffuse plus a GGX microfacet lobe, mixed as the
//! glTF 2.0 specification's appendix B describes (dielectric Fresnel mix, conductor Fresnel
//! tinted by the base colour). Works on 4-lane values: RGB (lanes 0-2) or 4 sampled wavelengths.
//!
//! A dielectric whose F0 is 0 (KHR_materials_specular factor 0, or KHR_materials_ior = 1) has no
//! specular lobe at all: that is how a glTF file says "pure Lambertian". (Schlick's grazing term
//! is dropped with it, since a surface of ior 1 reflects nothing.)
//!
//! The specular lobe samples visible normals (Dupuy and Benyoub 2023, "Sampling Visible GGX
//! Normals with Spherical Caps"), and shading normals are bent so that the view is never below
//! them (`bent_shading_normal`).

use std::f32::consts::{FRAC_1_PI, PI, TAU};

use glam::{Vec2, Vec3};

use crate::lanes::{Real, Vector};
use crate::sampling::{Frame, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::spectrum::SampledSpectrum;

/// Smallest GGX alpha, to keep the distribution finite for roughness 0.
const MIN_ALPHA: f32 = 1e-3;

/// A BSDF at one surface point, in its shading frame (z = shading normal).
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// The shading frame, world space; its z is the shading normal.
    pub frame: Frame,
    /// Base colour (albedo for dielectrics, F0 for metals).
    pub base: SampledSpectrum,
    /// Metalness in [0, 1]: 0 a dielectric, 1 a conductor, blends between.
    pub metallic: f32,
    /// Dielectric reflectance at normal incidence times the specular factor; 0 = no lobe.
    pub dielectric_f0: f32,
    /// Dielectric reflectance at grazing incidence: KHR_materials_specular's factor (1 without it).
    pub dielectric_f90: f32,
    /// GGX alpha = roughness^2.
    pub alpha: f32,
}

/// A sampled direction with its BSDF value and pdf (solid angle).
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The sampled direction toward the light, world space, unit length.
    pub wi: Vec3,
    /// BSDF value for `wi` (per steradian; no cosine factor).
    pub f: SampledSpectrum,
    /// Solid-angle pdf of `wi`, per steradian; always positive.
    pub pdf: f32,
}

fn schlick(f0: f32, f90: f32, cos: f32) -> f32 {
    f0 + (f90 - f0) * (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// GGX's D at the local half vector `h`; 1 + cos^2 (a^2 - 1) is summed as sin^2 + cos^2 a^2,
/// which keeps its precision at the peak of a sharp lobe (in f32, 1 - cos^2 cancels to 0 there).
fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (h.x * h.x + h.y * h.y) + h.z * h.z * a2;
    a2 / (PI * d * d)
}

/// Height-correlated Smith visibility G / (4 cos_i cos_o) for GGX (Heitz 2014).
fn smith_v(cos_i: f32, cos_o: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = cos_i * (cos_o * cos_o * (1.0 - a2) + a2).sqrt();
    let gl = cos_o * (cos_i * cos_i * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-12)
}

/// Smith's masking G1 for GGX toward a direction with cosine `cos` to the normal (Heitz 2014).
fn smith_g1(cos: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * cos / (cos + (a2 + (1.0 - a2) * cos * cos).sqrt())
}

/// A GGX normal visible from `o` (local, o.z > 0), drawn with density D_o(h) = G1(o) (o.h) D(h) /
/// o.z by Dupuy and Benyoub's spherical cap: in the configuration stretched to alpha 1, visible
/// normals are o plus a point uniform on the unit sphere's cap z > -o.z.
fn sample_visible_normal(o: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let o_std = Vec3::new(o.x * alpha, o.y * alpha, o.z).normalize();
    let z = (1.0 - u.y) * (1.0 + o_std.z) - o_std.z;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (TAU * u.x).sin_cos();
    let h_std = Vec3::new(r * cos, r * sin, z) + o_std;
    Vec3::new(h_std.x * alpha, h_std.y * alpha, h_std.z).normalize_or_zero()
}

/// The shading normal `ns` bent toward the geometric normal `ng` (facing the viewer `wo`) just as
/// far as needed for the mirror direction of `wo` about it to leave the surface at a cosine of at
/// least min(0.9 wo.ng, 0.01) to `ng`: the threshold of Cycles' `ensure_valid_specular_reflection`.
/// `wo` is then above the shading hemisphere too, so a smooth or normal-mapped surface seen at a
/// grazing angle is shaded, not black. Unchanged where the mirror direction already leaves.
pub fn bent_shading_normal(ns: Vec3, ng: Vec3, wo: Vec3) -> Vec3 {
    if shading_normal_stands(ns, ng, wo) {
        return ns;
    }
    let iz = wo.dot(ng);
    let threshold = (0.9 * iz).min(0.01);
    // In the plane of ng and ns, n(t) = sin t x + cos t ng reflects wo to a cosine of
    // 2 (n.wo)(n.ng) - iz = a cos(2t - phi) with ng: solve for the threshold, keep the root
    // nearer the original normal.
    let x = (ns - ng * ns.dot(ng)).normalize_or_zero();
    if x == Vec3::ZERO {
        return ng;
    }
    let ix = wo.dot(x);
    let a = (ix * ix + iz * iz).sqrt();
    let (phi, spread) = (ix.atan2(iz), (threshold / a).min(1.0).acos());
    let normal = |t: f32| x * t.sin() + ng * t.cos();
    let (plus, minus) = (normal(0.5 * (phi + spread)), normal(0.5 * (phi - spread)));
    if plus.dot(ns) >= minus.dot(ns) { plus } else { minus }
}

/// Where [`bent_shading_normal`] leaves `ns` as it is: `wo` below the surface (nothing to bend
/// toward), or the mirror direction of `wo` about `ns` already leaving. For one normal or a lane.
#[inline(always)]
pub fn shading_normal_stands<V: Vector>(ns: V, ng: V, wo: V) -> <V::Real as Real>::Mask {
    let iz = wo.dot(ng);
    let threshold = (iz * 0.9).min(V::Real::splat(0.01));
    !iz.gt(V::Real::splat(0.0)) | (ns.dot(wo) * 2.0 * ns.dot(ng) - iz).ge(threshold)
}

impl Bsdf {
    /// A BSDF from glTF parameters; `roughness` is perceptual (alpha = roughness^2).
    /// `dielectric_f0` and `dielectric_f90` are the dielectric Fresnel's reflectance at normal and
    /// grazing incidence (glTF's defaults: 0.04 and 1).
    pub fn new(
        frame: Frame,
        base: SampledSpectrum,
        metallic: f32,
        roughness: f32,
        dielectric_f0: f32,
        dielectric_f90: f32,
    ) -> Self {
        let r = roughness.clamp(0.0, 1.0);
        Self {
            frame,
            base,
            metallic: metallic.clamp(0.0, 1.0),
            dielectric_f0: dielectric_f0.clamp(0.0, 1.0),
            dielectric_f90: dielectric_f90.clamp(0.0, 1.0),
            alpha: (r * r).max(MIN_ALPHA),
        }
    }

    /// True when there is a specular lobe.
    pub fn has_specular(&self) -> bool {
        self.metallic > 0.0 || self.dielectric_f0 > 0.0
    }

    /// Probability of sampling the specular lobe: 1 without a diffuse lobe (a metal, or a black
    /// dielectric), else the lobes' rough weights kept within [0.05, 0.95] so neither starves.
    fn specular_probability(&self) -> f32 {
        if !self.has_specular() {
            return 0.0;
        }
        let lum = (self.base.0[0] + self.base.0[1] + self.base.0[2]) / 3.0;
        let w_spec = self.metallic + (1.0 - self.metallic) * (4.0 * self.dielectric_f0).min(1.0);
        let w_diff = (1.0 - self.metallic) * lum.max(0.0);
        if w_diff > 0.0 { (w_spec / (w_spec + w_diff)).clamp(0.05, 0.95) } else { 1.0 }
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
        let fd = if self.dielectric_f0 > 0.0 { schlick(self.dielectric_f0, self.dielectric_f90, cos_oh) } else { 0.0 };
        let dv = ggx_d(h, self.alpha) * smith_v(i.z, o.z, self.alpha);
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
        // D_o(h) / (4 o.h) with o.h cancelling: G1(o) D(h) / (4 o.z).
        let h = (o + i).normalize();
        let spec = smith_g1(o.z, self.alpha) * ggx_d(h, self.alpha) / (4.0 * o.z);
        ps * spec + (1.0 - ps) * diffuse
    }

    /// Samples a direction: the specular lobe (GGX normals visible from `wo`) or the diffuse one
    /// (cosine), chosen with `u_lobe`. None below the surface or for a failed sample.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let o = self.frame.to_local(wo);
        if o.z <= 0.0 {
            return None;
        }
        let ps = self.specular_probability();
        let i = if u_lobe < ps {
            let h = sample_visible_normal(o, self.alpha, u);
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
