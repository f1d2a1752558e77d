//! The ECS light system: Sample_Li batch throughput for point lights (the sampling pass's lane
//! kernel) and spot lights (their batch form) over 1M points (points x lights per second, and
//! bytes moved per second beside a plain memcpy); the whole schedule (light choice, Sample_Li,
//! shadow rays) for a 1M-point G-buffer on a real file's geometry, per light kind (entries per
//! second); and the frame update cost for 100k lights with 1% moving against a full rebuild.

use bevy_ecs::prelude::*;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec2;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::geometry::{Mesh, Ray, Rectangle, SceneBvh, Sphere};
use kelvin::lanes::{self, LANES, U32x16, Vec3x16};
use kelvin::light::{
    Amount, AreaLight, ColorQuery, DistantLight, GoniometricLight, LightSampleContext, LightTable, PointLight,
    ProjectionLight, SpotLight, UniformInfiniteLight,
};
use kelvin::render::scene_file::{spawn_env_map, spawn_gltf_file};
use kelvin::scene::ies::IesProfile;
use kelvin::scene::image::RgbImage;
use kelvin::shading::ShadingBatch;
use kelvin::systems::{LightingPlugin, ShadowRays};
use rayon::prelude::*;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

const POINTS: usize = 1 << 20;
const LIGHTS: usize = 8; // of each kind
const CHUNK: usize = 4096;
/// Bytes per (point, light): read a position (12), write a direction (12) and a radiance (12).
const BYTES: u64 = 36;

fn table_with_lights() -> LightTable {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    for i in 0..LIGHTS {
        let t = Transform::from_translation(Vec3::new(i as f32, 3.0, 0.0)).looking_to(Vec3::NEG_Y, Vec3::Z);
        world.spawn((PointLight::candela(100.0), t));
        world.spawn((SpotLight { amount: Amount::Candela(100.0), ..Default::default() }, t));
    }
    schedule.run(&mut world);
    world.resource::<LightTable>().clone()
}

/// Point light `row`'s Sample_Li for `positions` through the lane kernel the sampling pass runs
/// (`CHUNK` is a multiple of `LANES`), writing directions and radiance.
fn point_lanes(table: &LightTable, row: usize, positions: &[Vec3], wi: &mut [Vec3], radiance: &mut [Vec3]) {
    lanes::widest(
        #[inline(always)]
        || {
            for b in (0..positions.len()).step_by(LANES) {
                let lit = table.points().sample_li_rgb_lanes(U32x16::splat(row as u32), &Vec3x16::load(positions, b));
                lit.wi.store_vec3s(lanes::block_mut(wi, b));
                lit.radiance.store_vec3s(lanes::block_mut(radiance, b));
            }
        },
    )
}

/// Spots have no lane kernel yet: their one scalar Sample_Li, point by point.
fn spot_scalar(table: &LightTable, row: usize, p: &[Vec3], w: &mut [Vec3], l: &mut [Vec3]) {
    for ((p, w), l) in p.iter().zip(w.iter_mut()).zip(l.iter_mut()) {
        let s = table.spots().sample_li(row, &LightSampleContext::at(*p), ColorQuery::Rgb);
        let [r, g, b, ..] = s.as_ref().map_or([0.0; 4], |s| s.radiance.0);
        (*w, *l) = (s.map_or(Vec3::ZERO, |s| s.wi), Vec3::new(r, g, b));
    }
}

