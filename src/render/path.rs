//! The path tracer: a batch of camera samples becomes paths, and each bounce is a wavefront. The
//! bounce's surfaces are one `ShadingBatch`, run through the light system's schedule (light
//! choice, Sample_Li, shadow rays); each surface then adds its MIS-weighted light samples and
//! draws a BSDF sample; the BSDF rays are traced together, and what they find is weighted by MIS
//! against the light sampler (an emitter they hit, or the infinite lights when they escape). The
//! surfaces they hit are the next bounce's batch.
//!
//! Depth counts surfaces after the camera's, as in pbrt-v4: `max_depth` 1 is direct lighting
//! (light and BSDF samples at the camera's surface, and the emitters the BSDF ray finds), and a
//! closed furnace of albedo a and emission Le gives Le (1 - a^(d+1)) / (1 - a) at depth d.

use bevy_ecs::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use super::camera_pass::{CameraColumns, FoundSurface, write_found_surfaces};
use super::material::Material;
use super::normal_map::apply_normal_maps;
use super::renderer::{RenderStats, Strategy, to_rgb};
use super::shade::{Bounce, BounceRules, BsdfRay, Continuation, Materials, ShadeContext};
use crate::geometry::{ClosedSurfaces, Hit, RAY_CHUNK, SceneBvh, closest_hits_in_packets};
use crate::lanes::LANES;
use crate::light::ColorQuery;
use crate::rng::mix64;
use crate::shading::{RunReport, Settings, ShadingBatch};
use crate::spectrum::{SampledSpectrum, SampledWavelengths};
use crate::systems::ShadowRays;

/// How long paths are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathDepth {
    /// Surfaces after the camera's at most (1 = direct lighting, 0 = emission only).
    pub max_depth: u32,
    /// Russian roulette may end a path from this many surfaces on (pbrt-v4 starts after one).
    pub roulette_depth: u32,
}

impl PathDepth {
    /// 16 bounces, roulette from the fourth surface: a white room (albedo 0.8) keeps 0.8^17 =
    /// 2% of its light past 16 bounces, and roulette ends most paths long before.
    pub const DEFAULT: Self = Self { max_depth: 16, roulette_depth: 3 };
}

/// The light system's seed for the surfaces at `depth`: the settings' own at the camera's
/// surface (so that depth 1 draws what the direct integrator draws), a mix of it after.
pub fn bounce_seed(seed: u64, depth: u32) -> u64 {
    if depth == 0 { seed } else { mix64(seed ^ mix64(depth as u64 + 0x9e37_79b9)) }
}

/// Where a batch's paths start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Start {
    /// At the surfaces the camera rays hit: their emission counts.
    Camera,
    /// At given surface points (a lightmap's texels, `render::surface_paths`): their own emission
    /// never counts, the light reaching them straight from the lights only if `direct`, and each
    /// path notes whether its first ray met a back face within `leak_distance` (m).
    Surfaces {
        /// Whether light from the lights straight to the point counts (false: bounced light only).
        direct: bool,
        /// A first ray that meets a back face nearer than this marks its path as leaked.
        leak_distance: f32,
    },
}

/// Per-batch path state, reused across batches.
#[derive(Default)]
pub(super) struct Paths {
    /// Per camera sample of the batch: the light its path has gathered.
    radiance: Vec<SampledSpectrum>,
    /// Per camera sample (`Start::Surfaces` only): whether its first ray met a back face nearby.
    leaked: Vec<bool>,
    /// Per camera sample: its pixel, sample and (spectral mode) wavelengths.
    pixel: Vec<u32>,
    sample: Vec<u32>,
    wavelengths: Vec<SampledWavelengths>,
    /// Per slot of the current bounce's batch: the camera sample whose path it is, and the
    /// path's throughput up to that surface.
    path: Vec<u32>,
    beta: Vec<SampledSpectrum>,
    bounces: Vec<Bounce>,
    continuations: Vec<(u32, Continuation)>,
    hits: Vec<Option<Hit>>,
    found: Vec<SampledSpectrum>,
    next: Vec<FoundSurface>,
}

/// What the path tracer needs beyond the world.
pub(super) struct PathJob<'a> {
    pub(super) depth: PathDepth,
    pub(super) materials: &'a Materials,
    /// Seed of the renderer's own streams.
    pub(super) seed: u64,
    pub(super) strategy: Strategy,
    pub(super) start: Start,
    /// The primitives that bound solids, whose back faces are leaks whatever their material
    /// (`Start::Surfaces`; None: only one-sided back faces are).
    pub(super) closed: Option<&'a ClosedSurfaces>,
}

