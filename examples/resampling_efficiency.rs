//! Equal-time efficiency, 1 / (relMSE x seconds), of resampled light selection against the light
//! BVH alone, through the light system's schedule on images of ground points with shadows: RIS
//! over M light-BVH candidates, ReSTIR spatial reuse (k neighbours, unbiased and biased weights)
//! and spatial plus temporal reuse in the steady state of a still scene; on the scaling scene at
//! 10,000 and 100,000 point and spot lights, and the panel room lit by 10,082 emissive triangles.
//! Then the dynamic case: 10,000 lights with 1% moving per frame, temporal reuse against the BVH.
//!
//! `cargo run --release --example resampling_efficiency [rows]` (an image of 32 x 16 points by
//! default; `scripts/resampling_efficiency.sh` runs it). The reference is `LightSelection::All`
//! (exact for the delta lights; 16 samples of every triangle for the panel); relMSE is the
//! image's (see `rel_mse`). Every method renders the same `FRAMES` frames from no history, and is
//! judged by the average of its frames at the time all of them took: temporal reuse pays for the
//! frames that build its history, and the light BVH's frames are averaged as a still image's are.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{AreaLight, LightSampleContext};
use kelvin::scenes::{spawn_emissive_panel_room, spawn_scaling_scene};
use kelvin::shading::{DirectLighting, ImageLayout, LightSelection, Restir, ReuseWeights, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;

/// Image width, points.
const WIDTH: u32 = 32;
/// Distance between neighbouring points, m, and the neighbourhood radius, points: neighbours
/// within 0.3 m (the light changes over metres here; far neighbours' samples help little).
const SPACING: f32 = 0.1;
const RADIUS: u32 = 3;
/// Frames of a still scene per method: enough for temporal reuse to reach its history cap (20 x M).
const FRAMES: u32 = 25;

/// Per point, sum Li cos / pdf over its entries divided by the samples per point, and the time
/// of the schedule run that made them. The batch is `WIDTH` wide; `frame` is the sample index.
/// Temporal reuse finds last run's points unless `frame` is 0, which starts without history.
fn estimate(
    world: &mut World,
    schedule: &mut Schedule,
    points: &[LightSampleContext],
    (selection, spp): (LightSelection, u32),
    seed: u64,
    frame: u32,
) -> (Vec<f64>, f64) {
    world.insert_resource(Settings { selection, samples_per_point: spp, seed, ..Default::default() });
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, p) in points.iter().enumerate() {
            batch.push(p.p, p.n, i as u32, frame);
        }
        batch.layout = Some(ImageLayout { width: WIDTH, samples_per_pixel: 1, first: 0 });
        batch.previous = if frame == 0 { Vec::new() } else { (0..points.len() as u32).collect() };
    }
    let start = std::time::Instant::now();
    schedule.run(world);
    let seconds = start.elapsed().as_secs_f64();
    let lighting = world.resource::<DirectLighting>();
    let values = (0..points.len())
        .map(|i| {
            // Each entry's pdf carries the spp samples: the sum is the estimate.
            lighting.irradiance(i, points[i].n).0.iter().map(|&c| c as f64).sum::<f64>()
        })
        .collect();
    (values, seconds)
}

/// Relative MSE of the whole image: the squared errors summed over the squared values. (A mean of
/// per-point relative errors is dominated by the few points deep in shadow, where the exact
/// value is near zero, and moved several-fold between runs.)
fn rel_mse(estimate: &[f64], exact: &[f64]) -> f64 {
    let squared_error: f64 = estimate.iter().zip(exact).map(|(e, x)| (e - x).powi(2)).sum();
    squared_error / exact.iter().map(|x| x * x).sum::<f64>()
}

