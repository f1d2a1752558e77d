//! The knobs that trade accuracy for time, one render configuration per setting, and how a
//! configuration is applied to a world.

use bevy_ecs::prelude::*;

use crate::geometry::ShadowOffset;
use crate::light::ImageInfiniteLight;
use crate::render::path::PathDepth;
use crate::render::renderer::{Integrator, RenderOptions, Strategy};
use crate::shading::{ColorMode, LightPrecision, LightSamplerKind, LightSelection, Settings};

/// Everything the report varies about one render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Camera samples per pixel.
    pub spp: u32,
    /// RGB or spectral rendering.
    pub color: ColorMode,
    /// How a light is chosen for each sample.
    pub sampler: LightSamplerKind,
    /// One sampled light per point, or every light.
    pub selection: LightSelection,
    /// Light samples, BSDF samples or both combined by MIS.
    pub strategy: Strategy,
    /// How shadow rays are moved off the surface.
    pub offset: ShadowOffset,
    /// f32 or f64 light math.
    pub precision: LightPrecision,
    /// Largest env sampling-table width; None for the image's own width.
    pub env_table_width: Option<usize>,
    /// Direct lighting or paths (with their depth and roulette).
    pub integrator: Integrator,
}

impl Config {
    /// kelvin's defaults (light-BVH sampler, one light per sample, MIS, error-bound offsets, f32:
    /// the light system's from `Settings::default`; the path tracer with its default depth) at
    /// `spp` in colour mode `color`.
    pub fn baseline(spp: u32, color: ColorMode) -> Self {
        let settings = Settings::default();
        Self {
            spp,
            color,
            sampler: settings.light_sampler,
            selection: settings.selection,
            strategy: Strategy::Mis,
            offset: settings.shadow_offset,
            precision: settings.light_precision,
            env_table_width: None,
            integrator: Integrator::default(),
        }
    }

    /// The render options of this configuration.
    pub fn render_options(&self, width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            width,
            height,
            spp: self.spp,
            strategy: self.strategy,
            integrator: self.integrator,
            ..Default::default()
        }
    }

    /// Writes the light-system settings (with `seed`) and the env-table width into `world`. The
    /// image light is touched only when its width changes, so its tables are not rebuilt needlessly.
    pub fn apply(&self, world: &mut World, seed: u64) {
        {
            let mut s = world.resource_mut::<Settings>();
            s.color_mode = self.color;
            s.light_sampler = self.sampler;
            s.selection = self.selection;
            s.shadow_offset = self.offset;
            s.light_precision = self.precision;
            s.seed = seed;
        }
        let mut q = world.query::<&mut ImageInfiniteLight>();
        for mut light in q.iter_mut(world) {
            if light.table_max_width != self.env_table_width {
                light.table_max_width = self.env_table_width;
            }
        }
    }
}

/// A knob of the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Knob {
    /// Camera samples per pixel, doubling from 1.
    Spp,
    /// Uniform, power or light-BVH light selection.
    LightSampler,
    /// RGB or spectral rendering.
    Color,
    /// Width of the environment map's sampling table ([`ENV_TABLE_WIDTHS`] and the full width).
    EnvTable,
    /// MIS, light samples only or BSDF samples only.
    Strategy,
    /// One light per sample, or every light at fewer samples per pixel.
    Selection,
    /// Error-bound shadow-ray offsets or fixed ones ([`FIXED_EPSILONS`]).
    ShadowOffset,
    /// f32 or f64 light math.
    Precision,
    /// The path tracer's largest depth (direct lighting is depth 1).
    Depth,
    /// The depth from which roulette may end paths.
    Roulette,
}

/// Fixed-epsilon shadow offsets the report tries, m (scenes are 1-50 m across): none at all, the
/// usual small values, and large ones that let light leak into contact shadows.
pub const FIXED_EPSILONS: [f32; 5] = [0.0, 1e-6, 1e-4, 1e-2, 1e-1];
/// Env sampling-table widths the report tries (the map's own width is added).
pub const ENV_TABLE_WIDTHS: [usize; 4] = [4, 16, 64, 256];

impl Knob {
    /// Every knob, in table order.
    pub const ALL: [Knob; 10] = [
        Knob::Spp,
        Knob::LightSampler,
        Knob::Color,
        Knob::EnvTable,
        Knob::Strategy,
        Knob::Selection,
        Knob::ShadowOffset,
        Knob::Precision,
        Knob::Depth,
        Knob::Roulette,
    ];

