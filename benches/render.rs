//! Renderer throughput: camera samples per second for the default scene and the point light over
//! a plane, at 128x128 and 64 spp (1M samples per render).

use bevy_ecs::prelude::*;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use kelvin::render::renderer::{RenderOptions, Strategy, render};
use kelvin::systems::LightingPlugin;

fn world_with(spawn: fn(&mut World)) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    spawn(&mut world);
    (world, schedule)
}

fn bench_render(c: &mut Criterion) {
    let opts = RenderOptions { width: 128, height: 128, spp: 64, strategy: Strategy::Mis };
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

criterion_group!(benches, bench_render);
criterion_main!(benches);
