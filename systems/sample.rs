//! Choosing lights and evaluating Sample_Li for the whole shading batch (rayon over chunks), and
//! tracing each chunk's shadow rays as soon as the chunk is sampled.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::shadows::Shadows;
use crate::geometry::SceneBvh;
use crate::lanes::LANES;
use crate::light::{ColorQuery, LiSample, LightFlags, LightId, LightKind, LightSampleContext, LightTable};
use crate::light_sampler::LightSampler;
use crate::rng::SampleStream;
use crate::shading::{
    ColorMode, DirectLighting, LightPrecision, LightSelection, LightUpdates, RunReport, SceneBounds, Settings,
    ShadingBatch,
};

use crate::spectrum::SampledSpectrum;
pub use reuse::{MAX_NEIGHBOURS, Reservoirs};

/// Points per parallel task.
const CHUNK: usize = 1024;

/// The `light` of entries for which no light was chosen (their pdf is 0, so it is never read).
const NO_LIGHT: LightId = LightId { kind: LightKind::Point, row: 0 };

/// Where an entry's shadow ray ends, if it has one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowTarget {
    /// No ray: the sample failed or carries no light, its light casts no shadows, or shadows
    /// are off.
    #[default]
    None,
    /// A point with no surface (point-like lights): the ray stops just short of it.
    Point,
    /// A point on a light's surface (normal `ShadowRays::target_normal`), offset off it too.
    Surface,
    /// A light at infinity: the ray leaves along `target - origin`.
    Infinity,
}

/// The shadow rays of the last sampling run: how many there were and were blocked and, when an app
/// sets `keep`, each `DirectLighting` entry's segment and answer. The sampling pass traces a
/// chunk's rays as soon as it has sampled the chunk; without `keep` their ends live in scratch
/// of the task and the columns below stay empty. Entry `e` starts at point
/// `e / entries_per_point` of the `ShadingBatch` (its position, error bound and normal give the
/// offset origin), so no column repeats the batch.
/// Invariant: with `keep`, all columns have one slot per entry; without, they are empty.
#[derive(Resource, Clone, Debug, Default)]
pub struct ShadowRays {
    /// Keep every entry's segment and answer in the columns below (off by default: they cost
    /// memory traffic that the light system itself does not need).
    pub keep: bool,
    /// Entries per batch point (entry `e` starts at point `e / entries_per_point`).
    pub entries_per_point: usize,
    /// Where each entry's ray ends (`None`: the entry has no ray).
    pub kind: Vec<ShadowTarget>,
    /// Segment end (the light point), written for entries with a ray only: other entries keep
    /// what an earlier batch left (writing every slot would be a pass over the column for nothing).
    pub target: Vec<Vec3>,
    /// The light's surface normal at the target, written for `Surface` entries only.
    pub target_normal: Vec<Vec3>,
    /// The answers (false for entries without a ray, and for every entry when shadows are off or
    /// no geometry can block a ray).
    pub occluded: Vec<bool>,
    /// Number of entries with a ray.
    rays: usize,
    /// Number of rays found blocked.
    blocked: usize,
}

impl ShadowRays {
    /// Number of rays traced (entries with a ray).
    pub fn len(&self) -> usize {
        self.rays
    }
    /// True when no ray was traced.
    pub fn is_empty(&self) -> bool {
        self.rays == 0
    }
    /// Number of rays found blocked (the `true` entries of `occluded` under `keep`).
    pub fn blocked(&self) -> usize {
        self.blocked
    }
    /// Empties every column, keeping capacity.
    pub fn clear(&mut self) {
        self.kind.clear();
        self.target.clear();
        self.target_normal.clear();
        self.occluded.clear();
        (self.rays, self.blocked) = (0, 0);
    }
    /// Sizes the columns for `entries` entries of `entries_per_point` each (empties them without
    /// `keep`); the kinds, targets and answers are then written by the sampling pass.
    fn resize(&mut self, entries: usize, entries_per_point: usize) {
        self.entries_per_point = entries_per_point;
        (self.rays, self.blocked) = (0, 0);
        if !self.keep {
            self.kind.clear();
            self.target.clear();
            self.target_normal.clear();
            self.occluded.clear();
            return;
        }
        self.kind.resize(entries, ShadowTarget::None);
        self.target.resize(entries, Vec3::ZERO);
        self.target_normal.resize(entries, Vec3::ZERO);
        self.occluded.clear();
        self.occluded.resize(entries, false);
    }
}

