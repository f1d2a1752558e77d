//! Choosing lights and evaluating Sample_Li for the whole shading batch (rayon over chunks), the
//! shadow rays that follow, and applying their answers.

use bevy_ecs::prelude::*;
use glam::Vec3;
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

/// Shadow-ray segments from shading points to sampled light points, and their answers.
/// Invariant: all columns have the same length; `entry` indexes `DirectLighting`.
#[derive(Resource, Clone, Debug, Default)]
pub struct ShadowRays {
    /// Segment start (the shading point), its error bound and geometric normal, for the offset.
    pub origin: Vec<Vec3>,
    pub origin_error: Vec<Vec3>,
    pub origin_normal: Vec<Vec3>,
    /// Segment end (the light point) and the light's surface normal there (zero if none).
    pub target: Vec<Vec3>,
    pub target_normal: Vec<Vec3>,
    /// True for lights at infinity (distant, infinite): the ray leaves along `target - origin`.
    pub to_infinity: Vec<bool>,
    /// The `DirectLighting` entry each ray belongs to.
    pub entry: Vec<u32>,
    /// Answers, filled by the trace step.
    pub occluded: Vec<bool>,
}

/// One shadow ray, the row form of [`ShadowRays`]' input columns (see there).
pub struct ShadowRay {
    pub origin: Vec3,
    pub origin_error: Vec3,
    pub origin_normal: Vec3,
    pub target: Vec3,
    pub target_normal: Vec3,
    pub to_infinity: bool,
}

impl ShadowRays {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.origin.len()
    }
    /// True with no rays.
    pub fn is_empty(&self) -> bool {
        self.origin.is_empty()
    }
    /// Empties every column, keeping capacity.
    pub fn clear(&mut self) {
        self.origin.clear();
        self.origin_error.clear();
        self.origin_normal.clear();
        self.target.clear();
        self.target_normal.clear();
        self.to_infinity.clear();
        self.entry.clear();
        self.occluded.clear();
    }

    /// Replaces the rays by one ray per `DirectLighting` entry of `entry`, computed in parallel
    /// by `ray(entry)`; answers are reset to unoccluded.
    pub fn par_fill(&mut self, entry: Vec<u32>, ray: impl Fn(usize) -> ShadowRay + Sync) {
        let n = entry.len();
        // Every ray is written below, so the columns are only resized (no fill in steady state).
        self.origin.resize(n, Vec3::ZERO);
        self.origin_error.resize(n, Vec3::ZERO);
        self.origin_normal.resize(n, Vec3::ZERO);
        self.target.resize(n, Vec3::ZERO);
        self.target_normal.resize(n, Vec3::ZERO);
        self.to_infinity.resize(n, false);
        self.occluded.clear();
        self.occluded.resize(n, false);
        self.entry = entry;
        let columns = (
            self.origin.par_iter_mut(),
            self.origin_error.par_iter_mut(),
            self.origin_normal.par_iter_mut(),
            self.target.par_iter_mut(),
            self.target_normal.par_iter_mut(),
            self.to_infinity.par_iter_mut(),
            self.entry.par_iter(),
        );
        columns.into_par_iter().with_min_len(CHUNK).for_each(|(o, oe, on, t, tn, inf, &e)| {
            let r = ray(e as usize);
            (*o, *oe, *on, *t, *tn, *inf) =
                (r.origin, r.origin_error, r.origin_normal, r.target, r.target_normal, r.to_infinity);
        });
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

/// Each entry's sampled light point and the light's normal there, for its shadow ray: scratch
/// columns kept between updates so that each batch reuses their memory.
#[derive(Default)]
pub struct LightPoints {
    position: Vec<Vec3>,
    normal: Vec<Vec3>,
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
/// `DirectLighting` entry per sample (unoccluded), then lists the shadow rays to trace.
pub fn sample_direct_lighting(
    batch: Res<ShadingBatch>,
    table: Res<LightTable>,
    sampler: Res<LightSampler>,
    settings: Res<Settings>,
    mut out: ResMut<DirectLighting>,
    mut rays: ResMut<ShadowRays>,
    mut light_points: Local<LightPoints>,
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
    let LightPoints { position: p_light, normal: n_light } = &mut *light_points;
    p_light.resize(m, Vec3::ZERO);
    n_light.resize(m, Vec3::ZERO);

    let spp = settings.samples_per_point.max(1);
    let chunk = CHUNK * k.max(1);
    (
        out.radiance.par_chunks_mut(chunk),
        out.wi.par_chunks_mut(chunk),
        out.pdf.par_chunks_mut(chunk),
        out.light.par_chunks_mut(chunk),
        out.delta.par_chunks_mut(chunk),
        out.occluded.par_chunks_mut(chunk),
        p_light.par_chunks_mut(chunk),
        n_light.par_chunks_mut(chunk),
    )
        .into_par_iter()
        .enumerate()
        .for_each(|(c, (radiance, wi, pdf, light, delta, occluded, pl, nl))| {
            let first_point = c * CHUNK;
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
                        let u = rng.at_dimension(1 + 2 * light_index.unwrap_or(0) as u32).next_2d();
                        let ls = match settings.light_precision {
                            LightPrecision::F32 => table.sample_li(id, &ctx, u, query),
                            LightPrecision::F64 => table.sample_li_f64(id, &ctx, u, query),
                        }?;
                        (ls.pdf > 0.0 && ls.radiance.is_finite()).then_some((ls, pmf))
                    });
                    // A failed sample leaves a zero entry (its light is kept when one was chosen).
                    light[e] = chosen.map_or(NO_LIGHT, |(id, _)| id);
                    occluded[e] = false;
                    match sampled {
                        Some((ls, pmf)) => {
                            radiance[e] = ls.radiance;
                            wi[e] = ls.wi;
                            pdf[e] = ls.pdf * pmf;
                            delta[e] = table.flags(light[e]).is_delta();
                            pl[e] = ls.p_light;
                            nl[e] = ls.n_light;
                        }
                        None => {
                            radiance[e] = SampledSpectrum::default();
                            wi[e] = Vec3::ZERO;
                            pdf[e] = 0.0;
                            delta[e] = false;
                        }
                    }
                }
            }
        });

    if !settings.shadows {
        rays.clear();
        return;
    }
    // Entries that need a shadow ray, found in parallel and listed in entry order.
    let out = &*out;
    let needs_ray =
        |e: usize| out.pdf[e] > 0.0 && out.radiance[e].0.iter().any(|&v| v > 0.0) && table.casts_shadows(out.light[e]);
    let entries: Vec<u32> =
        (0..n * k).into_par_iter().with_min_len(CHUNK).filter(|&e| needs_ray(e)).map(|e| e as u32).collect();
    rays.par_fill(entries, |e| {
        let i = e / k;
        let flags = table.flags(out.light[e]);
        ShadowRay {
            origin: batch.position[i],
            origin_error: batch.position_error[i],
            origin_normal: batch.normal[i],
            target: p_light[e],
            target_normal: n_light[e],
            to_infinity: flags.contains(LightFlags::INFINITE) || flags.contains(LightFlags::DELTA_DIRECTION),
        }
    });
}

/// Zeroes the radiance of entries whose shadow ray was blocked.
pub fn apply_visibility(rays: Res<ShadowRays>, mut out: ResMut<DirectLighting>) {
    for (&e, &blocked) in rays.entry.iter().zip(&rays.occluded) {
        if blocked {
            out.radiance[e as usize] = SampledSpectrum::default();
            out.occluded[e as usize] = true;
        }
    }
}
