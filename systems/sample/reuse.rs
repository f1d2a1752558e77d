//! Reservoir reuse after RIS (Bitterli, Wyman, Pharr, Shirley, Lefohn and Jarosz 2020,
//! "Spatiotemporal reservoir resampling for real-time ray tracing with dynamic direct lighting",
//! ReSTIR): each entry's RIS reservoir is combined with the previous run's reservoir at the same
//! surface point (temporal, `ShadingBatch::previous`), then with k neighbours' in the batch's
//! image (spatial, `ShadingBatch::layout`), and the survivor gets the entry's one shadow ray.
//!
//! A reservoir holds one sample y (a light and the u its Sample_Li drew: primary sample space,
//! the domain every point shares), its unbiased contribution weight W and confidence M. Reservoir
//! j joins point q's combination with resampling weight p_hat_q(y_j) W_j M_j (Algorithm 4); the
//! result's W is sum w / (Z p_hat_q(y)), with 1/Z either the balance-heuristic weight
//! p_hat_s(y) / sum_j M_j p_hat_j(y) of the source s of y (the paper's Sec. 4.3, unbiased) or
//! 1 / sum_j M_j (biased where some p_hat_j(y) = 0 while p_hat_q(y) > 0).
//!
//! The target leaves visibility out (see `resampled`), so the combination is unbiased without a
//! shadow ray per neighbour, at the price that reuse does not learn occlusion: a shadowed point
//! keeps resampling lights it cannot see. Light sources move between runs: a previous sample is
//! re-evaluated against the current light table (its light found again by entity), and one whose
//! light was removed keeps its M with no sample. The previous point's p_hat is evaluated under the
//! current lights too, so a moved light biases temporal reuse slightly (as in the paper).

use bevy_ecs::entity::Entity;
use bevy_ecs::resource::Resource;
use glam::Vec2;
use rayon::prelude::*;

use super::resampled::{Kept, Reservoir, entry_sample, target};
use super::{CHUNK, NO_LIGHT, Sampled, Sampling};
use crate::lanes::LANES;
use crate::light::{LightId, LightKind, LightSampleContext, LightTable};
use crate::rng::SampleStream;
use crate::shading::{ImageLayout, Restir, ReuseWeights, ShadingBatch};

/// Most neighbours combined per entry (`Restir::spatial` is clamped to it).
pub const MAX_NEIGHBOURS: usize = 16;
/// Neighbours whose geometric normals differ by more than ~25 degrees are not reused (the
/// paper's heuristic; any rule that does not look at the samples keeps the result unbiased).
const NORMAL_COS: f32 = 0.9;

/// A reservoir between passes of one run: sample (light, u), W (0: no sample) and M.
#[derive(Clone, Copy, Debug)]
pub(super) struct Stored {
    light: LightId,
    u: Vec2,
    w: f32,
    m: f32,
}

impl Stored {
    const EMPTY: Self = Self { light: NO_LIGHT, u: Vec2::ZERO, w: 0.0, m: 0.0 };

    /// The light and the bits of u, W and M, for tests that compare reservoirs exactly.
    #[cfg(test)]
    pub(super) fn bits(&self) -> (LightId, [u32; 4]) {
        (self.light, [self.u.x, self.u.y, self.w, self.m].map(f32::to_bits))
    }
}

/// A reservoir kept for the next run: its light by entity (and triangle or shape index for
/// area lights), which stays valid while row numbers do not.
#[derive(Clone, Copy, Debug)]
struct Past {
    light: Option<(Entity, u32)>,
    u: Vec2,
    w: f32,
    m: f32,
}

/// The reservoirs of [`crate::shading::LightSelection::Restir`]: this run's, and the last run's
/// final ones with their points, for temporal reuse. Persists across schedule runs.
#[derive(Resource, Debug, Default)]
pub struct Reservoirs {
    current: Vec<Stored>,
    pub(super) next: Vec<Stored>,
    past: Vec<Past>,
    past_points: Vec<LightSampleContext>,
    past_entries_per_point: usize,
    /// Entries of the last run that found a previous reservoir.
    pub temporal_hits: usize,
    /// Neighbour reservoirs combined in the last run.
    pub neighbours: usize,
}

