//! Light samplers on the scaling scene (10k and 100k lights): building the BVH, refitting it
//! when 1% of the lights move, and choosing a light (uniform, power, BVH).

use criterion::{Criterion, criterion_group, criterion_main};
use kelvin::light_sampler::{BvhSampler, LightSampler};
use kelvin::report::lights::{move_fraction, scaling_scene_table};
use kelvin::scenes::scene_rng;
use kelvin::shading::LightSamplerKind;
use std::hint::black_box;
use std::time::{Duration, Instant};

const COUNTS: [usize; 2] = [10_000, 100_000];

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_bvh_build");
    group.sample_size(10);
    for n in COUNTS {
        let (table, _) = scaling_scene_table(n, 1, 1);
        group.bench_function(format!("{n}"), |b| b.iter(|| black_box(BvhSampler::build(black_box(&table)))));
    }
    group.finish();
}

fn refit(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_bvh_refit_1pct");
    for n in COUNTS {
        let (mut table, _) = scaling_scene_table(n, 1, 1);
        let mut sampler = BvhSampler::build(&table);
        let mut rng = scene_rng(2);
        // Each iteration is a frame: 1% of the lights move by up to 0.25 m (not timed), the sampler
        // follows.
        group.bench_function(format!("{n}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    table.clear_change_flags();
                    move_fraction(&mut table, 0.01, 0.25, &mut rng);
                    let t = Instant::now();
                    black_box(sampler.update(&table));
                    total += t.elapsed();
                }
                total
            })
        });
    }
    group.finish();
}

fn sample(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_sample");
    for n in COUNTS {
        let (table, points) = scaling_scene_table(n, 1, 256);
        for kind in [LightSamplerKind::Uniform, LightSamplerKind::Power, LightSamplerKind::Bvh] {
            let sampler = LightSampler::build(kind, &table);
            let (mut i, mut u) = (0usize, 0.1234f32);
            group.bench_function(format!("{kind:?}/{n}"), |b| {
                b.iter(|| {
                    i = (i + 1) % points.len();
                    u = (u + 0.618_034).fract();
                    black_box(sampler.sample(black_box(&points[i]), black_box(u)))
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, build, refit, sample);
criterion_main!(benches);
