//! Area lights: surfaces that emit uniform (optionally textured) Lambertian radiance, as pbrt-v4's
//! `DiffuseAreaLight` (section 12.5) on spheres, disks, rectangles and triangle meshes.
//!
//! The [`AreaLight`] component says how bright; the shape comes from the entity (a sphere, disk
//! or rectangle size, or a mesh) and is resolved with its `Transform` into one [`ResolvedArea`]
//! per shape or triangle. Sampling lives in [`shapes`].

mod fast;
mod lanes;
pub mod shapes;

use std::f32::consts::PI;
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};

use super::emitter::check_amount;
use super::{Amount, ColorQuery, Emitter, LiSample, LightBounds, LightError, LightSampleContext, PointLight, Quantity};
use crate::geometry::Transform;
use crate::spectrum::{SampledSpectrum, Spectrum};

pub use lanes::TriangleLightLanes;
pub use shapes::{
    AreaShape, MAX_SPHERICAL_SAMPLE_AREA, MIN_SPHERICAL_SAMPLE_AREA, SPHERE_NEAR_MARGIN, SamplingStrategy, ShapeSample,
    SurfacePoint,
};

/// Default luminance of an area light: 1000 nit, a bright diffuse panel or a frosted bulb surface.
pub const DEFAULT_AREA_NITS: f32 = 1000.0;

/// An emitting surface on its entity's shape or mesh.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct AreaLight {
    /// Radiance (nit or W/(m^2 sr)) or total power of the whole shape or mesh (lm or W; then
    /// L = phi / (pi * area * sides), divided by the texture's mean luminance if textured).
    /// Defaults to 1000 nit.
    pub amount: Amount,
    /// Spectral shape. Defaults to D65 (white).
    pub spectrum: Spectrum,
    /// Emits from both faces. Defaults to false: only on the side of the surface normal.
    pub two_sided: bool,
    /// Whether shadow rays are traced. Defaults to true.
    pub casts_shadows: bool,
    /// Linear-sRGB tint over the surface's uv, multiplying the radiance. Defaults to none.
    pub texture: Option<Arc<LightTexture>>,
}

impl AreaLight {
    /// The light of a glTF emissive surface: `amount` in nits, the colour's spectrum, and an
    /// optional emissive texture (linear RGB) tinting it.
    pub fn emissive(
        amount: Amount,
        spectrum: Spectrum,
        texture: Option<Arc<crate::scene::image::RgbImage>>,
        two_sided: bool,
    ) -> Self {
        let texture = texture.and_then(|t| LightTexture::new(t.width, t.height, t.pixels.clone()).ok()).map(Arc::new);
        Self { amount, spectrum, two_sided, casts_shadows: true, texture }
    }
}

impl Default for AreaLight {
    fn default() -> Self {
        Self {
            amount: Amount::Nits(DEFAULT_AREA_NITS),
            spectrum: Spectrum::d65(),
            two_sided: false,
            casts_shadows: true,
            texture: None,
        }
    }
}

/// A linear-sRGB image that tints an area light, looked up bilinearly by uv with repeat
/// wrapping; row 0 is v = 0 (the top of the image, as glTF). Scene loading converts decoded
/// images into this form.
#[derive(Clone, PartialEq)]
pub struct LightTexture {
    /// Width in texels, > 0.
    pub width: usize,
    /// Height in texels, > 0.
    pub height: usize,
    /// Row-major, `width * height` finite non-negative texels.
    pub texels: Vec<Vec3>,
    /// Mean Rec. 709 luminance of the texels (set by [`LightTexture::new`]).
    pub mean_luminance: f32,
}

impl std::fmt::Debug for LightTexture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "LightTexture({}x{}, mean luminance {})", self.width, self.height, self.mean_luminance)
    }
}

