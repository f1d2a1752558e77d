//! The batch renderer: camera rays -> closest hits -> the light system (via the `ShadingBatch`
//! and one run of the schedule) -> MIS with BSDF sampling -> film. It never bypasses the light
//! system: light selection, Sample_Li and shadow rays all happen in the ECS systems.

use bevy_ecs::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use super::bsdf::Bsdf;
use super::camera::{Camera, CameraModel, PinholeCamera};
use super::camera_pass::{CameraColumns, SampleRange, SampleSurface, trace_camera_rays};
use super::film::Film;
use super::material::Material;
use super::tiles::Crop;
use crate::geometry::{Hit, RAY_CHUNK, SceneBvh};
use crate::lanes::LANES;
use crate::light::{ColorQuery, LightSampleContext, LightTable};
use crate::light_sampler::LightSampler;
use crate::rng::SampleStream;
use crate::sampling::Frame;
use crate::shading::{ColorMode, DirectLighting, RunReport, RunSummary, SceneBounds, Settings, ShadingBatch};
use crate::spectrum::{SampledSpectrum, SampledWavelengths, color};
use crate::systems::GeometryIndex;

/// Camera samples per batch handed to the light system.
const BATCH_SAMPLES: usize = 1 << 14;
/// Salt that keeps the renderer's random dimensions apart from the light systems'.
const RENDER_SALT: u64 = 0x5eed_ca3e_7a11_0b0e;

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
    fn bsdf_weight(self, bsdf_pdf: f32, light_pdf: f32) -> f32 {
        match self {
            Self::Mis => power_heuristic(bsdf_pdf, light_pdf),
            Self::LightOnly => 0.0,
            Self::BsdfOnly => 1.0,
        }
    }
}

/// What to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Size of the full image, which the camera frames.
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// How light and BSDF samples are combined. Defaults to MIS.
    pub strategy: Strategy,
    /// Renders only this region of the full image (the film is its size), with the full image's
    /// camera rays and random streams: its pixels are bit for bit those of the full render. A crop
    /// is clipped to the image; [`Crop::check`] says whether it lies inside. None: the whole image.
    pub crop: Option<Crop>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { width: 256, height: 256, spp: 16, strategy: Strategy::Mis, crop: None }
    }
}

impl RenderOptions {
    /// The region of the image the film covers: the crop clipped to the image, or all of it.
    pub fn region(&self) -> Crop {
        self.crop.map_or(Crop::full(self.width, self.height), |c| c.clipped(self.width, self.height))
    }
}

/// Counts of a finished render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    pub seconds: f64,
    pub camera_samples: u64,
    pub shadow_rays: u64,
    pub bsdf_rays: u64,
    /// Where the time went, pass by pass (their sum is `seconds` less the set-up).
    pub passes: PassSeconds,
    /// The light system's run report over every update of the render (the one before the first
    /// batch, then one per batch): each warning, and per system its runs and summed counts.
    pub report: RunSummary,
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
fn to_rgb(v: SampledSpectrum, wavelengths: Option<&SampledWavelengths>) -> Vec3 {
    match wavelengths {
        None => Vec3::new(v.0[0], v.0[1], v.0[2]),
        Some(w) => color::xyz_to_srgb(w.to_xyz(v).as_dvec3()).as_vec3(),
    }
}

/// The material of geometry that has none.
static DEFAULT_MATERIAL: std::sync::LazyLock<Material> = std::sync::LazyLock::new(Material::default);

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
    // The render runs on a pool thread (rayon::scope moves it there), so each parallel pass
    // starts without handing its work to the pool and putting the calling thread to sleep.
    rayon::scope(|_| render_on_pool(world, schedule, opts, camera, progress))
}

