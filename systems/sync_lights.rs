//! Moving added, changed and removed lights into the `LightTable`: only what changed is touched.

use bevy_ecs::prelude::*;

use crate::geometry::Transform;
use crate::light::{DistantLight, LightError, LightTable, PointLight, SpotLight};
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

/// Removes the rows of lights whose component was removed or whose entity was despawned.
pub fn remove_lights(
    mut points: RemovedComponents<PointLight>,
    mut spots: RemovedComponents<SpotLight>,
    mut distant: RemovedComponents<DistantLight>,
    mut table: ResMut<LightTable>,
) {
    for entity in points.read().chain(spots.read()).chain(distant.read()) {
        table.remove(entity);
    }
}
