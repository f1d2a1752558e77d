//! Ray queries of [`LANES`] rays at once for scenes of a few flat shapes (a ground rectangle, a
//! disk light): the answers of [`SceneBvh::closest_hit`] and [`SceneBvh::occluded_from`] bit for
//! bit, from the same f64 operations in the same order (`PlacedShape::object_row`,
//! `flat_hit_from_rows`, `PlacedShape::flat_world_coordinate`) run as lane loops, which compile
//! to vector code inside `lanes::widest`. Other scenes answer one ray at a time.

use glam::{Vec2, Vec3};

use super::bvh::{GeometryId, NO_SHAPE, SceneBvh};
use super::ray::{Lanes3, Ray};
use super::shapes::{PlacedShape, Shape, flat_hit_from_rows};
use super::visibility::{FEW_PRIMITIVES, Hit};
use crate::lanes::LANES;

/// [`LANES`] rays as lane columns, widened to f64 (the precision of the flat-shape test).
/// Lanes never set hold invalid rays (zero direction), which hit nothing.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct RayLanes {
    o: [[f64; LANES]; 3],
    d: [[f64; LANES]; 3],
    t_max: [f32; LANES],
    /// [`Ray::is_valid`] per lane.
    valid: [bool; LANES],
}

impl Default for RayLanes {
    fn default() -> Self {
        Self { o: [[0.0; LANES]; 3], d: [[0.0; LANES]; 3], t_max: [0.0; LANES], valid: [false; LANES] }
    }
}

impl RayLanes {
    /// The rays as lanes.
    #[inline(always)]
    pub fn from_rays(rays: &[Ray; LANES]) -> Self {
        let mut r = Self::default();
        for (l, ray) in rays.iter().enumerate() {
            r.set(l, ray);
        }
        r
    }

    /// Rays from lane columns of origins and directions, all with the same `t_max`.
    #[inline(always)]
    pub fn from_columns([origin, dir]: &[Lanes3; 2], t_max: f32) -> Self {
        let mut valid = [false; LANES];
        for (l, valid) in valid.iter_mut().enumerate() {
            let finite = (0..3).all(|a| origin[a][l].is_finite() && dir[a][l].is_finite());
            let nonzero = dir[0][l] != 0.0 || dir[1][l] != 0.0 || dir[2][l] != 0.0;
            *valid = finite && nonzero && t_max > 0.0;
        }
        // Built whole, not over `default()`: t_max written lane by lane came out as two half
        // stores, and the full-width load of it in `closest_hits_lanes` stalled on them.
        let widen = |c: &Lanes3| c.map(|row| row.map(f64::from));
        Self { o: widen(origin), d: widen(dir), t_max: [t_max; LANES], valid }
    }

    /// Puts `ray` in lane `l`, reading its fields one by one (copying whole `Ray`s between
    /// arrays stalls on store-to-load forwarding).
    #[inline(always)]
    pub fn set(&mut self, l: usize, ray: &Ray) {
        for a in 0..3 {
            (self.o[a][l], self.d[a][l]) = (ray.origin[a] as f64, ray.dir[a] as f64);
        }
        (self.t_max[l], self.valid[l]) = (ray.t_max, ray.is_valid());
    }

    /// The ray of lane `l` (exact: the f64 values came from f32).
    fn ray(&self, l: usize) -> Ray {
        let v = |c: &[[f64; LANES]; 3]| Vec3::new(c[0][l] as f32, c[1][l] as f32, c[2][l] as f32);
        Ray { origin: v(&self.o), dir: v(&self.d), t_max: self.t_max[l] }
    }

    #[inline(always)]
    fn origin(&self, l: usize) -> [f64; 3] {
        [self.o[0][l], self.o[1][l], self.o[2][l]]
    }

    #[inline(always)]
    fn dir(&self, l: usize) -> [f64; 3] {
        [self.d[0][l], self.d[1][l], self.d[2][l]]
    }
}

