//! Sun and sky: a physical daylight (Hosek and Wilkie 2012, 2013; see `sunsky/hosek.rs`) with the sun
//! placed by direction or by place and UTC time (NOAA; see [`solar`]).
//!
//! Design: one light, one `LightTable` row of kind `SunSky`, holding two sampling techniques
//! combined as a one-sample mixture (Veach 1997, section 9.2.4): the sky is sampled like an image
//! light, from a lat-long table of the model's luminance (the env-map tables, rebuilt into
//! reused buffers when the light changes), and the sun on its own cone (uniform in the disc's
//! solid angle, as pbrt's and Mitsuba's cone sampling). Sample_Li picks the sun with probability
//! `p_sun` (its share of the luminous power) and `pdf_li` is the mixture density
//! p_sun pdf_sun + (1 - p_sun) pdf_sky, so BSDF-sampled rays that hit the sun or the sky get the
//! MIS weight of the combined strategy. One row (rather than an image row plus a disc row) keeps
//! one entity to one row, as the table's upsert expects, and lets the sky be evaluated from the
//! spectral model in spectral mode, which an image row cannot.
//!
//! Radiance is the model's own evaluation (not the table's texels): linear sRGB from the RGB
//! tables times 683 (nit) in RGB mode, the spectral tables in spectral mode. The model takes the
//! sun's geometric elevation; below the horizon its sky fades out through civil twilight
//! ([`twilight`]). Below the horizon (+Y up) is a Lambertian ground lit by sun and sky
//! ([`ground`]), sampled by the same table. Frame: +Y up, -Z north, +X east.

mod disc;
pub mod ground;
mod hosek;
mod sky_lanes;
pub mod solar;
pub mod twilight;

use std::f32::consts::PI;
use std::f64::consts::PI as PI64;
use std::sync::Arc;

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::tables::{EnvLookup, EnvMapTables, EnvTableOptions};
use super::{ColorQuery, LiSample, LightError, LightFlags, LightSampleContext, SceneSphere, far_distance};
use crate::lanes::{self, F32x16, LANES};
use crate::light::distant::SUN_ANGULAR_DIAMETER;
use crate::scene::image::{LUMINANCE_WEIGHTS, RgbImage};
use crate::spectrum::SampledSpectrum;
use crate::spectrum::cie::CIE_1931;
use crate::spectrum::photometry::K_M;

pub use disc::SunDisc;
pub use hosek::{ChannelConfig, RgbRow, SkyModel, SunModel, TURBIDITY_RANGE, WAVELENGTHS_NM};
pub use solar::{SolarPosition, UtcDateTime, direction_from_angles, solar_position};

/// Default turbidity: a clear sky (Hosek and Wilkie's tables span 1 to 10).
pub const DEFAULT_TURBIDITY: f32 = 3.0;
/// Default ground albedo (grass and soil, ~0.3; Mitsuba's default too).
pub const DEFAULT_GROUND_ALBEDO: f32 = 0.3;
/// Default width of the sky's sampling table, texels (height: half of it, rounded to even so the
/// horizon falls on a row edge): 0.7 degree texels.
pub const DEFAULT_SKY_TABLE_WIDTH: usize = 512;
/// Widths the sky table accepts.
pub const SKY_TABLE_WIDTHS: (usize, usize) = (8, 8192);

/// Where the sun is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SunPosition {
    /// Toward the sun, world frame (+Y up); need not be normalised.
    Direction(Vec3),
    /// From latitude (north positive) and longitude (east positive), degrees, and a UTC instant,
    /// by the NOAA solar position equations at the apparent (refracted) elevation.
    Location {
        /// Latitude, degrees in [-90, 90], north positive.
        latitude_deg: f64,
        /// Longitude, degrees in [-180, 180], east positive.
        longitude_deg: f64,
        /// The instant, UTC.
        time: UtcDateTime,
    },
}

