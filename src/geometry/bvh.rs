//! `SceneBvh`: one wide BVH over all world-space geometry (built by obvhs, traversed as `wide.rs`).
//!
//! **One flat, world-space BVH.** Mesh triangles are transformed to world space once, at build or
//! refit, so traversal needs no per-instance ray transforms and the intersection error bounds of
//! `ray.rs` hold directly in world coordinates.
//!
//! **Analytic shapes share the BVH with triangles** as custom primitives (a leaf slot is either a
//! triangle or an index into the placed shapes). A second small BVH would mean two traversals per
//! ray, and since area-light shapes sit inside the scene, the two root boxes overlap for almost
//! every ray, so nothing is saved; one tree also gives one any-hit loop that stops at the first
//! occluder of either kind. The cost is a single, well-predicted branch per primitive.
//!
//! **Build.** obvhs PLOC + parallel reinsertion, collapsed to 8 children per node (`wide.rs`),
//! with the `fast_build` preset: dynamic scenes rebuild when geometry is added or removed, and
//! `medium_build` buys little trace speed for a much slower build.
//!
//! **Refit, not rebuild, when only transforms change** (`refit.rs`). A refit rewrites the moved
//! instances' world triangles and recomputes only the boxes on their paths to the root, keeping
//! the topology, at a small fraction of a rebuild's cost. Small motions barely hurt the tree, but
//! objects that jump across the scene wreck it. So [`SceneBvh::update_transforms`] refits, tracks that
//! cost (sum of node surface areas over the root's) and rebuilds once it passes
//! [`REBUILD_COST_RATIO`] times its value after the last build. Adding or removing geometry
//! always rebuilds (a new `SceneBvh::build`).

use bevy_ecs::resource::Resource;
use glam::{Affine3A, Vec3};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;
use std::collections::HashMap;

use super::GeometryError;
use super::mesh::Mesh;
use super::shapes::{PlacedShape, Shape};
use super::transform::Transform;
use super::triangle::is_degenerate;
use super::wide::{LeafSource, WideBvh, box_corners, obvhs_box};

/// Rebuild after refits once the tree's SAH cost has grown by this factor since the last build.
pub const REBUILD_COST_RATIO: f32 = 1.5;

/// Which entity and which of its primitives (triangle index in the mesh; 0 for a shape).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GeometryId {
    /// `Entity::index()` of the owner.
    pub entity_index: u32,
    /// Triangle index in the owner's mesh; 0 for an analytic shape.
    pub primitive: u32,
}

impl GeometryId {
    /// No primitive (a point whose surface is unknown).
    pub const NONE: Self = Self { entity_index: u32::MAX, primitive: u32::MAX };
}

/// The geometry of one instance: a borrowed mesh (copied into the BVH) or an analytic shape.
#[derive(Clone, Copy, Debug)]
pub enum GeometryRef<'a> {
    /// A triangle mesh in the instance's local space.
    Mesh(&'a Mesh),
    /// An analytic shape, sized in the instance's local space.
    Shape(Shape),
}

/// One entity's geometry with its placement and ids, as handed to [`SceneBvh::build`].
#[derive(Clone, Copy, Debug)]
pub struct GeometryInstance<'a> {
    /// The mesh or shape, in local space.
    pub geometry: GeometryRef<'a>,
    /// Where it sits: local to world space.
    pub transform: Transform,
    /// `Entity::index()` of the owner, reported back in hits.
    pub entity_index: u32,
    /// Material id, reported back in hits.
    pub material: u32,
}

/// What the build left out, and why.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildReport {
    /// Instances left out entirely (bad transform or shape size); the error says which and why.
    pub skipped_instances: Vec<GeometryError>,
    /// Triangles left out because they have zero area (in local or world space) or a world-space
    /// vertex that is not finite or beyond [`crate::geometry::MAX_COORDINATE`].
    pub degenerate_triangles: Vec<GeometryId>,
}

/// What [`SceneBvh::update_transforms`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UpdateKind {
    /// Refitted; the SAH cost is now `cost_ratio` times its value after the last build.
    Refitted {
        /// SAH cost now over its value after the last build (1 = as built).
        cost_ratio: f32,
    },
    /// Rebuilt, because the cost ratio passed [`REBUILD_COST_RATIO`] or an instance entered or
    /// left the tree.
    Rebuilt,
}

/// Marks a triangle slot in [`LeafPrim::shape`].
pub(crate) const NO_SHAPE: u32 = u32::MAX;

/// A primitive in a leaf slot: a world-space triangle, or (if `shape != NO_SHAPE`) a shape.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LeafPrim {
    pub v: [Vec3; 3],
    pub shape: u32,
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Source {
    Mesh(u32),
    Shape(Shape),
}

