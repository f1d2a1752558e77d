//! `SceneBvh`: one compressed wide BVH (obvhs CWBVH) over all world-space geometry.
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
//! **Refit, not rebuild, when only transforms change.** The CWBVH is built with PLOC and parallel
//! reinsertion (obvhs), then converted to BVH8. A refit recomputes the moved instances' world
//! triangles and re-quantises every node's child boxes bottom-up in one pass over the nodes
//! (children always follow their parent in `nodes`), keeping the topology. Measured on this
//! machine (2 cores, `benches/visibility.rs`, 1,000 objects, 100k triangles): refit ~1.3 ms when 1%
//! of the objects move and ~3 ms when all move, versus ~60 ms for a full rebuild. Refit trades
//! tree quality for that speed, so [`SceneBvh::update_transforms`] tracks the SAH-style cost
//! (sum of node surface areas over the root's) and rebuilds once it exceeds
//! [`REBUILD_COST_RATIO`] times its value after the last build. Adding or removing geometry
//! always rebuilds (a new `SceneBvh::build`).

use bevy_ecs::resource::Resource;
use glam::{Affine3A, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh, node::CwBvhNode};
use obvhs::ploc::PlocBuilder;
use obvhs::{BvhBuildParams, PerComponent};
use std::collections::HashMap;

use super::GeometryError;
use super::mesh::Mesh;
use super::shapes::{PlacedShape, Shape};
use super::transform::Transform;
use super::triangle::is_degenerate;

/// Rebuild after refits once the tree's SAH cost has grown by this factor since the last build.
pub const REBUILD_COST_RATIO: f32 = 1.5;

/// Which entity and which of its primitives (triangle index in the mesh; 0 for a shape).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GeometryId {
    pub entity_index: u32,
    pub primitive: u32,
}

/// The geometry of one instance: a borrowed mesh (copied into the BVH) or an analytic shape.
#[derive(Clone, Copy, Debug)]
pub enum GeometryRef<'a> {
    Mesh(&'a Mesh),
    Shape(Shape),
}

/// One entity's geometry with its placement and ids, as handed to [`SceneBvh::build`].
#[derive(Clone, Copy, Debug)]
pub struct GeometryInstance<'a> {
    pub geometry: GeometryRef<'a>,
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
    /// Triangles left out because they have zero area (in local or world space).
    pub degenerate_triangles: Vec<GeometryId>,
}

/// What [`SceneBvh::update_transforms`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UpdateKind {
    /// Refitted; the SAH cost is now `cost_ratio` times its value after the last build.
    Refitted { cost_ratio: f32 },
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
enum Source {
    Mesh(u32),
    Shape(Shape),
}

