//! The batch renderer: camera rays -> closest hits -> the light system (via the `ShadingBatch`
//! and one run of the schedule) -> MIS with BSDF sampling -> film. It never bypasses the light
//! system: light selection, Sample_Li and shadow rays all happen in the ECS systems.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy_ecs::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use super::camera::{Camera, CameraModel, PinholeCamera};
use super::camera_pass::{CameraColumns, SampleRange, trace_camera_rays};
use super::film::Film;
use super::normal_map::apply_normal_maps;
use super::path::{PathDepth, PathJob, Paths, Start};
use super::shade::{Materials, ShadeContext};
use super::tiles::{Crop, TileError};
use crate::geometry::{RAY_CHUNK, SceneBvh};
use crate::lanes::LANES;
use crate::rng::SampleStream;
use crate::shading::{ColorMode, LightSelection, RunReport, RunSummary, SceneBounds, Settings, ShadingBatch};
use crate::spectrum::{SampledSpectrum, SampledWavelengths, color};

/// Camera samples per batch handed to the light system.
pub(super) const BATCH_SAMPLES: usize = 1 << 14;
/// Salt that keeps the renderer's random dimensions apart from the light systems'.
pub(super) const RENDER_SALT: u64 = 0x5eed_ca3e_7a11_0b0e;

/// How direct light is estimated at a surface point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Strategy {
    /// Light and BSDF samples combined by the power heuristic (Veach 1997, ch. 9).
    #[default]
    Mis,
    /// Light samples only.
    LightOnly,
    /// BSDF samples only. Delta lights keep their light samples (no BSDF sample can find them).
    BsdfOnly,
}

impl Strategy {
    /// Weight of a light sample of a non-delta light (pdfs of both strategies for its direction).
    pub(super) fn light_weight(self, light_pdf: f32, bsdf_pdf: f32) -> f32 {
        match self {
            Self::Mis => power_heuristic(light_pdf, bsdf_pdf),
            Self::LightOnly => 1.0,
            Self::BsdfOnly => 0.0,
        }
    }
    /// Weight of a BSDF sample that reached a light.
    pub(super) fn bsdf_weight(self, bsdf_pdf: f32, light_pdf: f32) -> f32 {
        match self {
            Self::Mis => power_heuristic(bsdf_pdf, light_pdf),
            Self::LightOnly => 0.0,
            Self::BsdfOnly => 1.0,
        }
    }
}

/// How light is carried from the lights to the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Direct lighting: light and BSDF samples at the surface the camera sees.
    Direct,
    /// Path tracing (`render::path`): every bounce's surfaces go through the light system.
    Path(PathDepth),
}

impl Default for Integrator {
    fn default() -> Self {
        Self::Path(PathDepth::DEFAULT)
    }
}

/// What to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Size of the full image, which the camera frames.
    pub width: u32,
    /// Height of the full image, pixels.
    pub height: u32,
    /// Samples per pixel in each pass.
    pub spp: u32,
    /// How light and BSDF samples are combined (at every bounce). Defaults to MIS.
    pub strategy: Strategy,
    /// Defaults to path tracing.
    pub integrator: Integrator,
    /// Render passes of `spp` samples per pixel until this much time has passed (at least one
    /// pass); None for one pass.
    pub time_budget: Option<std::time::Duration>,
    /// Renders only this region of the full image (the film is its size), with the full image's
    /// camera rays and random streams: its pixels are bit for bit those of the full render. A crop
    /// is clipped to the image; [`Crop::check`] says whether it lies inside. None: the whole image.
    pub crop: Option<Crop>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            spp: 16,
            strategy: Strategy::Mis,
            integrator: Integrator::default(),
            time_budget: None,
            crop: None,
        }
    }
}

impl RenderOptions {
    /// Direct lighting at `width` x `height` and `spp`, with MIS.
    pub fn direct(width: u32, height: u32, spp: u32) -> Self {
        Self { width, height, spp, integrator: Integrator::Direct, ..Default::default() }
    }

