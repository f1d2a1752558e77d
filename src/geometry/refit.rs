//! Moving instances: refit the wide tree in place, or rebuild when the tree has degraded.
//!
//! A refit rewrites the moved instances' world-space primitives and the lane blocks that hold
//! them, then recomputes the boxes on their paths to the root (`WideBvh::refit`). The topology is
//! kept; the SAH-style cost (sum of child box areas) tells [`SceneBvh::update_transforms`] when to
//! rebuild.

use super::GeometryError;
use super::bvh::{LeafView, REBUILD_COST_RATIO, SceneBvh, Source, UpdateKind, mesh_transform_ok, world_positions};
use super::shapes::PlacedShape;
use super::transform::Transform;
use super::triangle::is_degenerate;

impl SceneBvh {
    /// Moves instances to new transforms, refitting the tree; rebuilds instead when the tree has
    /// degraded past [`REBUILD_COST_RATIO`] or an instance enters or leaves it (its transform
    /// becomes valid or invalid). Errors only for unknown instance indices, before any change.
    pub fn update_transforms(&mut self, moved: &[(u32, Transform)]) -> Result<UpdateKind, GeometryError> {
        self.check_instances(moved)?;
        match self.refit(moved) {
            Ok(ratio) if ratio <= REBUILD_COST_RATIO => Ok(UpdateKind::Refitted { cost_ratio: ratio }),
            Ok(_) | Err(GeometryError::RefitNeedsRebuild { .. }) => {
                for &(i, t) in moved {
                    self.instances[i as usize].transform = t;
                }
                self.rebuild();
                Ok(UpdateKind::Rebuilt)
            }
            Err(e) => Err(e),
        }
    }

    /// Refits only: moves the given instances and re-fits every node box, keeping the topology.
    /// Returns the new cost ratio (see [`SceneBvh::cost_ratio`]). Fails, changing nothing, for an
    /// unknown instance or one that would have to enter or leave the tree (then rebuild).
    pub fn refit(&mut self, moved: &[(u32, Transform)]) -> Result<f32, GeometryError> {
        self.check_instances(moved)?;
        let mut placed = Vec::with_capacity(moved.len());
        for &(i, t) in moved {
            let rec = &self.instances[i as usize];
            let in_tree = rec.in_tree;
            let valid_now = match rec.source {
                Source::Shape(s) => {
                    let p = PlacedShape::new(s, &t);
                    placed.push(p.clone().ok());
                    p.is_ok()
                }
                Source::Mesh(_) => {
                    placed.push(None);
                    mesh_transform_ok(&t)
                }
            };
            if in_tree != valid_now {
                return Err(GeometryError::RefitNeedsRebuild { instance: i });
            }
        }
        let mut moved_slots = Vec::new();
        for (&(i, t), placed) in moved.iter().zip(placed) {
            let rec = &mut self.instances[i as usize];
            rec.transform = t;
            match rec.source {
                Source::Shape(_) => {
                    if let Some(p) = placed {
                        self.shapes[rec.shape as usize] = p;
                    }
                }
                Source::Mesh(m) => {
                    let mesh = &self.meshes[m as usize];
                    let world = world_positions(mesh, &t);
                    for p in rec.prims.clone() {
                        let tri = mesh.triangle_indices(self.prim_local[p as usize] as usize);
                        let mut v = tri.map(|k| world[k as usize]);
                        if is_degenerate(&v) {
                            // Collapse to a point: never hit, finite bounds.
                            let c = if v[0].is_finite() { v[0] } else { t.translation };
                            v = [c; 3];
                        }
                        let slot = self.slot_of_prim[p as usize];
                        self.leaf[slot as usize].v = v;
                        moved_slots.push(slot);
                    }
                }
            }
            if let Source::Shape(_) = rec.source {
                moved_slots.push(self.slot_of_prim[rec.prims.start as usize]);
            }
        }
        let mut wide = std::mem::take(&mut self.wide);
        self.cost = wide.refit(moved_slots, &LeafView(self)) as f32;
        self.wide = wide;
        Ok(self.cost_ratio())
    }