impl Reservoirs {
    /// Entries kept for the next run's temporal reuse.
    pub fn history_len(&self) -> usize {
        self.past.len()
    }
    /// Forgets the history (a camera cut).
    pub fn clear_history(&mut self) {
        self.past.clear();
        self.past_points.clear();
    }

    /// This run's initial (RIS, then temporal) reservoirs, before spatial reuse.
    #[cfg(test)]
    pub(super) fn initial(&self) -> &[Stored] {
        &self.current
    }
}

/// A past reservoir found for an entry: its light now, W, M and the point it was made at.
struct Found {
    light: Option<LightId>,
    u: Vec2,
    w: f32,
    m: f32,
    ctx: LightSampleContext,
}

impl Sampling<'_> {
    /// Builds the final reservoir of every entry into `res.next`: RIS, then temporal reuse, then
    /// spatial reuse. Lanes as `resampled_block` when `lanes`.
    pub(super) fn build_reservoirs(&self, restir: &Restir, res: &mut Reservoirs, entries: usize, lanes: bool) {
        let mut current = std::mem::take(&mut res.current);
        current.resize(entries, Stored::EMPTY);
        let chunk = CHUNK * self.k.max(1);
        let past = (restir.temporal && !res.past.is_empty()).then_some(&*res);
        let hits: usize = current
            .par_chunks_mut(chunk)
            .enumerate()
            .map(|(c, out)| {
                if lanes {
                    crate::lanes::widest(
                        #[inline(always)]
                        || self.initial_chunk(c * chunk, out, restir, past, true),
                    )
                } else {
                    self.initial_chunk(c * chunk, out, restir, past, false)
                }
            })
            .sum();
        (res.current, res.temporal_hits) = (current, hits);
        res.next.resize(entries, Stored::EMPTY);
        match self.batch.layout {
            Some(layout) if restir.spatial > 0 => {
                let current = &res.current;
                res.neighbours = res
                    .next
                    .par_chunks_mut(chunk)
                    .enumerate()
                    .map(|(c, out)| {
                        let mut used = 0;
                        for (e, slot) in out.iter_mut().enumerate() {
                            let (stored, n) = self.spatial(c * chunk + e, current, restir, &layout);
                            (*slot, used) = (stored, used + n);
                        }
                        used
                    })
                    .sum();
            }
            _ => {
                std::mem::swap(&mut res.current, &mut res.next);
                res.neighbours = 0;
            }
        }
    }

    /// RIS and temporal reuse for entries `first..first + out.len()`; returns how many found a
    /// previous reservoir.
    #[inline(always)]
    fn initial_chunk(
        &self,
        first: usize,
        out: &mut [Stored],
        restir: &Restir,
        past: Option<&Reservoirs>,
        lanes: bool,
    ) -> usize {
        let m = restir.candidates.max(1);
        let (mut hits, mut e) = (0, 0);
        while e < out.len() {
            let n = LANES.min(out.len() - e);
            let reservoirs = if lanes {
                self.resampled_block_reservoirs(first, e, n, m)
            } else {
                std::array::from_fn(|l| {
                    if l >= n {
                        return Reservoir::EMPTY;
                    }
                    let (i, _, stream) = self.point_and_stream(first + e + l);
                    let ctx = self.context(i);
                    if ctx.p.is_finite() { self.resampled_reservoir(i, stream, &ctx, m) } else { Reservoir::EMPTY }
                })
            };
            for l in 0..n {
                let (stored, hit) = self.temporal(first + e + l, reservoirs[l], restir, past);
                (out[e + l], hits) = (stored, hits + hit as usize);
            }
            e += n;
        }
        hits
    }

    /// Entry `g`'s RIS reservoir `r` combined with its previous reservoir, if any (and whether
    /// there was one).
    fn temporal(&self, g: usize, r: Reservoir, restir: &Restir, past: Option<&Reservoirs>) -> (Stored, bool) {
        let m0 = restir.candidates.max(1) as f32;
        let (i, slot, stream) = self.point_and_stream(g);
        let ctx = self.context(i);
        let found = past.and_then(|p| p.find(self.batch, self.table, i, slot, self.k));
        let Some(prev) = found.filter(|_| ctx.p.is_finite()) else {
            return (to_stored(&r, r.contribution_weight(m0), m0), false);
        };
        // The paper's M cap: history counts for at most `history_cap` initial reservoirs.
        let m_prev = prev.m.min(restir.history_cap.max(1) as f32 * m0);
        // The RIS reservoir's weight sum is its own p_hat W M: it is offer 0 as it stands.
        let mut c = r;
        if let Some(light) = prev.light
            && prev.w > 0.0
            && let Some((ls, _, flags)) = self.evaluate_at(i, &ctx, (light, 1.0), prev.u)
        {
            let t = target(&ctx, &ls);
            let r = SampleStream::new(self.settings.light_pattern(), self.settings.seed, self.batch.pixel[i], stream)
                .at_dimension(4 * m0 as u32)
                .next_f32();
            c.offer_weighted(Kept { light, u: prev.u, ls, flags, source: 1 }, t, t * prev.w * m_prev, r);
        }
        let sources = [(i, ctx, m0), (i, prev.ctx, m_prev)];
        (to_stored(&c, self.combined_weight(&c, &sources, restir.weights), m0 + m_prev), true)
    }

    /// Entry `g`'s reservoir of `current` combined with those of up to k neighbours in the
    /// image `layout`; returns it and how many neighbours joined.
    fn spatial(&self, g: usize, current: &[Stored], restir: &Restir, layout: &ImageLayout) -> (Stored, usize) {
        let own = current[g];
        let (i, slot, stream) = self.point_and_stream(g);
        let ctx = self.context(i);
        if !ctx.p.is_finite() {
            return (own, 0);
        }
        let rng = SampleStream::new(self.settings.light_pattern(), self.settings.seed, self.batch.pixel[i], stream);
        let k = (restir.spatial as usize).min(MAX_NEIGHBOURS);
        // Dimensions after RIS's 4M and temporal reuse's one.
        let base = 4 * restir.candidates.max(1) + 2;
        let r = restir.radius.max(1) as f32;
        let mut sources = [(i, ctx, own.m); MAX_NEIGHBOURS + 1];
        let mut stored = [own; MAX_NEIGHBOURS + 1];
        let mut n = 1;
        for j in 0..k as u32 {
            let d = rng.at_dimension(base + 2 * j).next_2d();
            let (dx, dy) = (((2.0 * d.x - 1.0) * r).round() as i64, ((2.0 * d.y - 1.0) * r).round() as i64);
            let Some(p) = neighbour(layout, self.batch.len(), i, dx, dy) else { continue };
            let near = self.context(p);
            if p == i || !near.p.is_finite() || near.n.dot(ctx.n) < NORMAL_COS {
                continue;
            }
            let Some(&s) = current.get(p * self.k + slot) else { continue };
            (sources[n], stored[n], n) = ((p, near, s.m), s, n + 1);
        }
        let mut c = Reservoir::EMPTY;
        for (j, s) in stored.iter().enumerate().take(n) {
            if s.w <= 0.0 {
                continue;
            }
            let Some((ls, _, flags)) = self.evaluate_at(i, &ctx, (s.light, 1.0), s.u) else { continue };
            let t = target(&ctx, &ls);
            let kept = Kept { light: s.light, u: s.u, ls, flags, source: j as u32 };
            c.offer_weighted(kept, t, t * s.w * s.m, rng.at_dimension(base + 2 * k as u32 + j as u32).next_f32());
        }
        let m: f32 = sources[..n].iter().map(|s| s.2).sum();
        (to_stored(&c, self.combined_weight(&c, &sources[..n], restir.weights), m), n - 1)
    }

    /// W of the combined reservoir `c` at the point of `sources[0]`, the sources being the
    /// combined reservoirs' (batch point, point, M) in offer order (see the module docs).
    fn combined_weight(
        &self,
        c: &Reservoir,
        sources: &[(usize, LightSampleContext, f32)],
        weights: ReuseWeights,
    ) -> f32 {
        let Some(kept) = &c.kept else { return 0.0 };
        match weights {
            ReuseWeights::Biased => c.contribution_weight(sources.iter().map(|s| s.2).sum()),
            ReuseWeights::Unbiased => {
                let (mut all, mut own) = (0.0, 0.0);
                for (j, &(p, ctx, m)) in sources.iter().enumerate() {
                    // p_hat_j(y), under j's colour query; at q (or a point equal to it) known.
                    let t = if j == 0 || ctx == sources[0].1 {
                        c.kept_target
                    } else {
                        self.evaluate_at(p, &ctx, (kept.light, 1.0), kept.u).map_or(0.0, |(ls, ..)| target(&ctx, &ls))
                    };
                    all += m * t;
                    if j == kept.source as usize {
                        own = t;
                    }
                }
                // 1/Z = p_hat_s(y) / sum_j M_j p_hat_j(y).
                c.contribution_weight(all / own)
            }
        }
    }

    /// Entry `e`'s light and sample from its final reservoir, re-evaluated at its point.
    pub(super) fn reservoir_sample(&self, i: usize, e: usize, ctx: &LightSampleContext) -> (LightId, Option<Sampled>) {
        let Some(s) = self.reservoirs.get(e).filter(|s| s.w > 0.0) else { return (NO_LIGHT, None) };
        let Some((ls, _, flags)) = self.evaluate_at(i, ctx, (s.light, 1.0), s.u) else { return (s.light, None) };
        let kept = Kept { light: s.light, u: s.u, ls, flags, source: 0 };
        (s.light, Some(entry_sample(kept, s.w)))
    }
}