/// Rebuilds or refreshes the light sampler (rebuild on a kind change; otherwise the sampler's
/// own update, which reads the table's change flags), then clears those flags.
pub fn update_light_sampler(
    mut table: ResMut<LightTable>,
    settings: Res<Settings>,
    mut sampler: ResMut<LightSampler>,
    mut report: ResMut<RunReport>,
) {
    let what = if sampler.kind() != settings.light_sampler {
        *sampler = LightSampler::build(settings.light_sampler, &table);
        "built"
    } else if settings.light_updates == LightUpdates::Rebuild && table.is_changed() {
        *sampler = LightSampler::build(settings.light_sampler, &table);
        "lights changed: built afresh (LightUpdates::Rebuild)"
    } else {
        sampler.update(&table)
    };
    // The sampler has caught up; clearing the flags is bookkeeping, not a change to the table.
    table.bypass_change_detection().clear_change_flags();
    report.record("light_sampler", true, what);
}

/// Entries per point under `settings` for a table of `n_lights` lights.
fn entries_per_point(settings: &Settings, n_lights: usize) -> usize {
    let spp = settings.samples_per_point.max(1) as usize;
    match settings.selection {
        LightSelection::OneSampled | LightSelection::Resampled { .. } | LightSelection::Restir(_) => spp,
        LightSelection::All => spp * n_lights,
    }
}

