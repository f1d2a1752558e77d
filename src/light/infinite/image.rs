//! Image infinite light: radiance from a lat-long environment map (pbrt-v4 `ImageInfiniteLight`,
//! which uses an equal-area octahedral map instead; kelvin reads the lat-long maps HDRI sites
//! publish, with the mapping of [`crate::scene::image`]).

use std::f64::consts::PI as PI64;
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{DVec3, Quat, Vec2, Vec3};
use rayon::prelude::*;

use super::tables::{EnvLookup, EnvMapTables, EnvTableOptions, clean_texel};
use super::{ColorQuery, Emitter, LiSample, LightError, LightFlags, LightSampleContext, SceneSphere, far_distance};
use crate::geometry::Transform;
use crate::light::Amount;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage, direction_to_lat_long};
use crate::spectrum::{SampledSpectrum, Spectrum};

/// An environment map around the scene, turned by its entity's `Transform` rotation.
#[derive(Component, Clone)]
pub struct ImageInfiniteLight {
    /// Lat-long map of linear RGB radiance relative to `spectrum`: row 0 at the zenith (+Y), the
    /// centre column looking along +X (see [`crate::scene::image`]).
    pub image: Arc<RgbImage>,
    /// Luminance of a texel of value (1, 1, 1), nit: a texel (r, g, b) emits
    /// `scale` * (r, g, b) nit of the spectrum's colour. Defaults to 1.
    pub scale: f32,
    /// Spectral shape that texels tint. Defaults to D65 (so texels are plain linear sRGB).
    pub spectrum: Spectrum,
    /// Also build the MIS-compensated table for [`ResolvedImageInfinite::sample_li_mis`].
    /// Defaults to true.
    pub mis_compensation: bool,
    /// Radiance between texel centres. Defaults to bilinear.
    pub lookup: EnvLookup,
    /// Largest sampling-table width (the importance is area-averaged down to it). None (the
    /// default) samples at the image's resolution.
    pub table_max_width: Option<usize>,
}

impl ImageInfiniteLight {
    /// A light of `image` with every other field at its default.
    pub fn new(image: Arc<RgbImage>) -> Self {
        Self {
            image,
            scale: 1.0,
            spectrum: Spectrum::d65(),
            mis_compensation: true,
            lookup: EnvLookup::Bilinear,
            table_max_width: None,
        }
    }

    /// Checks that the image has at least one pixel and width * height of them, that
    /// `table_max_width` is not 0 and that `scale` is finite and >= 0.
    pub fn validate(&self) -> Result<(), LightError> {
        let (w, h, n) = (self.image.width, self.image.height, self.image.pixels.len());
        if w == 0 || h == 0 || w.checked_mul(h) != Some(n) {
            let msg = format!("image is {w} x {h} with {n} pixels; needs at least 1 x 1 and width * height pixels");
            return Err(LightError::Invalid { light: "ImageInfiniteLight", msg });
        }
        if self.table_max_width == Some(0) {
            let msg = "table_max_width must be at least 1 (or None for the image width)".to_string();
            return Err(LightError::Invalid { light: "ImageInfiniteLight", msg });
        }
        Amount::Nits(self.scale).validate("ImageInfiniteLight", "scale")?;
        Ok(())
    }

    /// The sampling tables of this light's image (the expensive part: build once per image).
    pub fn build_tables(&self) -> Result<EnvMapTables, LightError> {
        self.validate()?;
        Ok(EnvMapTables::build_with(&self.image, self.table_options()))
    }

    /// How this light's tables are built (they depend on these and the image only).
    pub fn table_options(&self) -> EnvTableOptions {
        EnvTableOptions { compensate: self.mis_compensation, max_width: self.table_max_width, lookup: self.lookup }
    }

    /// World-space form; `scene` is the scene's bounding sphere (the preprocess step).
    pub fn resolve(&self, transform: &Transform, scene: SceneSphere) -> Result<ResolvedImageInfinite, LightError> {
        let tables = Arc::new(self.build_tables()?);
        self.resolve_with_tables(transform, scene, tables)
    }