/// An image of `WIDTH` x `rows` points `spacing` m apart, centred at `centre`: one contiguous
/// surface, as a camera sees it (neighbours in the image are neighbours on the ground).
fn image(centre: &LightSampleContext, rows: u32, spacing: f32) -> Vec<LightSampleContext> {
    let (half_x, half_y) = ((WIDTH as f32 - 1.0) / 2.0, (rows as f32 - 1.0) / 2.0);
    (0..WIDTH * rows)
        .map(|k| {
            let (x, y) = ((k % WIDTH) as f32 - half_x, (k / WIDTH) as f32 - half_y);
            LightSampleContext::on_surface(centre.p + Vec3::new(x, 0.0, y) * spacing, Vec3::Y)
        })
        .collect()
}

fn restir(candidates: u32, spatial: u32, temporal: bool, weights: ReuseWeights) -> LightSelection {
    LightSelection::Restir(Restir { candidates, spatial, radius: RADIUS, temporal, weights, ..Default::default() })
}

/// One table row; `mean` is the estimate's sum over the reference's (1 when unbiased), `last` the
/// relMSE of the last frame alone (NaN: not measured).
fn print_row(scene: &str, name: &str, (spp, seconds): (u32, f64), (error, mean, last): (f64, f64, f64), bvh: &mut f64) {
    let efficiency = 1.0 / (error * seconds);
    if *bvh == 0.0 {
        *bvh = efficiency;
    }
    let vs = efficiency / *bvh;
    let last = if last.is_nan() { "-".to_string() } else { format!("{last:.3e}") };
    println!(
        "| {scene} | {name} | {spp} | {seconds:.4} | {mean:.3} | {error:.3e} | {last} | {efficiency:.3e} | {vs:.2}x |"
    );
}

fn ratio(estimate: &[f64], exact: &[f64]) -> f64 {
    estimate.iter().sum::<f64>() / exact.iter().sum::<f64>()
}

fn main() {
    let rows: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(16);
    println!("| scene | method | spp | seconds | mean | relMSE | last frame relMSE | efficiency | vs BVH |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    // KELVIN_SCENES=panel (a substring) limits the run to matching scenes.
    let only = std::env::var("KELVIN_SCENES").unwrap_or_default();
    for scene in ["scaling 10k", "scaling 100k", "panel 10k triangles", "dynamic"] {
        if !scene.contains(only.as_str()) {
            continue;
        }
        if scene == "dynamic" {
            dynamic(rows);
            continue;
        }
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings::default());
        LightingPlugin::build(&mut world, &mut schedule);
        let points = match scene {
            "scaling 10k" => image(&spawn_scaling_scene(&mut world, 10_000, 1).ground_points(1, 3)[0], rows, SPACING),
            "scaling 100k" => image(&spawn_scaling_scene(&mut world, 100_000, 1).ground_points(1, 3)[0], rows, SPACING),
            _ => {
                let panel = spawn_emissive_panel_room(&mut world, 71, 1);
                // The panel's triangles emit instead of its stand-in spot lights.
                for e in &panel.lights {
                    world.despawn(*e);
                }
                world.entity_mut(panel.panel).insert(AreaLight::default());
                image(&LightSampleContext::on_surface(Vec3::ZERO, Vec3::Y), rows, SPACING)
            }
        };
        let reference_spp = if scene.starts_with("panel") { 16 } else { 1 };
        let all = (LightSelection::All, reference_spp);
        let (exact, _) = estimate(&mut world, &mut schedule, &points, all, 99, 0);
        let mut bvh_efficiency = 0.0;
        let spp = 64;
        let methods = [
            ("light BVH", LightSelection::OneSampled),
            ("RIS M=4", LightSelection::Resampled { candidates: 4 }),
            ("RIS M=8", LightSelection::Resampled { candidates: 8 }),
            ("spatial M=4 k=4", restir(4, 4, false, ReuseWeights::Unbiased)),
            ("spatial M=4 k=4 biased", restir(4, 4, false, ReuseWeights::Biased)),
            ("spatial M=1 k=4", restir(1, 4, false, ReuseWeights::Unbiased)),
            ("temporal M=4", restir(4, 0, true, ReuseWeights::Unbiased)),
            ("temporal M=1", restir(1, 0, true, ReuseWeights::Unbiased)),
            ("temporal+spatial M=4 k=4", restir(4, 4, true, ReuseWeights::Unbiased)),
            ("temporal+spatial M=1 k=4", restir(1, 4, true, ReuseWeights::Unbiased)),
            ("temporal+spatial M=1 k=4 biased", restir(1, 4, true, ReuseWeights::Biased)),
        ];
        for (name, selection) in methods {
            // An untimed run builds what the first one would (sampler kind, buffers); frame 0
            // then starts without history.
            estimate(&mut world, &mut schedule, &points, (selection, spp), 2, 0);
            let mut average = vec![0.0; points.len()];
            let (mut seconds, mut last) = (0.0, 0.0);
            for frame in 0..FRAMES {
                let (values, s) = estimate(&mut world, &mut schedule, &points, (selection, spp), 1, frame);
                for (a, v) in average.iter_mut().zip(&values) {
                    *a += v / FRAMES as f64;
                }
                seconds += s;
                last = rel_mse(&values, &exact);
            }
            let error = rel_mse(&average, &exact);
            let row = (error, ratio(&average, &exact), last);
            print_row(scene, name, (spp * FRAMES, seconds), row, &mut bvh_efficiency);
        }
    }
}