impl Paths {
    /// Traces the paths of the camera samples in `batch` and `columns` (as the camera pass wrote
    /// them) and writes each sample's RGB into `rgb`. Runs the schedule once per bounce; the
    /// light system's seed is restored afterwards.
    pub(super) fn trace(
        &mut self,
        world: &mut World,
        schedule: &mut Schedule,
        columns: &mut CameraColumns,
        job: &PathJob,
        rgb: &mut Vec<Vec3>,
        stats: &mut RenderStats,
    ) {
        let seed = world.resource::<Settings>().seed;
        let n = self.start(world.resource::<ShadingBatch>());
        let PathDepth { max_depth, roulette_depth } = job.depth;
        for depth in 0.. {
            if world.resource::<ShadingBatch>().is_empty() {
                break;
            }
            let rules = BounceRules {
                emission_only: depth == max_depth,
                last: depth + 1 >= max_depth,
                roulette: depth + 1 >= roulette_depth,
                emission: depth == 0 && job.start == Start::Camera,
                leak_probe: depth == 0 && matches!(job.start, Start::Surfaces { .. }),
                direct: depth > 0 || !matches!(job.start, Start::Surfaces { direct: false, .. }),
            };
            let light_start = std::time::Instant::now();
            if !rules.emission_only && rules.direct {
                world.resource_mut::<Settings>().seed = bounce_seed(seed, depth);
                schedule.run(world);
                stats.report.add(world.resource::<RunReport>());
                stats.shadow_rays += world.resource::<ShadowRays>().len() as u64;
            }
            let shading_start = std::time::Instant::now();
            stats.passes.light_system += (shading_start - light_start).as_secs_f64();
            let ctx = ShadeContext::new(world, columns, job.materials, job.seed, job.strategy);
            self.shade(&ctx, depth, rules);
            self.follow(&ctx, rules);
            if let (0, Start::Surfaces { leak_distance, .. }) = (depth, job.start) {
                self.note_leaks(leak_distance, &job.materials.materials, job.closed);
            }
            stats.bsdf_rays += self.continuations.len() as u64;
            drop(ctx);
            world.resource_scope(|world, mut batch: Mut<ShadingBatch>| {
                self.next_batch(&mut batch, columns);
                apply_normal_maps(&mut batch, columns, world.resource::<SceneBvh>(), job.materials);
            });
            stats.passes.shading += shading_start.elapsed().as_secs_f64();
        }
        world.resource_mut::<Settings>().seed = seed;
        rgb.clear();
        rgb.par_extend((0..n).into_par_iter().with_min_len(RAY_CHUNK).map(|k| {
            let wavelengths = self.wavelengths.get(k);
            to_rgb(self.radiance[k], wavelengths)
        }));
    }

    /// Per camera sample of the last batch traced from `Start::Surfaces`: whether its first ray
    /// met a back face within the leak distance (the point is inside geometry or behind a wall).
    pub(super) fn leaked(&self) -> &[bool] {
        &self.leaked
    }

    /// Starts one path per camera sample of `batch`; returns their number.
    fn start(&mut self, batch: &ShadingBatch) -> usize {
        let n = batch.len();
        self.leaked.clear();
        self.leaked.resize(n, false);
        self.radiance.clear();
        self.radiance.resize(n, SampledSpectrum::default());
        self.pixel.clone_from(&batch.pixel);
        self.sample.clone_from(&batch.sample);
        self.wavelengths.clone_from(&batch.wavelengths);
        self.path.clear();
        self.path.extend(0..n as u32);
        self.beta.clear();
        self.beta.resize(n, SampledSpectrum([1.0; 4]));
        n
    }

    /// Shades every surface of the bounce and adds its light to its path.
    fn shade(&mut self, ctx: &ShadeContext, depth: u32, rules: BounceRules) {
        let beta = &self.beta;
        self.bounces.clear();
        self.bounces.par_extend((0..beta.len()).into_par_iter().with_min_len(64).map(|j| {
            if ctx.columns.escaped(j) {
                // Only camera rays escape into the batch; later ones are weighed where traced.
                return Bounce { radiance: beta[j].mul(ctx.escaped(j)), next: None };
            }
            ctx.shade_path_vertex(j, depth, beta[j], rules)
        }));
        self.continuations.clear();
        for (j, b) in self.bounces.iter().enumerate() {
            let p = self.path[j];
            let r = &mut self.radiance[p as usize];
            *r = r.add(b.radiance);
            if let Some(c) = b.next {
                self.continuations.push((p, c));
            }
        }
    }