    fn check_instances(&self, moved: &[(u32, Transform)]) -> Result<(), GeometryError> {
        match moved.iter().find(|(i, _)| *i as usize >= self.instances.len()) {
            Some(&(instance, _)) => Err(GeometryError::UnknownInstance { instance, count: self.instances.len() }),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::bvh::{GeometryInstance, GeometryRef};
    use crate::geometry::mesh::Mesh;
    use crate::geometry::shapes::Sphere;
    use glam::Vec3;

    fn scene(mesh: &Mesh) -> Vec<GeometryInstance<'_>> {
        let mut v: Vec<GeometryInstance> = (0..20)
            .map(|i| GeometryInstance {
                geometry: GeometryRef::Mesh(mesh),
                transform: Transform::from_translation(Vec3::new(i as f32 * 3.0, (i % 3) as f32, 0.0)),
                entity_index: i,
                material: i % 4,
            })
            .collect();
        v.push(GeometryInstance {
            geometry: GeometryRef::Shape(Sphere { radius: 1.0 }.into()),
            transform: Transform::from_translation(Vec3::new(0.0, 5.0, 0.0)),
            entity_index: 100,
            material: 7,
        });
        v
    }

    #[test]
    fn refit_without_motion_reproduces_the_built_tree() {
        let mesh = Mesh::uv_sphere(1.0, 8, 6);
        let inst = scene(&mesh);
        // Refitting every instance in place recomputes every block and box from the primitives,
        // as the build did, and must reproduce them bit for bit.
        let bvh = SceneBvh::build(&inst);
        let mut again = bvh.clone();
        let all: Vec<(u32, Transform)> = inst.iter().enumerate().map(|(i, g)| (i as u32, g.transform)).collect();
        assert_eq!(again.refit(&all), Ok(1.0));
        assert_eq!(format!("{:?}", bvh.wide), format!("{:?}", again.wide));
        assert_eq!(bvh.meshes.len(), 1, "instances of one mesh share its copy");
        assert_eq!(bvh.primitive_count(), 20 * mesh.triangle_count() + 1);
    }

    #[test]
    fn partial_refit_equals_full_refit() {
        let mesh = Mesh::uv_sphere(1.0, 8, 6);
        let inst = scene(&mesh);
        let mut bvh = SceneBvh::build(&inst);
        let moved = [(3, Transform::from_translation(Vec3::new(9.0, 4.0, 1.0))), (20, Transform::IDENTITY)];
        let partial = bvh.refit(&moved).unwrap();
        let mut full = bvh.clone();
        let all: Vec<(u32, Transform)> =
            (0..inst.len() as u32).map(|i| (i, full.instances[i as usize].transform)).collect();
        let ratio = full.refit(&all).unwrap();
        assert_eq!(format!("{:?}", bvh.wide), format!("{:?}", full.wide));
        assert!((partial - ratio).abs() < 1e-5 && partial > 1.0, "{partial} vs {ratio}");
    }

    #[test]
    fn update_transforms_refits_then_rebuilds_when_quality_drops() {
        let mesh = Mesh::uv_sphere(1.0, 8, 6);
        let inst = scene(&mesh);
        let mut bvh = SceneBvh::build(&inst);
        let small = [(2, Transform::from_translation(Vec3::new(6.0, 0.5, 0.0)))];
        assert!(matches!(bvh.update_transforms(&small), Ok(UpdateKind::Refitted { .. })));
        // Scatter everything far apart in a different order: the old topology is now poor.
        let scatter: Vec<(u32, Transform)> = (0..20)
            .map(|i| (i, Transform::from_translation(Vec3::new(0.0, ((i * 7) % 20) as f32 * 50.0, 0.0))))
            .collect();
        assert_eq!(bvh.update_transforms(&scatter), Ok(UpdateKind::Rebuilt));
        assert!((bvh.cost_ratio() - 1.0).abs() < 1e-6);
        assert!(matches!(
            bvh.update_transforms(&[(99, Transform::IDENTITY)]),
            Err(GeometryError::UnknownInstance { .. })
        ));
    }
}
