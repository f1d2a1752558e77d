//! Moving added, changed and removed lights into the `LightTable`: only what changed is touched.

use bevy_ecs::prelude::*;

use crate::geometry::Transform;
use crate::light::{
    DistantLight, ImageInfiniteLight, LightError, LightTable, PointLight, SpotLight, UniformInfiniteLight,
};
use crate::shading::{RunReport, SceneBounds};

fn reject(table: &mut LightTable, report: &mut RunReport, entity: Entity, e: LightError) {
    table.remove(entity);
    report.warnings.push(format!("light {entity} skipped: {e}"));
}

/// Upserts point lights that were added or changed, or whose transform moved.
pub fn sync_point_lights(
    query: Query<(Entity, Ref<PointLight>, Ref<Transform>), Or<(Changed<PointLight>, Changed<Transform>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, transform) in &query {
        match light.resolve(&transform) {
            Ok(row) => table.upsert_point(entity, row, light.casts_shadows, light.is_changed()),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts spot lights that were added or changed, or whose transform moved.
pub fn sync_spot_lights(
    query: Query<(Entity, Ref<SpotLight>, Ref<Transform>), Or<(Changed<SpotLight>, Changed<Transform>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, transform) in &query {
        match light.resolve(&transform) {
            Ok(row) => table.upsert_spot(entity, row, light.casts_shadows, light.is_changed()),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts distant lights that changed; all of them when the scene bounds changed (their power
/// and far sample points depend on it).
pub fn sync_distant_lights(
    query: Query<(Entity, Ref<DistantLight>, Ref<Transform>)>,
    bounds: Res<SceneBounds>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, transform) in &query {
        if !(bounds.is_changed() || light.is_changed() || transform.is_changed()) {
            continue;
        }
        match light.resolve(&transform, bounds.sphere) {
            Ok(row) => {
                table.upsert_distant(entity, row, light.casts_shadows, light.is_changed() || bounds.is_changed())
            }
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts uniform skies that changed, or all of them when the scene bounds changed.
pub fn sync_uniform_infinite_lights(
    query: Query<(Entity, Ref<UniformInfiniteLight>)>,
    bounds: Res<SceneBounds>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light) in &query {
        if !(bounds.is_changed() || light.is_changed()) {
            continue;
        }
        match light.resolve(bounds.sphere) {
            Ok(row) => table.upsert_uniform_infinite(entity, row, true),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts image lights that changed (with the tables `build_env_tables` made), or whose
/// transform moved, or all of them when the scene bounds changed.
pub fn sync_image_infinite_lights(
    query: Query<(Entity, Ref<ImageInfiniteLight>, Option<Ref<Transform>>)>,
    bounds: Res<SceneBounds>,
    tables: Res<super::EnvTables>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, transform) in &query {
        let moved = transform.as_ref().is_some_and(|t| t.is_changed());
        if !(bounds.is_changed() || light.is_changed() || moved) {
            continue;
        }
        let Some(t) = tables.by_entity.get(&entity) else {
            table.remove(entity); // its tables failed to build; the warning says why
            continue;
        };
        let transform = transform.map_or(Transform::IDENTITY, |t| *t);
        match light.resolve_with_tables(&transform, bounds.sphere, t.clone()) {
            Ok(row) => table.upsert_image_infinite(entity, row, true),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Removes the rows of lights whose component was removed or whose entity was despawned.
pub fn remove_lights(
    mut points: RemovedComponents<PointLight>,
    mut spots: RemovedComponents<SpotLight>,
    mut distant: RemovedComponents<DistantLight>,
    mut uniform: RemovedComponents<UniformInfiniteLight>,
    mut image: RemovedComponents<ImageInfiniteLight>,
    mut table: ResMut<LightTable>,
) {
    let removed = points.read().chain(spots.read()).chain(distant.read()).chain(uniform.read()).chain(image.read());
    for entity in removed {
        table.remove(entity);
    }
}
