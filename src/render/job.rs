//! A render as `kelvin render` describes one: a scene file (or the default scene), the lights it
//! adds (an environment map, a sun and sky) and every option. The CLI and the Python package build
//! their renders from a [`RenderJob`], so one description gives one image, bit for bit.

use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::camera::CameraModel;
use super::film::Film;
use super::path::PathDepth;
use super::renderer::{Integrator, RenderOptions, RenderStats, Strategy, render_until};
use super::tiles::Crop;
use crate::light::SunSkyLight;
use crate::rng::Pattern;
use crate::shading::{ColorMode, LightSamplerKind, LightSelection, LightUpdates, Restir, ReuseWeights, Settings};
use crate::systems::LightingPlugin;

/// Accepted ranges of the numeric options (the CLI's parsers check the same).
pub const MAX_SIDE: u32 = 16384;
/// Camera samples per pixel.
pub const SPP: RangeInclusive<u32> = 1..=1 << 20;
/// Path depth and roulette depth.
pub const DEPTH: RangeInclusive<u32> = 0..=1024;
/// RIS candidates per sample.
pub const CANDIDATES: RangeInclusive<u32> = 1..=4096;
/// ReSTIR neighbours per pixel.
pub const NEIGHBOURS: RangeInclusive<u32> = 0..=256;
/// ReSTIR neighbourhood radius, pixels.
pub const RADIUS: RangeInclusive<u32> = 1..=MAX_SIDE;
/// An intensity multiplier (`env_intensity`, `sky_intensity`).
pub const INTENSITY: RangeInclusive<f32> = 0.0..=1e12;
/// A time budget, seconds (the end is excluded).
pub const SECONDS: std::ops::Range<f64> = 0.0..1e7;

/// How a light is chosen per sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum SamplerChoice {
    /// Every light equally likely.
    Uniform,
    /// Lights in proportion to their power.
    Power,
    /// The light BVH: lights weighed by what can reach the point (pbrt-v4's default).
    #[default]
    Bvh,
    /// Resampled importance sampling over several light-BVH candidates, one shadow ray.
    Ris,
    /// RIS, then reuse of neighbouring pixels' reservoirs (ReSTIR, spatial).
    Restir,
}

/// Path tracing or direct lighting.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum IntegratorChoice {
    /// Paths up to the maximum depth, every bounce through the light system.
    #[default]
    Path,
    /// Light and BSDF samples at the surface the camera sees.
    Direct,
}

/// What can be wrong with a job: an option out of range, a scene or map that does not load.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error("{0}")]
    /// An option out of range or inconsistent with another; the message names it.
    Invalid(String),
    #[error(transparent)]
    /// The scene file did not load.
    Gltf(#[from] crate::scene::gltf::GltfError),
    #[error(transparent)]
    /// The environment map did not load.
    Image(#[from] crate::scene::image::ImageError),
}

/// Every option of `kelvin render` but its outputs and animation frames. The defaults are the CLI's.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderJob {
    /// A glTF file (.gltf or .glb); None: the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Camera samples per pixel (per pass, with `time`).
    pub spp: u32,
    /// Render passes of `spp` until this many seconds have passed.
    pub time: Option<f64>,
    /// A lat-long environment map (.exr or .hdr) as an infinite light, and the luminance (nit) of
    /// a texel of value 1.
    pub env: Option<PathBuf>,
    /// Luminance (nit) of an environment texel of value 1.
    pub env_intensity: f32,
    /// A sun and sky: `"LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY]"`, and a multiplier of its radiance.
    pub sky: Option<String>,
    /// Multiplier of the sun and sky's physical radiance (the job's sky, or the scene file's `KELVIN_sun_sky`).
    pub sky_intensity: f32,
    /// Path tracing or direct lighting.
    pub integrator: IntegratorChoice,
    /// Path tracer: surfaces after the camera's at most, and where Russian roulette may start.
    pub depth: PathDepth,
    /// How a light is chosen per sample.
    pub light_sampler: SamplerChoice,
    /// RIS and ReSTIR: light-BVH candidates per resampled sample (None: 8). Set under another
    /// light sampler, it is refused.
    pub candidates: Option<u32>,
    /// ReSTIR: neighbour reservoirs combined per pixel (None: 4). Refused under other samplers.
    pub neighbours: Option<u32>,
    /// ReSTIR: radius of the neighbourhood, pixels (None: 16). Refused under other samplers.
    pub radius: Option<u32>,
    /// ReSTIR: weigh combined reservoirs 1/sum M (biased). Refused under other samplers.
    pub biased_reuse: bool,
    /// RGB or spectral rendering.
    pub color: ColorMode,
    /// Every light sampled at every point instead of one chosen light.
    pub all_lights: bool,
    /// MIS of light and BSDF samples (false: light samples only).
    pub mis: bool,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Which random numbers samples draw.
    pub pattern: Pattern,
    /// Render a lat-long map seen from this point instead of through the scene's camera.
    pub environment_at: Option<Vec3>,
    /// Render only this region of the image, bit for bit as in the full render.
    pub crop: Option<Crop>,
}

