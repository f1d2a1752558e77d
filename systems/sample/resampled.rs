//! Resampled importance sampling of lights (Talbot, Cline and Egbert 2005, "Importance
//! Resampling for Global Illumination"): M candidate light samples, each drawn as one light sample
//! is drawn (the light sampler's choice, then Sample_Li), one kept by weighted reservoir sampling
//! in proportion to w = p_hat / p, and one shadow ray for it.
//!
//! Target p_hat: the sum of the candidate's radiance channels times the cosine at the shading
//! normal (clamped at 0; the cosine is left out for points without a normal). The batch carries
//! no BSDF, so the target is the unshadowed irradiance contribution. It is zero only where the
//! reflected light is (a light behind an opaque surface, a black light), so the estimator
//! f(y) / p_hat(y) * (1/M) sum w stays unbiased for opaque BSDFs; a BSDF that transmits light
//! from behind the shading normal would be biased by it.

use glam::Vec2;

use super::{EntryColumns, NO_LIGHT, Sampled, Sampling};
use crate::lanes::{F32x16, LANES, U32x16};
use crate::light::area::TriangleLightLanes;
use crate::light::{ColorQuery, LiSample, LightFlags, LightId, LightKind, LightSampleContext};
use crate::rng::SampleStream;

/// A reservoir's kept sample: the light, its primary-sample-space point `u` (what Sample_Li
/// drew; zero for lights at a point), Sample_Li at the reservoir's point, and which of the
/// combined reservoirs it came from (0 for the point's own; see `reuse`).
#[derive(Clone, Copy)]
pub(super) struct Kept {
    pub(super) light: LightId,
    pub(super) u: Vec2,
    pub(super) ls: LiSample,
    pub(super) flags: LightFlags,
    pub(super) source: u32,
}

/// Weighted reservoir sampling over one point's candidates (or over whole reservoirs, see
/// `reuse`). Samples live in primary sample space (the light and its `u`), the one domain every
/// point shares, so a sample moves between points by re-running Sample_Li with its `u`.
#[derive(Clone, Copy)]
pub(super) struct Reservoir {
    pub(super) kept: Option<Kept>,
    /// p_hat of the kept sample at the reservoir's point, in primary sample space ([`target`]).
    pub(super) kept_target: f32,
    pub(super) weight_sum: f32,
}

impl Reservoir {
    pub(super) const EMPTY: Self = Self { kept: None, kept_target: 0.0, weight_sum: 0.0 };

    /// Offers candidate `light`'s sample at `u` (chosen with `pmf`); `r` decides whether it is
    /// kept. Its weight is p_hat / (pmf pdf), the pdf of u being the pmf alone.
    #[inline(always)]
    fn offer(&mut self, ctx: &LightSampleContext, light: LightId, u: Vec2, (ls, pmf, flags): Sampled, r: f32) {
        let t = target(ctx, &ls);
        self.offer_weighted(Kept { light, u, ls, flags, source: 0 }, t, t / pmf, r);
    }

    /// Offers `kept` (target `t` here) with resampling weight `w`, kept with probability
    /// w / (sum so far): the survivor is offer j with probability w_j / sum over all.
    #[inline(always)]
    pub(super) fn offer_weighted(&mut self, kept: Kept, t: f32, w: f32, r: f32) {
        if !(t > 0.0 && w > 0.0 && w.is_finite()) {
            return;
        }
        self.weight_sum += w;
        if r * self.weight_sum < w {
            (self.kept, self.kept_target) = (Some(kept), t);
        }
    }

    /// The unbiased contribution weight W of the kept sample, given the normalisation
    /// `z` (M for RIS: W = sum w / (M p_hat(y))); 0 for an empty reservoir.
    pub(super) fn contribution_weight(&self, z: f32) -> f32 {
        let w = self.weight_sum / (z * self.kept_target);
        if self.kept.is_some() && w.is_finite() && w > 0.0 { w } else { 0.0 }
    }