/// The flat-shape hit test (`PlacedShape::local_hit`) of every lane over (0, t_max[l]]: hit
/// flags, t, object-space x and y. Each shape kind gets its own loop, so that no `match` stops it vectorising.
#[inline(always)]
fn flat_hits(shape: &PlacedShape, r: &RayLanes, t_max: &[f32; LANES]) -> FlatHits {
    #[inline(always)]
    fn each(shape: &PlacedShape, r: &RayLanes, t_max: &[f32; LANES], contains: impl Fn(f64, f64) -> bool) -> FlatHits {
        // One step per loop over all lanes, so that LLVM vectorises across lanes.
        let (mut o_row, mut d_row) = ([[0.0f64; LANES]; 3], [[0.0f64; LANES]; 3]);
        for i in 0..3 {
            for l in 0..LANES {
                (o_row[i][l], d_row[i][l]) = shape.object_row(i, r.origin(l), r.dir(l));
            }
        }
        let mut out = FlatHits::default();
        for l in 0..LANES {
            let rows = [(o_row[0][l], d_row[0][l]), (o_row[1][l], d_row[1][l]), (o_row[2][l], d_row[2][l])];
            (out.hit[l], out.t[l], out.x[l], out.y[l]) = flat_hit_from_rows(rows, t_max[l], &contains);
        }
        out
    }
    match shape.shape {
        Shape::Rectangle(rect) => each(shape, r, t_max, |x, y| Shape::Rectangle(rect).flat_contains(x, y)),
        Shape::Disk(disk) => each(shape, r, t_max, |x, y| Shape::Disk(disk).flat_contains(x, y)),
        Shape::Sphere(_) => FlatHits::default(),
    }
}

/// What [`flat_hits`] finds per lane: whether the ray hits, t, and the object-space x and y.
/// 64-byte aligned, as `RayLanes` is (a tuple of these arrays had them straddle cache lines).
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct FlatHits {
    x: [f64; LANES],
    y: [f64; LANES],
    t: [f32; LANES],
    hit: [bool; LANES],
}

/// [`Shape::flat_uv`] of every lane, one loop per shape kind (as [`flat_hits`]).
#[inline(always)]
fn flat_uvs(shape: &Shape, x: &[f64; LANES], y: &[f64; LANES]) -> [[f32; LANES]; 2] {
    #[inline(always)]
    fn each(x: &[f64; LANES], y: &[f64; LANES], uv: impl Fn(f64, f64) -> Vec2) -> [[f32; LANES]; 2] {
        let mut out = [[0.0; LANES]; 2];
        for l in 0..LANES {
            (out[0][l], out[1][l]) = uv(x[l], y[l]).into();
        }
        out
    }
    match *shape {
        Shape::Rectangle(rect) => each(x, y, |x, y| Shape::Rectangle(rect).flat_uv(x, y)),
        Shape::Disk(disk) => each(x, y, |x, y| Shape::Disk(disk).flat_uv(x, y)),
        Shape::Sphere(_) => [[0.0; LANES]; 2],
    }
}

/// The closest hits of `LANES` rays that all hit the same flat primitive, as lane columns.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct FlatHitBlock {
    pub t: [f32; LANES],
    pub p: [[f32; LANES]; 3],
    pub p_error: [[f32; LANES]; 3],
    pub uv: [[f32; LANES]; 2],
    /// The shape's normal: the geometric and the shading normal of every lane.
    pub n: Vec3,
    pub id: GeometryId,
    pub material: u32,
    pub instance: u32,
}

impl FlatHitBlock {
    /// Lane `l` as a [`Hit`].
    #[inline(always)]
    pub fn hit(&self, l: usize) -> Hit {
        let v = |c: &[[f32; LANES]; 3]| Vec3::new(c[0][l], c[1][l], c[2][l]);
        let (t, n, uv) = (self.t[l], self.n, Vec2::new(self.uv[0][l], self.uv[1][l]));
        Hit {
            t,
            p: v(&self.p),
            p_error: v(&self.p_error),
            ng: n,
            ns: n,
            uv,
            id: self.id,
            material: self.material,
            instance: self.instance,
        }
    }
}

