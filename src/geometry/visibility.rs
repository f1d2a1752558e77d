//! Ray queries on a [`SceneBvh`]: any-hit (shadow rays) and closest-hit (camera rays), one at a
//! time or batched over rayon chunks, plus brute-force references for tests.
//!
//! Traversal uses obvhs's `traverse!` loop with our own node test. obvhs's node test clamps box
//! entry to t >= 1e-4 (which would drop occluders right next to a shadow-ray origin) and replaces
//! tiny direction components by +-1/f32::EPSILON; ours honours t in [0, t_max] exactly and pads
//! each slab by a bound on its own rounding (see `NODE_PAD`), so it never culls a box the exact
//! ray meets. With primitive tests shared between the two paths, BVH queries then return exactly
//! what testing every primitive returns (closest-hit ties go to the lowest input primitive index).

use std::cell::OnceCell;

use glam::{DVec3, UVec2, Vec2, Vec3, Vec3A, Vec4};
use obvhs::cwbvh::node::{CwBvhNode, extract_byte64};
use rayon::prelude::*;

use super::bvh::{GeometryId, NO_SHAPE, SceneBvh};
use super::ray::{Ray, SurfacePoint, triangle_point_error};
use super::triangle::ShearedRay;

/// Rays per rayon task in the batched queries.
pub const RAY_CHUNK: usize = 256;

/// Relative padding of each slab and of `t_max` in the node test (2^-18, 64 f32 ulps). A slab
/// parameter `q e / d + (p - o) / d` is computed with at most 5 roundings (error below
/// gamma(5) (|p - o| + 255 e) / |d|), and quantising child boxes can shave up to ~1000 ulps of
/// `e`; 2^-18 (|p - o| + 256 e) / |d| covers both with room to spare.
const NODE_PAD: f32 = 1.0 / (1u32 << 18) as f32;

/// Cap on |1/d| so that zero direction components give huge but finite slab parameters
/// (never inf * 0 = NaN): 2^100, valid for scene coordinates below 2^20.
const MAX_INV_DIR: f32 = 1.267_650_6e30;

/// Up to this many primitives, queries test each one rather than walk the tree: the same answers
/// (see the module docs), without the traversal's setup.
pub(super) const FEW_PRIMITIVES: usize = 4;

/// A closest hit, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Hit point, metres.
    pub p: Vec3,
    /// Per-axis error bound of `p` (see `ray.rs`).
    pub p_error: Vec3,
    /// Unit geometric normal: counter-clockwise front for triangles, outward / +Z for shapes.
    pub ng: Vec3,
    /// Unit shading normal (interpolated vertex normals, else `ng`); not flipped toward `ng`.
    pub ns: Vec3,
    /// Texture coordinates (interpolated; the barycentrics (b1, b2) if the mesh has none).
    pub uv: Vec2,
    /// Entity and primitive that were hit.
    pub id: GeometryId,
    /// Material id of the instance.
    pub material: u32,
    /// Instance index (position in the slice given to `SceneBvh::build`).
    pub instance: u32,
}

impl Hit {
    /// The hit as a surface point for spawning shadow rays (geometric normal).
    pub fn surface_point(&self) -> SurfacePoint {
        SurfacePoint { p: self.p, p_error: self.p_error, n: self.ng }
    }
}

/// Any-hit for every ray: `out[i]` is true if something blocks `rays[i]` in (0, t_max].
/// Invalid rays (see [`Ray::is_valid`]) are reported unoccluded. `out` is cleared and refilled,
/// so a caller can reuse its buffer across frames.
pub fn occluded(bvh: &SceneBvh, rays: &[Ray], out: &mut Vec<bool>) {
    out.clear();
    out.resize(rays.len(), false);
    out.par_chunks_mut(RAY_CHUNK).zip(rays.par_chunks(RAY_CHUNK)).for_each(|(out, rays)| {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = bvh.occluded(r);
        }
    });
}

/// Closest hit for every ray (`None` for misses and invalid rays); `out` is cleared and refilled.
pub fn closest_hits(bvh: &SceneBvh, rays: &[Ray], out: &mut Vec<Option<Hit>>) {
    out.clear();
    out.resize(rays.len(), None);
    out.par_chunks_mut(RAY_CHUNK).zip(rays.par_chunks(RAY_CHUNK)).for_each(|(out, rays)| {
        for (o, r) in out.iter_mut().zip(rays) {
            *o = bvh.closest_hit(r);
        }
    });
}

