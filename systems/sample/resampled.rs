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

use super::{EntryColumns, NO_LIGHT, Sampled, Sampling};
use crate::lanes::LANES;
use crate::light::{LiSample, LightFlags, LightId, LightKind, LightSampleContext};
use crate::rng::SampleStream;

/// Weighted reservoir sampling over one point's candidates.
#[derive(Clone, Copy)]
struct Reservoir {
    kept: Option<(LightId, LiSample, LightFlags)>,
    kept_target: f32,
    weight_sum: f32,
}

impl Reservoir {
    const EMPTY: Self = Self { kept: None, kept_target: 0.0, weight_sum: 0.0 };

    /// Offers candidate `light`'s sample (chosen with `pmf`); `u` decides whether it is kept.
    #[inline(always)]
    fn offer(&mut self, ctx: &LightSampleContext, light: LightId, (ls, pmf, flags): Sampled, u: f32) {
        let target = target(ctx, &ls);
        if target <= 0.0 {
            return;
        }
        let w = target / (pmf * ls.pdf);
        if !w.is_finite() {
            return;
        }
        self.weight_sum += w;
        // Kept with probability w / (sum so far): the survivor is candidate j with probability
        // w_j / sum over all.
        if u * self.weight_sum < w {
            (self.kept, self.kept_target) = (Some((light, ls, flags)), target);
        }
    }

    /// The survivor of `m` candidates and its sample, whose pdf is the estimator's 1/W with pmf 1.
    fn finish(self, m: u32) -> (LightId, Option<Sampled>) {
        match self.kept {
            None => (NO_LIGHT, None),
            Some((light, mut ls, flags)) => {
                // 1 / W, W = sum w / (M p_hat(y)).
                ls.pdf = m as f32 * self.kept_target / self.weight_sum;
                (light, Some((ls, 1.0, flags)))
            }
        }
    }
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
        let m = candidates.max(1);
        let rng = SampleStream::new(self.settings.seed, self.batch.pixel[i], stream);
        let mut reservoir = Reservoir::EMPTY;
        for j in 0..m {
            let u = rng.at_dimension(3 * j).next_f32();
            let Some(chosen) = self.sampler.sample(ctx, u) else { continue };
            let Some(sampled) = self.evaluate(i, stream, 3 * j + 1, ctx, chosen) else { continue };
            reservoir.offer(ctx, chosen.0, sampled, rng.at_dimension(3 * m + j).next_f32());
        }
        reservoir.finish(m)
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
        let m = candidates.max(1);
        let block = self.block(first, e, n);
        let rng: [SampleStream; LANES] =
            std::array::from_fn(|l| SampleStream::new(self.settings.seed, block.pixel[l], block.stream[l]));
        let ctx: [LightSampleContext; LANES] = std::array::from_fn(|l| self.context(block.point[l]));
        let mut reservoirs = [Reservoir::EMPTY; LANES];
        for j in 0..m {
            let u: [f32; LANES] = std::array::from_fn(|l| rng[l].at_dimension(3 * j).next_f32());
            let choices = self.sampler.sample_lanes(&block.p, &block.normal, &u, (1u32 << n) - 1);
            let (mut rows, mut points) = ([0u32; LANES], 0);
            for l in 0..n {
                if choices.chosen & (1 << l) != 0 && choices.light[l].kind == LightKind::Point {
                    (rows[l], points) = (choices.light[l].row, points + 1);
                }
            }
            let lit = if points > 0 { Some(self.table.points.sample_li_rgb_lanes(&rows, &block.p)) } else { None };
            for l in 0..n {
                if choices.chosen & (1 << l) == 0 {
                    continue;
                }
                let chosen = (choices.light[l], choices.pmf[l]);
                let sampled = match &lit {
                    Some(lit) if chosen.0.kind == LightKind::Point => {
                        lit.li_sample(l).map(|ls| (ls, chosen.1, LightKind::Point.flags()))
                    }
                    _ => self.evaluate(block.point[l], block.stream[l], 3 * j + 1, &ctx[l], chosen),
                };
                if let Some(sampled) = sampled {
                    reservoirs[l].offer(&ctx[l], chosen.0, sampled, rng[l].at_dimension(3 * m + j).next_f32());
                }
            }
        }
        let mut traced = 0;
        for (l, reservoir) in reservoirs.iter().enumerate().take(n) {
            let (light, sampled) = reservoir.finish(m);
            traced += self.write(cols, e + l, light, sampled) as usize;
        }
        traced
    }
}

/// The resampling target of a light sample at `ctx` (see the module docs).
fn target(ctx: &LightSampleContext, ls: &LiSample) -> f32 {
    let sum: f32 = ls.radiance.0.iter().map(|c| c.max(0.0)).sum();
    if ctx.ns == glam::Vec3::ZERO { sum } else { sum * ctx.ns.dot(ls.wi).max(0.0) }
}
