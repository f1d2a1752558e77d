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

/// The shapes the lane tests place: a rectangle, an annulus, and a tilted, shifted placement.
fn rect_disk_and_tilt() -> (Shape, Shape, Transform) {
    let tilted = Transform {
        rotation: Quat::from_rotation_x(0.7) * Quat::from_rotation_y(-0.3),
        ..Transform::from_translation(Vec3::new(0.5, 0.0, 0.25))
    };
    let rect = Shape::Rectangle(Rectangle { half_size: Vec2::new(2.0, 1.0) });
    (rect, Shape::Disk(Disk { radius: 1.5, inner_radius: 0.5 }), tilted)
}

#[test]
fn flat_lanes_match_one_ray_at_a_time() {
    let (rect, disk, tilted) = rect_disk_and_tilt();
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
            let occluded = crate::lanes::widest(|| bvh.occluded_lanes(&lanes, block.len(), &[GeometryId::NONE; LANES]));
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
#[allow(clippy::needless_range_loop)] // lanes by index, as the kernel reads them
fn rays_from_one_origin_match_one_ray_at_a_time() {
    let (rect, disk, tilted) = rect_disk_and_tilt();
    // One shape (the shared-origin path) and two (which builds the rays).
    let scenes = [vec![(rect, Transform::IDENTITY)], vec![(disk, tilted)], vec![(rect, tilted), (disk, tilted)]];
    // Hard cases: an origin in the plane, a NaN origin; zero, NaN and infinite directions.
    let origins = [Vec3::new(-1.0, 0.5, 3.0), Vec3::new(0.2, -2.0, -1.5), Vec3::new(0.3, 0.2, 0.0), Vec3::NAN];
    let mut rng = SplitMix64::new(11);
    let (mut hits, mut blocks) = (0, 0);
    for shapes in &scenes {
        let bvh = scene(shapes);
        for (k, &origin) in origins.iter().enumerate() {
            // Every other block aims at the middle of the shape, so that all its lanes hit.
            let spread = if k % 2 == 0 { 0.5 } else { 6.0 };
            let mut dirs: Lanes3 = [[0.0; LANES]; 3];
            for l in 0..LANES {
                let to = shapes[0].1.transform_point(Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, 0.0) * spread);
                let d = (to - origin).normalize_or(Vec3::X);
                (dirs[0][l], dirs[1][l], dirs[2][l]) = (d.x, d.y, d.z);
            }
            if k == 1 {
                (dirs[0][3], dirs[1][3], dirs[2][3]) = (0.0, 0.0, 0.0);
                (dirs[0][4], dirs[1][5]) = (f32::NAN, f32::INFINITY);
            }
            for t_max in [f32::INFINITY, 3.0, 0.0] {
                let mut sink = Recorder::default();
                crate::lanes::widest(|| bvh.closest_hits_from(origin, &dirs, t_max, &mut sink));
                for l in 0..LANES {
                    let dir = Vec3::new(dirs[0][l], dirs[1][l], dirs[2][l]);
                    let ray = Ray { t_max, ..Ray::new(origin, dir) };
                    assert_eq!(sink.got[l], bvh.closest_hit(&ray), "closest hit of {ray:?}");
                    hits += sink.got[l].is_some() as usize;
                }
                blocks += sink.blocks;
            }
        }
    }
    assert!(hits > 60 && blocks >= 3, "{hits} hits, {blocks} whole blocks");
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
