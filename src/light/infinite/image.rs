//! Image infinite light: radiance from a lat-long environment map (pbrt-v4 `ImageInfiniteLight`,
//! which uses an equal-area octahedral map instead; kelvin reads the lat-long maps HDRI sites
//! publish, with the mapping of [`crate::scene::image`]).

use std::f64::consts::PI as PI64;
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{DVec3, Mat3, Quat, Vec2, Vec3};
use rayon::prelude::*;

use super::tables::{EnvLookup, EnvMapTables, EnvTableOptions, clean_texel, clean_texel_of};
use super::{ColorQuery, Emitter, LiSample, LightError, LightFlags, LightSampleContext, SceneSphere, far_distance};
use crate::geometry::Transform;
use crate::lanes::{F32x16, LANES, Vec3x16, Vector};
use crate::light::Amount;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage, lat_long_of};
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
            rotation: transform.aim(),
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
        Some(LiSample { radiance, wi, pdf, p_light: self.beyond_scene(ctx.p, wi), n_light: Vec3::ZERO })
    }

    /// The point a shadow ray from `p` along `wi` aims at: past the scene's bounds.
    #[inline(always)]
    fn beyond_scene(&self, p: Vec3, wi: Vec3) -> Vec3 {
        p + wi * far_distance(self.scene, p)
    }

    /// [`Self::sample_li`] (`mis`: [`Self::sample_li_mis`]) in RGB from the points `p` of the
    /// lanes in `active`, at `u`, the same samples: the table's searches in lock step, the lookups
    /// of the directions found as in [`Self::le_and_pdf_rgb_lanes`]. None where the scalar call
    /// gives None (and in lanes not asked for).
    #[inline(always)]
    pub fn sample_li_rgb_lanes(
        &self,
        p: &Vec3x16,
        u: [F32x16; 2],
        active: u32,
        mis: bool,
    ) -> [Option<LiSample>; LANES] {
        let u: [Vec2; LANES] = std::array::from_fn(|l| Vec2::new(u[0][l], u[1][l]));
        let found = self.tables.sample_direction_lanes(&u, mis);
        let (mut wi, mut asked) = (Vec3x16::ZERO, 0);
        for (l, found) in found.iter().enumerate() {
            if let (Some((local, _)), true) = (found, active & 1 << l != 0) {
                wi.set_lane(l, (self.rotation * *local).normalize());
                asked |= 1 << l;
            }
        }
        let (le, [u, v]) = self.le_rgb_lanes(&wi);
        std::array::from_fn(|l| {
            if asked & 1 << l == 0 {
                return None;
            }
            // As in `sample`: a density of 0 fails; black radiance does not.
            let pdf = self.tables.pdf_solid_angle(Vec2::new(u[l], v[l]), mis);
            if !(pdf > 0.0) {
                return None;
            }
            let (wi, le) = (wi.lane(l), le.lane(l));
            let radiance = SampledSpectrum([le.x, le.y, le.z, 0.0]);
            Some(LiSample { radiance, wi, pdf, p_light: self.beyond_scene(p.lane(l), wi), n_light: Vec3::ZERO })
        })
    }

    /// The lat-long coordinates of world direction `wi` in the image.
    fn image_uv(&self, wi: Vec3) -> Vec2 {
        Vec2::from(lat_long_of::<f32>(to_image(&self.to_image_rows(), wi)))
    }

    /// The rows of the world-to-image rotation: the scalar lookups and the lane kernel turn
    /// directions with the same products.
    fn to_image_rows(&self) -> [Vec3; 3] {
        let m = Mat3::from_quat(self.rotation.inverse()).transpose();
        [m.x_axis, m.y_axis, m.z_axis]
    }

    /// [`Self::le_and_pdf`] in RGB for the lanes of `wi` in `active` (bit `l` for lane `l`), with
    /// the same bits: per lane the radiance's RGB and the density, and in `lit` the lanes where
    /// the radiance is not black (the others' densities are 0, not looked up).
    #[inline(always)]
    pub fn le_and_pdf_rgb_lanes(&self, wi: &Vec3x16, active: u32, mis: bool) -> ImageLanes {
        let (le, [u, v]) = self.le_rgb_lanes(wi);
        let zero = F32x16::ZERO;
        let black = le.x.eq(zero) & le.y.eq(zero) & le.z.eq(zero);
        // The densities one lane at a time: short independent lookups, whose loads overlap.
        let (mut pdf, mut lit) = ([0.0f32; LANES], 0);
        for (l, pdf) in pdf.iter_mut().enumerate() {
            if active & 1 << l != 0 && !black.test(l) {
                *pdf = self.tables.pdf_solid_angle(Vec2::new(u[l], v[l]), mis);
                lit |= 1 << l;
            }
        }
        ImageLanes { le, pdf, lit }
    }

    /// The radiance (RGB) along each lane's direction, and where the direction falls in the image.
    #[inline(always)]
    fn le_rgb_lanes(&self, wi: &Vec3x16) -> (Vec3x16, [F32x16; 2]) {
        let [u, v] = lat_long_of::<F32x16>(to_image(&self.to_image_rows(), *wi));
        let texel = match self.lookup {
            EnvLookup::Bilinear => clean_texel_of(self.image.bilinear_lanes(u, v)),
            EnvLookup::Nearest => {
                let mut t = Vec3x16::ZERO;
                for l in 0..LANES {
                    t.set_lane(l, texel_at(&self.image, self.lookup, Vec2::new(u[l], v[l])));
                }
                t
            }
        };
        // Emitter::eval_tinted in RGB: the emitter's RGB times the texel.
        let rgb = self.emitter.rgb;
        (Vec3x16 { x: texel.x * rgb.x, y: texel.y * rgb.y, z: texel.z * rgb.z }, [u, v])
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

/// What [`ResolvedImageInfinite::le_and_pdf_rgb_lanes`] finds per lane.
#[derive(Clone, Copy, Debug)]
pub struct ImageLanes {
    /// Radiance, linear sRGB (meaningful in `lit` lanes only).
    pub le: Vec3x16,
    /// Solid-angle density of the chosen table (zero outside `lit`).
    pub pdf: [f32; LANES],
    /// Lanes asked for whose radiance is not black.
    pub lit: u32,
}

/// World direction `wi` in the image's frame: the rows' dot products with it.
#[inline(always)]
fn to_image<V: Vector>(rows: &[Vec3; 3], wi: V) -> V {
    let [a, b, c] = rows.map(V::splat);
    V::new(a.dot(wi), b.dot(wi), c.dot(wi))
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

    /// A 64 x 32 map with a sun, a black band, negative and NaN texels, turned off every axis.
    fn hard_map_light(lookup: EnvLookup) -> ResolvedImageInfinite {
        let (w, h) = (64, 32);
        let mut pixels: Vec<Vec3> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                Vec3::new(0.2 + 0.1 * (x * 0.3).sin(), 0.3 + 0.01 * y, 0.5 + 0.2 * (y * 0.7).cos())
            })
            .collect();
        pixels[10 * w + 20] = Vec3::splat(1e6);
        pixels[20 * w..22 * w].fill(Vec3::ZERO);
        pixels[5 * w + 3] = Vec3::new(-1.0, 0.5, 0.5);
        pixels[7 * w + 63] = Vec3::new(f32::NAN, 1.0, 1.0);
        let light = ImageInfiniteLight {
            lookup,
            ..ImageInfiniteLight::new(Arc::new(RgbImage { width: w, height: h, pixels }))
        };
        let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let transform = Transform { rotation: turn, ..Transform::IDENTITY };
        light.resolve(&transform, SceneSphere { center: Vec3::ZERO, radius: 5.0 }).unwrap()
    }

    #[test]
    fn le_and_pdf_lanes_give_the_scalar_bits_at_every_level_and_in_the_hard_cases() {
        let mut dirs: Vec<Vec3> = (0..2000)
            .map(|i| {
                let (a, b) = (i as f32 * 0.618_034, i as f32 * 0.754_877_7);
                let (z, phi) = (1.0 - 2.0 * a.fract(), std::f32::consts::TAU * b.fract());
                let r = (1.0 - z * z).max(0.0).sqrt();
                Vec3::new(r * phi.cos(), z, r * phi.sin())
            })
            .collect();
        // Non-unit lengths, the zero vector, the poles and the seam (x < 0, z = +-0 and tiny), in
        // the image's own frame so that they land there whatever the rotation.
        dirs.extend([Vec3::ZERO, Vec3::new(1e-30, 0.0, 0.0), Vec3::X * 1e3, Vec3::new(0.3, -0.2, 0.1) * 1e-3]);
        let light = hard_map_light(EnvLookup::Bilinear);
        let to_world = light.rotation;
        for local in [
            Vec3::Y,
            -Vec3::Y,
            -Vec3::X,
            Vec3::new(-1.0, 0.0, -0.0),
            Vec3::new(-1.0, 0.0, 1e-7),
            Vec3::new(-1.0, 0.0, -1e-7),
            Vec3::new(-1.0, 1e-6, 0.0),
        ] {
            dirs.push(to_world * local);
        }
        for lookup in [EnvLookup::Bilinear, EnvLookup::Nearest] {
            let light = hard_map_light(lookup);
            for mis in [false, true] {
                let want: Vec<Option<(SampledSpectrum, f32)>> =
                    dirs.iter().map(|&d| light.le_and_pdf(d, ColorQuery::Rgb, mis)).collect();
                assert!(want.iter().any(|w| w.is_none()) && want.iter().filter(|w| w.is_some()).count() > 1000);
                for level in crate::lanes::Level::ALL {
                    let Some(got) = crate::lanes::at_level(*level, || {
                        dirs.chunks(LANES)
                            .flat_map(|chunk| {
                                let mut wi = Vec3x16::ZERO;
                                for (l, &d) in chunk.iter().enumerate() {
                                    wi.set_lane(l, d);
                                }
                                let active = (1u32 << chunk.len()) - 1;
                                let got = light.le_and_pdf_rgb_lanes(&wi, active, mis);
                                assert_eq!(got.lit & !active, 0);
                                (0..chunk.len()).map(move |l| {
                                    let le = got.le.lane(l);
                                    (got.lit & 1 << l != 0)
                                        .then_some((SampledSpectrum([le.x, le.y, le.z, 0.0]), got.pdf[l]))
                                })
                            })
                            .collect::<Vec<_>>()
                    }) else {
                        continue;
                    };
                    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                        let bits =
                            |v: &Option<(SampledSpectrum, f32)>| v.map(|(s, p)| (s.0.map(f32::to_bits), p.to_bits()));
                        assert_eq!(bits(g), bits(w), "{level:?} {lookup:?} mis {mis}: direction {i} {:?}", dirs[i]);
                    }
                }
            }
        }
    }
}