/// Per-ray constants of the node test.
struct NodeRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    inv_abs: Vec3A,
    neg: [bool; 3],
}

impl NodeRay {
    fn new(ray: &Ray) -> Self {
        let inv = |d: f32| {
            let i = 1.0 / d;
            if i.is_finite() && i.abs() <= MAX_INV_DIR { i } else { MAX_INV_DIR.copysign(d) }
        };
        let inv_dir = Vec3A::new(inv(ray.dir.x), inv(ray.dir.y), inv(ray.dir.z));
        let neg = [inv_dir.x < 0.0, inv_dir.y < 0.0, inv_dir.z < 0.0];
        Self { origin: ray.origin.into(), inv_dir, inv_abs: inv_dir.abs(), neg }
    }

    /// Hit mask of the node's children over t in [0, t_max], in obvhs's layout: inner children
    /// in the high byte (by traversal priority), leaf primitives in the low 24 bits.
    #[inline(always)]
    fn intersect(&self, node: &CwBvhNode, t_max: f32, oct_inv4: u32) -> u32 {
        let e = node.compute_extent();
        let rel = Vec3A::from(node.p) - self.origin;
        let scale = e * self.inv_dir;
        let adj = rel * self.inv_dir;
        let pad = (rel.abs() + 256.0 * e) * self.inv_abs * NODE_PAD;
        let (near, far) = (adj - pad, adj + pad);
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        let t_max = Vec4::splat(t_max * (1.0 + NODE_PAD));
        let mut hit_mask = 0;
        for half in 0..2 {
            let q = |a: &[u8; 8]| {
                let i = 4 * half;
                Vec4::new(a[i] as f32, a[i + 1] as f32, a[i + 2] as f32, a[i + 3] as f32)
            };
            let slab = |lo: &[u8; 8], hi: &[u8; 8], neg: bool| if neg { (q(hi), q(lo)) } else { (q(lo), q(hi)) };
            let (nx, fx) = slab(&node.child_min_x, &node.child_max_x, self.neg[0]);
            let (ny, fy) = slab(&node.child_min_y, &node.child_max_y, self.neg[1]);
            let (nz, fz) = slab(&node.child_min_z, &node.child_max_z, self.neg[2]);
            let t_near = (nx * scale.x + near.x).max(ny * scale.y + near.y).max(nz * scale.z + near.z).max(Vec4::ZERO);
            let t_far = (fx * scale.x + far.x).min(fy * scale.y + far.y).min(fz * scale.z + far.z).min(t_max);
            let mask = t_near.cmple(t_far).bitmask();
            for j in 0..4 {
                if mask & (1 << j) != 0 {
                    let c = 4 * half + j;
                    hit_mask |= extract_byte64(child_bits8, c) << extract_byte64(bit_index8, c);
                }
            }
        }
        hit_mask
    }
}

/// The best hit so far: parameter, input primitive index (tie-breaker), slot, barycentrics.
#[derive(Clone, Copy)]
struct Best {
    t: f32,
    prim: u32,
    slot: usize,
    b: [f32; 3],
}

impl Best {
    fn improves_on(&self, other: &Option<Best>) -> bool {
        other.is_none_or(|o| self.t < o.t || (self.t == o.t && self.prim < o.prim))
    }
}