/// A physical sun and sky around the scene (world frame: +Y up, -Z north, +X east; the entity's
/// transform is not used).
#[derive(Component, Clone, Debug, PartialEq)]
pub struct SunSkyLight {
    /// Defaults to 45 degrees above the southern horizon.
    pub sun: SunPosition,
    /// Atmospheric turbidity, in [1, 10]. Defaults to [`DEFAULT_TURBIDITY`].
    pub turbidity: f32,
    /// Ground albedo seen by the sky model, in [0, 1]. Defaults to [`DEFAULT_GROUND_ALBEDO`].
    pub ground_albedo: f32,
    /// Apparent diameter of the sun's disc, radians in (0, 0.5). Defaults to
    /// [`SUN_ANGULAR_DIAMETER`]; another size keeps the sun's illuminance (softer shadows, same
    /// exposure) by scaling its radiance by the solid-angle ratio.
    pub sun_angular_diameter: f32,
    /// Multiplies the model's absolute radiance (nit in RGB mode, W/(m^2 sr nm) in spectral
    /// mode), sky and sun alike. Defaults to 1.
    pub scale: f32,
    /// Width of the sky's sampling table, in [`SKY_TABLE_WIDTHS`]. Defaults to
    /// [`DEFAULT_SKY_TABLE_WIDTH`].
    pub table_width: usize,
}

impl Default for SunSkyLight {
    fn default() -> Self {
        Self {
            sun: SunPosition::Direction(direction_from_angles(45.0, 180.0)),
            turbidity: DEFAULT_TURBIDITY,
            ground_albedo: DEFAULT_GROUND_ALBEDO,
            sun_angular_diameter: SUN_ANGULAR_DIAMETER,
            scale: 1.0,
            table_width: DEFAULT_SKY_TABLE_WIDTH,
        }
    }
}

/// The generated sky image and its sampling tables, kept across rebuilds so a moving sun reuses
/// their buffers.
#[derive(Clone, Debug)]
pub struct SkyBuffers {
    /// Lat-long luminance image of the sky (nit, before `scale`), row 0 at the zenith.
    pub image: RgbImage,
    /// Tables of `image`; None until first built.
    pub tables: Option<EnvMapTables>,
    /// Per image column the cosine of its azimuth, then per column the sine: scratch for the
    /// image fill.
    pub columns: Vec<f32>,
    /// Per image row, the sum of its texels' luminance (f64): scratch for the sky's integral.
    pub row_luminance: Vec<f64>,
}

impl Default for SkyBuffers {
    fn default() -> Self {
        let image = RgbImage { width: 1, height: 1, pixels: vec![Vec3::ZERO] };
        Self { image, tables: None, columns: Vec::new(), row_luminance: Vec::new() }
    }
}

fn invalid(msg: String) -> LightError {
    LightError::Invalid { light: "SunSkyLight", msg }
}

impl SunSkyLight {
    /// A sky at the place and UTC time given, with defaults for the rest.
    pub fn at(latitude_deg: f64, longitude_deg: f64, time: UtcDateTime) -> Self {
        Self { sun: SunPosition::Location { latitude_deg, longitude_deg, time }, ..Default::default() }
    }

    /// Parses `LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY]` (degrees north and east, a UTC date-time,
    /// optionally seconds `:SS`), the form of `kelvin render --sky`, and checks the result.
    pub fn parse(spec: &str) -> Result<Self, LightError> {
        let form = "expected LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY] (degrees, UTC)";
        let parts: Vec<&str> = spec.split(',').map(str::trim).collect();
        let number = |name: &str, v: &str| -> Result<f64, LightError> {
            v.parse::<f64>().map_err(|_| invalid(format!("'{spec}': {name} '{v}' is not a number; {form}")))
        };
        let (lat, lon, time, turbidity) = match parts[..] {
            [lat, lon, time] => (lat, lon, time, None),
            [lat, lon, time, t] => (lat, lon, time, Some(t)),
            _ => return Err(invalid(format!("'{spec}': {form}"))),
        };
        let mut light = Self::at(number("latitude", lat)?, number("longitude", lon)?, UtcDateTime::parse(time)?);
        if let Some(t) = turbidity {
            light.turbidity = number("turbidity", t)? as f32;
        }
        light.validate()?;
        light.sun_direction()?;
        Ok(light)
    }

