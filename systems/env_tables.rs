//! Environment-map sampling tables: built once per image change, never per frame. A change
//! that leaves the image and table options as they were keeps the tables; one that rewrites some
//! rows of an image of the same size updates only those rows' tables and the marginals.

use std::sync::Arc;

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;

use rayon::prelude::*;

use crate::light::{EnvMapTables, EnvTableOptions, ImageInfiniteLight};
use crate::scene::image::RgbImage;
use crate::shading::RunReport;

use super::Work;

/// Sampling tables of each image infinite light, by entity.
#[derive(Resource, Clone, Debug, Default)]
pub struct EnvTables {
    /// The tables of each image infinite light's entity.
    pub by_entity: EntityHashMap<Arc<EnvMapTables>>,
    /// The image and options each entity's tables were built from.
    built_from: EntityHashMap<(Arc<RgbImage>, EnvTableOptions)>,
}

/// What a change of an image light did to its tables.
#[derive(Clone, Debug, PartialEq, Eq)]
enum TableWork {
    Kept,
    Rows(std::ops::Range<usize>),
    Rebuilt,
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
        tables.built_from.remove(&e);
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

/// Builds the sampling tables of added or changed image lights, or updates the rows that changed.
pub fn build_env_tables(
    changed: Query<(Entity, &ImageInfiniteLight), Changed<ImageInfiniteLight>>,
    mut tables: ResMut<EnvTables>,
    mut report: ResMut<RunReport>,
) {
    let tables = &mut *tables;
    for (entity, light) in &changed {
        if let Err(e) = light.validate() {
            tables.by_entity.remove(&entity);
            tables.built_from.remove(&entity);
            report.warnings.push(format!("environment light {entity} skipped: {e}"));
            continue;
        }
        let options = light.table_options();
        let work = match (tables.by_entity.get_mut(&entity), tables.built_from.get(&entity)) {
            (Some(t), Some((image, built))) if *built == options => match changed_rows(image, &light.image) {
                Some(rows) if rows.is_empty() => TableWork::Kept,
                Some(rows) => {
                    // Tables the light table also holds are copied first (cheaper than a build).
                    Arc::make_mut(t).update_rows(&light.image, rows.clone());
                    TableWork::Rows(rows)
                }
                None => {
                    Arc::make_mut(t).rebuild(&light.image, options);
                    TableWork::Rebuilt
                }
            },
            _ => {
                tables.by_entity.insert(entity, Arc::new(EnvMapTables::build_with(&light.image, options)));
                TableWork::Rebuilt
            }
        };
        tables.built_from.insert(entity, (light.image.clone(), options));
        let why = match &work {
            TableWork::Kept => format!("{entity}: image and table options unchanged, tables kept"),
            TableWork::Rows(r) => {
                format!("{entity}: rows {}..{} of {} changed, only they updated", r.start, r.end, light.image.height)
            }
            TableWork::Rebuilt => format!("{entity}: tables built"),
        };
        report.record("env_tables", work != TableWork::Kept, why);
    }
}

/// The rows (first to last) where `new` differs from `old`, or None when the sizes differ or
/// more than half the rows changed (a rebuild is then as cheap). The same image gives 0..0.
fn changed_rows(old: &Arc<RgbImage>, new: &Arc<RgbImage>) -> Option<std::ops::Range<usize>> {
    if Arc::ptr_eq(old, new) {
        return Some(0..0);
    }
    let (w, h) = (old.width, old.height);
    if (new.width, new.height) != (w, h) || w == 0 || old.pixels.len() != w * h || new.pixels.len() != w * h {
        return None;
    }
    let differs = |y: &usize| old.pixels[y * w..(y + 1) * w] != new.pixels[y * w..(y + 1) * w];
    let Some(first) = (0..h).into_par_iter().position_first(|y| differs(&y)) else { return Some(0..0) };
    let last = (0..h).into_par_iter().position_last(|y| differs(&y)).unwrap_or(first);
    (2 * (last + 1 - first) <= h).then_some(first..last + 1)
}