/// For every point of the batch, chooses lights and evaluates Sample_Li, writing one
/// `DirectLighting` entry per sample and, in the same task, tracing the entry's shadow ray once
/// its chunk is sampled: a blocked entry is zeroed and marked occluded.
pub fn sample_direct_lighting(
    batch: Res<ShadingBatch>,
    (table, sampler, settings): (Res<LightTable>, Res<LightSampler>, Res<Settings>),
    (bvh, bounds): (Res<SceneBvh>, Res<SceneBounds>),
    mut out: ResMut<DirectLighting>,
    mut rays: ResMut<ShadowRays>,
    (mut reservoirs, mut report): (ResMut<Reservoirs>, ResMut<RunReport>),
) {
    let n = batch.len();
    let k = entries_per_point(&settings, table.len());
    let all_ids: Vec<LightId> =
        if settings.selection == LightSelection::All { table.ids().collect() } else { Vec::new() };
    let out = &mut *out;
    // Every entry is written below, so the columns are only resized: steady-state batches of one
    // size never fill them first. The tasks write the offsets of their points too (a serial pass
    // over them would not run in parallel); the last one is written here.
    let m = n * k;
    out.offsets.resize(n + 1, 0);
    out.offsets[n] = m as u32;
    if k == 0 {
        // No entries, so no tasks.
        out.offsets.fill(0);
    }
    out.radiance.resize(m, SampledSpectrum::default());
    out.wi.resize(m, Vec3::ZERO);
    out.pdf.resize(m, 0.0);
    out.light.resize(m, NO_LIGHT);
    out.delta.resize(m, false);
    out.occluded.resize(m, false);
    rays.resize(m, k);

    let sampling = Sampling {
        batch: &batch,
        table: &table,
        sampler: &sampler,
        settings: &settings,
        all_ids: &all_ids,
        k,
        spp: settings.samples_per_point.max(1),
        reservoirs: &[],
    };
    // In RGB f32, scenes with point, area or image lights are sampled in blocks of lanes: the
    // light choice, and the Sample_Li of point, triangle and image lights, run as lane kernels;
    // other kinds one lane at a time. Scenes with none of these sample one entry at a time, which
    // was faster there (a lone directional light: 9% of the whole render).
    let lane_kernel = settings.color_mode == ColorMode::Rgb
        && settings.light_precision == LightPrecision::F32
        && (!table.points.is_empty() || !table.area.items.is_empty() || !table.image_infinite().items.is_empty());
    let lanes =
        lane_kernel && matches!(settings.selection, LightSelection::OneSampled | LightSelection::Resampled { .. });
    // ReSTIR builds every entry's final reservoir first; the entries are then written from them.
    let reservoirs = &mut *reservoirs;
    if let LightSelection::Restir(restir) = settings.selection {
        sampling.build_reservoirs(&restir, reservoirs, m, lane_kernel);
        report.record_count("reuse_reservoirs", true, reuse::summary(&restir, &batch, reservoirs), m as u64, "entries");
    }
    let sampling = Sampling { reservoirs: &reservoirs.next, ..sampling };
    let shadows = Shadows::new(&batch, &bvh, &settings, &bounds, k);
    let chunk = CHUNK * k.max(1);
    let rays = &mut *rays;
    // Each task's shadow-ray ends: the kept columns, or scratch of the task's own.
    let kept: Vec<Option<RayColumns>> = if rays.keep {
        let columns =
            (rays.kind.chunks_mut(chunk), rays.target.chunks_mut(chunk), rays.target_normal.chunks_mut(chunk));
        let columns = columns.0.zip(columns.1).zip(columns.2).zip(rays.occluded.chunks_mut(chunk));
        columns
            .map(|(((kind, target), target_normal), occluded)| Some((kind, target, target_normal, occluded)))
            .collect()
    } else {
        (0..out.pdf.chunks(chunk).len()).map(|_| None).collect()
    };
    (rays.rays, rays.blocked) = (
        out.offsets[..n].par_chunks_mut(CHUNK),
        out.radiance.par_chunks_mut(chunk),
        out.wi.par_chunks_mut(chunk),
        out.pdf.par_chunks_mut(chunk),
        out.light.par_chunks_mut(chunk),
        out.delta.par_chunks_mut(chunk),
        out.occluded.par_chunks_mut(chunk),
        kept,
    )
        .into_par_iter()
        .enumerate()
        .map(|(c, (offsets, radiance, wi, pdf, light, delta, occluded, kept))| {
            let first_entry = c * chunk;
            for (j, offset) in offsets.iter_mut().enumerate() {
                *offset = ((c * CHUNK + j) * k) as u32;
            }
            let (mut kinds, mut targets, mut normals) = (Vec::new(), Vec::new(), Vec::new());
            let (ray_kind, target, target_normal, ray_occluded) = match kept {
                Some((kind, target, normal, occluded)) => (kind, target, normal, Some(occluded)),
                None => {
                    kinds.resize(pdf.len(), ShadowTarget::None);
                    targets.resize(pdf.len(), Vec3::ZERO);
                    normals.resize(pdf.len(), Vec3::ZERO);
                    (&mut kinds[..], &mut targets[..], &mut normals[..], None)
                }
            };
            let mut cols = EntryColumns {
                radiance,
                wi,
                pdf,
                light,
                delta,
                occluded,
                ray_kind,
                target,
                target_normal,
                ray_occluded,
            };
            let shadows = shadows.as_ref();
            // The task samples its chunk, then traces the chunk's rays while its entries are still
            // in cache (interleaving the two per block of lanes was no faster; docs/performance.md,
            // "Shadow rays in the sampling pass").
            if lanes {
                crate::lanes::widest(
                    #[inline(always)]
                    || {
                        // Plain loops: iterator adapters may not inline into the wide code.
                        let (mut traced, mut e) = (0, 0);
                        while e < cols.len() {
                            traced += sampling.lane_block(first_entry, e, &mut cols);
                            e += LANES;
                        }
                        (traced, if traced > 0 { cols.trace_all(shadows, first_entry) } else { 0 })
                    },
                )
            } else {
                let traced = (0..cols.len()).map(|e| sampling.entry(first_entry, e, &mut cols) as usize).sum();
                let blocked = if traced > 0 {
                    crate::lanes::widest(
                        #[inline(always)]
                        || cols.trace_all(shadows, first_entry),
                    )
                } else {
                    0
                };
                (traced, blocked)
            }
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if shadows.is_none() || rays.rays == 0 {
        let why = if !settings.shadows {
            "shadows are off in Settings"
        } else if shadows.is_none() {
            "no occluding geometry"
        } else {
            "no shadow rays (no samples, every light has casts_shadows = false, or nothing can block them)"
        };
        // Rays that were not traced are not counted.
        rays.rays = 0;
        report.record("trace_shadow_rays", false, why);
    } else {
        let why = format!("{} rays against {} primitives", rays.rays, bvh.primitive_count());
        report.record_count("trace_shadow_rays", true, why, rays.rays as u64, "rays");
    }
    // Other selections leave the history as it is (an app may interleave a reference run).
    match settings.selection {
        LightSelection::Restir(r) if r.temporal => reservoirs.keep_history(&batch, &table, k),
        LightSelection::Restir(_) => reservoirs.clear_history(),
        _ => {}
    }
}

/// A light chosen for an entry, its Sample_Li, pmf and flags.
type Sampled = (LiSample, f32, LightFlags);

/// What the sampling pass reads.
struct Sampling<'a> {
    batch: &'a ShadingBatch,
    table: &'a LightTable,
    sampler: &'a LightSampler,
    settings: &'a Settings,
    /// Every light, for `LightSelection::All`.
    all_ids: &'a [LightId],
    /// Entries per point.
    k: usize,
    /// Light samples per point.
    spp: u32,
    /// Under `LightSelection::Restir`, each entry's final reservoir (else empty).
    reservoirs: &'a [reuse::Stored],
}

impl Sampling<'_> {
    /// The batch point of global entry `e`, its slot among the point's entries, and the sample
    /// index of its random stream.
    #[inline]
    fn point_and_stream(&self, e: usize) -> (usize, usize, u32) {
        // One entry per point is the common case; it spares a 64-bit division per entry.
        let (i, slot) = if self.k == 1 { (e, 0) } else { (e / self.k, e % self.k) };
        let s = match self.settings.selection {
            LightSelection::OneSampled | LightSelection::Resampled { .. } | LightSelection::Restir(_) => slot,
            LightSelection::All => slot / self.all_ids.len(),
        };
        (i, slot, self.batch.sample[i] * self.spp + s as u32)
    }

    #[inline]
    fn context(&self, i: usize) -> LightSampleContext {
        LightSampleContext { p: self.batch.position[i], n: self.batch.normal[i], ns: self.batch.shading_normal[i] }
    }

    /// Samples entry `e` of the chunk starting at global entry `first` one at a time; returns
    /// whether it has a shadow ray.
    fn entry(&self, first: usize, e: usize, cols: &mut EntryColumns) -> bool {
        let (i, slot, stream) = self.point_and_stream(first + e);
        let ctx = self.context(i);
        // A slot with no point (see `ShadingBatch::position`) gets no light.
        if !ctx.p.is_finite() {
            return self.write(cols, e, NO_LIGHT, None);
        }
        // Under `All`, light j of a sample draws its u from dimensions 1 + 2j.
        let (chosen, dim) = match self.settings.selection {
            LightSelection::All => {
                let j = slot % self.all_ids.len();
                (Some((self.all_ids[j], 1.0)), 1 + 2 * j as u32)
            }
            LightSelection::OneSampled => {
                // The choice at dimension 0, the light's u at 1, 2: one set of the stream.
                let mut rng =
                    SampleStream::new(self.settings.light_pattern(), self.settings.seed, self.batch.pixel[i], stream);
                let chosen = self.sampler.sample(&ctx, rng.next_f32());
                let sampled = chosen.and_then(|c| self.evaluate_at(i, &ctx, c, self.unless_delta(c.0, rng.next_2d())));
                return self.write(cols, e, chosen.map_or(NO_LIGHT, |(id, _)| id), sampled);
            }
            LightSelection::Resampled { candidates } => {
                let (light, sampled) = self.resampled(i, stream, &ctx, candidates);
                return self.write(cols, e, light, sampled);
            }
            LightSelection::Restir(_) => {
                let (light, sampled) = self.reservoir_sample(i, first + e, &ctx);
                return self.write(cols, e, light, sampled);
            }
        };
        let sampled = chosen.and_then(|c| self.evaluate(i, stream, dim, &ctx, c));
        self.write(cols, e, chosen.map_or(NO_LIGHT, |(id, _)| id), sampled)
    }

    /// Sample_Li of the chosen light (`id`, `pmf`) from batch point `i`, with u from dimension
    /// `dim` of sample `stream`'s random stream; None for a failed sample.
    fn evaluate(
        &self,
        i: usize,
        stream: u32,
        dim: u32,
        ctx: &LightSampleContext,
        (id, pmf): (LightId, f32),
    ) -> Option<Sampled> {
        self.evaluate_at(i, ctx, (id, pmf), self.light_u(i, stream, dim, id))
    }

    /// The u of light `id`'s Sample_Li for batch point `i`: dimension `dim` of sample
    /// `stream`'s random stream. Lights at a point ignore u: it is not drawn (the streams are
    /// counter based, so no other number changes) and is zero.
    #[inline]
    fn light_u(&self, i: usize, stream: u32, dim: u32, id: LightId) -> Vec2 {
        if self.table.flags(id).contains(LightFlags::DELTA_POSITION) {
            Vec2::ZERO
        } else {
            SampleStream::new(self.settings.light_pattern(), self.settings.seed, self.batch.pixel[i], stream)
                .at_dimension(dim)
                .next_2d()
        }
    }

    /// `u` for light `id`'s Sample_Li, already drawn: zero for lights at a point, as [`Self::light_u`].
    #[inline]
    fn unless_delta(&self, id: LightId, u: Vec2) -> Vec2 {
        if self.table.flags(id).contains(LightFlags::DELTA_POSITION) { Vec2::ZERO } else { u }
    }

    /// Sample_Li of light `id` (chosen with `pmf`) at `u` from `ctx`, in batch point `i`'s colour
    /// query (its wavelengths); None for a failed sample.
    fn evaluate_at(&self, i: usize, ctx: &LightSampleContext, (id, pmf): (LightId, f32), u: Vec2) -> Option<Sampled> {
        let query = match self.settings.color_mode {
            ColorMode::Rgb => ColorQuery::Rgb,
            ColorMode::Spectral => ColorQuery::Spectral(self.batch.wavelengths.get(i)?),
        };
        let ls = match self.settings.light_precision {
            LightPrecision::F32 => self.table.sample_li(id, ctx, u, query),
            LightPrecision::F64 => self.table.sample_li_f64(id, ctx, u, query),
        };
        self.accept((id, pmf), ls)
    }

    /// A Sample_Li of light `id` (chosen with `pmf`) as an entry takes it: None when it failed,
    /// has density 0 or non-finite radiance.
    #[inline(always)]
    fn accept(&self, (id, pmf): (LightId, f32), ls: Option<LiSample>) -> Option<Sampled> {
        ls.filter(|ls| ls.pdf > 0.0 && ls.radiance.is_finite()).map(|ls| (ls, pmf, self.table.flags(id)))
    }

    /// Writes entry `e` (chosen light `light`; a failed sample leaves a zero entry that keeps
    /// its light) and its shadow ray; returns whether it has one.
    #[inline]
    fn write(&self, cols: &mut EntryColumns, e: usize, light: LightId, sampled: Option<Sampled>) -> bool {
        cols.light[e] = light;
        cols.occluded[e] = false;
        cols.ray_kind[e] = ShadowTarget::None;
        let Some((ls, pmf, flags)) = sampled else {
            (cols.radiance[e], cols.wi[e], cols.pdf[e], cols.delta[e]) =
                (SampledSpectrum::default(), Vec3::ZERO, 0.0, false);
            return false;
        };
        // The density of the point's `spp` samples together (see `DirectLighting::pdf`).
        let pdf = ls.pdf * pmf * self.spp as f32;
        (cols.radiance[e], cols.wi[e], cols.pdf[e], cols.delta[e]) = (ls.radiance, ls.wi, pdf, flags.is_delta());
        if !self.wants_shadow_ray(pdf, &ls.radiance, light) {
            return false;
        }
        cols.ray_kind[e] = if flags.contains(LightFlags::INFINITE) || flags.contains(LightFlags::DELTA_DIRECTION) {
            ShadowTarget::Infinity
        } else if ls.n_light == Vec3::ZERO {
            ShadowTarget::Point
        } else {
            ShadowTarget::Surface
        };
        cols.target[e] = ls.p_light;
        if cols.ray_kind[e] == ShadowTarget::Surface {
            cols.target_normal[e] = ls.n_light;
        }
        true
    }

    /// Whether a sample of `light` with this pdf and radiance gets a shadow ray.
    #[inline(always)]
    fn wants_shadow_ray(&self, pdf: f32, radiance: &SampledSpectrum, light: LightId) -> bool {
        self.settings.shadows && pdf > 0.0 && radiance.0.iter().any(|&v| v > 0.0) && self.table.casts_shadows(light)
    }
}