impl Default for RenderJob {
    fn default() -> Self {
        Self {
            scene: None,
            width: 512,
            height: 512,
            spp: 32,
            time: None,
            env: None,
            env_intensity: 1.0,
            sky: None,
            sky_intensity: 1.0,
            integrator: IntegratorChoice::Path,
            depth: PathDepth::DEFAULT,
            light_sampler: SamplerChoice::Bvh,
            candidates: None,
            neighbours: None,
            radius: None,
            biased_reuse: false,
            color: ColorMode::Rgb,
            all_lights: false,
            mis: true,
            seed: 0,
            pattern: Pattern::Sobol,
            environment_at: None,
            crop: None,
        }
    }
}

/// A job's world, ready to render: its schedule, the glTF file's index in `GltfAnimations`, and
/// what loading said (warnings, and a one-line summary of the scene).
pub struct LoadedJob {
    /// The world with the scene, its lights and the light system's resources.
    pub world: World,
    /// The light system's schedule for that world.
    pub schedule: Schedule,
    /// The glTF file's index in `GltfAnimations` (None: the default scene).
    pub file: Option<usize>,
    /// The loaders' warnings.
    pub warnings: Vec<String>,
    /// A one-line summary of the loaded scene file.
    pub summary: Option<String>,
    /// The scene file's lights as the file describes them (names, glTF units, rest pose).
    pub lights: Vec<crate::scene::gltf::LightData>,
    /// The scene file's cameras as the file describes them.
    pub cameras: Vec<crate::scene::gltf::CameraData>,
    /// The scene file's mesh entities with their glTF names and lightmap uvs (what `kelvin bake` reads).
    pub primitives: Vec<crate::scene::spawn::SpawnedPrimitive>,
    /// Every file the load read (scene, what it references, environment map), hashed as read: what
    /// an output's provenance records.
    pub inputs: crate::provenance::Inputs,
}

fn check_in<T: PartialOrd + std::fmt::Display>(name: &str, v: T, range: RangeInclusive<T>) -> Result<(), JobError> {
    if range.contains(&v) {
        Ok(())
    } else {
        Err(JobError::Invalid(format!("{name} = {v} is outside {}..={}", range.start(), range.end())))
    }
}

impl RenderJob {
    /// Checks every option (ranges, the crop, tiling, the sky's text) without loading anything.
    pub fn check(&self) -> Result<(), JobError> {
        check_in("width", self.width, 1..=MAX_SIDE)?;
        check_in("height", self.height, 1..=MAX_SIDE)?;
        check_in("spp", self.spp, SPP)?;
        check_in("max_depth", self.depth.max_depth, DEPTH)?;
        check_in("roulette_depth", self.depth.roulette_depth, DEPTH)?;
        check_in("candidates", self.candidates(), CANDIDATES)?;
        check_in("neighbours", self.neighbours(), NEIGHBOURS)?;
        check_in("radius", self.radius(), RADIUS)?;
        self.check_light_choice()?;
        check_in("env_intensity", self.env_intensity, INTENSITY)?;
        check_in("sky_intensity", self.sky_intensity, INTENSITY)?;
        if let Some(t) = self.time
            && !(t.is_finite() && SECONDS.contains(&t))
        {
            return Err(JobError::Invalid(format!("time = {t} is outside [0, {})", SECONDS.end)));
        }
        if let Some(p) = self.environment_at
            && !p.is_finite()
        {
            return Err(JobError::Invalid(format!("environment_at = {p} is not finite")));
        }
        if let Some(crop) = self.crop {
            crop.check(self.width, self.height).map_err(|e| JobError::Invalid(e.to_string()))?;
            let opts = self.options();
            opts.check_tiling(&self.selection()).map_err(|e| JobError::Invalid(format!("crop {crop}: {e}")))?;
        }
        self.sun_sky()?;
        Ok(())
    }