fn render_on_pool(
    world: &mut World,
    schedule: &mut Schedule,
    opts: &RenderOptions,
    camera: Option<CameraModel>,
    mut progress: impl FnMut(f32),
) -> (Film, RenderStats) {
    let start = std::time::Instant::now();
    let mut stats = RenderStats::default();
    // Compensated env tables only pay off when BSDF samples cover the dim part of the sky.
    world.resource_mut::<Settings>().mis = opts.strategy == Strategy::Mis;
    // One update brings the BVH and light tables up to date before cameras are placed.
    world.resource_mut::<ShadingBatch>().clear();
    schedule.run(world);
    // Each update clears the world's run report: what it says (this update's warnings above all)
    // is kept in the render's own.
    stats.report.add(world.resource::<RunReport>());
    let camera = camera.unwrap_or_else(|| CameraModel::Pinhole(find_camera(world, opts.width, opts.height)));
    let materials: Vec<Material> = {
        let entities = world.resource::<GeometryIndex>().entities.clone();
        entities.iter().map(|&e| world.get::<Material>(e).cloned().unwrap_or_default()).collect()
    };
    let uniform_bsdfs: Vec<Option<Bsdf>> = materials.iter().map(Material::uniform_rgb_bsdf).collect();
    let settings = world.resource::<Settings>().clone();
    let spectral = settings.color_mode == ColorMode::Spectral;
    let seed = settings.seed ^ RENDER_SALT;

    let region = opts.region();
    let mut film = Film::new(region.width(), region.height());
    let total = region.pixels() * opts.spp as usize;
    let mut columns = CameraColumns::default();
    let mut contributions: Vec<Vec3> = Vec::new();
    let mut first = 0usize;
    while first < total {
        let len = BATCH_SAMPLES.min(total - first);
        let range = SampleRange { first, len, region, full_width: opts.width, spp: opts.spp, seed };
        let camera_start = std::time::Instant::now();
        // Every camera sample takes a slot of the batch (one with no point if its ray escaped).
        world.resource_scope(|world, mut batch: Mut<ShadingBatch>| {
            trace_camera_rays(&mut batch, &mut columns, world.resource::<SceneBvh>(), &camera, range);
            // Spectral mode: the wavelengths of each sample (dimension 2 of its stream).
            if spectral {
                let batch = &mut *batch;
                let lambda =
                    batch.pixel.par_iter().zip(&batch.sample).with_min_len(RAY_CHUNK).map(|(&pixel, &sample)| {
                        SampledWavelengths::sample_visible(
                            SampleStream::new(seed, pixel, sample).at_dimension(2).next_f32(),
                        )
                    });
                batch.wavelengths.par_extend(lambda);
            }
        });
        let light_system_start = std::time::Instant::now();
        schedule.run(world);
        let shading_start = std::time::Instant::now();
        stats.report.add(world.resource::<RunReport>());
        stats.passes.camera += (light_system_start - camera_start).as_secs_f64();
        stats.passes.light_system += (shading_start - light_system_start).as_secs_f64();
        stats.shadow_rays += world.resource::<crate::systems::ShadowRays>().len() as u64;

        let world_ref = &*world;
        let shade = ShadeContext {
            table: world_ref.resource::<LightTable>(),
            sampler: world_ref.resource::<LightSampler>(),
            lighting: world_ref.resource::<DirectLighting>(),
            batch: world_ref.resource::<ShadingBatch>(),
            bvh: world_ref.resource::<SceneBvh>(),
            columns: &columns,
            lights_of_instance: {
                let table = world_ref.resource::<LightTable>();
                world_ref.resource::<GeometryIndex>().entities.iter().map(|&e| table.rows_of(e)).collect()
            },
            materials: &materials,
            uniform_bsdfs: &uniform_bsdfs,
            seed,
            strategy: opts.strategy,
            offset: settings.shadow_offset,
            all_lights: settings.selection == crate::shading::LightSelection::All,
        };
        let escape_ids: Vec<_> = shade.table.escape_lights().collect();
        let bsdf_sampling = opts.strategy != Strategy::LightOnly && shade.table.has_non_delta_lights();
        let shade_one = |k: usize| {
            let lambda = shade.batch.wavelengths.get(k);
            if !columns.escaped(k) {
                return shade.shade(k, lambda, &escape_ids, bsdf_sampling);
            }
            // Escaped camera rays see the infinite lights directly.
            let query = lambda.map_or(ColorQuery::Rgb, ColorQuery::Spectral);
            let le = escape_ids
                .iter()
                .fold(SampledSpectrum::default(), |acc, &id| acc.add(shade.table.le(id, columns.dir(k), query)));
            (to_rgb(le, lambda), false)
        };
        // Where the lane kernel may apply (`shade_lanes.rs`), blocks of the common case go
        // through it; elsewhere samples are shaded one at a time. Either way the tasks count
        // their BSDF rays as they go (a pass of its own cost a parallel region per batch), and
        // write every contribution, so that column is only resized (no serial fill in steady
        // state).
        let lanes = !spectral && !bsdf_sampling && !super::shade_lanes::turned_off();
        let shade_chunk = |c: usize, out: &mut [Vec3]| -> usize {
            let first = c * RAY_CHUNK;
            if !lanes {
                let mut traced = 0;
                for (i, out) in out.iter_mut().enumerate() {
                    let (rgb, t) = shade_one(first + i);
                    (*out, traced) = (rgb, traced + t as usize);
                }
                return traced;
            }
            crate::lanes::widest(
                #[inline(always)]
                || {
                    let (mut b, mut traced) = (0, 0);
                    while b < out.len() {
                        let end = (b + LANES).min(out.len());
                        if !shade.shade_lanes(first + b, &mut out[b..end]) {
                            for (i, out) in out[b..end].iter_mut().enumerate() {
                                let (rgb, t) = shade_one(first + b + i);
                                (*out, traced) = (rgb, traced + t as usize);
                            }
                        }
                        b = end;
                    }
                    traced
                },
            )
        };
        contributions.resize(len, Vec3::ZERO);
        let chunks = contributions.par_chunks_mut(RAY_CHUNK).enumerate();
        // Sample k is sample k % spp of pixel k / spp (see `SampleRange`). Where each chunk holds
        // whole pixels, the task that shaded it adds them to the film (while they are in cache,
        // and without a parallel region of its own).
        let spp = opts.spp as usize;
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
            film.par_add_samples(first, spp, &contributions);
            traced
        };
        stats.passes.shading += shading_start.elapsed().as_secs_f64();
        stats.bsdf_rays += bsdf_rays as u64;
        stats.camera_samples += len as u64;
        first += len;
        progress(first as f32 / total as f32);
    }
    stats.seconds = start.elapsed().as_secs_f64();
    (film, stats)
}