    /// Short name (tables, CSV, plot legends).
    pub fn name(self) -> &'static str {
        match self {
            Knob::Spp => "spp",
            Knob::LightSampler => "light sampler",
            Knob::Color => "colour",
            Knob::EnvTable => "env table",
            Knob::Strategy => "strategy",
            Knob::Selection => "lights per sample",
            Knob::ShadowOffset => "shadow offset",
            Knob::Precision => "light math",
            Knob::Depth => "path depth",
            Knob::Roulette => "roulette",
        }
    }

    /// The settings of this knob around `base` as (label, configuration); the one equal to `base`
    /// is the knob's baseline.
    /// `max_spp` ends the spp ladder; `n_lights` sets the spp of "all lights" (the same number of
    /// light samples per pixel as the baseline, at least one camera sample).
    pub fn settings(self, base: &Config, max_spp: u32, n_lights: usize) -> Vec<(String, Config)> {
        let with = |f: &dyn Fn(&mut Config)| {
            let mut c = *base;
            f(&mut c);
            c
        };
        match self {
            Knob::Spp => std::iter::successors(Some(1u32), |s| (s * 2 <= max_spp).then_some(s * 2))
                .map(|spp| (format!("{spp} spp"), with(&|c| c.spp = spp)))
                .collect(),
            Knob::LightSampler => [
                ("uniform", LightSamplerKind::Uniform),
                ("power", LightSamplerKind::Power),
                ("bvh", LightSamplerKind::Bvh),
            ]
            .into_iter()
            .map(|(l, k)| (l.to_string(), with(&|c| c.sampler = k)))
            .collect(),
            Knob::Color => [("rgb", ColorMode::Rgb), ("spectral", ColorMode::Spectral)]
                .into_iter()
                .map(|(l, m)| (l.to_string(), with(&|c| c.color = m)))
                .collect(),
            Knob::EnvTable => std::iter::once(("full".to_string(), with(&|c| c.env_table_width = None)))
                .chain(
                    ENV_TABLE_WIDTHS
                        .iter()
                        .rev()
                        .map(|&w| (format!("{w} wide"), with(&|c| c.env_table_width = Some(w)))),
                )
                .collect(),
            Knob::Strategy => {
                [("mis", Strategy::Mis), ("light only", Strategy::LightOnly), ("bsdf only", Strategy::BsdfOnly)]
                    .into_iter()
                    .map(|(l, s)| (l.to_string(), with(&|c| c.strategy = s)))
                    .collect()
            }
            Knob::Selection => {
                let spp = (base.spp as usize / n_lights.max(1)).max(1) as u32;
                vec![
                    ("one".to_string(), *base),
                    (
                        format!("all {n_lights}"),
                        with(&|c| {
                            c.selection = LightSelection::All;
                            c.spp = spp;
                        }),
                    ),
                ]
            }
            Knob::ShadowOffset => {
                std::iter::once(("error bound".to_string(), with(&|c| c.offset = ShadowOffset::ErrorBound)))
                    .chain(FIXED_EPSILONS.iter().map(|&e| {
                        (
                            if e == 0.0 { "none".to_string() } else { format!("fixed {e:.0e} m") },
                            with(&|c| c.offset = ShadowOffset::FixedEpsilon(e)),
                        )
                    }))
                    .collect()
            }
            Knob::Precision => [("f32", LightPrecision::F32), ("f64", LightPrecision::F64)]
                .into_iter()
                .map(|(l, p)| (l.to_string(), with(&|c| c.precision = p)))
                .collect(),
            Knob::Depth | Knob::Roulette => {
                let Integrator::Path(depth) = base.integrator else { return vec![("direct".to_string(), *base)] };
                let path = |d: PathDepth| with(&|c| c.integrator = Integrator::Path(d));
                // The baseline's own value first, then the others of the ladder.
                let (own, ladder): (u32, &[u32]) = if self == Knob::Depth {
                    (depth.max_depth, &[1, 2, 4, 8, 16, 32])
                } else {
                    (depth.roulette_depth, &[1, 3, 8, u32::MAX])
                };
                let mut values: Vec<u32> = std::iter::once(own).chain(ladder.iter().copied()).collect();
                values.sort_unstable();
                values.dedup();
                values
                    .into_iter()
                    .map(|v| match self {
                        Knob::Depth => (format!("depth {v}"), path(PathDepth { max_depth: v, ..depth })),
                        _ if v == u32::MAX => ("off".to_string(), path(PathDepth { roulette_depth: v, ..depth })),
                        _ => (format!("from {v}"), path(PathDepth { roulette_depth: v, ..depth })),
                    })
                    .collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_knob_has_the_baseline_among_its_settings() {
        for color in [ColorMode::Rgb, ColorMode::Spectral] {
            let base = Config::baseline(16, color);
            for knob in Knob::ALL {
                let s = knob.settings(&base, 64, 4);
                assert!(s.len() >= 2 && s.iter().filter(|(_, c)| *c == base).count() == 1, "{knob:?}");
            }
        }
        // The light-sampler knob turns away from kelvin's default sampler, the light BVH.
        let base = Config::baseline(16, ColorMode::Rgb);
        let samplers = Knob::LightSampler.settings(&base, 64, 4);
        assert_eq!(samplers.iter().find(|(_, c)| *c == base).map(|(l, _)| l.as_str()), Some("bvh"));
        let spps: Vec<u32> =
            Knob::Spp.settings(&Config::baseline(16, ColorMode::Rgb), 64, 4).iter().map(|s| s.1.spp).collect();
        assert_eq!(spps, [1, 2, 4, 8, 16, 32, 64]);
    }
}
