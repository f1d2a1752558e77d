//! Renderer throughput: camera samples per second for the default scene and the point light over
//! a plane, at 128x128 and 64 spp (1M samples per render), and for the render suite's real glTF
//! files (`kelvin::report::render_bench::SUITE`, as `kelvin bench render` renders them) at
//! 128x128 and 4 spp.

use bevy_ecs::prelude::*;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use kelvin::render::renderer::{Integrator, RenderOptions, render};
use kelvin::report::render_bench::{RenderBenchConfig, SUITE, suite_options};
use kelvin::systems::LightingPlugin;

fn world_with(spawn: fn(&mut World)) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    spawn(&mut world);
    (world, schedule)
}

fn bench_render(c: &mut Criterion) {
    let opts = RenderOptions::direct(128, 128, 64);
    let mut group = c.benchmark_group("render_128x128_64spp");
    group.sample_size(10).throughput(Throughput::Elements(128 * 128 * 64));
    for (name, spawn) in [
        ("point_over_plane", kelvin::scenes::bench_scenes::spawn_point_over_plane as fn(&mut World)),
        ("default_scene", kelvin::scenes::default_scene::spawn_default_scene),
    ] {
        let (mut world, mut schedule) = world_with(spawn);
        group.bench_function(name, |b| b.iter(|| render(&mut world, &mut schedule, &opts, |_| {})));
    }
    group.finish();
}

/// Samples per pixel of the suite's criterion runs: small, so that the eight scenes take about a
/// minute; `kelvin bench render` times them at about a second per render.
const SUITE_SPP: u32 = 4;

fn bench_suite(c: &mut Criterion) {
    let data_dir = RenderBenchConfig::default().data_dir;
    let opts = suite_options(128, 128, SUITE_SPP, Integrator::Direct);
    let mut group = c.benchmark_group("suite_128x128_4spp");
    group.sample_size(10).throughput(Throughput::Elements(128 * 128 * SUITE_SPP as u64));
    group.warm_up_time(std::time::Duration::from_secs(1)).measurement_time(std::time::Duration::from_secs(3));
    for scene in SUITE {
        let (mut world, mut schedule, _) = scene.world(&data_dir).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        // The first render builds the scene BVH, light table and sampler; the timed ones reuse them.
        render(&mut world, &mut schedule, &suite_options(128, 128, 1, Integrator::Direct), |_| {});
        group.bench_function(scene.name, |b| b.iter(|| render(&mut world, &mut schedule, &opts, |_| {})));
    }
    group.finish();
}

criterion_group!(benches, bench_render, bench_suite);
criterion_main!(benches);
