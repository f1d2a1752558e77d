//! Closest hits and any hits of [`LANES`] rays at once over the wide tree (`wide/packet.rs`): for
//! rays that share a path, such as one pixel's camera samples or one point's shadow rays; lanes
//! that part ways finish their subtrees as single rays. Each lane's answer is
//! [`SceneBvh::closest_hit`]'s (or [`SceneBvh::occluded_from`]'s).

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::{GeometryId, SceneBvh};
use super::hits::{HitLanes, TriangleAttributes, TriangleLanes};
use super::ray::Ray;
use super::triangle::ShearedRay;
use super::visibility::{Best, FEW_PRIMITIVES, Hit, RAY_CHUNK};
use super::wide::PrimBlock;
use super::wide::packet::{RayPacket, triangle_lanes};
use crate::lanes::{F32x16, LANES, Mask16, Vec3x16};

/// No primitive: the `prim` of a lane without a hit.
const NO_PRIM: u32 = u32::MAX;

/// The closest hit so far of each lane of a packet (`best_t` beside it): input primitive, leaf
/// slot, barycentrics, the object-space point of a shape hit (see `SceneBvh::make_hit`), and the
/// lanes whose single-ray walk ran out of stack (they then test every primitive).
struct Nearest {
    prim: [u32; LANES],
    slot: [u32; LANES],
    b: Vec3x16,
    local: [Option<DVec3>; LANES],
    redo: u32,
}

/// Up to `LANES` rays as the lane columns the packet queries take: origins, directions and
/// t_max (lanes past `rays.len()` are zero, and a query told `n = rays.len()` ignores them).
pub fn ray_columns(rays: &[Ray]) -> (Vec3x16, Vec3x16, F32x16) {
    columns_of(rays.iter().copied())
}

/// [`ray_columns`] of the first `LANES` rays of `rays`.
#[inline(always)]
fn columns_of(rays: impl Iterator<Item = Ray>) -> (Vec3x16, Vec3x16, F32x16) {
    let (mut o, mut d, mut t) = (Vec3x16::ZERO, Vec3x16::ZERO, F32x16::ZERO);
    for (l, r) in rays.take(LANES).enumerate() {
        o.set_lane(l, r.origin);
        d.set_lane(l, r.dir);
        t[l] = r.t_max;
    }
    (o, d, t)
}

/// The closest hit of rays `ray(0..n)` (None for misses and invalid rays) into `out`, cleared and
/// refilled: as [`closest_hits`](super::closest_hits), traced as packets of [`LANES`] consecutive
/// rays, for batches whose neighbouring rays share a path (a pixel's samples, their bounces).
pub fn closest_hits_in_packets(
    bvh: &SceneBvh,
    n: usize,
    ray: impl Fn(usize) -> Ray + Sync,
    out: &mut Vec<Option<Hit>>,
) {
    out.clear();
    out.resize(n, None);
    out.par_chunks_mut(RAY_CHUNK).enumerate().for_each(|(c, out)| {
        crate::lanes::widest(
            #[inline(always)]
            || {
                let mut hits = HitLanes::default();
                for (k, out) in out.chunks_mut(LANES).enumerate() {
                    let first = c * RAY_CHUNK + k * LANES;
                    let (o, d, t) = columns_of((first..first + out.len()).map(&ray));
                    bvh.closest_hits_packet(&o, &d, &t, out.len(), &mut hits);
                    for (l, out) in out.iter_mut().enumerate() {
                        *out = hits.hit(l);
                    }
                }
            },
        )
    });
}