    /// The region of the image the film covers: the crop clipped to the image, or all of it.
    pub fn region(&self) -> Crop {
        self.crop.map_or(Crop::full(self.width, self.height), |c| c.clipped(self.width, self.height))
    }

    /// Whether the crop (if any) renders that region of the full render. Two things make a tile
    /// another image: ReSTIR's spatial reuse, whose neighbours come from the render's own samples
    /// and batches, and a time budget, which gives each tile as many passes as fit its own time.
    /// ReSTIR's temporal reuse alone tiles: a render never gives its batches previous points
    /// (`ShadingBatch::previous` stays empty), so no reservoir finds a history to reuse. A crop
    /// that covers the whole image is the full render.
    pub fn check_tiling(&self, selection: &LightSelection) -> Result<(), TileError> {
        if self.region() == Crop::full(self.width, self.height) {
            return Ok(());
        }
        if let LightSelection::Restir(r) = selection
            && r.spatial > 0
        {
            return Err(TileError::Reuse);
        }
        if self.time_budget.is_some() {
            return Err(TileError::TimeBudget);
        }
        Ok(())
    }
}

/// Counts of a finished render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall-clock time of the whole render, s (the first update included).
    pub seconds: f64,
    /// Samples per pixel rendered (more than asked under a time budget).
    pub spp: u64,
    /// Camera rays traced, one per sample (escaped ones included).
    pub camera_samples: u64,
    /// Shadow rays the light system traced, over every bounce.
    pub shadow_rays: u64,
    /// BSDF-sampled rays traced: for MIS at the surface, or (path tracing) to continue a path.
    pub bsdf_rays: u64,
    /// The light system's update before the first batch, s: what bringing the BVH and light
    /// tables up to date with the world cost (a scene's load, or an animation frame's changes).
    pub update_seconds: f64,
    /// Where the time went, pass by pass (their sum is `seconds` less the set-up).
    pub passes: PassSeconds,
    /// The light system's run report over every update of the render (the one before the first
    /// batch, then one per batch): each warning, and per system its runs and summed counts.
    pub report: RunSummary,
    /// The render was stopped before its samples were done (see [`render_until`]).
    pub stopped: bool,
}

/// Seconds spent in each pass of a render, summed over its batches.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassSeconds {
    /// Camera rays and their closest hits, written into the `ShadingBatch`.
    pub camera: f64,
    /// The schedule's run per batch: light choice, Sample_Li and shadow rays.
    pub light_system: f64,
    /// MIS with BSDF samples, and adding the samples to the film.
    pub shading: f64,
}

/// The power heuristic (beta = 2) weight of a strategy with pdf `a` against one with pdf `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    // Selects, not branches (`&`, the quotient always computed): lane loops vectorise.
    let ratio = a2 / (a2 + b2);
    let infinite = if a.is_infinite() { 1.0 } else { 0.0 };
    if (a2 + b2 > 0.0) & a2.is_finite() { ratio } else { infinite }
}

/// Photometric linear sRGB of a 4-lane value in the given mode.
pub(super) fn to_rgb(v: SampledSpectrum, wavelengths: Option<&SampledWavelengths>) -> Vec3 {
    match wavelengths {
        None => Vec3::new(v.0[0], v.0[1], v.0[2]),
        Some(w) => color::xyz_to_srgb(w.to_xyz(v).as_dvec3()).as_vec3(),
    }
}

/// The camera of the world (the first `Camera` with a `Transform`), or one framing the scene.
fn find_camera(world: &mut World, width: u32, height: u32) -> PinholeCamera {
    let mut q = world.query::<(&Camera, &crate::geometry::Transform)>();
    if let Some((c, t)) = q.iter(world).next() {
        return PinholeCamera::new(c, t, width, height);
    }
    let s = world.resource::<SceneBounds>().sphere;
    let (c, t) = PinholeCamera::framing(s.center, s.radius, width, height);
    PinholeCamera::new(&c, &t, width, height)
}

