//! Ray queries on a [`SceneBvh`]: any-hit (shadow rays) and closest-hit (camera rays), one at a
//! time or batched over rayon chunks, plus brute-force references for tests.
//!
//! Queries walk the wide tree (`wide.rs`: 8 exact child boxes per node, leaf triangles in lane
//! blocks), compiled for the widest instruction set the CPU has. Its node test never culls a box
//! the exact ray meets over [0, t_max] (obvhs's own clamps box entry to t >= 1e-4, which would drop
//! occluders right next to a shadow-ray origin), and its triangle lanes decide as the scalar test
//! does, so BVH queries return exactly what testing every primitive returns (closest-hit ties go to
//! the lowest input primitive index).

use std::cell::OnceCell;

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::bvh::{GeometryId, NO_SHAPE, SceneBvh};
use super::ray::{Ray, SurfacePoint};
use super::triangle::ShearedRay;
use super::wide::{PrimBlock, triangle_block_hits};

/// Rays per rayon task in the batched queries.
pub const RAY_CHUNK: usize = 256;

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
        crate::lanes::widest(
            #[inline(always)]
            || {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = bvh.occluded_in_lanes(r, GeometryId::NONE);
                }
            },
        )
    });
}

/// Closest hit for every ray (`None` for misses and invalid rays); `out` is cleared and refilled.
pub fn closest_hits(bvh: &SceneBvh, rays: &[Ray], out: &mut Vec<Option<Hit>>) {
    out.clear();
    out.resize(rays.len(), None);
    out.par_chunks_mut(RAY_CHUNK).zip(rays.par_chunks(RAY_CHUNK)).for_each(|(out, rays)| {
        crate::lanes::widest(
            #[inline(always)]
            || {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = bvh.closest_ref_in_lanes(r).map(|h| bvh.hit_record(r, h));
                }
            },
        )
    });
}

/// The best hit so far: parameter, leaf slot, barycentrics.
#[derive(Clone, Copy, Debug)]
pub(super) struct Best {
    pub(super) t: f32,
    pub(super) slot: usize,
    pub(super) b: [f32; 3],
}

/// A closest hit before its record is built: which primitive and where on it.
/// [`SceneBvh::hit_instance`] tells what it lies on; [`SceneBvh::hit_record`] builds the [`Hit`]
/// (the normals, uvs and ids it reads are loads a ray that only looks for emitters can skip).
#[derive(Clone, Copy, Debug)]
pub struct HitRef {
    best: Best,
    /// The object-space point of a shape hit, so that the record need not find it again.
    local: Option<DVec3>,
}

impl HitRef {
    /// The ray parameter of the hit.
    pub fn t(&self) -> f32 {
        self.best.t
    }
}

impl SceneBvh {
    /// Whether `candidate` beats `best`: nearer, or as near with a lower input primitive index
    /// (the brute-force order). The index is looked up on ties only: it is a load per slot.
    #[inline(always)]
    pub(super) fn improves_on(&self, candidate: &Best, best: &Option<Best>) -> bool {
        best.is_none_or(|o| {
            candidate.t < o.t || (candidate.t == o.t && self.prim_of_slot(candidate.slot) < self.prim_of_slot(o.slot))
        })
    }

