//! Keeping the `SceneBvh` in step with geometry entities: rebuilt when geometry is added,
//! removed or reshaped, refitted (or rebuilt past a quality threshold) when only transforms move.

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;

use crate::geometry::{
    Disk, GeometryInstance, GeometryRef, Mesh, Placement, Rectangle, SceneBvh, Shape, Sphere, Transform, UpdateKind,
};
use crate::light::SceneSphere;
use crate::shading::{RunReport, SceneBounds};

use super::Work;

/// Which entity each BVH instance is (instance index = position).
#[derive(Resource, Clone, Debug, Default)]
pub struct GeometryIndex {
    /// The entity of each BVH instance, by instance index.
    pub entities: Vec<Entity>,
    instance_of: EntityHashMap<u32>,
}

impl GeometryIndex {
    /// The BVH instance of `entity`.
    pub fn instance_of(&self, entity: Entity) -> Option<u32> {
        self.instance_of.get(&entity).copied()
    }
}

/// What the BVH needs this update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BvhWork {
    /// Nothing changed: keep the BVH as it is.
    #[default]
    None,
    /// Only transforms moved: refit the bounds.
    Refit,
    /// Geometry was added, removed or reshaped: build from scratch.
    Rebuild,
}

type AnyShape = Or<(With<Mesh>, With<Sphere>, With<Disk>, With<Rectangle>)>;
type ShapeChanged = Or<(Changed<Mesh>, Changed<Sphere>, Changed<Disk>, Changed<Rectangle>)>;

/// Decides between rebuild (geometry added, removed or reshaped), refit (only transforms moved)
/// and nothing.
#[allow(clippy::too_many_arguments)]
pub fn plan_bvh<P: Placement>(
    reshaped: Query<(), (ShapeChanged, AnyShape)>,
    moved: Query<(), (Changed<P>, AnyShape)>,
    mut removed_mesh: RemovedComponents<Mesh>,
    mut removed_sphere: RemovedComponents<Sphere>,
    mut removed_disk: RemovedComponents<Disk>,
    mut removed_rect: RemovedComponents<Rectangle>,
    mut work: ResMut<Work>,
    mut report: ResMut<RunReport>,
) {
    let removed = removed_mesh.read().count()
        + removed_sphere.read().count()
        + removed_disk.read().count()
        + removed_rect.read().count();
    let reshaped = reshaped.iter().count();
    let (w, why) = if reshaped + removed > 0 {
        (BvhWork::Rebuild, format!("{reshaped} geometry added or reshaped, {removed} removed"))
    } else if !moved.is_empty() {
        (BvhWork::Refit, format!("{} geometry transforms moved", moved.iter().count()))
    } else {
        (BvhWork::None, "no geometry changed".to_string())
    };
    work.bvh = w;
    report.record("update_scene_bvh", w != BvhWork::None, why);
}

fn shape_of<'a>(
    mesh: Option<&'a Mesh>,
    sphere: Option<&Sphere>,
    disk: Option<&Disk>,
    rect: Option<&Rectangle>,
) -> Option<GeometryRef<'a>> {
    match (mesh, sphere, disk, rect) {
        (Some(m), ..) => Some(GeometryRef::Mesh(m)),
        (_, Some(s), ..) => Some(GeometryRef::Shape(Shape::Sphere(*s))),
        (_, _, Some(d), _) => Some(GeometryRef::Shape(Shape::Disk(*d))),
        (_, _, _, Some(r)) => Some(GeometryRef::Shape(Shape::Rectangle(*r))),
        _ => None,
    }
}

/// Rebuilds or refits the BVH as planned, and updates the scene's bounding sphere.
#[allow(clippy::type_complexity)]
pub fn update_scene_bvh<P: Placement>(
    all: Query<(Entity, &P, Option<&Mesh>, Option<&Sphere>, Option<&Disk>, Option<&Rectangle>), AnyShape>,
    moved: Query<(Entity, &P), (Changed<P>, AnyShape)>,
    work: Res<Work>,
    mut bvh: ResMut<SceneBvh>,
    mut index: ResMut<GeometryIndex>,
    mut bounds: ResMut<SceneBounds>,
    mut report: ResMut<RunReport>,
) {
    let rebuild = |bvh: &mut SceneBvh, index: &mut GeometryIndex| {
        let mut entities = Vec::new();
        let instances: Vec<GeometryInstance> = all
            .iter()
            .filter_map(|(e, t, m, s, d, r)| {
                let geometry = shape_of(m, s, d, r)?;
                let slot = entities.len() as u32;
                entities.push(e);
                Some(GeometryInstance {
                    geometry,
                    transform: t.placement(),
                    entity_index: e.index_u32(),
                    material: slot,
                })
            })
            .collect();
        *bvh = SceneBvh::build(&instances);
        index.instance_of = entities.iter().enumerate().map(|(i, &e)| (e, i as u32)).collect();
        index.entities = entities;
    };
    match work.bvh {
        BvhWork::Rebuild => rebuild(&mut bvh, &mut index),
        BvhWork::Refit => {
            let moved: Vec<(u32, Transform)> =
                moved.iter().filter_map(|(e, t)| Some((index.instance_of(e)?, t.placement()))).collect();
            match bvh.update_transforms(&moved) {
                Ok(UpdateKind::Refitted { cost_ratio }) => {
                    report.record("bvh_refit", true, format!("cost ratio {cost_ratio:.2}"))
                }
                Ok(UpdateKind::Rebuilt) => report.record("bvh_refit", true, "tree quality degraded: rebuilt"),
                Err(e) => {
                    report.warnings.push(format!("BVH refit failed ({e}); rebuilding"));
                    rebuild(&mut bvh, &mut index);
                }
            }
        }
        BvhWork::None => return,
    }
    for e in &bvh.report().skipped_instances {
        report.warnings.push(format!("geometry skipped: {e}"));
    }
    let sphere = match bvh.world_bounds() {
        Some((lo, hi)) => SceneSphere { center: (lo + hi) * 0.5, radius: ((hi - lo) * 0.5).length().max(1e-3) },
        None => SceneSphere::default(),
    };
    if bounds.sphere != sphere {
        bounds.sphere = sphere;
    }
}