    /// Traces the continuing paths' BSDF rays and adds the light they find; keeps the surfaces
    /// they hit for the next bounce unless this one was the last.
    fn follow(&mut self, ctx: &ShadeContext, rules: BounceRules) {
        let bvh: &SceneBvh = ctx.bvh;
        let continuations = &self.continuations;
        closest_hits_in_packets(bvh, continuations.len(), |k| continuations[k].1.ray, &mut self.hits);
        let wavelengths = &self.wavelengths;
        // In blocks of `LANES` rays, whose light is found together (see `found_by_bsdf_rays`).
        self.found.clear();
        self.found.resize(self.continuations.len(), SampledSpectrum::default());
        let blocks =
            (self.found.par_chunks_mut(LANES), self.continuations.par_chunks(LANES), self.hits.par_chunks(LANES));
        if rules.direct {
            blocks.into_par_iter().with_min_len(4).for_each(|(found, continuations, hits)| {
                let ray = |k: usize| {
                    let (p, c) = &continuations[k];
                    let query = wavelengths.get(*p as usize).map_or(ColorQuery::Rgb, ColorQuery::Spectral);
                    BsdfRay { from: c.from, wi: c.wi, bsdf_pdf: c.bsdf_pdf, hit: hits[k].as_ref(), query }
                };
                ctx.found_by_bsdf_rays(ray, found);
                for (f, (_, c)) in found.iter_mut().zip(continuations) {
                    *f = c.beta.mul(*f);
                }
            });
        }
        self.next.clear();
        let (mut path, mut beta) = (std::mem::take(&mut self.path), std::mem::take(&mut self.beta));
        path.clear();
        beta.clear();
        for (((p, c), hit), found) in self.continuations.iter().zip(&self.hits).zip(&self.found) {
            let r = &mut self.radiance[*p as usize];
            *r = r.add(*found);
            if let (Some(hit), false) = (hit, rules.last) {
                let (pixel, sample) = (self.pixel[*p as usize], self.sample[*p as usize]);
                self.next.push(FoundSurface { dir: c.wi, hit: *hit, pixel, sample });
                path.push(*p);
                beta.push(c.beta);
            }
        }
        (self.path, self.beta) = (path, beta);
    }

    /// Marks the paths whose first ray (the continuations just followed) met a back face nearer
    /// than `leak_distance`: of a one-sided material, or of a closed surface (`closed`), whose
    /// back faces only its inside, double-sided or not. An open double-sided surface has no
    /// inside: its back is a face like its front (a two-sided lamp lights the ceiling above it
    /// with its back), not a leak. A first ray that meets a closed surface turned against the
    /// start's within its contact distance starts where a solid touches the surface (a floor under a box whose bottom
    /// lies a float step below the floor): a leak too.
    fn note_leaks(&mut self, leak_distance: f32, materials: &[Material], closed: Option<&ClosedSurfaces>) {
        let one_sided = |m: u32| materials.get(m as usize).is_none_or(|m| !m.double_sided);
        let solid = |h: Hit| closed.is_some_and(|c| c.contains(h.instance, h.id.primitive));
        for ((p, c), hit) in self.continuations.iter().zip(&self.hits) {
            // The ray's direction is unit length, so t is the distance.
            let back = hit.is_some_and(|h| {
                // Face to face only: a room's corner has its walls within reach too.
                let facing = h.ng.dot(c.from.n) < -0.5;
                let touching = facing && closed.is_some_and(|c| h.t < c.contact_distance()) && solid(h);
                touching || (h.ng.dot(c.wi) > 0.0 && h.t < leak_distance && (one_sided(h.material) || solid(h)))
            });
            self.leaked[*p as usize] = back;
        }
    }

    /// Writes the next bounce's surfaces into the batch (with their paths' wavelengths).
    fn next_batch(&self, batch: &mut ShadingBatch, columns: &mut CameraColumns) {
        write_found_surfaces(batch, columns, &self.next);
        if !self.wavelengths.is_empty() {
            batch.wavelengths.extend(self.path.iter().map(|&p| self.wavelengths[p as usize]));
        }
    }
}