#[derive(Clone, Debug)]
pub(crate) struct InstanceRecord {
    source: Source,
    pub transform: Transform,
    pub entity_index: u32,
    pub material: u32,
    /// Index into `shapes` for a shape instance in the tree; `NO_SHAPE` otherwise.
    pub shape: u32,
    /// Range of this instance's primitives in input order; empty when left out.
    prims: std::ops::Range<u32>,
    /// Whether the last rebuild accepted this instance (valid transform and shape).
    in_tree: bool,
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
    pub(crate) cwbvh: CwBvh,
    /// Leaf slot data, in `cwbvh.primitive_indices` order (slot -> input primitive).
    pub(crate) leaf: Vec<LeafPrim>,
    slot_of_prim: Vec<u32>,
    /// Exact (unquantised) box of every node, kept for incremental refits.
    node_bounds: Vec<Aabb>,
    /// Parent of every node (the root is its own parent) and the node holding each leaf slot.
    parent: Vec<u32>,
    slot_node: Vec<u32>,
    /// Refit scratch: nodes whose boxes must be recomputed.
    dirty: Vec<bool>,
    params: BvhBuildParams,
    /// Sum of node half-areas now and right after the last build.
    area_sum: f64,
    built_cost: f32,
    cost: f32,
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

fn mesh_transform_ok(t: &Transform) -> bool {
    t.translation.is_finite() && t.scale.is_finite() && t.rotation.is_finite() && t.rotation.length_squared() > 0.0
}

impl SceneBvh {
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
            cwbvh: CwBvh::default(),
            leaf: Vec::new(),
            slot_of_prim: Vec::new(),
            node_bounds: Vec::new(),
            parent: Vec::new(),
            slot_node: Vec::new(),
            dirty: Vec::new(),
            area_sum: 0.0,
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
        self.cwbvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
        self.leaf = self.cwbvh.primitive_indices.iter().map(|&p| prims[p as usize]).collect();
        self.slot_of_prim = vec![0; prims.len()];
        for (slot, &p) in self.cwbvh.primitive_indices.iter().enumerate() {
            self.slot_of_prim[p as usize] = slot as u32;
        }
        self.link_nodes();
        self.dirty.clear();
        self.dirty.resize(self.cwbvh.nodes.len(), true);
        self.node_bounds.clear();
        self.node_bounds.resize(self.cwbvh.nodes.len(), Aabb::empty());
        self.area_sum = 0.0;
        self.cost = self.refit_nodes(false);
        self.built_cost = self.cost;
    }

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
                        mark_dirty(&mut self.dirty, &self.parent, self.slot_node[slot as usize]);
                    }
                }
            }
            if let Source::Shape(_) = rec.source {
                let slot = self.slot_of_prim[rec.prims.start as usize];
                mark_dirty(&mut self.dirty, &self.parent, self.slot_node[slot as usize]);
            }
        }
        self.cost = self.refit_nodes(true);
        Ok(self.cost_ratio())
    }

    fn check_instances(&self, moved: &[(u32, Transform)]) -> Result<(), GeometryError> {
        match moved.iter().find(|(i, _)| *i as usize >= self.instances.len()) {
            Some(&(instance, _)) => Err(GeometryError::UnknownInstance { instance, count: self.instances.len() }),
            None => Ok(()),
        }
    }

    pub(crate) fn prim_bounds(&self, p: &LeafPrim) -> Aabb {
        if p.shape == NO_SHAPE {
            let v = p.v.map(Vec3A::from);
            Aabb::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
        } else {
            let (lo, hi) = self.shapes[p.shape as usize].world_bounds();
            Aabb::new(lo.into(), hi.into())
        }
    }

    /// Fills `parent` and `slot_node` from the CWBVH's child links.
    fn link_nodes(&mut self) {
        let nodes = &self.cwbvh.nodes;
        self.parent.clear();
        self.parent.resize(nodes.len(), 0);
        self.slot_node.clear();
        self.slot_node.resize(self.leaf.len(), 0);
        for (i, node) in nodes.iter().enumerate() {
            for ch in (0..8).filter(|&ch| !node.is_child_empty(ch)) {
                if node.is_leaf(ch) {
                    let (start, count) = node.child_primitives(ch);
                    self.slot_node[start as usize..(start + count) as usize].fill(i as u32);
                } else {
                    self.parent[node.child_node_index(ch) as usize] = i as u32;
                }
            }
        }
    }

    /// Recomputes the exact box of every dirty node bottom-up (children always follow their
    /// parent in `nodes`) and, if `requantize`, re-quantises its children as obvhs's BVH2 ->
    /// CWBVH conversion does (Ylitie et al. 2017, section 3.2). Clears the dirty flags. Returns
    /// the SAH-style cost: the sum of node surface areas over the root's.
    fn refit_nodes(&mut self, requantize: bool) -> f32 {
        let n = self.cwbvh.nodes.len();
        for i in (0..n).rev() {
            if !std::mem::take(&mut self.dirty[i]) {
                continue;
            }
            let node = self.cwbvh.nodes[i];
            let mut child = [Aabb::empty(); 8];
            let mut total = Aabb::empty();
            for (ch, child_box) in child.iter_mut().enumerate() {
                if node.is_child_empty(ch) {
                    continue;
                }
                *child_box = if node.is_leaf(ch) {
                    let (start, count) = node.child_primitives(ch);
                    (start..start + count)
                        .fold(Aabb::empty(), |b, s| b.union(&self.prim_bounds(&self.leaf[s as usize])))
                } else {
                    self.node_bounds[node.child_node_index(ch) as usize]
                };
                total = total.union(child_box);
            }
            let old = self.node_bounds[i];
            if old.valid() {
                self.area_sum -= old.half_area() as f64;
            }
            self.area_sum += total.half_area() as f64;
            self.node_bounds[i] = total;
            if requantize {
                quantize_node(&mut self.cwbvh.nodes[i], &total, &child);
            }
        }
        if n > 0 {
            self.cwbvh.total_aabb = self.node_bounds[0];
        }
        let root = self.node_bounds.first().map_or(0.0, |b| b.half_area() as f64);
        if root > 0.0 { (self.area_sum / root) as f32 } else { 0.0 }
    }

    /// Input index of the primitive in leaf slot `slot` (stable across refits; the tie-breaker
    /// that makes BVH and brute-force closest hits agree exactly).
    pub(crate) fn prim_of_slot(&self, slot: usize) -> u32 {
        self.cwbvh.primitive_indices[slot]
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

    pub(crate) fn mesh_of(&self, instance: u32) -> Option<&Mesh> {
        match self.instances[instance as usize].source {
            Source::Mesh(m) => Some(&self.meshes[m as usize]),
            Source::Shape(_) => None,
        }
    }
}

