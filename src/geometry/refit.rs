//! Moving instances: refit the CWBVH in place, or rebuild when the tree has degraded.
//!
//! A refit rewrites the moved instances' world-space primitives, flags the nodes on their paths
//! to the root, and recomputes those nodes' exact boxes bottom-up (children always follow their
//! parent in `nodes`), re-quantising their 8-bit child planes exactly as obvhs's BVH2 -> CWBVH
//! conversion does. The topology is kept; the SAH-style cost (sum of node areas over the root's)
//! is updated incrementally so [`SceneBvh::update_transforms`] can decide when to rebuild.

use glam::Vec3A;
use obvhs::PerComponent;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;

use super::GeometryError;
use super::bvh::{REBUILD_COST_RATIO, SceneBvh, Source, UpdateKind, mesh_transform_ok, world_positions};
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
        let mut wide = std::mem::take(&mut self.wide);
        wide.refit(&super::bvh::LeafView(self));
        self.wide = wide;
        Ok(self.cost_ratio())
    }

    fn check_instances(&self, moved: &[(u32, Transform)]) -> Result<(), GeometryError> {
        match moved.iter().find(|(i, _)| *i as usize >= self.instances.len()) {
            Some(&(instance, _)) => Err(GeometryError::UnknownInstance { instance, count: self.instances.len() }),
            None => Ok(()),
        }
    }

    /// Fills `parent` and `slot_node` from the CWBVH's child links.
    pub(crate) fn link_nodes(&mut self) {
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
    pub(crate) fn refit_nodes(&mut self, requantize: bool) -> f32 {
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