impl SceneBvh {
    /// Whether anything blocks `ray` in (0, t_max]; stops at the first blocker found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_from(ray, GeometryId::NONE)
    }

    /// [`Self::occluded`] for a ray leaving a point on primitive `origin` (or
    /// [`GeometryId::NONE`]): a flat `origin` does not block it (see [`Self::ignores`]).
    pub fn occluded_from(&self, ray: &Ray, origin: GeometryId) -> bool {
        if !ray.is_valid() || self.leaf.is_empty() {
            return false;
        }
        if self.leaf.len() <= FEW_PRIMITIVES {
            return self.occluded_each(ray, origin);
        }
        let tri_ray = OnceCell::new();
        let node_ray = NodeRay::new(ray);
        let mut state = self.cwbvh.new_traversal(Vec3A::from(ray.dir));
        let mut node;
        let mut blocked = false;
        'traversal: {
            obvhs::traverse!(self.cwbvh, node, state, node_ray.intersect(node, ray.t_max, state.oct_inv4), {
                let slot = state.primitive_id as usize;
                if !self.ignores(slot, origin) && self.slot_hit(slot, ray, &tri_ray, ray.t_max).is_some() {
                    blocked = true;
                    break 'traversal;
                }
            });
        }
        blocked
    }

    /// The nearest hit of `ray` in (0, t_max], or `None`.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() || self.leaf.is_empty() {
            return None;
        }
        if self.leaf.len() <= FEW_PRIMITIVES {
            return self.closest_hit_each(ray);
        }
        let tri_ray = OnceCell::new();
        let node_ray = NodeRay::new(ray);
        let mut state = self.cwbvh.new_traversal(Vec3A::from(ray.dir));
        let mut node;
        let mut best: Option<Best> = None;
        // The object-space point of the best shape hit, so that `make_hit` need not find it again.
        let mut best_local = None;
        let mut t_max = ray.t_max;
        obvhs::traverse!(self.cwbvh, node, state, node_ray.intersect(node, t_max, state.oct_inv4), {
            let slot = state.primitive_id as usize;
            if let Some((t, b, local)) = self.slot_hit(slot, ray, &tri_ray, t_max) {
                let candidate = Best { t, prim: self.prim_of_slot(slot), slot, b };
                if candidate.improves_on(&best) {
                    best = Some(candidate);
                    best_local = local;
                    t_max = t;
                }
            }
        });
        best.map(|b| self.make_hit(ray, b, best_local))
    }

    /// Reference any-hit: tests every primitive. For tests and benchmarks.
    pub fn occluded_brute_force(&self, ray: &Ray) -> bool {
        ray.is_valid() && self.occluded_each(ray, GeometryId::NONE)
    }

    /// Reference closest-hit: tests every primitive, ties to the lowest input index.
    pub fn closest_hit_brute_force(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        self.closest_hit_each(ray)
    }

    /// [`Self::occluded_from`] of a valid ray, testing every primitive.
    fn occluded_each(&self, ray: &Ray, origin: GeometryId) -> bool {
        let tri_ray = OnceCell::new();
        let blocks = |slot| !self.ignores(slot, origin) && self.slot_hit(slot, ray, &tri_ray, ray.t_max).is_some();
        (0..self.leaf.len()).any(blocks)
    }

    /// [`Self::closest_hit_brute_force`] for a valid ray.
    fn closest_hit_each(&self, ray: &Ray) -> Option<Hit> {
        let tri_ray = OnceCell::new();
        let mut best: Option<Best> = None;
        let mut best_local = None;
        let mut t_max = ray.t_max;
        for prim in 0..self.leaf.len() as u32 {
            let slot = self.slot_of(prim);
            // Farther hits cannot win; a tie at t_max still reaches the tie-break below.
            let Some((t, b, local)) = self.slot_hit(slot, ray, &tri_ray, t_max) else { continue };
            let candidate = Best { t, prim, slot, b };
            if candidate.improves_on(&best) {
                best = Some(candidate);
                best_local = local;
                t_max = t;
            }
        }
        best.map(|b| self.make_hit(ray, b, best_local))
    }

    /// The primitive in leaf slot `slot` against `ray` over (0, t_max]: t, barycentrics
    /// (triangles) and the object-space point (shapes). The sheared ray of the triangle test is
    /// built at the first triangle, so rays through shapes alone never build one.
    #[inline(always)]
    fn slot_hit(
        &self,
        slot: usize,
        ray: &Ray,
        tri_ray: &OnceCell<ShearedRay>,
        t_max: f32,
    ) -> Option<(f32, [f32; 3], Option<DVec3>)> {
        let prim = &self.leaf[slot];
        if prim.shape == NO_SHAPE {
            tri_ray.get_or_init(|| ShearedRay::new(ray)).intersect(&prim.v, t_max).map(|h| (h.t, h.b, None))
        } else {
            self.shapes[prim.shape as usize].local_hit(ray, t_max).map(|(t, p)| (t, [0.0; 3], Some(p)))
        }
    }

    /// The full hit record of `best`; `local` is the object-space point of a shape hit.
    fn make_hit(&self, ray: &Ray, best: Best, local: Option<DVec3>) -> Hit {
        let (instance, id, material) = self.id_of(best.prim);
        let leaf = &self.leaf[best.slot];
        if leaf.shape != NO_SHAPE {
            let shape = &self.shapes[leaf.shape as usize];
            let (sp, uv) = match local.map(|p| shape.hit_at_local(best.t, p)) {
                Some(h) => (h.point, h.uv),
                // Unreachable (shape hits carry their point); stay finite rather than panic.
                None => (SurfacePoint::from_point(ray.at(best.t), -ray.dir.normalize()), Vec2::ZERO),
            };
            return Hit { t: best.t, p: sp.p, p_error: sp.p_error, ng: sp.n, ns: sp.n, uv, id, material, instance };
        }
        let (v, b) = (&leaf.v, best.b);
        let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
        let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or(Vec3::Z);
        let mut ns = ng;
        let mut uv = Vec2::new(b[1], b[2]);
        if let Some(mesh) = self.mesh_of(instance) {
            let idx = mesh.triangle_indices(id.primitive as usize).map(|k| k as usize);
            if let Some(n) = mesh.normals() {
                let local = b[0] * n[idx[0]] + b[1] * n[idx[1]] + b[2] * n[idx[2]];
                let tr = self.instances[instance as usize].transform;
                // Normals map by the inverse transpose: rotation * (n / scale).
                let world = (tr.rotation * (local / tr.scale)).normalize_or_zero();
                if world.is_finite() && world != Vec3::ZERO {
                    ns = world;
                }
            }
            if let Some(t) = mesh.uvs() {
                uv = b[0] * t[idx[0]] + b[1] * t[idx[1]] + b[2] * t[idx[2]];
            }
        }
        Hit { t: best.t, p, p_error: triangle_point_error(v, b), ng, ns, uv, id, material, instance }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{GeometryInstance, GeometryRef, Mesh, Sphere, Transform};

    #[test]
    fn empty_and_single_primitive_scenes() {
        let empty = SceneBvh::build(&[]);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z);
        assert!(!empty.occluded(&ray) && empty.closest_hit(&ray).is_none());
        let one = SceneBvh::build(&[GeometryInstance {
            geometry: GeometryRef::Shape(Sphere { radius: 1.0 }.into()),
            transform: Transform::IDENTITY,
            entity_index: 9,
            material: 2,
        }]);
        let hit = one.closest_hit(&ray).unwrap();
        assert!((hit.t - 4.0).abs() < 1e-6 && hit.id.entity_index == 9 && hit.material == 2);
        assert!(one.occluded(&ray) && !one.occluded(&Ray { t_max: 3.9, ..ray }));
    }

    #[test]
    fn occluder_right_next_to_the_origin_is_found() {
        // obvhs's stock node test would cull boxes closer than t = 1e-4.
        let tri =
            Mesh::from_triangles(&[[Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]]);
        let tri = tri.unwrap();
        let bvh = SceneBvh::build(&[GeometryInstance {
            geometry: GeometryRef::Mesh(&tri),
            transform: Transform::IDENTITY,
            entity_index: 0,
            material: 0,
        }]);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 1e-6), Vec3::NEG_Z);
        assert!(bvh.occluded(&ray));
        assert!((bvh.closest_hit(&ray).unwrap().t - 1e-6).abs() < 1e-12);
    }

    #[test]
    fn axis_aligned_rays_hit_flat_boxes() {
        // Zero direction components and zero-thickness boxes together.
        let quad = Mesh::from_triangles(&[
            [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0)],
            [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0)],
        ])
        .unwrap();
        let bvh = SceneBvh::build(&[GeometryInstance {
            geometry: GeometryRef::Mesh(&quad),
            transform: Transform::IDENTITY,
            entity_index: 0,
            material: 0,
        }]);
        for x in [-0.999f32, -0.5, 0.0, 0.25, 0.999] {
            let down = Ray::new(Vec3::new(x, 3.0, 0.1), Vec3::NEG_Y);
            assert!(bvh.occluded(&down), "x = {x}");
            let h = bvh.closest_hit(&down).unwrap();
            assert_eq!(h.ng, Vec3::NEG_Y);
        }
        assert!(!bvh.occluded(&Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::NEG_Z)), "in-plane ray");
    }
}