    /// RIS candidates per resampled sample.
    pub fn candidates(&self) -> u32 {
        self.candidates.unwrap_or(8)
    }

    /// ReSTIR neighbours per pixel.
    pub fn neighbours(&self) -> u32 {
        self.neighbours.unwrap_or(4)
    }

    /// ReSTIR neighbourhood radius, pixels.
    pub fn radius(&self) -> u32 {
        self.radius.unwrap_or(16)
    }

    /// Refuses options that the light choice would silently ignore: every light sampled
    /// (`all_lights`) with a resampling sampler, resampling options under a sampler that does not
    /// resample, reuse options without ReSTIR.
    fn check_light_choice(&self) -> Result<(), JobError> {
        let sampler = format!("{:?}", self.light_sampler).to_lowercase();
        let refuse = |msg: String| Err(JobError::Invalid(msg));
        let resamples = matches!(self.light_sampler, SamplerChoice::Ris | SamplerChoice::Restir);
        if self.all_lights && resamples {
            return refuse(format!(
                "all_lights samples every light at every point, which light_sampler = {sampler} would replace: \
                 choose one"
            ));
        }
        if let Some(c) = self.candidates
            && !resamples
        {
            return refuse(format!("candidates = {c} is for light_sampler = ris or restir, not {sampler}"));
        }
        if self.light_sampler != SamplerChoice::Restir {
            let reuse = [
                self.neighbours.map(|n| format!("neighbours = {n}")),
                self.radius.map(|r| format!("radius = {r}")),
                self.biased_reuse.then(|| "biased_reuse".to_string()),
            ];
            if let Some(option) = reuse.into_iter().flatten().next() {
                return refuse(format!("{option} is for light_sampler = restir, not {sampler}"));
            }
        }
        Ok(())
    }

    /// How lights are chosen per point.
    pub fn selection(&self) -> LightSelection {
        match self.light_sampler {
            _ if self.all_lights => LightSelection::All,
            SamplerChoice::Ris => LightSelection::Resampled { candidates: self.candidates() },
            SamplerChoice::Restir => LightSelection::Restir(Restir {
                candidates: self.candidates(),
                spatial: self.neighbours(),
                radius: self.radius(),
                // One frame: no previous run to reuse.
                temporal: false,
                weights: if self.biased_reuse { ReuseWeights::Biased } else { ReuseWeights::Unbiased },
                ..Restir::default()
            }),
            _ => LightSelection::OneSampled,
        }
    }

    /// The light system's settings.
    pub fn settings(&self) -> Settings {
        Settings {
            color_mode: self.color,
            light_sampler: match self.light_sampler {
                SamplerChoice::Uniform => LightSamplerKind::Uniform,
                SamplerChoice::Power => LightSamplerKind::Power,
                SamplerChoice::Bvh | SamplerChoice::Ris | SamplerChoice::Restir => LightSamplerKind::Bvh,
            },
            selection: self.selection(),
            seed: self.seed,
            pattern: self.pattern,
            // A frame's bytes must not depend on the frames rendered before it in one process.
            light_updates: LightUpdates::Rebuild,
            ..Default::default()
        }
    }

