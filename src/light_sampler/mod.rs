//! Choosing a light (separate from sampling a point on it): uniform and power samplers behind one
//! `sample(ctx, u) -> (light, pmf)` / `pmf(ctx, light)` pair.

mod power;
mod uniform;

use bevy_ecs::resource::Resource;

use crate::light::{LightId, LightSampleContext, LightTable};
use crate::shading::LightSamplerKind;

pub use power::PowerSampler;
pub use uniform::UniformSampler;

/// The light sampler the `Settings` ask for, kept in step with the `LightTable`.
#[derive(Resource, Clone, Debug)]
pub enum LightSampler {
    Uniform(UniformSampler),
    Power(PowerSampler),
}

impl Default for LightSampler {
    fn default() -> Self {
        Self::Power(PowerSampler::default())
    }
}

impl LightSampler {
    /// A sampler of `kind` built over `table`.
    pub fn build(kind: LightSamplerKind, table: &LightTable) -> Self {
        match kind {
            LightSamplerKind::Uniform => Self::Uniform(UniformSampler::build(table)),
            // The BVH sampler arrives with the many-lights work; power is the closest stand-in.
            LightSamplerKind::Power | LightSamplerKind::Bvh => Self::Power(PowerSampler::build(table)),
        }
    }

    /// The kind this sampler implements.
    pub fn kind(&self) -> LightSamplerKind {
        match self {
            Self::Uniform(_) => LightSamplerKind::Uniform,
            Self::Power(_) => LightSamplerKind::Power,
        }
    }

    /// Brings the sampler up to date with `table`: rebuilds what depends on powers when they
    /// changed, and only the id list otherwise. Returns what it did, for the run report.
    pub fn update(&mut self, table: &LightTable) -> &'static str {
        match self {
            Self::Uniform(s) => s.update(table),
            Self::Power(s) => s.update(table),
        }
    }

    /// A light and the probability of choosing it, or None when there is no light with power.
    #[inline]
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(LightId, f32)> {
        match self {
            Self::Uniform(s) => s.sample(u),
            Self::Power(s) => s.sample(u),
        }
        .filter(|_| ctx.p.is_finite())
    }

    /// Probability that `sample` returns `light` at `ctx`.
    #[inline]
    pub fn pmf(&self, _ctx: &LightSampleContext, light: LightId) -> f32 {
        match self {
            Self::Uniform(s) => s.pmf(light),
            Self::Power(s) => s.pmf(light),
        }
    }
}