/// Where [`SceneBvh::closest_hits_lanes`] hands its hits. Any `FnMut(lane, hit)` is one.
pub trait HitSink {
    /// The closest hit of lane `l` (None: the ray hit nothing).
    fn hit(&mut self, l: usize, hit: Option<Hit>);
    /// Every lane hit the same flat primitive. By default, its lanes one by one.
    #[inline(always)]
    fn block(&mut self, hits: &FlatHitBlock) {
        for l in 0..LANES {
            self.hit(l, Some(hits.hit(l)));
        }
    }
}

impl<F: FnMut(usize, Option<Hit>)> HitSink for F {
    #[inline(always)]
    fn hit(&mut self, l: usize, hit: Option<Hit>) {
        self(l, hit)
    }
}

/// The leaf slot of no primitive.
const NO_SLOT: usize = usize::MAX;

impl SceneBvh {
    /// Whether [`Self::closest_hits_lanes`] and [`Self::occluded_lanes`] run in lanes: the scene
    /// has one to `FEW_PRIMITIVES` primitives, all flat shapes. Otherwise they answer one ray at
    /// a time, and callers holding single rays may as well ask for them directly.
    #[inline(always)]
    pub fn few_flat_shapes(&self) -> bool {
        let flat = |s: u32| s != NO_SHAPE && !matches!(self.shapes[s as usize].shape, Shape::Sphere(_));
        !self.leaf.is_empty() && self.leaf.len() <= FEW_PRIMITIVES && self.leaf.iter().all(|p| flat(p.shape))
    }

    /// [`Self::closest_hit`] of the `LANES` rays `r`, bit for bit, handed to `out` in place (a
    /// returned array of hits would be copied once more): lane by lane, or as one block when
    /// every lane hit the same flat primitive.
    #[inline(always)]
    pub fn closest_hits_lanes(&self, r: &RayLanes, out: &mut impl HitSink) {
        if !self.few_flat_shapes() {
            for l in 0..LANES {
                out.hit(l, self.closest_hit(&r.ray(l)));
            }
            return;
        }
        // As `closest_hit_each`: primitives in input order; a later one wins only when nearer.
        let (mut best_t, mut best_slot) = (r.t_max, [NO_SLOT; LANES]);
        let (mut best_x, mut best_y) = ([0.0f64; LANES], [0.0f64; LANES]);
        for prim in 0..self.leaf.len() as u32 {
            let slot = self.slot_of(prim);
            let hits = flat_hits(&self.shapes[self.leaf[slot].shape as usize], r, &best_t);
            for l in 0..LANES {
                let (hit, t, x, y) = (hits.hit[l], hits.t[l], hits.x[l], hits.y[l]);
                let first = best_slot[l] == NO_SLOT;
                if r.valid[l] & hit & (first | (t < best_t[l])) {
                    (best_t[l], best_slot[l], best_x[l], best_y[l]) = (t, slot, x, y);
                }
            }
        }
        if best_slot[0] != NO_SLOT && best_slot.iter().all(|&s| s == best_slot[0]) {
            out.block(&self.flat_hit_block(best_slot[0], &best_t, &best_x, &best_y));
            return;
        }
        for l in (0..LANES).filter(|&l| best_slot[l] == NO_SLOT) {
            out.hit(l, None);
        }
        // Hit records, one primitive's lanes at a time.
        for slot in 0..self.leaf.len() {
            if !best_slot.contains(&slot) {
                continue;
            }
            let block = self.flat_hit_block(slot, &best_t, &best_x, &best_y);
            for l in (0..LANES).filter(|&l| best_slot[l] == slot) {
                out.hit(l, Some(block.hit(l)));
            }
        }
    }

