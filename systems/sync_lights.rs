//! Moving added, changed and removed lights into the `LightTable`: only what changed is touched.

use bevy_ecs::prelude::*;

use crate::geometry::{Disk, Mesh, Placement, Rectangle, Sphere, Transform};
use crate::light::area::sphere_from_point_light;
use crate::light::table::AreaRow;
use crate::light::{
    AreaLight, DistantLight, GoniometricLight, ImageInfiniteLight, LightError, LightTable, PointLight, ProjectionLight,
    SpotLight, SunSkyLight, UniformInfiniteLight,
};
use crate::shading::{RunReport, SceneBounds};

fn reject(table: &mut LightTable, report: &mut RunReport, entity: Entity, e: LightError) {
    table.remove(entity);
    report.warnings.push(format!("light {entity} skipped: {e}"));
}

/// Upserts point lights that were added or changed, or whose transform moved.
pub fn sync_point_lights<P: Placement>(
    query: Query<(Entity, Ref<PointLight>, Ref<P>), Or<(Changed<PointLight>, Changed<P>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, placement) in &query {
        let transform = placement.placement();
        // A point light with a radius is a sphere area light of the same power.
        let result = sphere_from_point_light(&light, &transform).map(|sphere| match sphere {
            Some(s) => {
                let rows = vec![AreaRow { light: s, primitive: 0 }];
                table.upsert_area(entity, rows, light.casts_shadows, light.is_changed())
            }
            None => match light.resolve(&transform) {
                Ok(row) => table.upsert_point(entity, row, light.casts_shadows, light.is_changed()),
                Err(e) => reject(&mut table, &mut report, entity, e),
            },
        });
        if let Err(e) = result {
            reject(&mut table, &mut report, entity, e);
        }
    }
}

/// The emitting shapes of an area light on its entity's geometry.
fn area_rows(
    light: &AreaLight,
    t: &Transform,
    mesh: Option<&Mesh>,
    sphere: Option<&Sphere>,
    disk: Option<&Disk>,
    rect: Option<&Rectangle>,
) -> Result<(Vec<AreaRow>, usize), LightError> {
    let one = |l| Ok((vec![AreaRow { light: l, primitive: 0 }], 0));
    match (mesh, sphere, disk, rect) {
        (Some(m), ..) => {
            let r = light.resolve_mesh(m.positions(), m.uvs().unwrap_or(&[]), m.indices(), t)?;
            let rows = r.triangles.into_iter().zip(r.primitives).map(|(light, primitive)| AreaRow { light, primitive });
            Ok((rows.collect(), r.skipped_degenerate))
        }
        (_, Some(s), ..) => one(light.resolve_sphere(s.radius, t)?),
        (_, _, Some(d), _) => one(light.resolve_disk(d.radius, t)?),
        (_, _, _, Some(r)) => one(light.resolve_rectangle(2.0 * r.half_size.x, 2.0 * r.half_size.y, t)?),
        _ => Err(LightError::Invalid {
            light: "AreaLight",
            msg: "needs a Mesh, Sphere, Disk or Rectangle on the same entity".into(),
        }),
    }
}

