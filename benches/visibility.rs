//! Visibility benchmarks: any-hit and closest-hit rays per second (coherent camera rays and
//! incoherent random rays) on a generated ~100k-triangle scene, BVH build time for 100k and 1M
//! triangles, and refit versus rebuild when 1% and 100% of the objects move.
//!
//! Run: `cargo bench --bench visibility -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{EulerRot, Quat, Vec2, Vec3};
use kelvin::geometry::{
    Disk, GeometryInstance, GeometryRef, Hit, Mesh, Ray, SceneBvh, Sphere, Transform, closest_hits, occluded,
};
use kelvin::rng::SplitMix64;
use obvhs::BvhBuildParams;
use std::hint::black_box;

/// A uniform point in the box [lo, hi).
fn point_in_box(rng: &mut SplitMix64, lo: Vec3, hi: Vec3) -> Vec3 {
    Vec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z))
}

/// Scene extent: objects are scattered over a 100 m x 100 m area, 0 to 8 m high.
const LO: Vec3 = Vec3::new(-50.0, 0.0, -50.0);
const HI: Vec3 = Vec3::new(50.0, 8.0, 50.0);
const RAYS: usize = 1 << 16;

struct Scene {
    object: Mesh,
    ground: Mesh,
    transforms: Vec<Transform>,
}

impl Scene {
    /// `objects` copies of a 96-triangle sphere with random placement, rotation and scale, a
    /// 2-triangle ground, and 40 analytic shapes (spheres and disks, as area lights would be).
    fn new(objects: usize, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let transforms = (0..objects).map(|_| random_transform(&mut rng)).collect();
        let g = 60.0;
        let ground = Mesh::from_triangles(&[
            [Vec3::new(-g, 0.0, -g), Vec3::new(-g, 0.0, g), Vec3::new(g, 0.0, g)],
            [Vec3::new(-g, 0.0, -g), Vec3::new(g, 0.0, g), Vec3::new(g, 0.0, -g)],
        ])
        .unwrap();
        Self { object: Mesh::uv_sphere(1.0, 8, 7), ground, transforms }
    }

    fn instances(&self) -> Vec<GeometryInstance<'_>> {
        let mut out: Vec<GeometryInstance> = self
            .transforms
            .iter()
            .enumerate()
            .map(|(i, &transform)| GeometryInstance {
                geometry: GeometryRef::Mesh(&self.object),
                transform,
                entity_index: i as u32,
                material: 0,
            })
            .collect();
        out.push(GeometryInstance {
            geometry: GeometryRef::Mesh(&self.ground),
            transform: Transform::IDENTITY,
            entity_index: out.len() as u32,
            material: 1,
        });
        let mut rng = SplitMix64::new(99);
        for i in 0..40 {
            let transform =
                Transform::from_translation(point_in_box(&mut rng, LO, HI)).looking_to(Vec3::NEG_Y, Vec3::Z);
            let geometry = if i % 2 == 0 {
                GeometryRef::Shape(Sphere { radius: 0.3 }.into())
            } else {
                GeometryRef::Shape(Disk::new(0.5).into())
            };
            out.push(GeometryInstance { geometry, transform, entity_index: out.len() as u32, material: 2 });
        }
        out
    }

    fn triangles(&self) -> usize {
        self.transforms.len() * self.object.triangle_count() + 2
    }
}

fn random_transform(rng: &mut SplitMix64) -> Transform {
    let tau = std::f32::consts::TAU;
    Transform {
        translation: point_in_box(rng, LO + Vec3::Y, HI),
        rotation: Quat::from_euler(EulerRot::XYZ, rng.range(0.0, tau), rng.range(0.0, tau), 0.0),
        scale: Vec3::splat(rng.range(0.3, 1.5)),
        shear: Vec3::ZERO,
    }
}

/// A 256 x 256 pinhole camera above the scene, looking across it.
fn camera_rays() -> Vec<Ray> {
    let eye = Vec3::new(0.0, 12.0, 60.0);
    let fwd = (Vec3::new(0.0, 0.0, 0.0) - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    (0..RAYS)
        .map(|i| {
            let px = Vec2::new((i % 256) as f32 + 0.5, (i / 256) as f32 + 0.5) / 256.0 * 2.0 - 1.0;
            Ray::new(eye, fwd + 0.6 * (px.x * right - px.y * up))
        })
        .collect()
}

/// Random origins in the scene box, uniformly random directions, to infinity.
fn random_rays() -> Vec<Ray> {
    let mut rng = SplitMix64::new(7);
    (0..RAYS)
        .map(|_| {
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, std::f32::consts::TAU);
            let r = (1.0 - z * z).sqrt();
            Ray::new(point_in_box(&mut rng, LO, HI), Vec3::new(r * phi.cos(), z, r * phi.sin()))
        })
        .collect()
}