#[derive(Clone, Debug)]
pub(crate) struct InstanceRecord {
    pub source: Source,
    pub transform: Transform,
    pub entity_index: u32,
    pub material: u32,
    /// Index into `shapes` for a shape instance in the tree; `NO_SHAPE` otherwise.
    pub shape: u32,
    /// Range of this instance's primitives in input order; empty when left out.
    pub prims: std::ops::Range<u32>,
    /// Whether the last rebuild accepted this instance (valid transform and shape).
    pub in_tree: bool,
}

/// The scene's ray-tracing acceleration structure (a bevy resource; usable without a World).
#[derive(Resource, Clone, Debug)]
pub struct SceneBvh {
    pub(crate) instances: Vec<InstanceRecord>,
    pub(crate) meshes: Vec<Mesh>,
    pub(crate) shapes: Vec<PlacedShape>,
    /// Per primitive in input order: owning instance and triangle index in its mesh.
    pub(crate) prim_instance: Vec<u32>,
    pub(crate) prim_local: Vec<u32>,
    /// Leaf slot data, in the order of the build's leaves (slot -> input primitive:
    /// `prim_of_slot`).
    pub(crate) leaf: Vec<LeafPrim>,
    prim_of_slot: Vec<u32>,
    pub(crate) slot_of_prim: Vec<u32>,
    /// The tree queries traverse: the same hierarchy, 8 children per node with exact boxes.
    pub(crate) wide: WideBvh,
    params: BvhBuildParams,
    /// Sum of child box half-areas right after the last build, and now.
    pub(crate) built_cost: f32,
    pub(crate) cost: f32,
    report: BuildReport,
}

impl Default for SceneBvh {
    fn default() -> Self {
        Self::build(&[])
    }
}

fn affine(t: &Transform) -> Affine3A {
    t.to_affine()
}

pub(crate) fn mesh_transform_ok(t: &Transform) -> bool {
    t.translation.is_finite()
        && t.scale.is_finite()
        && t.shear.is_finite()
        && t.rotation.is_finite()
        && t.rotation.length_squared() > 0.0
}

impl SceneBvh {
    /// The tree of one mesh at the identity, entity 0, material 0: what most geometry tests trace.
    #[cfg(test)]
    pub(crate) fn of_mesh(mesh: &super::Mesh) -> Self {
        Self::build(&[GeometryInstance {
            geometry: GeometryRef::Mesh(mesh),
            transform: Transform::IDENTITY,
            entity_index: 0,
            material: 0,
        }])
    }

    /// Builds with obvhs's `fast_build` preset (PLOC, light reinsertion).
    pub fn build(instances: &[GeometryInstance]) -> Self {
        Self::build_with_params(instances, BvhBuildParams::fast_build())
    }

    /// Builds from `instances` (their index in the slice is the instance index used by refits).
    /// Never fails: bad instances and degenerate triangles are left out and listed in
    /// [`SceneBvh::report`]. `params.pre_split` is ignored (refit needs one slot per primitive).
    pub fn build_with_params(instances: &[GeometryInstance], params: BvhBuildParams) -> Self {
        let mut mesh_ids: HashMap<*const Mesh, u32> = HashMap::new();
        let mut meshes = Vec::new();
        let records = instances
            .iter()
            .map(|inst| {
                let source = match inst.geometry {
                    GeometryRef::Mesh(m) => Source::Mesh(*mesh_ids.entry(m as *const Mesh).or_insert_with(|| {
                        meshes.push(m.clone());
                        meshes.len() as u32 - 1
                    })),
                    GeometryRef::Shape(s) => Source::Shape(s),
                };
                InstanceRecord {
                    source,
                    transform: inst.transform,
                    entity_index: inst.entity_index,
                    material: inst.material,
                    shape: NO_SHAPE,
                    prims: 0..0,
                    in_tree: false,
                }
            })
            .collect();
        let mut bvh = Self {
            instances: records,
            meshes,
            shapes: Vec::new(),
            prim_instance: Vec::new(),
            prim_local: Vec::new(),
            leaf: Vec::new(),
            prim_of_slot: Vec::new(),
            slot_of_prim: Vec::new(),
            wide: WideBvh::default(),
            params: BvhBuildParams { pre_split: false, ..params },
            built_cost: 0.0,
            cost: 0.0,
            report: BuildReport::default(),
        };
        bvh.rebuild();
        bvh
    }

    /// What the last build left out.
    pub fn report(&self) -> &BuildReport {
        &self.report
    }

    /// Number of primitives (triangles and shapes) in the tree.
    pub fn primitive_count(&self) -> usize {
        self.leaf.len()
    }

    /// Number of instances given to the build, including left-out ones.
    pub fn instance_count(&self) -> usize {
        self.instances.len()
    }