    /// Whether anything blocks `ray` in (0, t_max]; stops at the first blocker found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_from(ray, GeometryId::NONE)
    }

    /// [`Self::occluded`] for a ray leaving a point on primitive `origin` (or
    /// [`GeometryId::NONE`]): a flat `origin` does not block it (see `SceneBvh::ignores`).
    pub fn occluded_from(&self, ray: &Ray, origin: GeometryId) -> bool {
        crate::lanes::widest(
            #[inline(always)]
            || self.occluded_in_lanes(ray, origin),
        )
    }

    /// [`Self::occluded_from`] for a caller that already runs at `lanes::widest`'s level (a batch
    /// of rays, a lane kernel): the walk compiles into the caller, without a dispatch per ray.
    #[inline(always)]
    pub(crate) fn occluded_in_lanes(&self, ray: &Ray, origin: GeometryId) -> bool {
        if !ray.is_valid() || self.leaf.is_empty() {
            return false;
        }
        if self.leaf.len() <= FEW_PRIMITIVES {
            return self.occluded_each(ray, origin);
        }
        self.occluded_wide(ray, origin)
    }

    /// The nearest hit of `ray` in (0, t_max], or `None`.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_ref(ray).map(|h| self.hit_record(ray, h))
    }

    /// [`Self::closest_hit`] without its record.
    pub fn closest_hit_ref(&self, ray: &Ray) -> Option<HitRef> {
        crate::lanes::widest(
            #[inline(always)]
            || self.closest_ref_in_lanes(ray),
        )
    }

    /// [`Self::closest_hit_ref`] for a caller that already runs at `lanes::widest`'s level (see
    /// [`Self::occluded_in_lanes`]).
    #[inline(always)]
    pub(crate) fn closest_ref_in_lanes(&self, ray: &Ray) -> Option<HitRef> {
        if !ray.is_valid() || self.leaf.is_empty() {
            return None;
        }
        if self.leaf.len() <= FEW_PRIMITIVES {
            return self.closest_ref_each(ray);
        }
        self.closest_ref_wide(ray)
    }

    /// The instance (index into the built instances) that `hit` lies on.
    pub fn hit_instance(&self, hit: &HitRef) -> u32 {
        self.prim_instance[self.prim_of_slot(hit.best.slot) as usize]
    }

    /// The record of `hit`, a closest hit of `ray`: what [`Self::closest_hit`] returns.
    pub fn hit_record(&self, ray: &Ray, hit: HitRef) -> Hit {
        self.make_hit(ray, hit.best, hit.local)
    }

    /// [`Self::occluded_from`] of a valid ray over the wide tree.
    #[inline(always)]
    fn occluded_wide(&self, ray: &Ray, origin: GeometryId) -> bool {
        // Built at the first leaf: many rays leave the tree without reaching one.
        let mut sheared = None;
        let mut t_max = ray.t_max;
        let mut blocked = false;
        let complete = self.wide.traverse::<false>(
            ray,
            &mut t_max,
            #[inline(always)]
            |block: &PrimBlock, t_max: &mut f32| {
                let sheared = sheared.get_or_insert_with(|| ShearedRay::new(ray));
                blocked = self.block_blocks(block, ray, sheared, *t_max, origin);
                blocked
            },
        );
        if complete { blocked } else { self.occluded_each(ray, origin) }
    }

    /// Whether a primitive of `block` other than a flat `origin` blocks `ray` over (0, t_max].
    #[inline(always)]
    pub(super) fn block_blocks(
        &self,
        block: &PrimBlock,
        ray: &Ray,
        sheared: &ShearedRay,
        t_max: f32,
        origin: GeometryId,
    ) -> bool {
        if block.triangles != 0 {
            let (hit, exact, ..) = triangle_block_hits(block, sheared, t_max);
            let mut lanes = hit | exact;
            while lanes != 0 {
                let l = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let slot = block.slot[l] as usize;
                if self.ignores(slot, origin) {
                    continue;
                }
                if hit & (1 << l) != 0 || sheared.intersect(&self.leaf[slot].v, t_max).is_some() {
                    return true;
                }
            }
        }
        let mut lanes = block.shapes;
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let slot = block.slot[l] as usize;
            if !self.ignores(slot, origin) && self.shape_in_slot(slot).local_hit(ray, t_max).is_some() {
                return true;
            }
        }
        false
    }

    /// [`Self::closest_hit`] of a valid ray over the wide tree.
    #[inline(always)]
    fn closest_ref_wide(&self, ray: &Ray) -> Option<HitRef> {
        // Built at the first leaf: many rays leave the tree without reaching one.
        let mut sheared = None;
        let mut best: Option<Best> = None;
        // The object-space point of the best shape hit, so that `make_hit` need not find it again.
        let mut best_local = None;
        let mut t_max = ray.t_max;
        let complete = self.wide.traverse::<true>(
            ray,
            &mut t_max,
            #[inline(always)]
            |block: &PrimBlock, t_max: &mut f32| {
                let sheared = sheared.get_or_insert_with(|| ShearedRay::new(ray));
                self.closest_in_block(block, ray, sheared, t_max, &mut best, &mut best_local);
                false
            },
        );
        if !complete {
            return self.closest_ref_each(ray);
        }
        best.map(|best| HitRef { best, local: best_local })
    }

    /// Folds the hits of `block`'s primitives over (0, t_max] into `best` (lowering `t_max`).
    #[inline(always)]
    pub(super) fn closest_in_block(
        &self,
        block: &PrimBlock,
        ray: &Ray,
        sheared: &ShearedRay,
        t_max: &mut f32,
        best: &mut Option<Best>,
        best_local: &mut Option<DVec3>,
    ) {
        if block.triangles != 0 {
            let (hit, exact, t, b) = triangle_block_hits(block, sheared, *t_max);
            let mut lanes = hit | exact;
            while lanes != 0 {
                let l = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let slot = block.slot[l] as usize;
                let (t, b) = if hit & (1 << l) != 0 {
                    (t[l], [b[0][l], b[1][l], b[2][l]])
                } else {
                    match sheared.intersect(&self.leaf[slot].v, *t_max) {
                        Some(h) => (h.t, h.b),
                        None => continue,
                    }
                };
                let candidate = Best { t, slot, b };
                if self.improves_on(&candidate, best) {
                    (*best, *best_local, *t_max) = (Some(candidate), None, t);
                }
            }
        }
        let mut lanes = block.shapes;
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let slot = block.slot[l] as usize;
            if let Some((t, p)) = self.shape_in_slot(slot).local_hit(ray, *t_max) {
                let candidate = Best { t, slot, b: [0.0; 3] };
                if self.improves_on(&candidate, best) {
                    (*best, *best_local, *t_max) = (Some(candidate), Some(p), t);
                }
            }
        }
    }

    /// The shape in leaf slot `slot` (which must hold one).
    #[inline(always)]
    pub(super) fn shape_in_slot(&self, slot: usize) -> &super::shapes::PlacedShape {
        &self.shapes[self.leaf[slot].shape as usize]
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
    pub(super) fn closest_hit_each(&self, ray: &Ray) -> Option<Hit> {
        self.closest_ref_each(ray).map(|h| self.hit_record(ray, h))
    }

    /// [`Self::closest_hit_each`] without its record.
    fn closest_ref_each(&self, ray: &Ray) -> Option<HitRef> {
        let tri_ray = OnceCell::new();
        let mut best: Option<Best> = None;
        let mut best_local = None;
        let mut t_max = ray.t_max;
        for prim in 0..self.leaf.len() as u32 {
            let slot = self.slot_of(prim);
            // Farther hits cannot win; a tie at t_max still reaches the tie-break below.
            let Some((t, b, local)) = self.slot_hit(slot, ray, &tri_ray, t_max) else { continue };
            let candidate = Best { t, slot, b };
            if self.improves_on(&candidate, &best) {
                best = Some(candidate);
                best_local = local;
                t_max = t;
            }
        }
        best.map(|best| HitRef { best, local: best_local })
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
    pub(super) fn make_hit(&self, ray: &Ray, best: Best, local: Option<DVec3>) -> Hit {
        let leaf = &self.leaf[best.slot];
        if leaf.shape != NO_SHAPE {
            let (instance, id, material) = self.id_of(self.prim_of_slot(best.slot));
            let shape = &self.shapes[leaf.shape as usize];
            let (sp, uv) = match local.map(|p| shape.hit_at_local(best.t, p)) {
                Some(h) => (h.point, h.uv),
                // Unreachable (shape hits carry their point); stay finite rather than panic.
                None => (SurfacePoint::from_point(ray.at(best.t), -ray.dir.normalize()), Vec2::ZERO),
            };
            return Hit { t: best.t, p: sp.p, p_error: sp.p_error, ng: sp.n, ns: sp.n, uv, id, material, instance };
        }
        self.triangle_attributes(self.prim_of_slot(best.slot), best.slot).hit(best.t, best.b)
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
        let bvh = SceneBvh::of_mesh(&tri);
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
        let bvh = SceneBvh::of_mesh(&quad);
        for x in [-0.999f32, -0.5, 0.0, 0.25, 0.999] {
            let down = Ray::new(Vec3::new(x, 3.0, 0.1), Vec3::NEG_Y);
            assert!(bvh.occluded(&down), "x = {x}");
            let h = bvh.closest_hit(&down).unwrap();
            assert_eq!(h.ng, Vec3::NEG_Y);
        }
        assert!(!bvh.occluded(&Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::NEG_Z)), "in-plane ray");
    }
}
