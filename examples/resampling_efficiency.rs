//! Equal-time efficiency, 1 / (relMSE x seconds), of resampled light selection (RIS over M
//! light-BVH candidates) against the light BVH alone, through the light system's schedule on
//! ground points with shadows: the scaling scene at 10,000 and 100,000 point and spot lights, and
//! the panel room lit by 10,082 emissive triangles.
//!
//! `cargo run --release --example resampling_efficiency [points]` (default 256 points). The
//! reference is `LightSelection::All` (exact for the delta lights; 16 samples of every triangle
//! for the panel).

use bevy_ecs::prelude::*;
use kelvin::light::{AreaLight, LightSampleContext};
use kelvin::scenes::{spawn_emissive_panel_room, spawn_scaling_scene};
use kelvin::shading::{DirectLighting, LightSelection, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;

/// Per point, sum Li cos / pdf over its entries divided by the samples per point, and the time
/// of the schedule run that made them.
fn estimate(
    world: &mut World,
    schedule: &mut Schedule,
    points: &[LightSampleContext],
    selection: LightSelection,
    spp: u32,
    seed: u64,
) -> (Vec<f64>, f64) {
    world.insert_resource(Settings { selection, samples_per_point: spp, seed, ..Default::default() });
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, p) in points.iter().enumerate() {
            batch.push(p.p, p.n, i as u32, 0);
        }
    }
    let start = std::time::Instant::now();
    schedule.run(world);
    let seconds = start.elapsed().as_secs_f64();
    let lighting = world.resource::<DirectLighting>();
    let values = (0..points.len())
        .map(|i| {
            let sum: f64 = lighting.irradiance(i, points[i].n).0.iter().map(|&c| c as f64).sum();
            sum / spp as f64
        })
        .collect();
    (values, seconds)
}

fn rel_mse(estimate: &[f64], exact: &[f64]) -> f64 {
    estimate.iter().zip(exact).map(|(e, x)| (e - x).powi(2) / (x * x + 1e-6)).sum::<f64>() / exact.len() as f64
}

fn main() {
    let n_points: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(256);
    println!("| scene | method | spp | seconds | relMSE | efficiency | vs BVH |");
    println!("|---|---|---:|---:|---:|---:|---:|");
    for scene in ["scaling 10k", "scaling 100k", "panel 10k triangles"] {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings::default());
        LightingPlugin::build(&mut world, &mut schedule);
        let points = match scene {
            "scaling 10k" => spawn_scaling_scene(&mut world, 10_000, 1).ground_points(n_points, 3),
            "scaling 100k" => spawn_scaling_scene(&mut world, 100_000, 1).ground_points(n_points, 3),
            _ => {
                let panel = spawn_emissive_panel_room(&mut world, 71, 1);
                // The panel's triangles emit instead of its stand-in spot lights.
                for e in &panel.lights {
                    world.despawn(*e);
                }
                world.entity_mut(panel.panel).insert(AreaLight::default());
                panel.floor_points(n_points, 3)
            }
        };
        let reference_spp = if scene.starts_with("panel") { 16 } else { 1 };
        let (exact, _) = estimate(&mut world, &mut schedule, &points, LightSelection::All, reference_spp, 99);
        let mut bvh_efficiency = 0.0;
        let methods = [
            ("light BVH", LightSelection::OneSampled),
            ("RIS M=4", LightSelection::Resampled { candidates: 4 }),
            ("RIS M=8", LightSelection::Resampled { candidates: 8 }),
            ("RIS M=16", LightSelection::Resampled { candidates: 16 }),
        ];
        for (name, selection) in methods {
            let spp = 64;
            // A warm-up run builds what the first one would (sampler kind, buffers).
            estimate(&mut world, &mut schedule, &points, selection, spp, 1);
            let (mut error, mut seconds) = (0.0, f64::INFINITY);
            for seed in 2..5 {
                let (values, s) = estimate(&mut world, &mut schedule, &points, selection, spp, seed);
                (error, seconds) = (error + rel_mse(&values, &exact) / 3.0, seconds.min(s));
            }
            let efficiency = 1.0 / (error * seconds);
            if bvh_efficiency == 0.0 {
                bvh_efficiency = efficiency;
            }
            println!(
                "| {scene} | {name} | {spp} | {seconds:.4} | {error:.3e} | {efficiency:.3e} | {:.2}x |",
                efficiency / bvh_efficiency
            );
        }
    }
}