    /// The current transform of instance `instance`.
    pub fn instance_transform(&self, instance: u32) -> Option<Transform> {
        self.instances.get(instance as usize).map(|r| r.transform)
    }

    /// The placed shape of instance `instance`, if it is a shape in the tree (for light sampling).
    pub fn placed_shape(&self, instance: u32) -> Option<&PlacedShape> {
        let r = self.instances.get(instance as usize)?;
        self.shapes.get(r.shape as usize)
    }

    /// World-space vertices of triangle `triangle` of mesh instance `instance`, exactly as the
    /// tree stores them (sample mesh area lights from these so samples lie on the traced
    /// surface). `None` for shapes, left-out instances and degenerate triangles.
    pub fn world_triangle(&self, instance: u32, triangle: u32) -> Option<[Vec3; 3]> {
        let rec = self.instances.get(instance as usize)?;
        if !matches!(rec.source, Source::Mesh(_)) {
            return None;
        }
        let range = rec.prims.start as usize..rec.prims.end as usize;
        let k = self.prim_local[range.clone()].binary_search(&triangle).ok()?;
        Some(self.leaf[self.slot_of_prim[range.start + k] as usize].v)
    }

    /// World-space bounding box of everything in the tree, or None when it is empty.
    pub fn world_bounds(&self) -> Option<(Vec3, Vec3)> {
        self.wide.bounds().map(|b| box_corners(&b))
    }

    /// SAH-style cost of the tree now, relative to its value after the last build (1 = as built).
    pub fn cost_ratio(&self) -> f32 {
        if self.built_cost > 0.0 { self.cost / self.built_cost } else { 1.0 }
    }

    /// Rebuilds the whole tree from the stored meshes, shapes and current transforms.
    pub fn rebuild(&mut self) {
        self.report = BuildReport::default();
        self.shapes.clear();
        self.prim_instance.clear();
        self.prim_local.clear();
        let mut prims: Vec<LeafPrim> = Vec::new();
        for (i, rec) in self.instances.iter_mut().enumerate() {
            let start = prims.len() as u32;
            rec.shape = NO_SHAPE;
            rec.in_tree = false;
            let fail = |e: GeometryError| GeometryError::Instance {
                instance: i as u32,
                entity_index: rec.entity_index,
                source: Box::new(e),
            };
            match rec.source {
                Source::Shape(shape) => match PlacedShape::new(shape, &rec.transform) {
                    Ok(placed) => {
                        rec.shape = self.shapes.len() as u32;
                        rec.in_tree = true;
                        self.shapes.push(placed);
                        prims.push(LeafPrim { v: [Vec3::ZERO; 3], shape: rec.shape });
                        self.prim_instance.push(i as u32);
                        self.prim_local.push(0);
                    }
                    Err(e) => self.report.skipped_instances.push(fail(e)),
                },
                Source::Mesh(_) if !mesh_transform_ok(&rec.transform) => {
                    let e = GeometryError::InvalidTransform { transform: rec.transform };
                    self.report.skipped_instances.push(fail(e));
                }
                Source::Mesh(m) => {
                    rec.in_tree = true;
                    let mesh = &self.meshes[m as usize];
                    let world = world_positions(mesh, &rec.transform);
                    for t in 0..mesh.triangle_count() {
                        let v = mesh.triangle_indices(t).map(|k| world[k as usize]);
                        if mesh.is_degenerate(t) || is_degenerate(&v) {
                            let id = GeometryId { entity_index: rec.entity_index, primitive: t as u32 };
                            self.report.degenerate_triangles.push(id);
                            continue;
                        }
                        prims.push(LeafPrim { v, shape: NO_SHAPE });
                        self.prim_instance.push(i as u32);
                        self.prim_local.push(t as u32);
                    }
                }
            }
            rec.prims = start..prims.len() as u32;
        }
        self.build_tree(prims);
    }