/// A task's chunk of the kept `ShadowRays` columns: kinds, targets, target normals, answers.
type RayColumns<'a> = (&'a mut [ShadowTarget], &'a mut [Vec3], &'a mut [Vec3], &'a mut [bool]);

/// One chunk of the columns the sampling pass writes, indexed by entry within the chunk.
struct EntryColumns<'a> {
    radiance: &'a mut [SampledSpectrum],
    wi: &'a mut [Vec3],
    pdf: &'a mut [f32],
    light: &'a mut [LightId],
    delta: &'a mut [bool],
    occluded: &'a mut [bool],
    /// The shadow rays' ends: the kept `ShadowRays` columns, or the task's scratch.
    ray_kind: &'a mut [ShadowTarget],
    target: &'a mut [Vec3],
    target_normal: &'a mut [Vec3],
    /// The kept answers (`ShadowRays::keep`).
    ray_occluded: Option<&'a mut [bool]>,
}

impl EntryColumns<'_> {
    fn len(&self) -> usize {
        self.pdf.len()
    }

    /// Traces the shadow rays of the chunk (starting at global entry `first`), just sampled, a
    /// block of lanes at a time, and zeroes the blocked entries; returns how many were blocked (0
    /// without a tracer: shadows off, or no geometry).
    #[inline(always)]
    fn trace_all(&mut self, shadows: Option<&Shadows>, first: usize) -> usize {
        let Some(shadows) = shadows else { return 0 };
        // A plain loop: iterator adapters may not inline into the wide code.
        let (mut blocked, mut e) = (0, 0);
        while e < self.len() {
            blocked += self.trace(shadows, first, e);
            e += LANES;
        }
        blocked
    }

    /// Traces the shadow rays of entries `e..e + LANES` (or to the chunk's end) of the chunk
    /// starting at global entry `first` and zeroes the blocked ones; returns how many were blocked.
    #[inline(always)]
    fn trace(&mut self, shadows: &Shadows, first: usize, e: usize) -> usize {
        let end = self.len().min(e + LANES);
        let (kind, target, normal) = (&self.ray_kind[e..end], &self.target[e..end], &self.target_normal[e..end]);
        if kind.iter().all(|&k| k == ShadowTarget::None) {
            return 0;
        }
        let blocked = shadows.trace_block(first + e, kind, target, normal);
        let mut left = blocked;
        while left != 0 {
            let l = e + left.trailing_zeros() as usize;
            (self.radiance[l], self.occluded[l]) = (SampledSpectrum::default(), true);
            if let Some(kept) = self.ray_occluded.as_deref_mut() {
                kept[l] = true;
            }
            left &= left - 1;
        }
        blocked.count_ones() as usize
    }
}

mod lane_block;
mod resampled;
mod reuse;
#[cfg(test)]
mod tests;
