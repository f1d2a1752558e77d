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

use super::{Sampled, Sampling};
use crate::light::{LightId, LightSampleContext};
use crate::rng::SampleStream;

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
        let (mut kept, mut kept_target, mut weight_sum) = (None, 0.0f32, 0.0f32);
        for j in 0..m {
            let u = rng.at_dimension(3 * j).next_f32();
            let Some(chosen) = self.sampler.sample(ctx, u) else { continue };
            let Some((ls, pmf, flags)) = self.evaluate(i, stream, 3 * j + 1, ctx, chosen) else { continue };
            let target = target(ctx, &ls);
            if target <= 0.0 {
                continue;
            }
            let w = target / (pmf * ls.pdf);
            if !w.is_finite() {
                continue;
            }
            weight_sum += w;
            // Kept with probability w / (sum so far): the survivor is candidate j with
            // probability w_j / sum over all.
            if rng.at_dimension(3 * m + j).next_f32() * weight_sum < w {
                kept = Some((chosen.0, ls, flags));
                kept_target = target;
            }
        }
        match kept {
            None => (crate::light::LightId { kind: crate::light::LightKind::Point, row: 0 }, None),
            Some((light, mut ls, flags)) => {
                // 1 / W, W = sum w / (M p_hat(y)).
                ls.pdf = m as f32 * kept_target / weight_sum;
                (light, Some((ls, 1.0, flags)))
            }
        }
    }
}

/// The resampling target of a light sample at `ctx` (see the module docs).
fn target(ctx: &LightSampleContext, ls: &crate::light::LiSample) -> f32 {
    let sum: f32 = ls.radiance.0.iter().map(|c| c.max(0.0)).sum();
    if ctx.ns == glam::Vec3::ZERO { sum } else { sum * ctx.ns.dot(ls.wi).max(0.0) }
}
