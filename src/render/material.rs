//! `Material`: the glTF metallic-roughness material as a component, and its BSDF at a point.

use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};

use super::bsdf::Bsdf;
use crate::light::ColorQuery;
use crate::sampling::Frame;
use crate::scene::image::RgbImage;
use crate::spectrum::{SampledSpectrum, rgb_reflectance};

/// glTF's default dielectric index of refraction.
pub const DEFAULT_IOR: f32 = 1.5;

/// A surface's appearance (glTF 2.0 metallic-roughness with KHR_materials_specular/_ior).
/// Defaults to a white (0.8) Lambertian-plus-specular dielectric, roughness 0.5.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Material {
    /// Linear-sRGB base colour (albedo / metal F0).
    pub base_color: Vec3,
    /// Multiplies `base_color` (linear RGB, sampled at the hit's uv).
    pub base_color_texture: Option<Arc<RgbImage>>,
    /// Metalness in [0, 1]: 0 a dielectric, 1 a metal.
    pub metallic: f32,
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// glTF packs roughness in G and metallic in B.
    pub metallic_roughness_texture: Option<Arc<RgbImage>>,
    /// Tangent-space normals (linear, [0, 1] per axis as glTF stores them), on meshes with uvs.
    pub normal_texture: Option<Arc<RgbImage>>,
    /// glTF `normalTexture.scale`: multiplies the map's x and y.
    pub normal_scale: f32,
    /// KHR_materials_specular `specularFactor`; 0 removes the dielectric specular lobe.
    pub specular: f32,
    /// KHR_materials_ior; 1 removes the dielectric specular lobe.
    pub ior: f32,
    /// Whether the back face shades like the front (glTF `doubleSided`).
    pub double_sided: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            metallic: 0.0,
            roughness: 0.5,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            specular: 1.0,
            ior: DEFAULT_IOR,
            double_sided: false,
        }
    }
}

impl Material {
    /// A pure Lambertian surface of the given albedo (specular factor 0).
    pub fn lambertian(albedo: Vec3) -> Self {
        Self { base_color: albedo, specular: 0.0, ..Default::default() }
    }

    /// The shading normal the normal texture gives at `uv` (None without one): the map's
    /// tangent-space normal, x and y scaled, in the frame of `tangent` (dp/du), `bitangent`
    /// (dp/dv) and `ns`, the front-side shading normal. Tangents are made orthogonal to `ns`.
    pub fn mapped_normal(&self, uv: Vec2, ns: Vec3, tangent: Vec3, bitangent: Vec3) -> Option<Vec3> {
        let map = self.normal_texture.as_ref()?;
        let t = map.bilinear(uv) * 2.0 - Vec3::ONE;
        // Not normalised: scaling `local` leaves the direction of `n` (normalised below) as it is,
        // and a zero `local` still gives a zero `n`, hence None. That spares a sqrt and a division.
        let local = Vec3::new(t.x * self.normal_scale, t.y * self.normal_scale, t.z);
        let tangent = (tangent - ns * ns.dot(tangent)).normalize_or_zero();
        if tangent == Vec3::ZERO {
            return None;
        }
        // The bitangent's side follows the uv layout (mirrored uvs flip it), as glTF's tangent.w.
        let handedness = if ns.cross(tangent).dot(bitangent) < 0.0 { -1.0 } else { 1.0 };
        let bitangent = ns.cross(tangent) * handedness;
        let n = (tangent * local.x + bitangent * local.y + ns * local.z).normalize_or_zero();
        (n != Vec3::ZERO).then_some(n)
    }

    /// Dielectric F0 = ((ior - 1) / (ior + 1))^2 times the specular factor (KHR_materials_ior,
    /// KHR_materials_specular).
    pub fn dielectric_f0(&self) -> f32 {
        let r = (self.ior - 1.0) / (self.ior + 1.0);
        (r * r * self.specular).clamp(0.0, 1.0)
    }

    /// Dielectric reflectance at grazing incidence: the specular factor (KHR_materials_specular).
    pub fn dielectric_f90(&self) -> f32 {
        self.specular.clamp(0.0, 1.0)
    }

    /// The BSDF this material has at every point in RGB mode, apart from its frame (left as the
    /// identity), when nothing varies over the surface (no textures); None otherwise. Renderers
    /// work it out once per material and set the frame per hit.
    pub fn uniform_rgb_bsdf(&self) -> Option<Bsdf> {
        let untextured = self.base_color_texture.is_none() && self.metallic_roughness_texture.is_none();
        untextured
            .then(|| self.bsdf(Vec2::ZERO, Vec3::Z, ColorQuery::Rgb))
            .map(|b| Bsdf { frame: Frame::IDENTITY, ..b })
    }

    /// The BSDF at a surface point with texture coordinates `uv`, shading normal `ns`, in the
    /// query's colour mode (base colour as RGB, or its reflectance spectrum at the wavelengths).
    pub fn bsdf(&self, uv: Vec2, ns: Vec3, query: ColorQuery) -> Bsdf {
        let mut base = self.base_color;
        if let Some(t) = &self.base_color_texture {
            base *= t.bilinear(uv);
        }
        let (mut metallic, mut roughness) = (self.metallic, self.roughness);
        if let Some(t) = &self.metallic_roughness_texture {
            let mr = t.bilinear(uv);
            roughness *= mr.y;
            metallic *= mr.z;
        }
        let base = base.clamp(Vec3::ZERO, Vec3::ONE);
        let base = match query {
            ColorQuery::Rgb => SampledSpectrum([base.x, base.y, base.z, 0.0]),
            ColorQuery::Spectral(w) => {
                let rgb = [base.x as f64, base.y as f64, base.z as f64];
                SampledSpectrum(w.lambda.map(|l| rgb_reflectance(rgb, l as f64) as f32))
            }
        };
        Bsdf::new(Frame::from_z(ns), base, metallic, roughness, self.dielectric_f0(), self.dielectric_f90())
    }
}