impl LightTexture {
    /// A texture from row-major texels; errors if the count is not width * height (both > 0)
    /// or a texel is negative or not finite.
    pub fn new(width: usize, height: usize, texels: Vec<Vec3>) -> Result<Self, LightError> {
        let invalid = |msg: String| LightError::Invalid { light: "AreaLight", msg };
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(invalid(format!("texture has {} texels for {width} x {height}", texels.len())));
        }
        if let Some(i) = texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
            return Err(invalid(format!("texture texel {i} = {} must be finite and >= 0", texels[i])));
        }
        let sum: f64 = texels.iter().map(|t| t.dot(crate::scene::image::LUMINANCE_WEIGHTS) as f64).sum();
        let mean_luminance = (sum / texels.len() as f64) as f32;
        Ok(Self { width, height, texels, mean_luminance })
    }

    /// Bilinear lookup at `uv` (texel centres at half-integers), wrapping around.
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        if !uv.is_finite() {
            return Vec3::ZERO;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: f32, j: f32| {
            let i = (i as i64).rem_euclid(self.width as i64) as usize;
            let j = (j as i64).rem_euclid(self.height as i64) as usize;
            self.texels[j * self.width + i]
        };
        let top = texel(x0, y0).lerp(texel(x0 + 1.0, y0), fx);
        let bottom = texel(x0, y0 + 1.0).lerp(texel(x0 + 1.0, y0 + 1.0), fx);
        top.lerp(bottom, fy)
    }
}

/// An area light's shape and emission in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedArea {
    /// The emitting surface, world space.
    pub shape: AreaShape,
    /// Emitted radiance, W/(m^2 sr) (photometric RGB in nit).
    pub radiance: Emitter,
    /// Emits from both faces; otherwise only on the side of the surface normal.
    pub two_sided: bool,
    /// Linear-sRGB tint looked up at the surface's uv, multiplying `radiance`.
    pub texture: Option<Arc<LightTexture>>,
    /// Area of `shape`, m^2.
    pub area: f32,
    /// `shape.plane_normal()`, zero for spheres: computed once for the f32 sampling path.
    pub normal: Vec3,
}

/// The triangles of a mesh light and how many degenerate triangles were left out.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedMesh {
    /// One light per non-degenerate triangle, world space.
    pub triangles: Vec<ResolvedArea>,
    /// Index in the mesh of each of `triangles` (degenerate ones are missing).
    pub primitives: Vec<u32>,
    /// Triangles skipped for zero area, collinear or non-finite vertices.
    pub skipped_degenerate: usize,
}

fn bad_size(field: &'static str, value: f32, scaled: f32) -> LightError {
    LightError::BadSize { light: "AreaLight", field, value, scaled }
}

fn check_transform(t: &Transform) -> Result<(), LightError> {
    if t.translation.is_finite() && t.rotation.is_finite() && t.scale.is_finite() && t.shear.is_finite() {
        Ok(())
    } else {
        Err(LightError::Invalid { light: "AreaLight", msg: format!("transform is not finite: {t:?}") })
    }
}

/// An analytic shape's transform: finite and not shearing it (`shear` = the shear components
/// that act on the shape; a flat one's lie at local z = 0, where only the xy shear does).
fn check_shape_transform(t: &Transform, shape: &str, shear: f32) -> Result<(), LightError> {
    check_transform(t)?;
    if shear.abs() > 1e-5 {
        let msg = format!("a {shape} cannot be sheared (shear {}): only meshes follow a shearing transform", t.shear);
        return Err(LightError::Invalid { light: "AreaLight", msg });
    }
    Ok(())
}

/// True when the transform mirrors (negative determinant): glTF then reverses triangle winding.
fn mirrors(t: &Transform) -> bool {
    t.scale.x * t.scale.y * t.scale.z < 0.0
}

