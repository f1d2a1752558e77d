//! The ECS light system: Sample_Li batch throughput for point lights (the sampling pass's lane
//! kernel) and spot lights (their batch form) over 1M points (points x lights per second, and
//! bytes moved per second beside a plain memcpy), and the frame update cost for 100k lights with
//! 1% moving against a full rebuild.

use bevy_ecs::prelude::*;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::lanes::{self, LANES};
use kelvin::light::{Amount, LightTable, PointLight, SpotLight};
use kelvin::systems::LightingPlugin;
use rayon::prelude::*;
use std::hint::black_box;

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
                let lit =
                    table.points.sample_li_rgb_lanes(&[row as u32; LANES], &lanes::columns(lanes::block(positions, b)));
                let (w, l) = (lanes::block_mut(wi, b), lanes::block_mut(radiance, b));
                for k in 0..LANES {
                    w[k] = Vec3::new(lit.wi[0][k], lit.wi[1][k], lit.wi[2][k]);
                    l[k] = Vec3::new(lit.radiance[0][k], lit.radiance[1][k], lit.radiance[2][k]);
                }
            }
        },
    )
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
                            _ => table.spots.sample_li_batch_rgb(row, p, w, l),
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

criterion_group!(benches, sample_li_batch, frame_update);
criterion_main!(benches);