/// Upserts area lights whose light, transform or shape changed (one row per emitting shape or
/// mesh triangle).
#[allow(clippy::type_complexity)]
pub fn sync_area_lights<P: Placement>(
    query: Query<
        (Entity, Ref<AreaLight>, &P, Option<&Mesh>, Option<&Sphere>, Option<&Disk>, Option<&Rectangle>),
        Or<(Changed<AreaLight>, Changed<P>, Changed<Mesh>, Changed<Sphere>, Changed<Disk>, Changed<Rectangle>)>,
    >,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, t, mesh, sphere, disk, rect) in &query {
        match area_rows(&light, &t.placement(), mesh, sphere, disk, rect) {
            Ok((rows, skipped)) => {
                if skipped > 0 {
                    report.warnings.push(format!("area light {entity}: {skipped} degenerate triangles skipped"));
                }
                table.upsert_area(entity, rows, light.casts_shadows, light.is_changed());
            }
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts spot lights that were added or changed, or whose transform moved.
pub fn sync_spot_lights<P: Placement>(
    query: Query<(Entity, Ref<SpotLight>, Ref<P>), Or<(Changed<SpotLight>, Changed<P>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, placement) in &query {
        match light.resolve(&placement.placement()) {
            Ok(row) => table.upsert_spot(entity, row, light.casts_shadows, light.is_changed()),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts projection lights that were added or changed, or whose transform moved.
pub fn sync_projection_lights<P: Placement>(
    query: Query<(Entity, Ref<ProjectionLight>, Ref<P>), Or<(Changed<ProjectionLight>, Changed<P>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, placement) in &query {
        match light.resolve(&placement.placement()) {
            Ok(row) => table.upsert_projection(entity, row, light.casts_shadows, light.is_changed()),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts goniometric lights that were added or changed, or whose transform moved.
pub fn sync_goniometric_lights<P: Placement>(
    query: Query<(Entity, Ref<GoniometricLight>, Ref<P>), Or<(Changed<GoniometricLight>, Changed<P>)>>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, placement) in &query {
        match light.resolve(&placement.placement()) {
            Ok(row) => table.upsert_goniometric(entity, row, light.casts_shadows, light.is_changed()),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts distant lights that changed; all of them when the scene bounds changed (their power
/// and far sample points depend on it).
pub fn sync_distant_lights<P: Placement>(
    query: Query<(Entity, Ref<DistantLight>, Ref<P>)>,
    bounds: Res<SceneBounds>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light, placement) in &query {
        if !(bounds.is_changed() || light.is_changed() || placement.is_changed()) {
            continue;
        }
        match light.resolve(&placement.placement(), bounds.sphere) {
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
pub fn sync_image_infinite_lights<P: Placement>(
    query: Query<(Entity, Ref<ImageInfiniteLight>, Option<Ref<P>>)>,
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
        let transform = transform.map_or(Transform::IDENTITY, |t| t.placement());
        match light.resolve_with_tables(&transform, bounds.sphere, t.clone()) {
            Ok(row) => table.upsert_image_infinite(entity, row, true),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Upserts sun-and-sky lights: a changed light rebuilds its sky table into the buffers its row
/// held; a change of scene bounds alone only rescales the power (no rebuild).
pub fn sync_sun_sky_lights(
    query: Query<(Entity, Ref<SunSkyLight>)>,
    bounds: Res<SceneBounds>,
    mut table: ResMut<LightTable>,
    mut report: ResMut<RunReport>,
) {
    for (entity, light) in &query {
        let row = if light.is_changed() {
            if let Ok(Some(dark)) = light.dark_reason() {
                report.warnings.push(format!("sun and sky {entity}: {dark}"));
            }
            let buffers = table.take_sun_sky_buffers(entity);
            light.resolve_reusing(bounds.sphere, buffers)
        } else if bounds.is_changed() {
            match table.sun_sky_of(entity) {
                Some(r) => Ok(r.with_scene(bounds.sphere)),
                None => light.resolve(bounds.sphere),
            }
        } else {
            continue;
        };
        match row {
            Ok(row) => table.upsert_sun_sky(entity, row, true),
            Err(e) => reject(&mut table, &mut report, entity, e),
        }
    }
}

/// Removes the rows of lights whose component was removed or whose entity was despawned.
// A system: one parameter per light component.
#[allow(clippy::too_many_arguments)]
pub fn remove_lights(
    mut points: RemovedComponents<PointLight>,
    mut spots: RemovedComponents<SpotLight>,
    mut distant: RemovedComponents<DistantLight>,
    mut area: RemovedComponents<AreaLight>,
    mut projection: RemovedComponents<ProjectionLight>,
    mut goniometric: RemovedComponents<GoniometricLight>,
    mut uniform: RemovedComponents<UniformInfiniteLight>,
    mut image: RemovedComponents<ImageInfiniteLight>,
    mut sun_sky: RemovedComponents<SunSkyLight>,
    mut table: ResMut<LightTable>,
) {
    let removed = points
        .read()
        .chain(spots.read())
        .chain(distant.read())
        .chain(area.read())
        .chain(projection.read())
        .chain(goniometric.read())
        .chain(uniform.read())
        .chain(image.read())
        .chain(sun_sky.read());
    for entity in removed {
        table.remove(entity);
    }
}