impl AreaLight {
    /// The radiance emitter for a light of total area `area` (m^2).
    fn radiance_emitter(&self, area: f32) -> Result<Emitter, LightError> {
        let amount = check_amount(
            self.amount,
            "AreaLight",
            "amount",
            &[Quantity::Radiance, Quantity::Power],
            "nit, W/(m^2 sr), lm or W",
        )?;
        let e = Emitter::from_amount(self.spectrum.clone(), amount);
        if amount.quantity() == Quantity::Radiance {
            return Ok(e);
        }
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        let tint = self.texture.as_ref().map_or(1.0, |t| t.mean_luminance);
        let denom = PI * area * sides * tint;
        if !(denom > 0.0 && denom.is_finite()) {
            return Err(LightError::Invalid {
                light: "AreaLight",
                msg: format!(
                    "cannot spread {} {} over area {area} m^2 with texture luminance {tint}",
                    amount.value(),
                    amount.unit()
                ),
            });
        }
        Ok(e.scaled(1.0 / denom))
    }

    fn resolved(&self, shape: AreaShape, radiance: Emitter) -> ResolvedArea {
        ResolvedArea::new(shape, radiance, self.two_sided, self.texture.clone())
    }

    /// A sphere of local `radius` (m) at the transform's translation; the radius scales by the
    /// largest scale component.
    pub fn resolve_sphere(&self, radius: f32, transform: &Transform) -> Result<ResolvedArea, LightError> {
        check_shape_transform(transform, "sphere", transform.shear.abs().max_element())?;
        let r = radius * transform.scale.abs().max_element();
        if !(radius > 0.0 && r > 0.0 && r.is_finite()) {
            return Err(bad_size("radius", radius, r));
        }
        let shape = AreaShape::Sphere { center: transform.translation, radius: r };
        Ok(self.resolved(shape, self.radiance_emitter(shape.area())?))
    }

    /// A disk of local `radius` (m) in the local XY plane, normal +Z; the radius scales by the
    /// larger of the X and Y scales.
    pub fn resolve_disk(&self, radius: f32, transform: &Transform) -> Result<ResolvedArea, LightError> {
        check_shape_transform(transform, "disk", transform.shear.x)?;
        let r = radius * transform.scale.x.abs().max(transform.scale.y.abs());
        if !(radius > 0.0 && r > 0.0 && r.is_finite()) {
            return Err(bad_size("radius", radius, r));
        }
        // Normals transform by the inverse transpose: the emitting side follows sign(scale.z).
        let normal = (transform.rotation * Vec3::Z * transform.scale.z.signum()).normalize();
        let shape = AreaShape::Disk { center: transform.translation, normal, radius: r };
        Ok(self.resolved(shape, self.radiance_emitter(shape.area())?))
    }

    /// A `width` x `height` (m) rectangle centred in the local XY plane, normal +Z.
    pub fn resolve_rectangle(
        &self,
        width: f32,
        height: f32,
        transform: &Transform,
    ) -> Result<ResolvedArea, LightError> {
        check_shape_transform(transform, "rectangle", transform.shear.x)?;
        if !(width > 0.0 && width.is_finite()) {
            return Err(bad_size("width", width, width));
        }
        if !(height > 0.0 && height.is_finite()) {
            return Err(bad_size("height", height, height));
        }
        let mut corner = transform.transform_point(Vec3::new(-0.5 * width, -0.5 * height, 0.0));
        let mut ex = transform.transform_vector(Vec3::X * width);
        let ey = transform.transform_vector(Vec3::Y * height);
        if mirrors(transform) {
            // Keep the emitting side where the local +Z points after the mirror.
            corner += ex;
            ex = -ex;
        }
        let shape = AreaShape::Rectangle { corner, ex, ey };
        if !(shape.area() > 0.0) {
            return Err(LightError::Invalid {
                light: "AreaLight",
                msg: format!("rectangle has zero area under {transform:?}"),
            });
        }
        Ok(self.resolved(shape, self.radiance_emitter(shape.area())?))
    }