/// Renders the world's scene through its camera (the first `Camera`, or one framing the scene).
/// The world must have had `LightingPlugin::build` applied to it and `schedule`; `Settings`
/// choose colour mode, light sampler and selection.
pub fn render(
    world: &mut World,
    schedule: &mut Schedule,
    opts: &RenderOptions,
    progress: impl FnMut(f32) + Send,
) -> (Film, RenderStats) {
    render_with(world, schedule, opts, None, progress)
}

/// Renders a lat-long radiance map seen from `origin` (an environment camera): a `width` x
/// `height` image whose pixels are radiance (nit) along `lat_long_direction`, ready to light
/// another scene as an `ImageInfiniteLight` (with scale 1 and a white spectrum).
pub fn render_environment(
    world: &mut World,
    schedule: &mut Schedule,
    origin: Vec3,
    opts: &RenderOptions,
) -> (crate::scene::image::RgbImage, RenderStats) {
    let model = CameraModel::LatLong { origin, width: opts.width, height: opts.height };
    let (film, stats) = render_with(world, schedule, opts, Some(model), |_| {});
    let (width, height) = (film.width as usize, film.height as usize);
    (crate::scene::image::RgbImage { width, height, pixels: film.pixels() }, stats)
}

/// Renders through `camera`, or the world's camera when None.
pub fn render_with(
    world: &mut World,
    schedule: &mut Schedule,
    opts: &RenderOptions,
    camera: Option<CameraModel>,
    progress: impl FnMut(f32) + Send,
) -> (Film, RenderStats) {
    render_until(world, schedule, opts, camera, progress, &AtomicBool::new(false))
}

/// [`render_with`] that ends after the batch in flight once `stop` is set (an app's cancel, a
/// Ctrl-C): the film then holds the samples finished so far and `RenderStats::stopped` is true.
pub fn render_until(
    world: &mut World,
    schedule: &mut Schedule,
    opts: &RenderOptions,
    camera: Option<CameraModel>,
    progress: impl FnMut(f32) + Send,
    stop: &AtomicBool,
) -> (Film, RenderStats) {
    // The render runs on a pool thread (rayon::scope moves it there), so each parallel pass
    // starts without handing its work to the pool and putting the calling thread to sleep.
    rayon::scope(|_| render_on_pool(world, schedule, opts, camera, progress, stop))
}