    /// As [`Self::resolve`] with tables built earlier by [`Self::build_tables`] for this image (a
    /// change of rotation or scale does not need new tables).
    pub fn resolve_with_tables(
        &self,
        transform: &Transform,
        scene: SceneSphere,
        tables: Arc<EnvMapTables>,
    ) -> Result<ResolvedImageInfinite, LightError> {
        self.validate()?;
        let emitter = Emitter::from_amount(self.spectrum.clone(), Amount::Nits(self.scale));
        let texel_integral = texel_solid_angle_integral(&self.image, self.lookup);
        // Y(le) = sum_c W_c rgb_c t_c in RGB mode: linear in the texel, so it integrates through.
        let weights = (LUMINANCE_WEIGHTS * emitter.rgb).as_dvec3();
        let disc = PI64 * scene.radius as f64 * scene.radius as f64;
        let luminous_phi = disc * weights.dot(texel_integral);
        let y_white = weights.element_sum();
        let phi = if y_white > 0.0 { luminous_phi / y_white * emitter.radiometric as f64 } else { 0.0 };
        Ok(ResolvedImageInfinite {
            image: self.image.clone(),
            tables,
            lookup: self.lookup,
            rotation: transform.rotation.normalize(),
            emitter,
            scene,
            phi: phi as f32,
            luminous_phi: luminous_phi as f32,
        })
    }
}

/// The image's size, not its pixels, in debug output.
struct ImageShape<'a>(&'a RgbImage);
impl std::fmt::Debug for ImageShape<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "RgbImage {{ {} x {} }}", self.0.width, self.0.height)
    }
}

impl std::fmt::Debug for ImageInfiniteLight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImageInfiniteLight")
            .field("image", &ImageShape(&self.image))
            .field("scale", &self.scale)
            .field("spectrum", &self.spectrum)
            .field("mis_compensation", &self.mis_compensation)
            .field("lookup", &self.lookup)
            .field("table_max_width", &self.table_max_width)
            .finish()
    }
}

impl std::fmt::Debug for ResolvedImageInfinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResolvedImageInfinite")
            .field("image", &ImageShape(&self.image))
            .field("tables", &self.tables)
            .field("lookup", &self.lookup)
            .field("rotation", &self.rotation)
            .field("emitter", &self.emitter)
            .field("scene", &self.scene)
            .field("phi", &self.phi)
            .finish()
    }
}

/// An image infinite light in world space.
///
/// Two sampling modes, as pbrt-v4's `allowIncompletePDF`: [`Self::sample_li`] / [`Self::pdf_li`]
/// sample the luminance and are unbiased on their own; [`Self::sample_li_mis`] /
/// [`Self::pdf_li_mis`] use the compensated table (zero density in the sky's dim part) and are
/// only for estimators that combine them with BSDF sampling by MIS.
#[derive(Clone)]
pub struct ResolvedImageInfinite {
    /// Lat-long map of relative linear RGB radiance (see [`ImageInfiniteLight::image`]).
    pub image: Arc<RgbImage>,
    /// Sampling tables of `image`, shared by every light of the same image.
    pub tables: Arc<EnvMapTables>,
    /// Radiance between texel centres.
    pub lookup: EnvLookup,
    /// Image-to-world rotation (unit).
    pub rotation: Quat,
    /// Radiance of a (1, 1, 1) texel, W/(m^2 sr) (with its photometric RGB in nit).
    pub emitter: Emitter,
    /// Bounds of the scene, used to place sample points beyond it and to compute the power.
    pub scene: SceneSphere,
    phi: f32,
    luminous_phi: f32,
}

impl ResolvedImageInfinite {
    /// Infinite: seen by escaping rays, never a delta.
    pub fn flags(&self) -> LightFlags {
        LightFlags::INFINITE
    }

