//! Choosing a light (separate from sampling a point on it): uniform, power and light-BVH samplers
//! behind one `sample(ctx, u) -> (light, pmf)` / `pmf(ctx, light)` pair.

mod bvh;
mod bvh_build;
mod bvh_lanes;
pub mod importance;
mod importance_lanes;
mod power;
mod uniform;
mod wide;

use bevy_ecs::resource::Resource;

use crate::lanes::{F32x16, LANES, Vec3x16};
use crate::light::{LightId, LightSampleContext, LightTable};
use crate::shading::LightSamplerKind;

pub use bvh::{BvhSampler, BvhUpdate, LIGHT_TREE_REBUILD_RATIO};
pub use bvh_lanes::LaneChoices;
pub use power::PowerSampler;
pub use uniform::UniformSampler;

/// The light sampler the `Settings` ask for, kept in step with the `LightTable`.
// One sampler lives in the world (a resource), so the size of its largest variant costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Resource, Clone, Debug)]
pub enum LightSampler {
    /// Every light equally likely.
    Uniform(UniformSampler),
    /// Proportional to emitted power.
    Power(PowerSampler),
    /// Light BVH, by each light's importance at the shading point.
    Bvh(BvhSampler),
}

/// An empty sampler of the default kind (the light BVH, as `Settings` default to).
impl Default for LightSampler {
    fn default() -> Self {
        Self::Bvh(BvhSampler::default())
    }
}

impl LightSampler {
    /// A sampler of `kind` built over `table`.
    pub fn build(kind: LightSamplerKind, table: &LightTable) -> Self {
        match kind {
            LightSamplerKind::Uniform => Self::Uniform(UniformSampler::build(table)),
            LightSamplerKind::Power => Self::Power(PowerSampler::build(table)),
            LightSamplerKind::Bvh => Self::Bvh(BvhSampler::build(table)),
        }
    }

    /// The kind this sampler implements.
    pub fn kind(&self) -> LightSamplerKind {
        match self {
            Self::Uniform(_) => LightSamplerKind::Uniform,
            Self::Power(_) => LightSamplerKind::Power,
            Self::Bvh(_) => LightSamplerKind::Bvh,
        }
    }

    /// Brings the sampler up to date with `table`, doing only what its changes call for (see
    /// each sampler's `update`). Returns what it did, for the run report.
    pub fn update(&mut self, table: &LightTable) -> &'static str {
        match self {
            Self::Uniform(s) => s.update(table),
            Self::Power(s) => s.update(table),
            Self::Bvh(s) => s.update(table),
        }
    }

    /// A light and the probability of choosing it, or None when there is no light with power.
    #[inline]
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(LightId, f32)> {
        match self {
            Self::Uniform(s) => s.sample(u),
            Self::Power(s) => s.sample(u),
            Self::Bvh(s) => s.sample(ctx, u),
        }
        .filter(|_| ctx.p.is_finite())
    }

    /// [`Self::sample`] for `LANES` points (`p`, shading normals `n` as lane columns, zero for none)
    /// with numbers `u`, in the lanes of `active`: the same choices and pmfs, lane by lane. The
    /// BVH sampler weighs each node's clusters for all the points at it at once. Run it inside
    /// `lanes::widest`.
    #[inline(always)]
    pub fn sample_lanes(&self, p: &Vec3x16, n: &Vec3x16, u: &F32x16, active: u32) -> LaneChoices {
        let finite = p.is_finite();
        let mut active = active;
        for l in 0..LANES {
            active &= !(u32::from(!finite.test(l)) << l);
        }
        if let Self::Bvh(s) = self {
            return s.sample_lanes(p, n, u, active);
        }
        let none = LightId { kind: crate::light::LightKind::Point, row: 0 };
        let mut out = LaneChoices { light: [none; LANES], pmf: [0.0; LANES], chosen: 0 };
        while active != 0 {
            let l = active.trailing_zeros() as usize;
            active &= active - 1;
            let ctx = LightSampleContext::at(p.lane(l));
            if let Some((id, q)) = self.sample(&ctx, u.0[l]) {
                (out.light[l], out.pmf[l], out.chosen) = (id, q, out.chosen | 1 << l);
            }
        }
        out
    }

    /// Calls `f` with every light and its pmf at `ctx`, in one pass (for exact variances).
    pub fn for_each_pmf(&self, ctx: &LightSampleContext, f: impl FnMut(LightId, f32)) {
        match self {
            Self::Uniform(s) => s.for_each_pmf(f),
            Self::Power(s) => s.for_each_pmf(f),
            Self::Bvh(s) => s.for_each_pmf(ctx, f),
        }
    }

    /// Probability that `sample` returns `light` at `ctx`.
    #[inline]
    pub fn pmf(&self, ctx: &LightSampleContext, light: LightId) -> f32 {
        if !ctx.p.is_finite() {
            return 0.0;
        }
        match self {
            Self::Uniform(s) => s.pmf(light),
            Self::Power(s) => s.pmf(light),
            Self::Bvh(s) => s.pmf(ctx, light),
        }
    }
}