    fn build_tree(&mut self, prims: Vec<LeafPrim>) {
        let aabbs: Vec<Aabb> = prims.iter().map(|p| self.prim_bounds(p)).collect();
        let params = self.params;
        let mut bvh2 = PlocBuilder::with_capacity(aabbs.len()).build(
            params.ploc_search_distance,
            &aabbs,
            (0..aabbs.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        // Slots follow the binary tree's leaf order, which keeps neighbours in space together.
        self.prim_of_slot = bvh2.primitive_indices.clone();
        self.leaf = self.prim_of_slot.iter().map(|&p| prims[p as usize]).collect();
        self.slot_of_prim = vec![0; prims.len()];
        for (slot, &p) in self.prim_of_slot.iter().enumerate() {
            self.slot_of_prim[p as usize] = slot as u32;
        }
        self.wide = WideBvh::from_bvh2(&bvh2, &self.slot_of_prim, &LeafView(self));
        self.cost = self.wide.cost() as f32;
        self.built_cost = self.cost;
    }

    pub(crate) fn prim_bounds(&self, p: &LeafPrim) -> Aabb {
        if p.shape == NO_SHAPE {
            let v = p.v;
            obvhs_box(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
        } else {
            let (lo, hi) = self.shapes[p.shape as usize].world_bounds();
            obvhs_box(lo, hi)
        }
    }

    /// Whether rays leaving a point on primitive `origin` ignore leaf slot `slot`: it is that
    /// primitive, and it is flat (a triangle, disk or rectangle). A ray leaving a plane meets it
    /// only where it starts, so only rounding could make it count; Cycles skips a ray's own
    /// primitive likewise. A sphere can stand in the way of rays leaving it inward.
    #[inline(always)]
    pub(crate) fn ignores(&self, slot: usize, origin: GeometryId) -> bool {
        let shape = self.leaf[slot].shape;
        origin != GeometryId::NONE
            && self.geometry_of_slot(slot) == origin
            && (shape == NO_SHAPE || !matches!(self.shapes[shape as usize].shape, Shape::Sphere(_)))
    }

    /// Which entity and primitive leaf slot `slot` holds.
    #[inline(always)]
    pub(crate) fn geometry_of_slot(&self, slot: usize) -> GeometryId {
        self.id_of(self.prim_of_slot(slot)).1
    }

    /// Input index of the primitive in leaf slot `slot` (stable across refits; the tie-breaker
    /// that makes BVH and brute-force closest hits agree exactly).
    pub(crate) fn prim_of_slot(&self, slot: usize) -> u32 {
        self.prim_of_slot[slot]
    }

    pub(crate) fn slot_of(&self, prim: u32) -> usize {
        self.slot_of_prim[prim as usize] as usize
    }

    /// Ids of input primitive `prim`.
    pub(crate) fn id_of(&self, prim: u32) -> (u32, GeometryId, u32) {
        let inst = self.prim_instance[prim as usize];
        let rec = &self.instances[inst as usize];
        let id = GeometryId { entity_index: rec.entity_index, primitive: self.prim_local[prim as usize] };
        (inst, id, rec.material)
    }

    /// World-space dp/du and dp/dv of triangle `primitive` of mesh instance `instance` (see
    /// [`Mesh::uv_derivatives`]); None for shapes, meshes without uvs and degenerate uvs.
    pub fn uv_derivatives(&self, instance: u32, primitive: u32) -> Option<(Vec3, Vec3)> {
        let mesh = self.mesh_of(instance)?;
        let (dpdu, dpdv) = mesh.uv_derivatives(primitive as usize)?;
        let t = self.instances[instance as usize].transform;
        Some((t.transform_vector(dpdu), t.transform_vector(dpdv)))
    }

    pub(crate) fn mesh_of(&self, instance: u32) -> Option<&Mesh> {
        match self.instances[instance as usize].source {
            Source::Mesh(m) => Some(&self.meshes[m as usize]),
            Source::Shape(_) => None,
        }
    }
}

/// The leaf slots of a `SceneBvh` as the wide tree reads them.
pub(crate) struct LeafView<'a>(pub(crate) &'a SceneBvh);

impl LeafSource for LeafView<'_> {
    fn leaf_count(&self) -> usize {
        self.0.leaf.len()
    }
    fn triangle(&self, slot: usize) -> Option<[Vec3; 3]> {
        let p = &self.0.leaf[slot];
        (p.shape == NO_SHAPE).then_some(p.v)
    }
    fn bounds(&self, slot: usize) -> Aabb {
        self.0.prim_bounds(&self.0.leaf[slot])
    }
}

pub(crate) fn world_positions(mesh: &Mesh, t: &Transform) -> Vec<Vec3> {
    let a = affine(t);
    mesh.positions().iter().map(|&p| a.transform_point3(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::Disk;

    #[test]
    fn bad_instances_are_reported_not_fatal() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X], vec![0, 1, 2, 0, 1, 3]).unwrap();
        let inst = [
            GeometryInstance {
                geometry: GeometryRef::Mesh(&mesh),
                transform: Transform::IDENTITY,
                entity_index: 3,
                material: 0,
            },
            GeometryInstance {
                geometry: GeometryRef::Shape(Disk { radius: -1.0, inner_radius: 0.0 }.into()),
                transform: Transform::IDENTITY,
                entity_index: 4,
                material: 0,
            },
        ];
        let bvh = SceneBvh::build(&inst);
        assert_eq!(bvh.primitive_count(), 1);
        assert_eq!(bvh.report().degenerate_triangles, vec![GeometryId { entity_index: 3, primitive: 1 }]);
        assert!(matches!(
            bvh.report().skipped_instances[..],
            [GeometryError::Instance { instance: 1, entity_index: 4, .. }]
        ));
    }
}