    /// The render's options (image, samples, integrator, crop).
    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.width,
            height: self.height,
            spp: self.spp,
            strategy: if self.mis { Strategy::Mis } else { Strategy::LightOnly },
            integrator: match self.integrator {
                IntegratorChoice::Path => Integrator::Path(self.depth),
                IntegratorChoice::Direct => Integrator::Direct,
            },
            time_budget: self.time.map(std::time::Duration::from_secs_f64),
            crop: self.crop,
        }
    }

    /// The environment camera, or None for the scene's own.
    pub fn camera(&self) -> Option<CameraModel> {
        self.environment_at.map(|origin| CameraModel::LatLong { origin, width: self.width, height: self.height })
    }

    /// The sun and sky the job names, checked.
    fn sun_sky(&self) -> Result<Option<SunSkyLight>, JobError> {
        let Some(spec) = &self.sky else { return Ok(None) };
        let bad = |e: crate::light::LightError| JobError::Invalid(format!("--sky {spec}: {e}"));
        let light = SunSkyLight { scale: self.sky_intensity, ..SunSkyLight::parse(spec).map_err(bad)? };
        light.validate().map_err(bad)?;
        Ok(Some(light))
    }

    /// Checks the job and builds its world: settings, the scene (file or default), the
    /// environment map and the sun and sky.
    pub fn load(&self) -> Result<LoadedJob, JobError> {
        self.check()?;
        let mut sky = self.sun_sky()?;
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(self.settings());
        LightingPlugin::build(&mut world, &mut schedule);
        let (mut lights, mut cameras, mut primitives) = (Vec::new(), Vec::new(), Vec::new());
        let mut inputs = crate::provenance::Inputs::default();
        let (mut warnings, file, summary) = match &self.scene {
            Some(path) => {
                let start = std::time::Instant::now();
                let mut scene = crate::scene::gltf::load_gltf(path)?;
                // The job's sky replaces the file's; `sky_intensity` scales whichever is used.
                match (scene.sky.take(), &mut sky) {
                    (Some(_), Some(_)) => scene.warnings.push(format!(
                        "{}: the file's {} is replaced by the job's sky",
                        path.display(),
                        crate::scene::gltf::sky::SUN_SKY
                    )),
                    (Some(file_sky), None) => {
                        sky = Some(SunSkyLight { scale: file_sky.scale * self.sky_intensity, ..file_sky })
                    }
                    (None, _) => {}
                }
                let mut report = crate::scene::spawn::spawn_gltf(&mut world, &scene);
                let mut read = std::mem::take(&mut scene.inputs).into_iter();
                inputs.scene = read.next();
                inputs.referenced = read.chain(std::mem::take(&mut report.inputs)).collect();
                (lights, cameras, primitives) = (scene.lights, scene.cameras, std::mem::take(&mut report.primitives));
                let summary = format!(
                    "scene {} (loaded in {:.1} ms): {} meshes ({} triangles, {} emissive), {} lights, {} cameras, {} animations",
                    path.display(),
                    start.elapsed().as_secs_f64() * 1e3,
                    report.meshes,
                    report.triangles,
                    report.emissive_meshes,
                    report.lights,
                    report.cameras,
                    report.animations
                );
                (report.warnings, Some(report.file), Some(summary))
            }
            None => {
                spawn_default_scene(&mut world)?;
                (Vec::new(), None, None)
            }
        };
        if let Some(path) = &self.env {
            let (env_warnings, read) = super::scene_file::spawn_env_map_recorded(&mut world, path, self.env_intensity)?;
            warnings.extend(env_warnings);
            inputs.env = Some(read);
        }
        if let Some(light) = sky {
            world.spawn(light);
        }
        Ok(LoadedJob { world, schedule, file, warnings, summary, lights, cameras, primitives, inputs })
    }
}

/// The embedded default scene (feature `scenes`).
#[cfg(feature = "scenes")]
fn spawn_default_scene(world: &mut World) -> Result<(), JobError> {
    crate::scenes::default_scene::spawn_default_scene(world);
    Ok(())
}

#[cfg(not(feature = "scenes"))]
fn spawn_default_scene(_: &mut World) -> Result<(), JobError> {
    Err(JobError::Invalid("no scene given, and the embedded default scene needs the `scenes` feature".into()))
}

impl LoadedJob {
    /// Renders the job's image (its crop, if it has one); `progress` gets the finished fraction,
    /// and setting `stop` ends the render after the batch in flight (`RenderStats::stopped`).
    pub fn render(
        &mut self,
        job: &RenderJob,
        progress: impl FnMut(f32) + Send,
        stop: &AtomicBool,
    ) -> (Film, RenderStats) {
        render_until(&mut self.world, &mut self.schedule, &job.options(), job.camera(), progress, stop)
    }
}