/// Read-only state for shading one batch in parallel.
pub(super) struct ShadeContext<'a> {
    table: &'a LightTable,
    sampler: &'a LightSampler,
    pub(super) lighting: &'a DirectLighting,
    pub(super) batch: &'a ShadingBatch,
    bvh: &'a SceneBvh,
    /// The camera samples' directions and surfaces, indexed like `batch`.
    pub(super) columns: &'a CameraColumns,
    /// The light rows of each BVH instance's entity (empty for geometry that emits nothing).
    pub(super) lights_of_instance: Vec<&'a [crate::light::LightId]>,
    materials: &'a [Material],
    /// Each material's [`Material::uniform_rgb_bsdf`].
    pub(super) uniform_bsdfs: &'a [Option<Bsdf>],
    seed: u64,
    pub(super) strategy: Strategy,
    /// How BSDF rays leave the surface (as shadow rays do).
    offset: crate::geometry::ShadowOffset,
    /// Every light is sampled for every point (pmf 1) rather than one chosen by the sampler.
    all_lights: bool,
}

impl ShadeContext<'_> {
    /// The area light `hit` landed on and its radiance toward `w` (unit, away from the surface).
    fn emitted(&self, hit: &Hit, w: Vec3, query: ColorQuery) -> Option<(crate::light::LightId, SampledSpectrum)> {
        let surface = SampleSurface {
            uv: hit.uv,
            material: hit.material,
            instance: hit.instance,
            primitive: hit.id.primitive,
            flipped: false,
        };
        self.emitted_at(&surface, hit.p, hit.ng, w, query)
    }

    /// [`Self::emitted`] at point `p` of `surface`, whose geometric normal is `ng`.
    fn emitted_at(
        &self,
        surface: &SampleSurface,
        p: Vec3,
        ng: Vec3,
        w: Vec3,
        query: ColorQuery,
    ) -> Option<(crate::light::LightId, SampledSpectrum)> {
        let rows = self.lights_of_instance.get(surface.instance as usize)?;
        if rows.is_empty() {
            return None;
        }
        let id = self.table.area_light_among(rows, surface.primitive)?;
        let light = &self.table.area.items[id.row as usize].light;
        Some((id, light.radiance(p, ng, surface.uv, w, query)))
    }

    /// Direct light at camera sample `j`, which hit a surface (at `wavelengths` in spectral mode):
    /// the light system's samples weighted by MIS, plus one BSDF sample toward non-delta lights.
    /// Returns RGB and whether a ray was traced.
    fn shade(
        &self,
        j: usize,
        wavelengths: Option<&SampledWavelengths>,
        escape_ids: &[crate::light::LightId],
        bsdf_sampling: bool,
    ) -> (Vec3, bool) {
        let surface = self.columns.surface(j, self.batch.geometry[j].primitive);
        let (p, n) = (self.batch.position[j], self.batch.normal[j]);
        let query = wavelengths.map_or(ColorQuery::Rgb, ColorQuery::Spectral);
        let wo = -self.columns.dir(j);
        let ns = self.batch.shading_normal[j];
        let material = self.materials.get(surface.material as usize).unwrap_or(&DEFAULT_MATERIAL);
        let bsdf = match (query, self.uniform_bsdfs.get(surface.material as usize)) {
            (ColorQuery::Rgb, Some(Some(b))) => Bsdf { frame: Frame::from_z(ns), ..*b },
            _ => material.bsdf(surface.uv, ns, query),
        };
        // Light the camera sees on emitters directly (their sidedness needs the unflipped normal).
        let ng = if surface.flipped { -n } else { n };
        let mut l = self.emitted_at(&surface, p, ng, wo, query).map_or(SampledSpectrum::default(), |(_, le)| le);
        for e in self.lighting.entries(j) {
            let (li, wi, pdf) = (self.lighting.radiance[e], self.lighting.wi[e], self.lighting.pdf[e]);
            if pdf <= 0.0 {
                continue;
            }
            let f = bsdf.f(wo, wi);
            let w = if self.lighting.delta[e] { 1.0 } else { self.strategy.light_weight(pdf, bsdf.pdf(wo, wi)) };
            if w == 0.0 {
                continue;
            }
            l = l.add(f.mul(li).scale(wi.dot(ns).abs() * w / pdf));
        }
        let mut traced = false;
        if bsdf_sampling {
            let mut rng = SampleStream::new(self.seed, self.batch.pixel[j], self.batch.sample[j]).at_dimension(16);
            if let Some(bs) = bsdf.sample(wo, rng.next_f32(), rng.next_2d()) {
                traced = true;
                let from = crate::geometry::SurfacePoint { p, p_error: self.batch.position_error[j], n };
                let ray = self.offset.spawn_ray(&from, bs.wi);
                let ctx = LightSampleContext { p, n, ns };
                let pmf = |id| if self.all_lights { 1.0 } else { self.sampler.pmf(&ctx, id) };
                if let Some(h2) = self.bvh.closest_hit(&ray) {
                    if let Some((id, le)) = self.emitted(&h2, -bs.wi, query) {
                        let w = self.strategy.bsdf_weight(bs.pdf, pmf(id) * self.table.pdf_li(id, &ctx, bs.wi));
                        l = l.add(bs.f.mul(le).scale(bs.wi.dot(ns).abs() * w / bs.pdf));
                    }
                } else {
                    for &id in escape_ids {
                        let Some((le, pdf)) = self.table.le_and_pdf_li(id, &ctx, bs.wi, query) else {
                            continue;
                        };
                        let light_pdf = pmf(id) * pdf;
                        let w = self.strategy.bsdf_weight(bs.pdf, light_pdf);
                        l = l.add(bs.f.mul(le).scale(bs.wi.dot(ns).abs() * w / bs.pdf));
                    }
                }
            }
        }
        (to_rgb(l, wavelengths), traced)
    }
}