/// 10,000 lights, 1% of them moving each frame; per frame a few samples per point. The error of
/// each method against the exact per-frame sum (every 5th frame), and the time per frame.
fn dynamic(rows: u32) {
    println!();
    println!(
        "| dynamic: 10k lights, 1% moving | method | spp | seconds per frame | mean | relMSE | - | efficiency | vs BVH |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    let spp = 4;
    // The BVH averaged over frames (an exponential average of weight 1/20 a frame, the history
    // temporal reuse keeps at M=1) is what a still image's accumulation becomes when lights move.
    let methods = [
        ("light BVH", LightSelection::OneSampled),
        ("light BVH, averaged over frames", LightSelection::OneSampled),
        ("RIS M=4", LightSelection::Resampled { candidates: 4 }),
        ("temporal M=4", restir(4, 0, true, ReuseWeights::Unbiased)),
        ("temporal M=1", restir(1, 0, true, ReuseWeights::Unbiased)),
        ("temporal+spatial M=1 k=4", restir(1, 4, true, ReuseWeights::Unbiased)),
    ];
    let mut bvh_efficiency = 0.0;
    for (name, selection) in methods {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        world.insert_resource(Settings::default());
        LightingPlugin::build(&mut world, &mut schedule);
        let scene = spawn_scaling_scene(&mut world, 10_000, 1);
        let points = image(&scene.ground_points(1, 3)[0], rows, SPACING);
        let mut rng = kelvin::rng::SplitMix64::new(11);
        let (mut error, mut mean, mut seconds, mut measured) = (0.0, 0.0, 0.0, 0);
        let mut average: Option<Vec<f64>> = None;
        for frame in 0..100u32 {
            for _ in 0..scene.lights.len() / 100 {
                let e = scene.lights[rng.below(scene.lights.len())];
                let step = Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0));
                if let Some(mut t) = world.get_mut::<Transform>(e) {
                    t.translation += step;
                }
            }
            // Every frame's time counts, the ones that build temporal reuse's history too.
            let (mut values, s) = estimate(&mut world, &mut schedule, &points, (selection, spp), 1, frame);
            seconds += s;
            if name.contains("averaged") {
                let a = average.get_or_insert_with(|| values.clone());
                for (a, v) in a.iter_mut().zip(&values) {
                    *a += (v - *a) / 20.0;
                }
                values.clone_from(a);
            }
            if frame >= 20 && frame % 5 == 0 {
                let (exact, _) = estimate(&mut world, &mut schedule, &points, (LightSelection::All, 1), 99, 0);
                (error, measured) = (error + rel_mse(&values, &exact), measured + 1);
                mean += ratio(&values, &exact);
            }
        }
        let n = measured as f64;
        print_row("10k moving", name, (spp, seconds / 100.0), (error / n, mean / n, f64::NAN), &mut bvh_efficiency);
    }
}