    /// The unit direction toward the sun (world frame).
    pub fn sun_direction(&self) -> Result<Vec3, LightError> {
        match self.sun {
            SunPosition::Direction(d) => {
                let n = d.normalize_or_zero();
                if !n.is_finite() || n == Vec3::ZERO {
                    return Err(invalid(format!("sun direction {d} must be finite and nonzero")));
                }
                Ok(n)
            }
            SunPosition::Location { latitude_deg, longitude_deg, time } => {
                Ok(solar_position(latitude_deg, longitude_deg, &time)?.direction())
            }
        }
    }

    /// The sun's geometric (unrefracted) elevation, radians: what the Hosek-Wilkie model and the
    /// twilight fade take ([`twilight`]). With a direction it is the direction's elevation.
    pub fn geometric_elevation(&self) -> Result<f32, LightError> {
        match self.sun {
            SunPosition::Direction(_) => Ok(self.sun_direction()?.y.clamp(-1.0, 1.0).asin()),
            SunPosition::Location { latitude_deg, longitude_deg, time } => {
                Ok(solar_position(latitude_deg, longitude_deg, &time)?.elevation_deg.to_radians() as f32)
            }
        }
    }

    /// Why this light gives no light, when the sun is past the end of civil twilight (see
    /// [`twilight`]; the night sky is not modelled). None while sun or sky give light.
    pub fn dark_reason(&self) -> Result<Option<String>, LightError> {
        let h = self.geometric_elevation()?;
        if twilight::sky_fade(h) > 0.0 || self.sun_direction()?.y > -(0.5 * self.sun_angular_diameter).sin() {
            return Ok(None);
        }
        let at = match self.sun {
            SunPosition::Location { latitude_deg, longitude_deg, time: t } => format!(
                " at {latitude_deg}, {longitude_deg} on {:04}-{:02}-{:02}T{:02}:{:02} UTC",
                t.year, t.month, t.day, t.hour, t.minute
            ),
            SunPosition::Direction(_) => String::new(),
        };
        Ok(Some(format!(
            "the sun is {:.1} degrees below the horizon{at}: the sun and sky give no light (the sky fades out \
             by the end of civil twilight, {} degrees; the night sky is not modelled)",
            -h.to_degrees(),
            twilight::CIVIL_TWILIGHT_END_DEG
        )))
    }

    /// Checks every field is in range (what [`Self::resolve`] checks first).
    pub fn validate(&self) -> Result<(), LightError> {
        let (t, a, d) = (self.turbidity, self.ground_albedo, self.sun_angular_diameter);
        if !(TURBIDITY_RANGE.0..=TURBIDITY_RANGE.1).contains(&t) {
            return Err(invalid(format!("turbidity {t} must be in [1, 10], the model's range")));
        }
        if !(0.0..=1.0).contains(&a) {
            return Err(invalid(format!("ground_albedo {a} must be in [0, 1]")));
        }
        if !(d > 0.0 && d < 0.5) {
            return Err(invalid(format!("sun_angular_diameter {d} must be in (0, 0.5) radians")));
        }
        if !(self.scale.is_finite() && self.scale >= 0.0) {
            return Err(invalid(format!("scale {} must be finite and >= 0", self.scale)));
        }
        let (lo, hi) = SKY_TABLE_WIDTHS;
        if !(lo..=hi).contains(&self.table_width) {
            return Err(invalid(format!("table_width {} must be in {lo}..={hi}", self.table_width)));
        }
        Ok(())
    }

    /// World-space form with fresh buffers; `scene` is the scene's bounding sphere.
    pub fn resolve(&self, scene: SceneSphere) -> Result<ResolvedSunSky, LightError> {
        self.resolve_reusing(scene, SkyBuffers::default())
    }