fn render_on_pool(
    world: &mut World,
    schedule: &mut Schedule,
    opts: &RenderOptions,
    camera: Option<CameraModel>,
    mut progress: impl FnMut(f32),
    stop: &AtomicBool,
) -> (Film, RenderStats) {
    let start = std::time::Instant::now();
    let mut stats = RenderStats::default();
    // Compensated env tables only pay off when BSDF samples cover the dim part of the sky.
    world.resource_mut::<Settings>().mis = opts.strategy == Strategy::Mis;
    // One update brings the BVH and light tables up to date before cameras are placed.
    world.resource_mut::<ShadingBatch>().clear();
    schedule.run(world);
    stats.update_seconds = start.elapsed().as_secs_f64();
    // Each update clears the world's run report: what it says (this update's warnings above all)
    // is kept in the render's own.
    stats.report.add(world.resource::<RunReport>());
    let camera = camera.unwrap_or_else(|| CameraModel::Pinhole(find_camera(world, opts.width, opts.height)));
    let materials = Materials::of(world);
    let settings = world.resource::<Settings>().clone();
    if let Err(e) = opts.check_tiling(&settings.selection) {
        stats.report.warnings.push(format!("crop {}: {e}", opts.region()));
    }
    let spectral = settings.color_mode == ColorMode::Spectral;
    let seed = settings.seed ^ RENDER_SALT;

    let region = opts.region();
    let mut film = Film::new(region.width(), region.height());
    let total = region.pixels() * opts.spp as usize;
    let mut columns = CameraColumns::default();
    let mut contributions: Vec<Vec3> = Vec::new();
    let mut paths = Paths::default();
    // Passes of `spp` samples per pixel: one, or as many as fit in the time budget (each pass
    // draws the next samples of every pixel's streams).
    'passes: for pass in 0u32..=u32::MAX {
        let Some(first_sample) = first_sample_of_pass(pass, opts.spp) else { break };
        let mut first = 0usize;
        while first < total {
            let len = BATCH_SAMPLES.min(total - first);
            let pattern = settings.pattern;
            let range =
                SampleRange { first, len, region, full_width: opts.width, spp: opts.spp, seed, pattern, first_sample };
            let camera_start = std::time::Instant::now();
            // Every camera sample takes a slot of the batch (one with no point if its ray escaped).
            world.resource_scope(|world, mut batch: Mut<ShadingBatch>| {
                let bvh = world.resource::<SceneBvh>();
                trace_camera_rays(&mut batch, &mut columns, bvh, &camera, range);
                apply_normal_maps(&mut batch, &columns, bvh, &materials);
                // Spectral mode: the wavelengths of each sample (dimension 0 of its stream).
                if spectral {
                    let batch = &mut *batch;
                    let lambda =
                        batch.pixel.par_iter().zip(&batch.sample).with_min_len(RAY_CHUNK).map(|(&pixel, &sample)| {
                            SampledWavelengths::sample_visible(
                                SampleStream::new(pattern, seed, pixel, sample).at_dimension(0).next_f32(),
                            )
                        });
                    batch.wavelengths.par_extend(lambda);
                }
            });
            stats.passes.camera += camera_start.elapsed().as_secs_f64();
            match opts.integrator {
                Integrator::Direct => {
                    let job = DirectJob { columns: &columns, materials: &materials, seed, strategy: opts.strategy };
                    job.shade(world, schedule, (&mut film, first, opts.spp as usize), &mut contributions, &mut stats);
                }
                Integrator::Path(depth) => {
                    let (strategy, start) = (opts.strategy, Start::Camera);
                    let job = PathJob { depth, materials: &materials, seed, strategy, start, closed: None };
                    paths.trace(world, schedule, &mut columns, &job, &mut contributions, &mut stats);
                    let film_start = std::time::Instant::now();
                    film.par_add_samples(first, opts.spp as usize, &contributions);
                    stats.passes.shading += film_start.elapsed().as_secs_f64();
                }
            }
            stats.camera_samples += len as u64;
            first += len;
            let done = match opts.time_budget {
                None => first as f32 / total as f32,
                Some(budget) => (start.elapsed().as_secs_f64() / budget.as_secs_f64()).min(1.0) as f32,
            };
            progress(done);
            if stop.load(Ordering::Relaxed) {
                stats.stopped = true;
                break 'passes;
            }
        }
        stats.spp += u64::from(opts.spp);
        if opts.time_budget.is_none_or(|budget| start.elapsed() >= budget) {
            break;
        }
    }
    stats.seconds = start.elapsed().as_secs_f64();
    (film, stats)
}

/// The index of the first sample of pass `pass` of `spp` samples per pixel, or None when the pass
/// would run past the sample streams' u32 index (2^32 samples per pixel): a time budget stops
/// there instead of wrapping round to samples already drawn.
fn first_sample_of_pass(pass: u32, spp: u32) -> Option<u32> {
    let first = pass.checked_mul(spp)?;
    first.checked_add(spp.saturating_sub(1)).map(|_| first)
}

/// What the direct integrator needs beyond the world.
struct DirectJob<'a> {
    columns: &'a CameraColumns,
    materials: &'a Materials,
    seed: u64,
    strategy: Strategy,
}