impl SceneBvh {
    /// The closest hit of each of the first `n` rays `origin[l] + t dir[l]`, t in (0, `t_max[l]`],
    /// written to `out`'s lane columns (`found` is false past `n`). Run it inside
    /// `lanes::widest` so that the lane loops compile to vector code.
    #[inline(always)]
    pub fn closest_hits_packet(&self, origin: &Vec3x16, dir: &Vec3x16, t_max: &F32x16, n: usize, out: &mut HitLanes) {
        let ray = |l: usize| Ray { origin: origin.lane(l), dir: dir.lane(l), t_max: t_max[l] };
        out.found = Mask16::splat(false);
        if self.leaf.len() <= FEW_PRIMITIVES {
            // No tree walk pays for so few primitives (as `closest_hit`).
            for l in 0..n {
                out.set(l, self.closest_hit(&ray(l)));
            }
            return;
        }
        let rays = RayPacket::new(origin, dir, &t_max.0, n);
        let mut best_t = t_max.0;
        let mut st =
            Nearest { prim: [NO_PRIM; LANES], slot: [0; LANES], b: Vec3x16::ZERO, local: [None; LANES], redo: 0 };
        let complete = self.wide.traverse_packet::<true, _>(
            &rays,
            rays.valid,
            &mut best_t,
            &mut st,
            #[inline(always)]
            |st, block, mask, best_t| {
                let mut triangles = block.triangles;
                while triangles != 0 {
                    let k = triangles.trailing_zeros() as usize;
                    triangles &= triangles - 1;
                    let s = block.slot[k];
                    let p = self.prim_of_slot(s as usize);
                    let hits = triangle_lanes(block, k, &rays, mask, best_t);
                    for l in 0..LANES {
                        let t = hits.t[l];
                        let wins = (hits.hit >> l) & 1 != 0 && (t < best_t[l] || (t == best_t[l] && p < st.prim[l]));
                        if wins {
                            (best_t[l], st.prim[l], st.slot[l]) = (t, p, s);
                            (st.b[0][l], st.b[1][l], st.b[2][l]) = (hits.b[0][l], hits.b[1][l], hits.b[2][l]);
                            st.local[l] = None;
                        }
                    }
                    let mut exact = hits.exact;
                    while exact != 0 {
                        let l = exact.trailing_zeros() as usize;
                        exact &= exact - 1;
                        let Some(h) = ShearedRay::new(&ray(l)).intersect(&self.leaf[s as usize].v, best_t[l]) else {
                            continue;
                        };
                        if h.t < best_t[l] || (h.t == best_t[l] && p < st.prim[l]) {
                            (best_t[l], st.prim[l], st.slot[l], st.local[l]) = (h.t, p, s, None);
                            (st.b[0][l], st.b[1][l], st.b[2][l]) = (h.b[0], h.b[1], h.b[2]);
                        }
                    }
                }
                let mut shapes = block.shapes;
                while shapes != 0 {
                    let k = shapes.trailing_zeros() as usize;
                    shapes &= shapes - 1;
                    let s = block.slot[k];
                    let p = self.prim_of_slot(s as usize);
                    let mut lanes = mask;
                    while lanes != 0 {
                        let l = lanes.trailing_zeros() as usize;
                        lanes &= lanes - 1;
                        let Some((t, at)) = self.shape_in_slot(s as usize).local_hit(&ray(l), best_t[l]) else {
                            continue;
                        };
                        if t < best_t[l] || (t == best_t[l] && p < st.prim[l]) {
                            (best_t[l], st.prim[l], st.slot[l], st.local[l]) = (t, p, s, Some(at));
                            (st.b[0][l], st.b[1][l], st.b[2][l]) = (0.0, 0.0, 0.0);
                        }
                    }
                }
                0
            },
            #[inline(always)]
            |st, entry, mask, best_t| {
                let mut lanes = mask;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let (ray, mut t) = (ray(l), best_t[l]);
                    let sheared = ShearedRay::new(&ray);
                    let mut best = (st.prim[l] != NO_PRIM).then(|| Best {
                        t: best_t[l],
                        slot: st.slot[l] as usize,
                        b: [st.b[0][l], st.b[1][l], st.b[2][l]],
                    });
                    let mut best_local = st.local[l];
                    let complete = self.wide.traverse_from::<true>(
                        entry,
                        &ray,
                        &mut t,
                        #[inline(always)]
                        |block: &PrimBlock, t: &mut f32| {
                            self.closest_in_block(block, &ray, &sheared, t, &mut best, &mut best_local);
                            false
                        },
                    );
                    st.redo |= u32::from(!complete) << l;
                    if let Some(h) = best {
                        let prim = self.prim_of_slot(h.slot);
                        (best_t[l], st.prim[l], st.slot[l], st.local[l]) = (h.t, prim, h.slot as u32, best_local);
                        (st.b[0][l], st.b[1][l], st.b[2][l]) = (h.b[0], h.b[1], h.b[2]);
                    }
                }
                0
            },
        );
        // Triangle hits go to lane columns, their surfaces computed together; coherent lanes mostly
        // hit one triangle, whose shared data is looked up once per run. The rest are set over.
        let mut triangles = TriangleLanes::new();
        let (mut shared, mut others) = (None::<(u32, TriangleAttributes)>, 0u32);
        // Lanes whose walk ran out of stack test every primitive instead (all, if the packet's did).
        let redo = if complete { st.redo } else { u32::MAX };
        for l in 0..n {
            let unsure = redo & (1 << l) != 0;
            if rays.valid & (1 << l) == 0 || (!unsure && st.prim[l] == NO_PRIM) {
                continue;
            }
            if unsure || st.local[l].is_some() {
                others |= 1 << l;
                continue;
            }
            let attributes = match shared {
                Some((p, a)) if p == st.prim[l] => a,
                _ => {
                    let a = self.triangle_attributes(st.prim[l], st.slot[l] as usize);
                    shared = Some((st.prim[l], a));
                    a
                }
            };
            triangles.set(l, &attributes, best_t[l], out);
        }
        triangles.surfaces(&st.b, out);
        while others != 0 {
            let l = others.trailing_zeros() as usize;
            others &= others - 1;
            let hit = if redo & (1 << l) != 0 {
                self.closest_hit_each(&ray(l))
            } else {
                let best = Best { t: best_t[l], slot: st.slot[l] as usize, b: [0.0; 3] };
                Some(self.make_hit(&ray(l), best, st.local[l]))
            };
            out.set(l, hit);
        }
    }

    /// Whether something other than a flat origin blocks each of the first `n` rays over
    /// (0, `t_max[l]`]: bit l is [`SceneBvh::occluded_from`]`(ray l, origins[l])`. Lanes leave the
    /// packet at their first blocker. Run it inside `lanes::widest`.
    #[inline(always)]
    pub fn occluded_packet(
        &self,
        origin: &Vec3x16,
        dir: &Vec3x16,
        t_max: &F32x16,
        n: usize,
        origins: &[GeometryId; LANES],
    ) -> u32 {
        let ray = |l: usize| Ray { origin: origin.lane(l), dir: dir.lane(l), t_max: t_max[l] };
        let rays = RayPacket::new(origin, dir, &t_max.0, n);
        if self.leaf.len() <= FEW_PRIMITIVES {
            let mut blocked = 0;
            for l in 0..n {
                blocked |= u32::from(self.occluded_from(&ray(l), origins[l])) << l;
            }
            return blocked;
        }
        let mut blocked = 0u32;
        let mut limits = t_max.0;
        let complete = self.wide.traverse_packet::<false, _>(
            &rays,
            rays.valid,
            &mut limits,
            &mut blocked,
            #[inline(always)]
            |blocked, block, mask, t_max| {
                let mut found = 0u32;
                let mut triangles = block.triangles;
                while triangles != 0 {
                    let k = triangles.trailing_zeros() as usize;
                    triangles &= triangles - 1;
                    let s = block.slot[k] as usize;
                    let hits = triangle_lanes(block, k, &rays, mask & !found, t_max);
                    let mut lanes = hits.hit | hits.exact;
                    while lanes != 0 {
                        let l = lanes.trailing_zeros() as usize;
                        lanes &= lanes - 1;
                        if self.ignores(s, origins[l]) {
                            continue;
                        }
                        let exact = (hits.exact >> l) & 1 != 0;
                        if !exact || ShearedRay::new(&ray(l)).intersect(&self.leaf[s].v, t_max[l]).is_some() {
                            found |= 1 << l;
                        }
                    }
                }
                let mut shapes = block.shapes;
                while shapes != 0 {
                    let k = shapes.trailing_zeros() as usize;
                    shapes &= shapes - 1;
                    let s = block.slot[k] as usize;
                    let mut lanes = mask & !found;
                    while lanes != 0 {
                        let l = lanes.trailing_zeros() as usize;
                        lanes &= lanes - 1;
                        if !self.ignores(s, origins[l]) && self.shape_in_slot(s).local_hit(&ray(l), t_max[l]).is_some()
                        {
                            found |= 1 << l;
                        }
                    }
                }
                *blocked |= found;
                found
            },
            #[inline(always)]
            |blocked, entry, mask, t_max| {
                let mut found = 0u32;
                let mut lanes = mask;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let (ray, mut t) = (ray(l), t_max[l]);
                    let sheared = ShearedRay::new(&ray);
                    let mut hit = false;
                    let complete = self.wide.traverse_from::<false>(
                        entry,
                        &ray,
                        &mut t,
                        #[inline(always)]
                        |block: &PrimBlock, t: &mut f32| {
                            hit = self.block_blocks(block, &ray, &sheared, *t, origins[l]);
                            hit
                        },
                    );
                    let blocks = if complete { hit } else { self.occluded_from(&ray, origins[l]) };
                    found |= u32::from(blocks) << l;
                }
                *blocked |= found;
                found
            },
        );
        if !complete {
            // Too deep for the stack: the lanes not yet answered test every primitive.
            let mut rest = rays.valid & !blocked;
            while rest != 0 {
                let l = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                blocked |= u32::from(self.occluded_from(&ray(l), origins[l])) << l;
            }
        }
        blocked
    }
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec2, Vec3};

    use crate::geometry::{
        GeometryId, GeometryInstance, GeometryRef, Hit, HitLanes, Mesh, Ray, SceneBvh, Shape, Sphere, Transform,
    };
    use crate::lanes::{F32x16, LANES, Vec3x16};
    use crate::rng::SplitMix64;

    fn v(rng: &mut SplitMix64, r: f32) -> Vec3 {
        Vec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
    }

    /// Random triangles with normals and uvs, a fan whose shared edges and centre vertex lie on
    /// the z axis, both under a rotated and scaled transform, and two spheres among them.
    fn scene(rng: &mut SplitMix64) -> (Mesh, Mesh) {
        let tris: Vec<[Vec3; 3]> = (0..400)
            .map(|_| {
                let c = v(rng, 4.0);
                [c, c + v(rng, 0.6), c + v(rng, 0.6)]
            })
            .collect();
        let n = tris.len() * 3;
        let soup = Mesh::from_triangles(&tris)
            .unwrap()
            .with_normals((0..n).map(|_| v(rng, 1.0).normalize_or(Vec3::Y)).collect())
            .unwrap()
            .with_uvs((0..n).map(|_| Vec2::new(rng.f32(), rng.f32())).collect())
            .unwrap();
        let fan: Vec<[Vec3; 3]> = (0..8)
            .map(|k| {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                let b = a + std::f32::consts::FRAC_PI_4;
                [Vec3::ZERO, Vec3::new(a.cos(), a.sin(), 0.0), Vec3::new(b.cos(), b.sin(), 0.0)]
            })
            .collect();
        (soup, Mesh::from_triangles(&fan).unwrap())
    }

    /// Each lane of a packet gets `closest_hit`'s answer bit for bit, in lane code and not:
    /// coherent packets (one origin, a narrow cone), incoherent ones whose lanes have different
    /// dominant axes, rays down the fan's shared edges and centre vertex (edge functions exactly
    /// zero), short t_max that cut hits off, and invalid lanes (zero direction, NaN origin,
    /// t_max 0) and lanes past `n`, which report nothing. Any-hit likewise, with half the lanes
    /// leaving the primitive they first hit (which then must not block them). Incoherent packets
    /// hand subtrees to single rays (the hybrid), carrying each lane's best hit so far across; the
    /// test runs at the hybrid's threshold and with every subtree handed over.
    #[test]
    fn packets_match_one_ray_at_a_time() {
        use crate::geometry::wide::packet::SINGLE_RAY_LANES_FOR_TESTS;
        for threshold in [SINGLE_RAY_LANES_FOR_TESTS.with(|c| c.get()), LANES as u32] {
            SINGLE_RAY_LANES_FOR_TESTS.with(|c| c.set(threshold));
            packets_match_one_ray_at_a_time_at_this_threshold();
        }
    }

    /// A batch traced in packets gets `closest_hits`'s answers ray for ray: 1,000 rays (a partial
    /// rayon chunk and a partial packet at the end), in groups of 16 from one origin as a pixel's
    /// bounces, others random, some invalid, on a sheared instance with vertex normals and uvs.
    #[test]
    fn batches_in_packets_match_closest_hits() {
        let mut rng = SplitMix64::new(5);
        let (soup, _) = scene(&mut rng);
        let sheared = Transform { shear: Vec3::new(0.4, -0.3, 0.2), ..Transform::from_translation(Vec3::X) };
        let bvh = SceneBvh::build(&[GeometryInstance {
            geometry: GeometryRef::Mesh(&soup),
            transform: sheared,
            entity_index: 3,
            material: 1,
        }]);
        let rays: Vec<Ray> = (0..1000)
            .map(|k| {
                let origin = if k % 32 < 16 {
                    Vec3::new(0.0, 0.0, 7.0) + Vec3::X * (k / 32) as f32 * 0.1
                } else {
                    v(&mut rng, 6.0)
                };
                let t_max = if k % 97 == 0 { 0.0 } else { f32::INFINITY };
                Ray { origin, dir: v(&mut rng, 2.0) - origin, t_max }
            })
            .collect();
        let (mut want, mut got) = (Vec::new(), Vec::new());
        crate::geometry::closest_hits(&bvh, &rays, &mut want);
        super::closest_hits_in_packets(&bvh, rays.len(), |k| rays[k], &mut got);
        assert!(want.iter().filter(|h| h.is_some()).count() > 200, "the rays find the mesh");
        assert_eq!(got, want);
    }

    fn packets_match_one_ray_at_a_time_at_this_threshold() {
        let mut rng = SplitMix64::new(11);
        let (soup, fan) = scene(&mut rng);
        let placed = Transform {
            translation: Vec3::new(0.3, -0.2, 0.1),
            rotation: Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
            scale: Vec3::new(1.0, 1.5, 0.8),
            shear: glam::Vec3::ZERO,
        };
        let instance = |geometry, transform, entity_index| GeometryInstance {
            geometry,
            transform,
            entity_index,
            material: entity_index,
        };
        let sphere = |r| GeometryRef::Shape(Shape::Sphere(Sphere { radius: r }));
        let bvh = SceneBvh::build(&[
            instance(GeometryRef::Mesh(&soup), placed, 0),
            instance(GeometryRef::Mesh(&fan), Transform::IDENTITY, 1),
            instance(sphere(0.7), Transform::from_translation(Vec3::new(1.0, 1.0, -2.0)), 2),
            instance(sphere(0.4), Transform::from_translation(Vec3::new(-2.0, 0.5, 1.0)), 3),
        ]);
        let (mut hits, mut exact_cases, mut blocked_count) = (0, 0, 0);
        for case in 0..1200 {
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); LANES];
            let origin = v(&mut rng, 6.0);
            let aim = v(&mut rng, 3.0);
            for (l, ray) in rays.iter_mut().enumerate() {
                *ray = match case % 4 {
                    0 => Ray::new(origin, aim - origin + v(&mut rng, 0.05)),
                    1 => Ray { origin: v(&mut rng, 6.0), dir: v(&mut rng, 1.0), t_max: rng.range(0.5, 12.0) },
                    // Down the fan's axis and along its shared edges, from either side.
                    2 => {
                        let a = (l % 8) as f32 * std::f32::consts::FRAC_PI_4;
                        let on_edge = Vec3::new(a.cos(), a.sin(), 0.0) * rng.range(0.0, 0.9) * (l >= 8) as u8 as f32;
                        let z = if l % 2 == 0 { 3.0 } else { -3.0 };
                        Ray::new(on_edge + Vec3::Z * z, Vec3::Z * -z.signum())
                    }
                    _ => Ray { origin, dir: aim - origin + v(&mut rng, 0.3), t_max: rng.range(0.0, 8.0) },
                };
            }
            if case % 4 == 3 {
                rays[3].dir = Vec3::ZERO;
                rays[5].origin.y = f32::NAN;
                rays[7].t_max = 0.0;
            }
            let n = if case % 5 == 0 { 1 + case % LANES } else { LANES };
            let (o, d, t) = super::ray_columns(&rays);
            for wide in [false, true] {
                let mut out = HitLanes::default();
                if wide {
                    crate::lanes::widest(|| bvh.closest_hits_packet(&o, &d, &t, n, &mut out));
                } else {
                    bvh.closest_hits_packet(&o, &d, &t, n, &mut out);
                }
                let got: [Option<Hit>; LANES] = std::array::from_fn(|l| out.hit(l));
                // Any-hit from an origin on the lane's first hit (which then does not block it,
                // unless it is a sphere), or from nowhere.
                let mut origins = [GeometryId::NONE; LANES];
                for (l, ray) in rays.iter().enumerate() {
                    let want = (l < n).then(|| bvh.closest_hit(ray));
                    assert_eq!(got[l], want.flatten(), "case {case}, lane {l}, {ray:?}");
                    hits += want.flatten().is_some() as usize;
                    exact_cases += (case % 4 == 2 && want.flatten().is_some()) as usize;
                    if l % 2 == 0 {
                        origins[l] = want.flatten().map_or(GeometryId::NONE, |h| h.id);
                    }
                }
                let blocked = if wide {
                    crate::lanes::widest(|| bvh.occluded_packet(&o, &d, &t, n, &origins))
                } else {
                    bvh.occluded_packet(&o, &d, &t, n, &origins)
                };
                for (l, ray) in rays.iter().enumerate() {
                    let want = l < n && bvh.occluded_from(ray, origins[l]);
                    assert_eq!((blocked >> l) & 1 != 0, want, "any-hit: case {case}, lane {l}, {ray:?}");
                    blocked_count += want as usize;
                }
            }
        }
        assert!(hits > 5000 && exact_cases > 1000, "hits compared {hits}, on the fan's edges {exact_cases}");
        assert!(blocked_count > 3000, "blocked rays compared {blocked_count}");
    }

    /// A ray leaving a flat primitive passes it, however its origin was rounded (hard case: an
    /// origin just below the plane heading up through it); a ray leaving a sphere inward meets
    /// its far side.
    #[test]
    fn rays_pass_the_flat_primitive_they_leave_but_not_a_sphere() {
        use crate::geometry::Rectangle;
        let one = |shape| {
            let geometry = GeometryRef::Shape(shape);
            SceneBvh::build(&[GeometryInstance {
                geometry,
                transform: Transform::IDENTITY,
                entity_index: 0,
                material: 0,
            }])
        };
        let column = Vec3x16::splat;
        let plane = one(Shape::Rectangle(Rectangle { half_size: Vec2::new(2.0, 1.0) }));
        let id = |bvh: &SceneBvh| bvh.geometry_of_slot(0);
        let up = Ray::new(Vec3::new(0.3, 0.2, -1e-6), Vec3::Z);
        let (o, d, t) = (column(up.origin), column(up.dir), F32x16::splat(up.t_max));
        assert!(plane.occluded(&up) && !plane.occluded_from(&up, id(&plane)));
        assert_eq!(plane.occluded_packet(&o, &d, &t, LANES, &[GeometryId::NONE; LANES]), (1 << LANES) - 1);
        let mut origins = [id(&plane); LANES];
        origins[5] = GeometryId::NONE;
        assert_eq!(plane.occluded_packet(&o, &d, &t, LANES, &origins), 1 << 5);
        let ball = one(Shape::Sphere(Sphere { radius: 1.0 }));
        let inward = Ray::new(Vec3::Z, Vec3::NEG_Z);
        let (o, d) = (column(inward.origin), column(inward.dir));
        assert_eq!(ball.occluded_packet(&o, &d, &t, LANES, &[id(&ball); LANES]), (1 << LANES) - 1);
    }
}