fn queries(c: &mut Criterion, name: &str, bvh: &SceneBvh) {
    let sets = [("coherent", camera_rays()), ("incoherent", random_rays())];
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(RAYS as u64));
    let mut blocked = Vec::new();
    let mut hits: Vec<Option<Hit>> = Vec::new();
    for (kind, rays) in &sets {
        occluded(bvh, rays, &mut blocked);
        let frac = blocked.iter().filter(|&&b| b).count() as f32 / RAYS as f32;
        eprintln!("{name}/{kind}: {:.0}% of rays hit something", 100.0 * frac);
        group.bench_function(format!("any_hit/{kind}"), |b| b.iter(|| occluded(bvh, black_box(rays), &mut blocked)));
        group.bench_function(format!("closest_hit/{kind}"), |b| {
            b.iter(|| closest_hits(bvh, black_box(rays), &mut hits))
        });
    }
    group.finish();
}

fn bench_queries(c: &mut Criterion) {
    let scene = Scene::new(1042, 1);
    let bvh = SceneBvh::build(&scene.instances());
    eprintln!("query scene: {} triangles + 40 shapes, {} primitives", scene.triangles(), bvh.primitive_count());
    queries(c, "rays_100k_tris", &bvh);
}

fn bench_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    for (label, objects) in [("100k_tris", 1042), ("1M_tris", 10_417)] {
        let scene = Scene::new(objects, 2);
        let instances = scene.instances();
        eprintln!("build/{label}: {} triangles", scene.triangles());
        group.bench_function(format!("{label}/fast"), |b| b.iter(|| SceneBvh::build(black_box(&instances))));
        if objects < 2000 {
            let medium = BvhBuildParams::medium_build();
            group.bench_function(format!("{label}/medium"), |b| {
                b.iter(|| SceneBvh::build_with_params(black_box(&instances), medium))
            });
        }
    }
    group.finish();
}

/// Refit when 1% and 100% of the 1,042 objects move (small random motion), against the full
/// rebuild the ECS would otherwise run; then what a refit costs in tree quality.
fn bench_refit(c: &mut Criterion) {
    let scene = Scene::new(1042, 3);
    let instances = scene.instances();
    let mut group = c.benchmark_group("update_100k_tris");
    group.sample_size(20);
    for (label, step) in [("1pct", 100), ("100pct", 1)] {
        let mut rng = SplitMix64::new(11);
        let jitter = |rng: &mut SplitMix64, t: Transform| Transform {
            translation: t.translation + Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0)),
            ..t
        };
        let moves: Vec<Vec<(u32, Transform)>> = (0..2)
            .map(|_| {
                (0..scene.transforms.len())
                    .step_by(step)
                    .map(|i| (i as u32, jitter(&mut rng, scene.transforms[i])))
                    .collect()
            })
            .collect();
        let mut bvh = SceneBvh::build(&instances);
        let mut flip = 0;
        group.bench_function(format!("refit/{label}"), |b| {
            b.iter(|| {
                flip ^= 1;
                bvh.refit(black_box(&moves[flip])).unwrap()
            })
        });
        eprintln!("refit/{label}: {} objects moved, cost ratio after refit {:.3}", moves[0].len(), bvh.cost_ratio());
    }
    group.bench_function("rebuild", |b| b.iter(|| SceneBvh::build(black_box(&instances))));
    group.finish();

    // Worst case for refit: every object jumps to an unrelated place. Trace the same rays
    // through the refitted tree and through a fresh build.
    let mut refitted = SceneBvh::build(&instances);
    let mut rng = SplitMix64::new(5);
    let scatter: Vec<(u32, Transform)> =
        (0..scene.transforms.len() as u32).map(|i| (i, random_transform(&mut rng))).collect();
    refitted.refit(&scatter).unwrap();
    let mut rebuilt = refitted.clone();
    rebuilt.rebuild();
    eprintln!("scatter: cost ratio after refit {:.2} (rebuild threshold 1.5)", refitted.cost_ratio());
    let rays = random_rays();
    let mut blocked = Vec::new();
    let mut group = c.benchmark_group("after_scatter");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.bench_function("any_hit/incoherent/refitted", |b| b.iter(|| occluded(&refitted, &rays, &mut blocked)));
    group.bench_function("any_hit/incoherent/rebuilt", |b| b.iter(|| occluded(&rebuilt, &rays, &mut blocked)));
    group.finish();
}

criterion_group!(benches, bench_queries, bench_build, bench_refit);
criterion_main!(benches);