    /// A direction drawn in proportion to luminance (complete pdf); None for a black map.
    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        self.sample(ctx, u, query, false)
    }

    /// A direction from the MIS-compensated table (falls back to [`Self::sample_li`] when the
    /// light has none); for MIS estimators only.
    pub fn sample_li_mis(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        self.sample(ctx, u, query, true)
    }

    /// Solid-angle density of [`Self::sample_li`] at unit `wi`; 0 for a black map.
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        self.pdf(wi, false)
    }

    /// Solid-angle density of [`Self::sample_li_mis`] at unit `wi`.
    pub fn pdf_li_mis(&self, wi: Vec3) -> f32 {
        self.pdf(wi, true)
    }

    fn sample(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery, mis: bool) -> Option<LiSample> {
        let (local, _) = self.tables.sample_direction(u, mis)?;
        let wi = (self.rotation * local).normalize();
        // Density and radiance are taken at `wi` itself, so that pdf == pdf_li(wi) and
        // radiance == le(wi) exactly: the uv -> direction -> uv round trip can cross a texel edge.
        let uv = self.image_uv(wi);
        let pdf = self.tables.pdf_solid_angle(uv, mis);
        if !(pdf > 0.0) {
            return None;
        }
        let radiance = self.emitter.eval_tinted(query, texel_at(&self.image, self.lookup, uv));
        let p_light = ctx.p + wi * far_distance(self.scene, ctx.p);
        Some(LiSample { radiance, wi, pdf, p_light, n_light: Vec3::ZERO })
    }

    /// The lat-long coordinates of world direction `wi` in the image.
    fn image_uv(&self, wi: Vec3) -> Vec2 {
        direction_to_lat_long(self.rotation.inverse() * wi)
    }

    fn pdf(&self, wi: Vec3, mis: bool) -> f32 {
        self.tables.pdf_solid_angle(self.image_uv(wi), mis)
    }

    /// [`Self::le`] and the density of [`Self::pdf_li`] (`mis`: of [`Self::pdf_li_mis`]) at
    /// `wi`, from one lat-long lookup; None (and no density lookup) where `le` is black.
    pub fn le_and_pdf(&self, wi: Vec3, query: ColorQuery, mis: bool) -> Option<(SampledSpectrum, f32)> {
        let uv = self.image_uv(wi);
        let le = self.emitter.eval_tinted(query, texel_at(&self.image, self.lookup, uv));
        if le.0.iter().all(|&v| v == 0.0) {
            return None;
        }
        Some((le, self.tables.pdf_solid_angle(uv, mis)))
    }

    /// The texel value (clean, linear RGB relative to the spectrum) seen along `wi`.
    pub fn texel(&self, wi: Vec3) -> Vec3 {
        texel_at(&self.image, self.lookup, self.image_uv(wi))
    }

    /// Radiance along an escaping ray with direction `wi`, in the query's colour mode.
    pub fn le(&self, wi: Vec3, query: ColorQuery) -> SampledSpectrum {
        self.emitter.eval_tinted(query, self.texel(wi))
    }

    /// Radiant power through the scene's bounding disc, W: pi R^2 * integral of L over the
    /// sphere (pbrt-v4 `ImageInfiniteLight::Phi`), with the integral of the lookup's radiance
    /// taken exactly (see `texel_solid_angle_integral`). Coloured texels are weighted by their
    /// luminance relative to a white texel's (exact in RGB mode; in spectral mode the texel's
    /// reflectance spectrum shifts the luminous efficacy slightly).
    pub fn phi(&self) -> f32 {
        self.phi
    }

    /// Luminous flux through the scene's bounding disc, lm: pi R^2 * integral of Y(le) over the
    /// sphere, with `le` in RGB mode.
    pub fn luminous_phi(&self) -> f32 {
        self.luminous_phi
    }
}