/// The stored form of reservoir `c` with contribution weight `w` and confidence `m`.
fn to_stored(c: &Reservoir, w: f32, m: f32) -> Stored {
    match &c.kept {
        Some(k) if w > 0.0 => Stored { light: k.light, u: k.u, w, m },
        _ => Stored { m, ..Stored::EMPTY },
    }
}

/// The batch point at pixel offset (dx, dy) from point `i` in `layout` (same sample of its
/// pixel), if it is in the batch of `len` points.
fn neighbour(layout: &ImageLayout, len: usize, i: usize, dx: i64, dy: i64) -> Option<usize> {
    let (spp, width) = (layout.samples_per_pixel.max(1) as u64, layout.width as u64);
    if width == 0 {
        return None;
    }
    let g = layout.first.checked_add(i as u64)?;
    let (pixel, sample) = (g / spp, g % spp);
    let (x, y) = ((pixel % width) as i64 + dx, (pixel / width) as i64 + dy);
    if x < 0 || x >= width as i64 || y < 0 {
        return None;
    }
    let slot = (y as u64).checked_mul(width)?.checked_add(x as u64)?.checked_mul(spp)?.checked_add(sample)?;
    let p = slot.checked_sub(layout.first)?;
    (p < len as u64).then_some(p as usize)
}