    /// The hit records of every lane as hits on leaf `slot` at flat coordinates (x, y).
    #[inline(always)]
    fn flat_hit_block(&self, slot: usize, t: &[f32; LANES], x: &[f64; LANES], y: &[f64; LANES]) -> FlatHitBlock {
        let shape = &self.shapes[self.leaf[slot].shape as usize];
        let (mut p, mut p_error) = ([[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3]);
        for a in 0..3 {
            for l in 0..LANES {
                (p[a][l], p_error[a][l]) = shape.flat_world_coordinate(a, x[l], y[l]);
            }
        }
        let uv = flat_uvs(&shape.shape, x, y);
        let (instance, id, material) = self.id_of(self.prim_of_slot(slot));
        let n = shape.flat_normal.unwrap_or(Vec3::Z);
        FlatHitBlock { t: *t, p, p_error, uv, n, id, material, instance }
    }

    /// [`Self::occluded_from`] of the first `n` of `LANES` rays, leaving from `origins`, bit for
    /// bit (later lanes: false).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops on purpose (see below)
    pub fn occluded_lanes(&self, r: &RayLanes, n: usize, origins: &[GeometryId; LANES]) -> [bool; LANES] {
        let mut out = [false; LANES];
        if !self.few_flat_shapes() {
            for (l, o) in out.iter_mut().enumerate().take(n) {
                *o = self.occluded_from(&r.ray(l), origins[l]);
            }
            return out;
        }
        // Plain index loops: iterator adapters may stay out of the wide code.
        let mut origin = [0u64; LANES];
        for l in 0..LANES {
            origin[l] = origins[l].key();
        }
        for slot in 0..self.leaf.len() {
            // Every primitive here is flat, so none blocks rays leaving it (`Self::ignores`).
            let id = self.geometry_of_slot(slot).key();
            let mut others = [false; LANES];
            for l in 0..LANES {
                others[l] = origin[l] != id;
            }
            if !others.contains(&true) {
                continue;
            }
            let hits = flat_hits(&self.shapes[self.leaf[slot].shape as usize], r, &r.t_max);
            for l in 0..LANES {
                out[l] |= hits.hit[l] & others[l];
            }
        }
        for l in 0..LANES {
            out[l] &= r.valid[l] & (l < n);
        }
        out
    }

    /// Whether no primitive can block rays leaving `origins`: the scene is one flat primitive,
    /// and every ray leaves it. Callers may then skip building the rays.
    #[inline(always)]
    pub fn blocks_nothing_from(&self, origins: &[GeometryId]) -> bool {
        let Some(&first) = origins.first() else { return true };
        if self.leaf.len() != 1 || !self.ignores(0, first) {
            return false;
        }
        // A fold without early exit, so that it vectorises over long slices.
        let key = first.key();
        origins.iter().fold(true, |all, o| all & (o.key() == key))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, GeometryInstance, GeometryRef, Rectangle, Transform};
    use crate::rng::SplitMix64;
    use glam::{Quat, Vec2};

    fn scene(shapes: &[(Shape, Transform)]) -> SceneBvh {
        let instances: Vec<_> = shapes
            .iter()
            .enumerate()
            .map(|(i, &(shape, transform))| GeometryInstance {
                geometry: GeometryRef::Shape(shape),
                transform,
                entity_index: i as u32,
                material: 10 + i as u32,
            })
            .collect();
        SceneBvh::build(&instances)
    }

    /// Rays from around the shapes toward points near them (some short), plus hard cases: a ray
    /// in the plane, zero, NaN and infinite directions, a zero t_max, a t_max just short of the
    /// plane.
    fn rays(rng: &mut SplitMix64) -> Vec<Ray> {
        let mut v = |s: Vec3| Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * s;
        let mut rays: Vec<Ray> = (0..500)
            .map(|i| {
                let (from, to) = (v(Vec3::splat(8.0)), v(Vec3::new(5.0, 4.0, 0.5)));
                let t_max = if i % 5 == 0 { 2.0 } else { f32::INFINITY };
                Ray { t_max, ..Ray::new(from, (to - from).normalize_or(Vec3::X)) }
            })
            .collect();
        let down = Ray::new(Vec3::new(0.3, 0.2, 2.0), Vec3::NEG_Z);
        rays.extend([
            Ray::new(Vec3::new(-5.0, 0.1, 0.0), Vec3::X),
            Ray::new(Vec3::ONE, Vec3::ZERO),
            Ray::new(Vec3::ONE, Vec3::new(f32::NAN, 0.0, -1.0)),
            Ray::new(Vec3::ONE, Vec3::new(0.0, f32::INFINITY, -1.0)),
            Ray { t_max: 0.0, ..down },
            Ray { t_max: 2.0f32.next_down(), ..down },
            Ray { t_max: 2.0, ..down },
            down,
        ]);
        rays
    }

    #[test]
    fn lanes_from_columns_equal_lanes_from_rays() {
        let mut rng = SplitMix64::new(5);
        let mut rays = rays(&mut rng);
        rays.retain(|r| r.t_max == f32::INFINITY);
        rays.reverse(); // The hard cases (zero, NaN and infinite directions) come first.
        for block in rays.chunks_exact(LANES) {
            let rays: [Ray; LANES] = std::array::from_fn(|l| block[l]);
            let column =
                |f: fn(&Ray) -> Vec3| -> Lanes3 { std::array::from_fn(|a| std::array::from_fn(|l| f(&rays[l])[a])) };
            let (a, b) = (
                RayLanes::from_rays(&rays),
                RayLanes::from_columns(&[column(|r| r.origin), column(|r| r.dir)], f32::INFINITY),
            );
            let bits =
                |r: &RayLanes| (r.o.map(|c| c.map(f64::to_bits)), r.d.map(|c| c.map(f64::to_bits)), r.t_max, r.valid);
            assert_eq!(bits(&a), bits(&b));
        }
    }

    #[test]
    fn flat_lanes_match_one_ray_at_a_time() {
        let tilted = Transform {
            rotation: Quat::from_rotation_x(0.7) * Quat::from_rotation_y(-0.3),
            ..Transform::from_translation(Vec3::new(0.5, 0.0, 0.25))
        };
        let rect = Shape::Rectangle(Rectangle { half_size: Vec2::new(2.0, 1.0) });
        let disk = Shape::Disk(Disk { radius: 1.5, inner_radius: 0.5 });
        // The same rectangle twice makes exact ties (the first primitive must win).
        let scenes = [
            vec![(rect, Transform::IDENTITY)],
            vec![(rect, Transform::IDENTITY), (disk, tilted), (rect, Transform::IDENTITY)],
            vec![(disk, Transform::IDENTITY), (rect, tilted)],
        ];
        let mut rng = SplitMix64::new(7);
        for shapes in &scenes {
            let bvh = scene(shapes);
            assert!(bvh.few_flat_shapes());
            let ids: Vec<_> = (0..bvh.leaf.len()).map(|slot| bvh.geometry_of_slot(slot)).collect();
            let rays = rays(&mut rng);
            let (mut hits, mut blocked) = (0, 0);
            for block in rays.chunks(LANES) {
                let mut lane_rays = [Ray::new(Vec3::ZERO, Vec3::ZERO); LANES];
                lane_rays[..block.len()].copy_from_slice(block);
                let lanes = RayLanes::from_rays(&lane_rays);
                let mut got = [None; LANES];
                crate::lanes::widest(|| {
                    bvh.closest_hits_lanes(&RayLanes::from_rays(&lane_rays), &mut |l, hit| got[l] = hit)
                });
                let occluded =
                    crate::lanes::widest(|| bvh.occluded_lanes(&lanes, block.len(), &[GeometryId::NONE; LANES]));
                // Rays leaving some primitive (or none), which then blocks nothing.
                let origins = std::array::from_fn(|_| {
                    ids.get(rng.next_u64() as usize % (ids.len() + 1)).copied().unwrap_or(GeometryId::NONE)
                });
                let occluded_from = crate::lanes::widest(|| bvh.occluded_lanes(&lanes, block.len(), &origins));
                for (l, ray) in block.iter().enumerate() {
                    assert_eq!(got[l], bvh.closest_hit(ray), "closest hit of {ray:?}");
                    assert_eq!(occluded[l], bvh.occluded(ray), "any hit of {ray:?}");
                    assert_eq!(occluded_from[l], bvh.occluded_from(ray, origins[l]), "{ray:?} from {:?}", origins[l]);
                    (hits, blocked) = (hits + got[l].is_some() as usize, blocked + occluded[l] as usize);
                }
                assert!(occluded[block.len()..].iter().all(|&o| !o));
            }
            // Enough of both answers for the comparison to mean something.
            assert!(hits > 50 && hits < rays.len() - 50, "{hits} hits");
            assert!(blocked >= hits);
        }
    }

    #[test]
    fn rays_pass_the_flat_primitive_they_leave_but_not_a_sphere() {
        let rect = Shape::Rectangle(Rectangle { half_size: Vec2::new(2.0, 1.0) });
        let sphere = Shape::Sphere(crate::geometry::Sphere { radius: 1.0 });
        let plane = scene(&[(rect, Transform::IDENTITY)]);
        let id = |bvh: &SceneBvh| bvh.geometry_of_slot(0);
        // Hard case: an origin rounded to just below the plane, heading up through it.
        let up = Ray::new(Vec3::new(0.3, 0.2, -1e-6), Vec3::Z);
        assert!(plane.occluded(&up));
        assert!(!plane.occluded_from(&up, id(&plane)));
        let rays = RayLanes::from_rays(&[up; LANES]);
        assert_eq!(plane.occluded_lanes(&rays, LANES, &[GeometryId::NONE; LANES]), [true; LANES]);
        assert_eq!(plane.occluded_lanes(&rays, LANES, &[id(&plane); LANES]), [false; LANES]);
        assert!(plane.blocks_nothing_from(&[id(&plane); LANES]));
        let mut one_unknown = [id(&plane); LANES];
        one_unknown[5] = GeometryId::NONE;
        assert!(!plane.blocks_nothing_from(&one_unknown));
        // A whole chunk of origins, the last one unknown.
        let mut chunk = vec![id(&plane); 1000];
        assert!(plane.blocks_nothing_from(&chunk));
        chunk[999] = GeometryId::NONE;
        assert!(!plane.blocks_nothing_from(&chunk));
        // A ray leaving a sphere inward meets its far side.
        let ball = scene(&[(sphere, Transform::IDENTITY)]);
        let inward = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::NEG_Z);
        assert!(ball.occluded_from(&inward, id(&ball)));
        assert!(!ball.blocks_nothing_from(&[id(&ball); LANES]));
    }