    /// As [`Self::resolve`], building the sky's image and tables into `buffers` (from an earlier
    /// resolve: [`ResolvedSunSky::into_buffers`]), so a changing sky allocates nothing.
    pub fn resolve_reusing(&self, scene: SceneSphere, mut buffers: SkyBuffers) -> Result<ResolvedSunSky, LightError> {
        self.validate()?;
        // The disc is drawn where it is seen (refracted); the models take the geometric elevation
        // (clamped to their range at 0) and the sky fades below it (see `twilight`).
        let sun_dir = self.sun_direction()?;
        let elevation = self.geometric_elevation()?;
        let fade = twilight::sky_fade(elevation);
        let sky = (fade > 0.0).then(|| SkyModel::new(elevation, self.turbidity, self.ground_albedo).scaled(fade));
        // The disc shines while a part of it is above the horizon (`le` clips the rest).
        let disc_up = sun_dir.y > -(0.5 * self.sun_angular_diameter).sin() && sky.is_some();
        let sun =
            disc_up.then(|| SunDisc::new(SunModel::new(elevation, self.turbidity), sun_dir, self.sun_angular_diameter));
        let (mut sky_lum, mut sky_rad) = (0.0, 0.0);
        let (mut ground_rgb, mut ground_spectral) = (Vec3::ZERO, [0.0; 11]);
        if let Some(sky) = &sky {
            let b = &mut buffers;
            fill_sky_image(&mut b.image, &mut b.columns, &mut b.row_luminance, self.table_width, sky, sun_dir);
            let sky_e = ground::image_horizontal_irradiance(&b.image);
            (ground_rgb, ground_spectral) =
                ground::ground_radiance(sky, sun_dir, sun.as_ref(), sky_e, self.ground_albedo);
            ground::fill_ground(&mut b.image, &mut b.row_luminance, ground_rgb);
            let options = EnvTableOptions { compensate: false, max_width: None, lookup: EnvLookup::Nearest };
            match &mut buffers.tables {
                Some(t) => t.rebuild(&buffers.image, options),
                None => buffers.tables = Some(EnvMapTables::build_with(&buffers.image, options)),
            }
            // The texels' integral (`texel_solid_angle_integral`, nearest) from the fill's row sums.
            let (h, d_phi) = (buffers.image.height, std::f64::consts::TAU / buffers.image.width as f64);
            let band = |y: usize| (PI64 * y as f64 / h as f64).cos() - (PI64 * (y + 1) as f64 / h as f64).cos();
            sky_lum = buffers.row_luminance.iter().enumerate().map(|(y, l)| l * d_phi * band(y)).sum();
            sky_rad = sky_lum / sky_efficacy(sky, sun_dir);
        }
        let s = self.scale as f64;
        let (sun_lum, sun_rad) = sun.as_ref().map_or((0.0, 0.0), |d| (d.illuminance, d.irradiance));
        let (sky_lum, sky_rad, sun_lum, sun_rad) = (sky_lum * s, sky_rad * s, sun_lum * s, sun_rad * s);
        let total = sky_lum + sun_lum;
        Ok(ResolvedSunSky {
            sun_dir,
            sky,
            sun,
            ground_rgb,
            ground_spectral,
            buffers: Arc::new(buffers),
            scale: self.scale,
            p_sun: if total > 0.0 { (sun_lum / total) as f32 } else { 0.0 },
            scene,
            luminous_integral: total as f32,
            radiometric_integral: (sky_rad + sun_rad) as f32,
        })
    }
}