impl Reservoirs {
    /// The past reservoir of point `i`'s sample slot `slot`, through `batch.previous`, with its
    /// light found in the current `table`; None without one. A reservoir whose light was removed
    /// keeps its M with no sample (as Bitterli et al.): dropping exactly the reservoirs that held
    /// it would leave the others' history over-represented, biasing the frame bright.
    fn find(&self, batch: &ShadingBatch, table: &LightTable, i: usize, slot: usize, k: usize) -> Option<Found> {
        if k != self.past_entries_per_point {
            return None;
        }
        let p = *batch.previous.get(i)? as usize;
        let ctx = *self.past_points.get(p)?;
        let past = self.past.get(p.checked_mul(k)?.checked_add(slot)?)?;
        let light = past.light.and_then(|(entity, primitive)| match primitive {
            u32::MAX => table.rows_of(entity).first().copied().filter(|id| id.kind != LightKind::Area),
            _ => table.area_light_at(entity, primitive),
        });
        Some(Found { light, u: past.u, w: past.w, m: past.m, ctx })
    }

    /// Keeps this run's final reservoirs (`next`) and the batch's points for the next run.
    pub(super) fn keep_history(&mut self, batch: &ShadingBatch, table: &LightTable, k: usize) {
        let Self { next, past, past_points, .. } = self;
        past.clear();
        past.par_extend(next.par_iter().map(|s| Past {
            light: (s.w > 0.0).then(|| {
                let primitive = if s.light.kind == LightKind::Area {
                    table.area.items[s.light.row as usize].primitive
                } else {
                    u32::MAX
                };
                (table.owner(s.light), primitive)
            }),
            u: s.u,
            w: s.w,
            m: s.m,
        }));
        past_points.clear();
        past_points.par_extend((0..batch.len()).into_par_iter().map(|i| LightSampleContext {
            p: batch.position[i],
            n: batch.normal[i],
            ns: batch.shading_normal[i],
        }));
        self.past_entries_per_point = k;
    }
}