fn sample_li_batch(c: &mut Criterion) {
    let table = table_with_lights();
    let positions: Vec<Vec3> =
        (0..POINTS).map(|i| Vec3::new((i % 1024) as f32 * 0.01, 0.0, (i / 1024) as f32 * 0.01)).collect();
    let mut wi = vec![Vec3::ZERO; POINTS];
    let mut li = vec![Vec3::ZERO; POINTS];
    let mut g = c.benchmark_group("sample_li_batch_1M_points");
    g.sample_size(10);
    g.throughput(Throughput::Elements((POINTS * LIGHTS) as u64));
    for kind in ["point", "spot"] {
        g.bench_function(format!("{kind}_x{LIGHTS}_lights"), |b| {
            b.iter(|| {
                for row in 0..LIGHTS {
                    (positions.par_chunks(CHUNK), wi.par_chunks_mut(CHUNK), li.par_chunks_mut(CHUNK))
                        .into_par_iter()
                        .for_each(|(p, w, l)| match kind {
                            "point" => point_lanes(&table, row, p, w, l),
                            _ => spot_scalar(&table, row, p, w, l),
                        });
                }
                black_box(&li);
            })
        });
    }
    g.throughput(Throughput::Bytes(POINTS as u64 * LIGHTS as u64 * BYTES));
    g.bench_function(format!("point_x{LIGHTS}_lights_bytes"), |b| {
        b.iter(|| {
            for row in 0..LIGHTS {
                (positions.par_chunks(CHUNK), wi.par_chunks_mut(CHUNK), li.par_chunks_mut(CHUNK))
                    .into_par_iter()
                    .for_each(|(p, w, l)| point_lanes(&table, row, p, w, l));
            }
            black_box(&li);
        })
    });
    // memcpy of the same bytes: 36 bytes per (point, light), in the same parallel chunks.
    let src = vec![0u8; POINTS * BYTES as usize];
    let mut dst = vec![0u8; POINTS * BYTES as usize];
    g.bench_function("memcpy_same_bytes", |b| {
        b.iter(|| {
            for _ in 0..LIGHTS {
                dst.par_chunks_mut(CHUNK * BYTES as usize)
                    .zip(src.par_chunks(CHUNK * BYTES as usize))
                    .for_each(|(d, s)| d.copy_from_slice(s));
            }
            black_box(&dst);
        })
    });
    g.finish();
}

/// The light kinds of the per-kind group, each as a few entities spawned into `world`.
const KINDS: [&str; 10] = [
    "point",
    "spot",
    "distant",
    "rectangle",
    "sphere",
    "triangle_mesh",
    "uniform_sky",
    "image_sky",
    "ies",
    "projection",
];

fn spawn_kind(world: &mut World, kind: &str, data: &Path) {
    let above = |x: f32, z: f32| Transform::from_translation(Vec3::new(x, 4.0, z)).looking_to(Vec3::NEG_Y, Vec3::Z);
    let each = [(-2.0, -2.0), (2.0, -2.0), (-2.0, 2.0), (2.0, 2.0)];
    let area = || AreaLight { amount: Amount::Nits(1000.0), ..Default::default() };
    for (x, z) in each {
        let at = above(x, z);
        // One-sided area lights emit along local +Z: turned to face down.
        let facing_down = Transform::from_translation(at.translation).looking_to(Vec3::Y, Vec3::Z);
        match kind {
            "point" => drop(world.spawn((PointLight::candela(100.0), at))),
            "spot" => drop(world.spawn((SpotLight { amount: Amount::Candela(100.0), ..Default::default() }, at))),
            "rectangle" => drop(world.spawn((area(), Rectangle { half_size: Vec2::splat(0.3) }, facing_down))),
            "sphere" => drop(world.spawn((area(), Sphere { radius: 0.2 }, at))),
            "triangle_mesh" => {
                // A 4x4 grid of quads facing down: 32 emitting triangles.
                let (mut positions, mut indices) = (Vec::new(), Vec::new());
                for j in 0..5 {
                    for i in 0..5 {
                        positions.push(Vec3::new(i as f32 * 0.15 - 0.3, j as f32 * 0.15 - 0.3, 0.0));
                    }
                }
                for j in 0..4u32 {
                    for i in 0..4u32 {
                        let v = j * 5 + i;
                        indices.extend([v, v + 1, v + 6, v, v + 6, v + 5]);
                    }
                }
                let mesh = Mesh::new(positions, indices).expect("a valid grid");
                world.spawn((area(), mesh, facing_down));
            }
            "ies" => {
                let profile = IesProfile::from_file(&data.join("ies/luxcore/ASA_15M_R2.ies")).expect("test data");
                world.spawn((GoniometricLight::from_ies(Arc::new(profile)), at));
            }
            "projection" => {
                let pixels = (0..64).map(|i| Vec3::splat(1.0 + (i % 7) as f32)).collect();
                let image = RgbImage { width: 8, height: 8, pixels };
                world.spawn((ProjectionLight::new(Arc::new(image), 1.0), at));
            }
            _ => {}
        }
    }
    match kind {
        "distant" => {
            world.spawn((DistantLight::default(), Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z)));
        }
        "uniform_sky" => {
            world.spawn((UniformInfiniteLight::default(), Transform::default()));
        }
        "image_sky" => {
            let env = data.join("env/spiaggia_di_mondello_1k.hdr");
            spawn_env_map(world, &env, 1.0).expect("test data");
        }
        _ => {}
    }
}