/// Fills `image` (resized to `width` x its even half, buffers reused) with the sky's luminance
/// at texel centres, in parallel over rows, and `row_luminance` with each row's luminance sum; the
/// lower half (below the horizon) is left black for [`ground::fill_ground`]. The directions are those of
/// [`crate::scene::image::lat_long_direction`], with each row's zenith-angle factors and each
/// column's sin/cos of phi computed once (`columns`, reused). Blocks of [`LANES`] texels go
/// through the lane kernel ([`SkyModel::rgb_nits_lanes`]), the rest of a row through the scalar model.
fn fill_sky_image(
    image: &mut RgbImage,
    columns: &mut Vec<f32>,
    row_luminance: &mut Vec<f64>,
    width: usize,
    sky: &SkyModel,
    sun: Vec3,
) {
    let height = width.div_ceil(4) * 2;
    (image.width, image.height) = (width, height);
    image.pixels.resize(width * height, Vec3::ZERO);
    row_luminance.resize(height, 0.0);
    let phi = |x: usize| std::f32::consts::TAU * ((x as f32 + 0.5) / width as f32 - 0.5);
    columns.clear();
    columns.extend((0..width).map(|x| phi(x).cos()));
    columns.extend((0..width).map(|x| phi(x).sin()));
    let (cos_phi, sin_phi) = columns.split_at(width);
    let whole = width / LANES * LANES;
    let weights = LUMINANCE_WEIGHTS.as_dvec3();
    image.pixels.par_chunks_mut(width).zip(row_luminance.par_iter_mut()).enumerate().for_each(|(y, (row, sum))| {
        *sum = 0.0;
        if 2 * y >= height {
            row.fill(Vec3::ZERO);
            return;
        }
        let (sin_t, cos_t) = (PI * (y as f32 + 0.5) / height as f32).sin_cos();
        let factors = sky.rgb_row(cos_t);
        // Luminance per lane, summed while the block is in registers.
        let mut acc = [0.0f64; LANES];
        lanes::widest(
            #[inline(always)]
            || {
                // Index loops: `step_by` may stay out of the widest code (see `lanes::widest`).
                for k in 0..whole / LANES {
                    let b = k * LANES;
                    let (c, s) = (F32x16::load(cos_phi, b), F32x16::load(sin_phi, b));
                    let rgb = sky.rgb_nits_lanes(&factors, (sin_t, cos_t), &c, &s, sun);
                    rgb.store_vec3s(lanes::block_mut(row, b));
                    for l in 0..LANES {
                        let [r, g, b] = rgb.lane(l).to_array().map(f64::from);
                        acc[l] += weights.x * r + weights.y * g + weights.z * b;
                    }
                }
            },
        );
        for x in whole..width {
            let w = Vec3::new(sin_t * cos_phi[x], cos_t, sin_t * sin_phi[x]);
            row[x] = sky.rgb_nits_in_row(&factors, w, sun);
            acc[0] += weights.dot(row[x].as_dvec3());
        }
        *sum = acc.iter().sum();
    });
}

/// Luminous efficacy of the sky's zenith spectrum, lm/W: converts the table's luminous integral
/// to watts (the samplers weigh by luminous power, so this only feeds `phi`).
fn sky_efficacy(sky: &SkyModel, sun: Vec3) -> f64 {
    let (mut y, mut e) = (0.0, 0.0);
    for nm in 360..=830usize {
        let l = sky.spectral(nm as f32, Vec3::Y, sun) as f64;
        y += l * CIE_1931.at_nm(nm)[1];
        e += l;
    }
    if e > 0.0 { K_M * y / e } else { K_M }
}

/// A sun-and-sky light, ready to sample (see the module docs for the design).
#[derive(Clone)]
pub struct ResolvedSunSky {
    /// Unit direction toward the sun.
    pub sun_dir: Vec3,
    /// The sky model (twilight fade included); None past the end of civil twilight.
    pub sky: Option<SkyModel>,
    /// The sun's disc; None with the whole disc below the horizon.
    pub sun: Option<SunDisc>,
    /// Radiance of the ground below the horizon, photometric linear sRGB (nit), before `scale`.
    pub ground_rgb: Vec3,
    /// The same at the model's wavelengths, W/(m^2 sr nm) ([`WAVELENGTHS_NM`]; held beyond).
    pub ground_spectral: [f32; 11],
    /// The sky's image and sampling tables.
    pub buffers: Arc<SkyBuffers>,
    /// Multiplies sky and sun radiance alike (see [`SunSkyLight::scale`]).
    pub scale: f32,
    /// Probability that Sample_Li samples the sun rather than the sky.
    pub p_sun: f32,
    /// Bounds of the scene, used to place sample points beyond it and to compute the power.
    pub scene: SceneSphere,
    /// Integral of luminance over the sphere, nit sr (= lx), and of radiance, W/m^2.
    luminous_integral: f32,
    radiometric_integral: f32,
}

impl std::fmt::Debug for ResolvedSunSky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResolvedSunSky")
            .field("sun_dir", &self.sun_dir)
            .field("night", &self.sky.is_none())
            .field("tables", &self.buffers.tables)
            .field("p_sun", &self.p_sun)
            .field("scale", &self.scale)
            .field("scene", &self.scene)
            .finish()
    }
}

impl ResolvedSunSky {
    /// Infinite: seen by escaping rays, never a delta.
    pub fn flags(&self) -> LightFlags {
        LightFlags::INFINITE
    }

    /// True past the end of civil twilight: the light is black.
    pub fn is_night(&self) -> bool {
        self.sky.is_none()
    }