impl DirectJob<'_> {
    /// Runs the schedule on the camera pass's batch, shades each sample, and adds them to the
    /// film (samples `first..` of `spp` per pixel), using `contributions` as scratch.
    fn shade(
        &self,
        world: &mut World,
        schedule: &mut Schedule,
        (film, first, spp): (&mut Film, usize, usize),
        contributions: &mut Vec<Vec3>,
        stats: &mut RenderStats,
    ) {
        let light_system_start = std::time::Instant::now();
        schedule.run(world);
        let shading_start = std::time::Instant::now();
        stats.report.add(world.resource::<RunReport>());
        stats.passes.light_system += (shading_start - light_system_start).as_secs_f64();
        stats.shadow_rays += world.resource::<crate::systems::ShadowRays>().len() as u64;

        let shade = ShadeContext::new(world, self.columns, self.materials, self.seed, self.strategy);
        let len = shade.batch.len();
        let bsdf_sampling = shade.bsdf_sampling();
        // Blocks of `LANES` samples: where the lane kernel may apply (`shade_lanes.rs`), it shades
        // the block; elsewhere its samples are shaded one at a time and their BSDF rays' light
        // found together. Either way the tasks count their BSDF rays as they go (a pass of its
        // own cost a parallel region per batch), and write every contribution, so that column is
        // only resized (no serial fill in steady state).
        let spectral = !shade.batch.wavelengths.is_empty();
        let lanes = !spectral && !bsdf_sampling && !super::shade_lanes::turned_off();
        let shade_chunk = |c: usize, out: &mut [Vec3]| -> usize {
            let first = c * RAY_CHUNK;
            let (mut b, mut traced) = (0, 0);
            while b < out.len() {
                let end = (b + LANES).min(out.len());
                let block = &mut out[b..end];
                let lane_kernel = lanes
                    && crate::lanes::widest(
                        #[inline(always)]
                        || shade.shade_lanes(first + b, block),
                    );
                if !lane_kernel {
                    traced += shade.shade_direct_block(first + b, block, bsdf_sampling);
                }
                b = end;
            }
            traced
        };
        contributions.resize(len, Vec3::ZERO);
        let chunks = contributions.par_chunks_mut(RAY_CHUNK).enumerate();
        // Sample k is sample k % spp of pixel k / spp (see `SampleRange`). Where each chunk holds
        // whole pixels, the task that shaded it adds them to the film (while they are in cache,
        // and without a parallel region of its own).
        let bsdf_rays: usize = if let Some(runs) = film.pixel_runs_mut(first, len, spp, RAY_CHUNK) {
            chunks
                .zip(runs)
                .map(|((c, out), run)| {
                    let traced = shade_chunk(c, out);
                    run.add_whole_pixels(spp, out);
                    traced
                })
                .sum()
        } else {
            let traced = chunks.map(|(c, out)| shade_chunk(c, out)).sum();
            film.par_add_samples(first, spp, contributions);
            traced
        };
        stats.passes.shading += shading_start.elapsed().as_secs_f64();
        stats.bsdf_rays += bsdf_rays as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::first_sample_of_pass;

    /// Hard case: `--time` with the largest `--spp` (2^20) reaches the end of the u32 sample index
    /// after 4,096 passes; pass 4,096 would wrap to sample 0 and repeat every pixel's samples.
    #[test]
    fn passes_stop_where_the_sample_index_would_wrap() {
        let spp = 1 << 20;
        assert_eq!(first_sample_of_pass(4095, spp), Some(4095 << 20));
        assert_eq!(first_sample_of_pass(4096, spp), None);
        assert_eq!(first_sample_of_pass(u32::MAX, 1), Some(u32::MAX));
        assert_eq!(first_sample_of_pass(1 << 31, 3), None, "a pass whose last sample is past u32::MAX");
        assert_eq!(first_sample_of_pass(0, u32::MAX), Some(0));
    }
}