/// Flags `node` and its ancestors up to the first already-flagged one.
fn mark_dirty(dirty: &mut [bool], parent: &[u32], mut node: u32) {
    while !dirty[node as usize] {
        dirty[node as usize] = true;
        if node == 0 {
            break;
        }
        node = parent[node as usize];
    }
}

fn world_positions(mesh: &Mesh, t: &Transform) -> Vec<Vec3> {
    let a = affine(t);
    mesh.positions().iter().map(|&p| a.transform_point3(p)).collect()
}

/// Sets `node.p`, `node.e` and the 8-bit child planes from exact boxes, rounding outward.
fn quantize_node(node: &mut CwBvhNode, total: &Aabb, child: &[Aabb; 8]) {
    const DENOM: f32 = 1.0 / 255.0;
    node.p = total.min.into();
    let e = ((total.max - total.min).max(Vec3A::splat(1e-20)) * DENOM).log2().ceil().exp2();
    let rcp_e = 1.0 / e;
    let bits: glam::UVec3 = e.per_comp(|c: f32| c.to_bits() >> 23);
    node.e = [bits.x as u8, bits.y as u8, bits.z as u8];
    for (i, b) in child.iter().enumerate() {
        if node.is_child_empty(i) {
            continue;
        }
        let lo = ((b.min - total.min) * rcp_e).floor().clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        let hi = ((b.max - total.min) * rcp_e).ceil().clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        node.child_min_x[i] = lo.x as u8;
        node.child_min_y[i] = lo.y as u8;
        node.child_min_z[i] = lo.z as u8;
        node.child_max_x[i] = hi.x as u8;
        node.child_max_y[i] = hi.y as u8;
        node.child_max_z[i] = hi.z as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{Disk, Sphere};

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
    fn refit_without_motion_reproduces_the_converted_tree() {
        let mesh = Mesh::uv_sphere(1.0, 8, 6);
        let inst = scene(&mesh);
        // The build keeps obvhs's quantisation; refitting every instance in place re-quantises
        // every node and must reproduce it bit for bit.
        let bvh = SceneBvh::build(&inst);
        let mut again = bvh.clone();
        let all: Vec<(u32, Transform)> = inst.iter().enumerate().map(|(i, g)| (i as u32, g.transform)).collect();
        assert_eq!(again.refit(&all), Ok(1.0));
        assert!(again.dirty.iter().all(|d| !d));
        assert_eq!(bvh.cwbvh.nodes, again.cwbvh.nodes);
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
        assert_eq!(bvh.cwbvh.nodes, full.cwbvh.nodes);
        assert!((partial - ratio).abs() < 1e-5 && partial > 1.0, "{partial} vs {ratio}");
    }

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
