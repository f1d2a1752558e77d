//! Choosing lights and evaluating Sample_Li for the whole shading batch (rayon over chunks), the
//! shadow rays that follow, and applying their answers.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::light::{ColorQuery, LightFlags, LightId, LightKind, LightSampleContext, LightTable};
use crate::light_sampler::LightSampler;
use crate::rng::SampleStream;
use crate::shading::{ColorMode, DirectLighting, LightPrecision, LightSelection, RunReport, Settings, ShadingBatch};
use crate::spectrum::SampledSpectrum;

/// Points per parallel task.
const CHUNK: usize = 1024;

/// The `light` of entries for which no light was chosen (their pdf is 0, so it is never read).
const NO_LIGHT: LightId = LightId { kind: LightKind::Point, row: 0 };

/// Where an entry's shadow ray ends, if it has one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowTarget {
    /// No ray: the sample failed or carries no light, its light casts no shadows, or shadows are
    /// off.
    #[default]
    None,
    /// A point with no surface (point-like lights): the ray stops just short of it.
    Point,
    /// A point on a light's surface (normal `ShadowRays::target_normal`), offset off it too.
    Surface,
    /// A light at infinity: the ray leaves along `target - origin`.
    Infinity,
}

/// The shadow ray of each `DirectLighting` entry, written by the sampling step in the same pass
/// as the entry. Entry `e` starts at point `e / entries_per_point` of the `ShadingBatch` (its
/// position, error bound and normal give the offset origin), so no column repeats the batch.
/// Invariant: all columns have one slot per entry.
#[derive(Resource, Clone, Debug, Default)]
pub struct ShadowRays {
    /// Entries per batch point (entry `e` starts at point `e / entries_per_point`).
    pub entries_per_point: usize,
    /// Where each entry's ray ends (`None`: the entry has no ray).
    pub kind: Vec<ShadowTarget>,
    /// Segment end (the light point) and the light's surface normal there (`Surface` only).
    pub target: Vec<Vec3>,
    pub target_normal: Vec<Vec3>,
    /// Answers, filled by the trace step (false for entries without a ray).
    pub occluded: Vec<bool>,
    /// Number of entries with a ray.
    rays: usize,
}

impl ShadowRays {
    /// Number of rays to trace (entries whose kind is not `None`).
    pub fn len(&self) -> usize {
        self.rays
    }
    /// True with no rays to trace.
    pub fn is_empty(&self) -> bool {
        self.rays == 0
    }
    /// Empties every column, keeping capacity.
    pub fn clear(&mut self) {
        self.kind.clear();
        self.target.clear();
        self.target_normal.clear();
        self.occluded.clear();
        self.rays = 0;
    }
    /// Sizes the columns for `entries` entries of `entries_per_point` each; the kinds, targets
    /// and count are then written by the sampling step, and the answers reset to unoccluded.
    fn resize(&mut self, entries: usize, entries_per_point: usize) {
        self.entries_per_point = entries_per_point;
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
    } else {
        sampler.update(&table)
    };
    // The sampler has caught up; clearing the flags is bookkeeping, not a change to the table.
    table.bypass_change_detection().clear_change_flags();
    report.record("light_sampler", true, what);
    // The sampler has consumed the change log; clearing it is bookkeeping, not a table change.
    table.bypass_change_detection().clear_change_flags();
}

/// Entries per point under `settings` for a table of `n_lights` lights.
fn entries_per_point(settings: &Settings, n_lights: usize) -> usize {
    let spp = settings.samples_per_point.max(1) as usize;
    match settings.selection {
        LightSelection::OneSampled => spp,
        LightSelection::All => spp * n_lights,
    }
}