    /// One light per triangle of an indexed mesh (local positions and optional uvs, empty for
    /// none); a power amount is shared by area over the whole mesh. Degenerate triangles are
    /// skipped and counted; bad indices or uv counts are errors.
    pub fn resolve_mesh(
        &self,
        positions: &[Vec3],
        uvs: &[Vec2],
        indices: &[u32],
        transform: &Transform,
    ) -> Result<ResolvedMesh, LightError> {
        let invalid = |msg: String| LightError::Invalid { light: "AreaLight", msg };
        check_transform(transform)?;
        if !indices.len().is_multiple_of(3) {
            return Err(invalid(format!("mesh has {} indices, not a multiple of 3", indices.len())));
        }
        if !uvs.is_empty() && uvs.len() != positions.len() {
            return Err(invalid(format!("mesh has {} uvs for {} positions", uvs.len(), positions.len())));
        }
        let mut shapes = Vec::with_capacity(indices.len() / 3);
        let mut primitives = Vec::with_capacity(indices.len() / 3);
        let mut skipped = 0;
        for (t, tri) in indices.chunks_exact(3).enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(invalid(format!("triangle {t}: index {i} out of range ({} positions)", positions.len())));
            }
            let mut ids = [tri[0], tri[1], tri[2]].map(|i| i as usize);
            if mirrors(transform) {
                ids.swap(1, 2);
            }
            let p = ids.map(|i| transform.transform_point(positions[i]));
            let uv = ids.map(|i| uvs.get(i).copied().unwrap_or(Vec2::ZERO));
            if is_degenerate(&p) {
                skipped += 1;
                continue;
            }
            shapes.push(AreaShape::Triangle { p, uv });
            primitives.push(t as u32);
        }
        let total: f64 = shapes.iter().map(|s| s.area() as f64).sum();
        let radiance = if shapes.is_empty() { Emitter::black() } else { self.radiance_emitter(total as f32)? };
        let triangles = shapes.into_iter().map(|s| self.resolved(s, radiance.clone())).collect();
        Ok(ResolvedMesh { triangles, primitives, skipped_degenerate: skipped })
    }
}

/// The sphere area light of a [`PointLight`] with a positive radius (None for radius 0): one-sided,
/// radiance I / (pi r^2), so its power (4 pi I) and its intensity far away match the point form.
pub fn sphere_from_point_light(light: &PointLight, transform: &Transform) -> Result<Option<ResolvedArea>, LightError> {
    let point = light.resolve(transform)?;
    if light.radius == 0.0 {
        return Ok(None);
    }
    let shape = AreaShape::Sphere { center: point.position, radius: light.radius };
    let radiance = point.intensity.scaled(1.0 / (PI * light.radius * light.radius));
    Ok(Some(ResolvedArea::new(shape, radiance, false, None)))
}

