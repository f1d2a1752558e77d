//! Deciding which expensive work an update needs: each `plan_*` system reads the world, records
//! its decision and reason in the `RunReport`, and sets a flag in `Work` that the work system's
//! run condition reads.

use bevy_ecs::prelude::*;

use crate::light::LightTable;
use crate::light_sampler::LightSampler;
use crate::shading::{RunReport, Settings, ShadingBatch};

/// This update's decisions.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Update the light sampler (the light table changed, or the settings ask for another kind).
    pub sampler: bool,
    /// Sample direct lighting (there are points and lights).
    pub sampling: bool,
    /// Rebuild, refit or keep the scene BVH.
    pub bvh: super::geometry::BvhWork,
    /// Build environment-map sampling tables (an image infinite light was added or changed).
    pub env_tables: bool,
}

/// A run condition that reads one of `Work`'s flags.
pub fn planned(flag: fn(&Work) -> bool) -> impl FnMut(Res<Work>) -> bool + Clone {
    move |work: Res<Work>| flag(&work)
}

/// Starts an update: empties the run report (it holds one update's decisions and warnings; see
/// `RunReport` for keeping more) and the decisions, and passes settings the light table needs.
pub fn begin_update(
    mut report: ResMut<RunReport>,
    mut work: ResMut<Work>,
    settings: Res<Settings>,
    mut table: ResMut<LightTable>,
) {
    report.entries.clear();
    report.warnings.clear();
    *work = Work::default();
    let compensate = settings.compensates_image_lights();
    if table.mis_compensation != compensate {
        table.mis_compensation = compensate;
    }
}

/// The sampler is updated when the table changed or the settings ask for another kind.
pub fn plan_sampler(
    table: Res<LightTable>,
    sampler: Res<LightSampler>,
    settings: Res<Settings>,
    mut work: ResMut<Work>,
    mut report: ResMut<RunReport>,
) {
    let (run, why) = if sampler.kind() != settings.light_sampler {
        (true, "settings changed the sampler kind")
    } else if table.is_changed() {
        (true, "light table changed")
    } else {
        (false, "no light changed")
    };
    work.sampler = run;
    report.record("update_light_sampler", run, why);
}

/// Light sampling runs when there are points to shade and lights to sample.
pub fn plan_sampling(
    batch: Res<ShadingBatch>,
    table: Res<LightTable>,
    settings: Res<Settings>,
    mut work: ResMut<Work>,
    mut report: ResMut<RunReport>,
    mut out: ResMut<crate::shading::DirectLighting>,
    mut rays: ResMut<super::ShadowRays>,
) {
    let (run, why) = if batch.is_empty() {
        (false, "shading batch is empty".to_string())
    } else if table.is_empty() {
        (false, "no lights".to_string())
    } else {
        let mode = match settings.color_mode {
            crate::shading::ColorMode::Rgb => "RGB",
            crate::shading::ColorMode::Spectral => "spectral",
        };
        let selection = match settings.selection {
            crate::shading::LightSelection::OneSampled => String::new(),
            crate::shading::LightSelection::All => ", every light".to_string(),
            crate::shading::LightSelection::Resampled { candidates } => {
                format!(", resampled (RIS) from {} candidates", candidates.max(1))
            }
            crate::shading::LightSelection::Restir(r) => {
                format!(", resampled (ReSTIR) from {} candidates with reuse", r.candidates.max(1))
            }
        };
        (true, format!("{} points x {} lights, {mode} mode{selection}", batch.len(), table.len()))
    };
    work.sampling = run;
    if run {
        report.record_count("sample_direct_lighting", true, why, batch.len() as u64, "points");
    } else {
        report.record("sample_direct_lighting", run, why);
    }
    if !run {
        // Every point gets no entries: nothing from an earlier update may linger.
        out.clear();
        out.offsets.resize(batch.len() + 1, 0);
        rays.clear();
    }
}