/// The run report's line on reuse: which stages ran, with M and k.
pub(super) fn summary(restir: &Restir, batch: &ShadingBatch, res: &Reservoirs) -> String {
    let m = restir.candidates.max(1);
    let weights = match restir.weights {
        ReuseWeights::Unbiased => "unbiased MIS",
        ReuseWeights::Biased => "biased 1/sum M",
    };
    let temporal = match (restir.temporal, batch.previous.is_empty()) {
        (false, _) => "temporal off".to_string(),
        (true, true) => "temporal: no previous points in the batch".to_string(),
        (true, false) => format!(
            "temporal: {} entries reused history (M capped at {}x{m})",
            res.temporal_hits,
            restir.history_cap.max(1)
        ),
    };
    let k = (restir.spatial as usize).min(MAX_NEIGHBOURS);
    let spatial = match (k, batch.layout) {
        (0, _) => "spatial off".to_string(),
        (_, None) => "spatial: the batch has no image layout".to_string(),
        (k, Some(_)) => {
            format!("spatial: k={k} within {} px, {} neighbours combined", restir.radius.max(1), res.neighbours)
        }
    };
    format!("ReSTIR: RIS M={m}; {temporal}; {spatial}; {weights}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A renderer's batch: slots are samples of pixels row-major, the batch starting mid-image.
    /// Neighbours keep the sample index, stay in the image's row, and in the batch.
    #[test]
    fn neighbours_are_the_same_sample_of_nearby_pixels_in_the_batch() {
        // Width 5, 3 samples per pixel, first slot 7 (pixel 2, sample 1), 16 slots.
        let layout = ImageLayout { width: 5, samples_per_pixel: 3, first: 7 };
        assert_eq!(neighbour(&layout, 16, 0, 1, 0), Some(3), "pixel 3, sample 1 = slot 10");
        assert_eq!(neighbour(&layout, 16, 0, 2, 0), Some(6));
        assert_eq!(neighbour(&layout, 16, 0, 3, 0), None, "past the row's end");
        assert_eq!(neighbour(&layout, 16, 0, -1, 0), None, "before the batch");
        assert_eq!(neighbour(&layout, 16, 0, 0, 1), Some(15), "pixel 7, sample 1 = slot 22");
        assert_eq!(neighbour(&layout, 15, 0, 0, 1), None, "past a batch of 15 slots");
        assert_eq!(neighbour(&layout, 16, 0, 0, -1), None, "above the image");
        let huge = ImageLayout { width: u32::MAX, samples_per_pixel: u32::MAX, first: u64::MAX };
        assert_eq!(neighbour(&huge, 4, 3, 1, 1), None);
    }
}