/// Non-finite, zero-area or so thin (|e1 x e2| <= 1e-6 |e1| |e2|) that its normal is noise.
fn is_degenerate(p: &[Vec3; 3]) -> bool {
    let [a, b, c] = p.map(|v| v.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let cross = e1.cross(e2).length();
    !(cross.is_finite() && cross > 1e-6 * e1.length() * e2.length())
}

impl ResolvedArea {
    /// A light on `shape` with radiance `radiance` (W/(m^2 sr)).
    pub fn new(shape: AreaShape, radiance: Emitter, two_sided: bool, texture: Option<Arc<LightTexture>>) -> Self {
        let normal = shape.plane_normal().unwrap_or(Vec3::ZERO);
        Self { area: shape.area(), normal, shape, radiance, two_sided, texture }
    }

    /// Radiance leaving surface point `p` (normal `n`, texture coordinate `uv`) toward unit
    /// direction `w`; zero behind a one-sided light. `p` is unused by uniform emitters.
    pub fn radiance(&self, _p: Vec3, n: Vec3, uv: Vec2, w: Vec3, query: ColorQuery) -> SampledSpectrum {
        if !self.two_sided && n.dot(w) <= 0.0 {
            return SampledSpectrum::default();
        }
        match &self.texture {
            Some(t) => self.radiance.eval_tinted(query, t.lookup(uv)),
            None => self.radiance.eval(query),
        }
    }

    /// The strategy `sample_li` uses from `p` (for tests and diagnostics).
    pub fn strategy(&self, p: Vec3) -> SamplingStrategy {
        self.shape.strategy(p)
    }

    /// A direction toward the light with the radiance arriving along it; None where the
    /// light cannot be sampled (degenerate shape, `ctx.p` in its plane) or sends no light along
    /// the sampled direction (the back of a one-sided light, a black texel). Through the f32
    /// kernels ([`AreaShape::sample_fast`]); [`Self::sample_li_f64`] is its reference.
    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let s = self.shape.sample_fast_with(self.normal, self.area, ctx.p, u)?;
        self.li_sample(s, query)
    }

    /// [`Self::sample_li`] through the f64 reference ([`AreaShape::sample`]).
    pub fn sample_li_f64(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let s = self.shape.sample(ctx.p, u)?;
        self.li_sample(s, query)
    }

    fn li_sample(&self, s: ShapeSample, query: ColorQuery) -> Option<LiSample> {
        let radiance = self.radiance(s.point.p, s.point.n, s.point.uv, -s.wi, query);
        if radiance.0.iter().all(|&v| v == 0.0) {
            return None;
        }
        Some(LiSample { radiance, wi: s.wi, pdf: s.pdf, p_light: s.point.p, n_light: s.point.n })
    }

    /// Solid-angle density with which `sample_li` picks `wi` (1/sr; 0 if the ray misses). It is
    /// the density of the sampling strategy, also where the light shows its back. Through the
    /// f32 kernels ([`AreaShape::hit_fast`]); [`Self::pdf_li_f64`] is its reference.
    pub fn pdf_li(&self, ctx: &LightSampleContext, wi: Vec3) -> f32 {
        self.shape.hit_fast_with(self.normal, self.area, ctx.p, wi).map_or(0.0, |h| h.pdf)
    }

    /// [`Self::pdf_li`] through the f64 reference ([`AreaShape::hit`]).
    pub fn pdf_li_f64(&self, ctx: &LightSampleContext, wi: Vec3) -> f32 {
        self.shape.hit(ctx.p, wi).map_or(0.0, |h| h.pdf)
    }

    /// The surface point the ray from `ctx.p` along `wi` sees, its radiance toward `ctx.p` and
    /// the density of `wi` (for MIS of directions sampled otherwise), as [`Self::pdf_li`] finds it.
    pub fn li(&self, ctx: &LightSampleContext, wi: Vec3, query: ColorQuery) -> Option<(ShapeSample, SampledSpectrum)> {
        let h = self.shape.hit_fast_with(self.normal, self.area, ctx.p, wi)?;
        Some((h, self.radiance(h.point.p, h.point.n, h.point.uv, -h.wi, query)))
    }

    /// Radiant power, W: L * area * pi per emitting side, times the texture's mean luminance.
    pub fn phi(&self) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        let tint = self.texture.as_ref().map_or(1.0, |t| t.mean_luminance);
        self.radiance.radiometric * self.area * PI * sides * tint
    }

    /// Bounds for light BVHs (pbrt-v4 `DiffuseAreaLight::Bounds`): the shape's box, its normal
    /// with cos theta_o = 1 (planar) or -1 (sphere), and cos theta_e = cos(pi/2) = 0.
    pub fn bounds(&self) -> LightBounds {
        let (min, max) = self.shape.bounds();
        let (w, cos_theta_o) = match self.shape.plane_normal() {
            Some(n) => (n, 1.0),
            None => (Vec3::Z, -1.0),
        };
        LightBounds { min, max, phi: self.phi(), w, cos_theta_o, cos_theta_e: 0.0, two_sided: self.two_sided }
    }
}