    /// Records hits lane by lane, and whole blocks as their lanes.
    #[derive(Default)]
    struct Recorder {
        got: [Option<Hit>; LANES],
        blocks: usize,
    }

    impl HitSink for Recorder {
        fn hit(&mut self, l: usize, hit: Option<Hit>) {
            self.got[l] = hit;
        }
        fn block(&mut self, hits: &FlatHitBlock) {
            self.blocks += 1;
            self.got = std::array::from_fn(|l| Some(hits.hit(l)));
        }
    }

    #[test]
    fn blocks_that_hit_one_shape_come_whole() {
        let rect = Shape::Rectangle(Rectangle { half_size: Vec2::new(2.0, 1.0) });
        let over =
            Transform { rotation: Quat::from_rotation_x(0.7), ..Transform::from_translation(Vec3::new(1.5, 0.0, 1.0)) };
        let bvh = scene(&[(rect, Transform::IDENTITY), (Shape::Disk(Disk { radius: 0.5, inner_radius: 0.0 }), over)]);
        // Rays from above toward the rectangle: a block that sees the disk or misses has mixed
        // lanes. Every other block aims at the half of the rectangle away from the disk.
        let mut rng = SplitMix64::new(3);
        let (mut blocks, mut mixed) = (0, 0);
        for i in 0..64 {
            let (from, width) = (Vec3::new(-1.0, 0.0, 4.0), if i % 2 == 0 { 1.4 } else { 4.5 });
            let rays: [Ray; LANES] = std::array::from_fn(|_| {
                let to = Vec3::new(width * rng.f32() - 1.9, 1.9 * rng.f32() - 0.95, 0.0);
                Ray::new(from, (to - from).normalize())
            });
            let mut sink = Recorder::default();
            crate::lanes::widest(|| bvh.closest_hits_lanes(&RayLanes::from_rays(&rays), &mut sink));
            for (l, ray) in rays.iter().enumerate() {
                assert_eq!(sink.got[l], bvh.closest_hit(ray), "closest hit of {ray:?}");
            }
            let same = rays.iter().all(|r| bvh.closest_hit(r).is_some_and(|h| h.instance == 0));
            assert_eq!(sink.blocks, same as usize);
            (blocks, mixed) = (blocks + sink.blocks, mixed + !same as usize);
        }
        assert!(blocks > 5 && mixed > 5, "{blocks} whole blocks, {mixed} mixed");
    }
}