    /// The same light for another scene sphere (power scales with its cross-section; nothing is
    /// rebuilt).
    pub fn with_scene(&self, scene: SceneSphere) -> Self {
        Self { scene, ..self.clone() }
    }

    /// The buffers, for [`SunSkyLight::resolve_reusing`]; fresh ones if another owner holds them.
    pub fn into_buffers(self) -> SkyBuffers {
        Arc::try_unwrap(self.buffers).unwrap_or_default()
    }

    fn tables(&self) -> Option<&EnvMapTables> {
        self.buffers.tables.as_ref().filter(|_| self.sky.is_some())
    }

    /// A direction toward the sun (probability `p_sun`) or the sky; None at night or when the
    /// direction carries no light (a part of the disc below the horizon).
    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2, query: ColorQuery) -> Option<LiSample> {
        let wi = match &self.sun {
            Some(sun) if u.x < self.p_sun => sun.sample(Vec2::new(u.x / self.p_sun, u.y)),
            _ => {
                let ux = if self.p_sun > 0.0 { (u.x - self.p_sun) / (1.0 - self.p_sun) } else { u.x };
                self.tables()?.sample_direction(Vec2::new(ux.clamp(0.0, 1.0 - f32::EPSILON / 2.0), u.y), false)?.0
            }
        };
        // Density and radiance at `wi` itself, so pdf == pdf_li(wi) and radiance == le(wi).
        let pdf = self.pdf_li(wi);
        let radiance = self.le(wi, query);
        if !(pdf > 0.0) || radiance.0.iter().all(|&v| v == 0.0) {
            return None;
        }
        let p_light = ctx.p + wi * far_distance(self.scene, ctx.p);
        Some(LiSample { radiance, wi, pdf, p_light, n_light: Vec3::ZERO })
    }

    /// Solid-angle density of [`Self::sample_li`] choosing unit `wi`: the mixture of the sun's
    /// cone and the sky table.
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        let sky = self.tables().map_or(0.0, |t| t.pdf_direction(wi, false));
        let sun = self.sun.as_ref().map_or(0.0, |s| s.pdf(wi));
        self.p_sun * sun + (1.0 - self.p_sun) * sky
    }

    /// Radiance along an escaping ray of direction `wi` (unit): sky plus sun disc above the
    /// horizon, the ground below it.
    pub fn le(&self, wi: Vec3, query: ColorQuery) -> SampledSpectrum {
        let Some(sky) = &self.sky else { return SampledSpectrum::default() };
        if !(wi.y > 0.0) {
            let g = match query {
                ColorQuery::Rgb => SampledSpectrum([self.ground_rgb.x, self.ground_rgb.y, self.ground_rgb.z, 0.0]),
                ColorQuery::Spectral(w) => SampledSpectrum(w.lambda.map(|l| {
                    let (i, f) = hosek::wavelength_cell(l);
                    let (a, b) = (self.ground_spectral[i], self.ground_spectral[i + 1]);
                    a + f * (b - a)
                })),
            };
            return g.scale(self.scale);
        }
        let mut l = match query {
            ColorQuery::Rgb => {
                let c = sky.rgb_nits(wi, self.sun_dir);
                SampledSpectrum([c.x, c.y, c.z, 0.0])
            }
            ColorQuery::Spectral(w) => SampledSpectrum(w.lambda.map(|lambda| sky.spectral(lambda, wi, self.sun_dir))),
        };
        if let Some(sun) = self.sun.as_ref().and_then(|s| s.le(wi, query)) {
            l = l.add(sun);
        }
        l.scale(self.scale)
    }

    /// Power through the scene's bounding disc, W: pi R^2 times the integral of radiance.
    pub fn phi(&self) -> f32 {
        PI * self.scene.radius * self.scene.radius * self.radiometric_integral
    }

    /// Luminous power through the scene's bounding disc, lm.
    pub fn luminous_phi(&self) -> f32 {
        PI * self.scene.radius * self.scene.radius * self.luminous_integral
    }

    /// Illuminance of the sun's disc on a surface facing it, lx (with `scale`); 0 at night.
    pub fn sun_illuminance(&self) -> f32 {
        self.sun.as_ref().map_or(0.0, |s| (s.illuminance * self.scale as f64) as f32)
    }
}