/// For every point of the batch, chooses lights and evaluates Sample_Li, writing one
/// `DirectLighting` entry per sample (unoccluded) and, in the same pass, the entry's shadow ray.
pub fn sample_direct_lighting(
    batch: Res<ShadingBatch>,
    table: Res<LightTable>,
    sampler: Res<LightSampler>,
    settings: Res<Settings>,
    mut out: ResMut<DirectLighting>,
    mut rays: ResMut<ShadowRays>,
) {
    let n = batch.len();
    let k = entries_per_point(&settings, table.len());
    let all_ids: Vec<LightId> =
        if settings.selection == LightSelection::All { table.ids().collect() } else { Vec::new() };
    let out = &mut *out;
    // Every entry is written below, so the columns are only resized: steady-state batches of one
    // size never fill them first.
    out.offsets.clear();
    out.offsets.extend((0..=n).map(|i| (i * k) as u32));
    let m = n * k;
    out.radiance.resize(m, SampledSpectrum::default());
    out.wi.resize(m, Vec3::ZERO);
    out.pdf.resize(m, 0.0);
    out.light.resize(m, NO_LIGHT);
    out.delta.resize(m, false);
    out.occluded.resize(m, false);
    rays.resize(m, k);

    let spp = settings.samples_per_point.max(1);
    let chunk = CHUNK * k.max(1);
    let rays = &mut *rays;
    rays.rays = (
        out.radiance.par_chunks_mut(chunk),
        out.wi.par_chunks_mut(chunk),
        out.pdf.par_chunks_mut(chunk),
        out.light.par_chunks_mut(chunk),
        out.delta.par_chunks_mut(chunk),
        out.occluded.par_chunks_mut(chunk),
        rays.kind.par_chunks_mut(chunk),
        rays.target.par_chunks_mut(chunk),
        rays.target_normal.par_chunks_mut(chunk),
    )
        .into_par_iter()
        .enumerate()
        .map(|(c, (radiance, wi, pdf, light, delta, occluded, ray_kind, target, target_normal))| {
            let first_point = c * CHUNK;
            let mut traced = 0;
            // Entry e = point * k + slot of this chunk; nested loops spare a division per entry.
            for point in 0..radiance.len() / k {
                let i = first_point + point;
                let ctx = LightSampleContext { p: batch.position[i], n: batch.normal[i], ns: batch.shading_normal[i] };
                let query = match settings.color_mode {
                    ColorMode::Rgb => ColorQuery::Rgb,
                    ColorMode::Spectral => ColorQuery::Spectral(&batch.wavelengths[i]),
                };
                for slot in 0..k {
                    let e = point * k + slot;
                    let (s, light_index) = match settings.selection {
                        LightSelection::OneSampled => (slot as u32, None),
                        LightSelection::All => ((slot / all_ids.len()) as u32, Some(slot % all_ids.len())),
                    };
                    let mut rng = SampleStream::new(settings.seed, batch.pixel[i], batch.sample[i] * spp + s);
                    let chosen = match light_index {
                        Some(j) => Some((all_ids[j], 1.0)),
                        None => sampler.sample(&ctx, rng.next_f32()),
                    };
                    let sampled = chosen.and_then(|(id, pmf)| {
                        let flags = table.flags(id);
                        // Lights at a point ignore u: skip drawing it (the streams are counter
                        // based, so no other number changes).
                        let u = if flags.contains(LightFlags::DELTA_POSITION) {
                            Vec2::ZERO
                        } else {
                            rng.at_dimension(1 + 2 * light_index.unwrap_or(0) as u32).next_2d()
                        };
                        let ls = match settings.light_precision {
                            LightPrecision::F32 => table.sample_li(id, &ctx, u, query),
                            LightPrecision::F64 => table.sample_li_f64(id, &ctx, u, query),
                        }?;
                        (ls.pdf > 0.0 && ls.radiance.is_finite()).then_some((ls, pmf, flags))
                    });
                    // A failed sample leaves a zero entry (its light is kept when one was chosen).
                    light[e] = chosen.map_or(NO_LIGHT, |(id, _)| id);
                    occluded[e] = false;
                    ray_kind[e] = ShadowTarget::None;
                    let Some((ls, pmf, flags)) = sampled else {
                        radiance[e] = SampledSpectrum::default();
                        wi[e] = Vec3::ZERO;
                        pdf[e] = 0.0;
                        delta[e] = false;
                        continue;
                    };
                    radiance[e] = ls.radiance;
                    wi[e] = ls.wi;
                    pdf[e] = ls.pdf * pmf;
                    delta[e] = flags.is_delta();
                    if settings.shadows
                        && pdf[e] > 0.0
                        && ls.radiance.0.iter().any(|&v| v > 0.0)
                        && table.casts_shadows(light[e])
                    {
                        ray_kind[e] =
                            if flags.contains(LightFlags::INFINITE) || flags.contains(LightFlags::DELTA_DIRECTION) {
                                ShadowTarget::Infinity
                            } else if ls.n_light == Vec3::ZERO {
                                ShadowTarget::Point
                            } else {
                                ShadowTarget::Surface
                            };
                        (target[e], target_normal[e]) = (ls.p_light, ls.n_light);
                        traced += 1;
                    }
                }
            }
            traced
        })
        .sum();
}

/// Zeroes the radiance of entries whose shadow ray was blocked.
pub fn apply_visibility(rays: Res<ShadowRays>, mut out: ResMut<DirectLighting>) {
    let out = &mut *out;
    let columns = (out.radiance.par_iter_mut(), out.occluded.par_iter_mut(), rays.occluded.par_iter());
    columns.into_par_iter().with_min_len(CHUNK).for_each(|(radiance, occluded, &blocked)| {
        if blocked {
            (*radiance, *occluded) = (SampledSpectrum::default(), true);
        }
    });
}