/// The clean texel value at `uv` with the given lookup.
pub fn texel_at(image: &RgbImage, lookup: EnvLookup, uv: Vec2) -> Vec3 {
    match lookup {
        EnvLookup::Bilinear => clean_texel(image.bilinear(uv)),
        EnvLookup::Nearest => {
            // The same f64 bin arithmetic as the sampling table, so both agree on texel edges.
            let x = ((uv.x as f64 * image.width as f64) as usize).min(image.width - 1);
            let y = ((uv.y as f64 * image.height as f64) as usize).min(image.height - 1);
            clean_texel(image.pixels[y * image.width + x])
        }
    }
}

/// The integral over the sphere of the radiance the lookup returns, in texel units times sr.
///
/// Nearest: each texel is constant over its cell, of solid angle (2 pi / w)(cos theta0 - cos theta1).
/// Bilinear: a periodic linear interpolant keeps the mean in u, so integrating over u leaves the
/// row means, linear in theta between row centres and constant beyond the first and last; the
/// theta integral against sin(theta) is then exact per segment (integrals of sin and theta sin).
pub fn texel_solid_angle_integral(image: &RgbImage, lookup: EnvLookup) -> DVec3 {
    let (w, h) = (image.width, image.height);
    // Each row's serial sum on the pool, then the rows in order as before: the same result, and a
    // moved sun's sky no longer waits ~1 ms on one core for this.
    let sums: Vec<DVec3> = image
        .pixels
        .par_chunks(w.max(1))
        .take(h)
        .map(|row| row.iter().map(|&t| clean_texel(t).as_dvec3()).sum())
        .collect();
    let row_sum = |y: usize| sums[y];
    let d_phi = 2.0 * PI64 / w as f64;
    match lookup {
        EnvLookup::Nearest => (0..h)
            .map(|y| {
                let (t0, t1) = (PI64 * y as f64 / h as f64, PI64 * (y + 1) as f64 / h as f64);
                row_sum(y) * d_phi * (t0.cos() - t1.cos())
            })
            .sum(),
        EnvLookup::Bilinear => {
            let weights = bilinear_row_weights(h);
            (0..h).map(|y| row_sum(y) * d_phi * weights[y]).sum()
        }
    }
}

/// Weights W_j with integral_0^pi m(theta) sin(theta) dtheta = sum_j m_j W_j for m piecewise
/// linear through (theta_j, m_j) at the row centres theta_j = pi (j + 1/2) / h and constant beyond
/// the first and last. They sum to 2.
pub fn bilinear_row_weights(h: usize) -> Vec<f64> {
    let theta = |j: usize| PI64 * (j as f64 + 0.5) / h as f64;
    let mut w = vec![0.0; h];
    w[0] += 1.0 - theta(0).cos();
    w[h - 1] += 1.0 + theta(h - 1).cos();
    for j in 0..h.saturating_sub(1) {
        let (a, b) = (theta(j), theta(j + 1));
        let d = b - a;
        // integral_a^b (b - t)/d sin t dt and integral_a^b (t - a)/d sin t dt.
        w[j] += (d * a.cos() + a.sin() - b.sin()) / d;
        w[j + 1] += (b.sin() - a.sin() - d * b.cos()) / d;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_row_weights_integrate_sin_and_theta() {
        for h in [1usize, 2, 3, 16, 1000] {
            let w = bilinear_row_weights(h);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-12, "h {h}: {}", w.iter().sum::<f64>());
            // m(theta) = clamp(theta, t0, t1) is linear between the end centres: compare with the
            // closed form of its integral against sin(theta).
            if h >= 2 {
                let (t0, t1) = (PI64 * 0.5 / h as f64, PI64 * (h as f64 - 0.5) / h as f64);
                let m: f64 = (0..h).map(|j| PI64 * (j as f64 + 0.5) / h as f64 * w[j]).sum();
                let exact = t0 * (1.0 - t0.cos())
                    + (-t1 * t1.cos() + t1.sin() + t0 * t0.cos() - t0.sin())
                    + t1 * (1.0 + t1.cos());
                assert!((m - exact).abs() < 1e-9, "h {h}: {m} vs {exact}");
            }
        }
    }
}