    /// The survivor of `m` candidates and its sample, whose pdf is the estimator's 1/W with pmf 1.
    fn finish(self, m: u32) -> (LightId, Option<Sampled>) {
        let w = self.contribution_weight(m as f32);
        match self.kept {
            Some(k) if w > 0.0 => (k.light, Some(entry_sample(k, w))),
            _ => (NO_LIGHT, None),
        }
    }
}

/// The entry of a kept sample of contribution weight `w` (primary sample space): Li cos / pdf
/// must be f(u) W = (Li cos / pdf_li) W, so its pdf is pdf_li / W, with pmf 1.
pub(super) fn entry_sample(k: Kept, w: f32) -> Sampled {
    let mut ls = k.ls;
    ls.pdf /= w;
    (ls, 1.0, k.flags)
}

impl Sampling<'_> {
    /// The resampled light sample of batch point `i` (sample `stream` of its random stream) out
    /// of `candidates`: the survivor's light and its sample, whose pdf is the estimator's 1/W
    /// with pmf 1. Candidate j draws its choice from dimension 3j and its Sample_Li from 3j + 1
    /// (candidate 0 is the one-sampled light), the reservoir's u from dimension 3M + j.
    pub(super) fn resampled(
        &self,
        i: usize,
        stream: u32,
        ctx: &LightSampleContext,
        candidates: u32,
    ) -> (LightId, Option<Sampled>) {
        self.resampled_reservoir(i, stream, ctx, candidates).finish(candidates.max(1))
    }

    /// The reservoir [`Self::resampled`] finishes.
    pub(super) fn resampled_reservoir(
        &self,
        i: usize,
        stream: u32,
        ctx: &LightSampleContext,
        candidates: u32,
    ) -> Reservoir {
        let m = candidates.max(1);
        // One stream for the candidates (dimensions 3j..3j + 3), one for the reservoir's choices
        // (3m + j): each keeps the set of 4 it last drew.
        let mut rng = SampleStream::new(self.settings.light_pattern(), self.settings.seed, self.batch.pixel[i], stream);
        let mut keep = rng;
        let mut reservoir = Reservoir::EMPTY;
        for j in 0..m {
            rng = rng.at_dimension(3 * j);
            let Some(chosen) = self.sampler.sample(ctx, rng.next_f32()) else { continue };
            let u = self.unless_delta(chosen.0, rng.next_2d());
            let Some(sampled) = self.evaluate_at(i, ctx, chosen, u) else { continue };
            keep = keep.at_dimension(3 * m + j);
            reservoir.offer(ctx, chosen.0, u, sampled, keep.next_f32());
        }
        reservoir
    }

    /// [`Self::resampled`] for entries `e..e + n` of the chunk starting at global entry `first`
    /// (RGB, f32): each candidate's light chosen for the whole block at once, point lights
    /// through the lane kernel, the rest one at a time. The same entries, bit for bit. Returns
    /// the number of shadow rays.
    #[inline(always)]
    pub(super) fn resampled_block(
        &self,
        first: usize,
        e: usize,
        n: usize,
        cols: &mut EntryColumns,
        candidates: u32,
    ) -> usize {
        let reservoirs = self.resampled_block_reservoirs(first, e, n, candidates);
        let mut traced = 0;
        for (l, reservoir) in reservoirs.iter().enumerate().take(n) {
            let (light, sampled) = reservoir.finish(candidates.max(1));
            traced += self.write(cols, e + l, light, sampled) as usize;
        }
        traced
    }

    /// The reservoirs [`Self::resampled_block`] finishes (lanes `n..` empty).
    #[inline(always)]
    pub(super) fn resampled_block_reservoirs(
        &self,
        first: usize,
        e: usize,
        n: usize,
        candidates: u32,
    ) -> [Reservoir; LANES] {
        let m = candidates.max(1);
        let block = self.block(first, e, n);
        // Per lane, one stream for the candidates (dimensions 3j..3j + 3) and one for the
        // reservoir's choices (3m + j): each keeps the set of 4 it last drew.
        let mut rng: [SampleStream; LANES] = std::array::from_fn(|l| {
            SampleStream::new(self.settings.light_pattern(), self.settings.seed, block.pixel[l], block.stream[l])
        });
        let mut keep = rng;
        let ctx: [LightSampleContext; LANES] = std::array::from_fn(|l| self.context(block.point[l]));
        let mut reservoirs = [Reservoir::EMPTY; LANES];
        for j in 0..m {
            for r in &mut rng {
                *r = r.at_dimension(3 * j);
            }
            let u = F32x16(std::array::from_fn(|l| rng[l].next_f32()));
            let choices = self.sampler.sample_lanes(&block.p, &block.normal, &u, (1u32 << n) - 1);
            let (mut rows, mut points) = ([0u32; LANES], 0);
            // Area and image lights draw their u here (each lane's stream in the order
            // `evaluate_at`'s caller below would), for their kernels.
            let (mut area_rows, mut areas, mut images, mut kernel_u) = ([0u32; LANES], 0u32, 0u32, [F32x16::ZERO; 2]);
            for l in 0..n {
                let id = choices.light[l];
                if choices.chosen & (1 << l) != 0 && id.kind == LightKind::Point {
                    (rows[l], points) = (id.row, points + 1);
                } else if choices.chosen & (1 << l) != 0 && id.kind == LightKind::Area {
                    let u = rng[l].next_2d();
                    (area_rows[l], areas, kernel_u[0][l], kernel_u[1][l]) = (id.row, areas | 1 << l, u.x, u.y);
                } else if choices.chosen & (1 << l) != 0 && id.kind == LightKind::ImageInfinite {
                    let u = rng[l].next_2d();
                    (images, kernel_u[0][l], kernel_u[1][l]) = (images | 1 << l, u.x, u.y);
                }
            }
            let lit =
                if points > 0 { Some(self.table.points.sample_li_rgb_lanes(U32x16(rows), &block.p)) } else { None };
            let items = &self.table.area.items;
            let triangles = if areas != 0 {
                Some(TriangleLightLanes::sample(items, &area_rows, areas, &block.p, kernel_u))
            } else {
                None
            };
            let skies = self.image_lanes(images, &choices.light, &block.p, kernel_u);
            for l in 0..n {
                if choices.chosen & (1 << l) == 0 {
                    continue;
                }
                let chosen = (choices.light[l], choices.pmf[l]);
                let (sampled, u) = match &lit {
                    Some(lit) if chosen.0.kind == LightKind::Point => {
                        (lit.li_sample(l).map(|ls| (ls, chosen.1, LightKind::Point.flags())), Vec2::ZERO)
                    }
                    _ if areas & (1 << l) != 0 => {
                        let u = Vec2::new(kernel_u[0][l], kernel_u[1][l]);
                        let light = &items[chosen.0.row as usize].light;
                        let lane = triangles.as_ref().and_then(|t| t.sample_li(light, l, &ctx[l], u, ColorQuery::Rgb));
                        let sampled = match lane {
                            Some(ls) => self.accept(chosen, ls),
                            None => self.evaluate_at(block.point[l], &ctx[l], chosen, u),
                        };
                        (sampled, u)
                    }
                    _ if images & (1 << l) != 0 => {
                        (self.accept(chosen, skies[l]), Vec2::new(kernel_u[0][l], kernel_u[1][l]))
                    }
                    _ => {
                        let u = self.unless_delta(chosen.0, rng[l].next_2d());
                        (self.evaluate_at(block.point[l], &ctx[l], chosen, u), u)
                    }
                };
                if let Some(sampled) = sampled {
                    keep[l] = keep[l].at_dimension(3 * m + j);
                    reservoirs[l].offer(&ctx[l], chosen.0, u, sampled, keep[l].next_f32());
                }
            }
        }
        reservoirs
    }
}

/// The resampling target of a light sample at `ctx` (see the module docs), in primary sample
/// space: the unshadowed contribution over Sample_Li's pdf (the Jacobian from u to the light
/// point), so that targets of one sample at different points are densities on the same domain.
pub(super) fn target(ctx: &LightSampleContext, ls: &LiSample) -> f32 {
    let sum: f32 = ls.radiance.0.iter().map(|c| c.max(0.0)).sum();
    let t = if ctx.ns == glam::Vec3::ZERO { sum } else { sum * ctx.ns.dot(ls.wi).max(0.0) };
    t / ls.pdf
}
