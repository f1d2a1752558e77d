//! Environment-map sampling tables: built once per image change, never per frame.

use std::sync::Arc;

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;

use crate::light::{EnvMapTables, ImageInfiniteLight};
use crate::shading::RunReport;

use super::Work;

/// Sampling tables of each image infinite light, by entity.
#[derive(Resource, Clone, Debug, Default)]
pub struct EnvTables {
    pub by_entity: EntityHashMap<Arc<EnvMapTables>>,
}

/// Tables are built only when an image infinite light exists and was added or changed.
pub fn plan_env_tables(
    changed: Query<(), Changed<ImageInfiniteLight>>,
    all: Query<(), With<ImageInfiniteLight>>,
    mut removed: RemovedComponents<ImageInfiniteLight>,
    mut tables: ResMut<EnvTables>,
    mut work: ResMut<Work>,
    mut report: ResMut<RunReport>,
) {
    for e in removed.read() {
        tables.by_entity.remove(&e);
    }
    let n = changed.iter().count();
    let (run, why) = if all.is_empty() {
        (false, "no image infinite light".to_string())
    } else if n == 0 {
        (false, "no environment image changed".to_string())
    } else {
        (true, format!("{n} environment light(s) added or changed"))
    };
    work.env_tables = run;
    report.record("build_env_tables", run, why);
}

/// Builds the sampling tables of added or changed image lights (in parallel over lights).
pub fn build_env_tables(
    changed: Query<(Entity, &ImageInfiniteLight), Changed<ImageInfiniteLight>>,
    mut tables: ResMut<EnvTables>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light) in &changed {
        match light.build_tables() {
            Ok(t) => {
                tables.by_entity.insert(entity, Arc::new(t));
            }
            Err(e) => {
                tables.by_entity.remove(&entity);
                report.warnings.push(format!("environment light {entity} skipped: {e}"));
            }
        }
    }
}