/// A G-buffer of `POINTS` surface points: rays straight down over a grid onto the geometry of
/// `sphere_65k.glb` (a 65,536-triangle sphere on a floor), with their hits' primitives.
fn gbuffer(world: &mut World, schedule: &mut Schedule) {
    schedule.run(world);
    let side = (POINTS as f32).sqrt() as usize;
    let bvh = world.resource::<SceneBvh>().clone();
    let mut batch = world.resource_mut::<ShadingBatch>();
    batch.clear();
    let mut geometry = Vec::with_capacity(POINTS);
    for j in 0..side {
        for i in 0..side {
            let (x, z) = ((i as f32 + 0.5) / side as f32 * 8.0 - 4.0, (j as f32 + 0.5) / side as f32 * 8.0 - 4.0);
            let ray = Ray::new(Vec3::new(x, 10.0, z), Vec3::NEG_Y);
            if let Some(hit) = bvh.closest_hit(&ray) {
                batch.push_with_error(hit.p, hit.p_error, hit.ng, hit.ns, (j * side + i) as u32, 0);
                geometry.push(hit.id);
            }
        }
    }
    // Filled whole or left empty (see `ShadingBatch::geometry`).
    batch.geometry = geometry;
}

/// The schedule as an embedding app runs it, per light kind: 4 lights of the kind (one for the
/// skies and the distant light) over a G-buffer on a real file, one light sample per point and
/// its shadow ray among 65k triangles.
fn schedule_per_kind(c: &mut Criterion) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut g = c.benchmark_group("schedule_1M_gbuffer_sphere_65k");
    g.sample_size(10).warm_up_time(std::time::Duration::from_secs(1));
    for kind in KINDS {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        LightingPlugin::build(&mut world, &mut schedule);
        spawn_gltf_file(&mut world, &data.join("gltf/bench/sphere_65k.glb")).expect("test data");
        // The file's own point light goes: one kind at a time.
        let own: Vec<Entity> = world.query_filtered::<Entity, With<PointLight>>().iter(&world).collect();
        for e in own {
            world.despawn(e);
        }
        spawn_kind(&mut world, kind, &data);
        gbuffer(&mut world, &mut schedule);
        let entries = world.resource::<ShadingBatch>().len() as u64;
        g.throughput(Throughput::Elements(entries));
        g.bench_function(kind, |b| b.iter(|| schedule.run(&mut world)));
        let rays = world.resource::<ShadowRays>().len();
        eprintln!("{kind}: {entries} points, {rays} shadow rays per run");
    }
    g.finish();
}

fn frame_update(c: &mut Criterion) {
    let n = 100_000;
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    let lights: Vec<Entity> = (0..n)
        .map(|i| {
            let p = Vec3::new((i % 300) as f32, 3.0, (i / 300) as f32);
            world.spawn((PointLight::candela(1.0 + (i % 7) as f32), Transform::from_translation(p))).id()
        })
        .collect();
    schedule.run(&mut world);
    let mut g = c.benchmark_group("frame_update_100k_lights");
    g.sample_size(20);
    g.bench_function("move_1_percent", |b| {
        let mut k = 0usize;
        b.iter(|| {
            for _ in 0..n / 100 {
                k = (k + 7919) % n;
                world.get_mut::<Transform>(lights[k]).unwrap().translation.y += 0.01;
            }
            schedule.run(&mut world);
        })
    });
    g.bench_function("full_rebuild", |b| {
        b.iter(|| {
            for &e in &lights {
                world.get_mut::<PointLight>(e).unwrap().set_changed();
            }
            schedule.run(&mut world);
        })
    });
    g.finish();
}

criterion_group!(benches, sample_li_batch, schedule_per_kind, frame_update);
criterion_main!(benches);
