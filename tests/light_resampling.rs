//! Resampled importance sampling of lights (`LightSelection::Resampled`) through the schedule:
//! unbiased against the exact sum over every light on the 10,000-light scaling scene, with error
//! falling as 1/spp and below the light BVH's alone at equal samples; a target that is zero where
//! no light reflects (a light under the floor) adds no bias.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::{Rectangle, Transform};
use kelvin::light::{LightSampleContext, PointLight};
use kelvin::scenes::spawn_scaling_scene;
use kelvin::shading::{DirectLighting, LightSelection, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;

/// Per point, the cosine-weighted estimate sum Li cos / pdf over its entries, averaged over its
/// samples (irradiance, RGB summed over channels), with shadows.
fn irradiance(
    world: &mut World,
    schedule: &mut Schedule,
    points: &[LightSampleContext],
    selection: LightSelection,
    spp: u32,
) -> Vec<f64> {
    let light_sampler = world.resource::<Settings>().light_sampler;
    world.insert_resource(Settings {
        selection,
        samples_per_point: spp,
        seed: 17,
        light_sampler,
        ..Default::default()
    });
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, p) in points.iter().enumerate() {
            batch.push(p.p, p.n, i as u32, 0);
        }
    }
    schedule.run(world);
    let lighting = world.resource::<DirectLighting>();
    (0..points.len())
        .map(|i| {
            let sum: f64 = lighting.irradiance(i, points[i].n).0.iter().map(|&c| c as f64).sum();
            let n = if selection == LightSelection::All { 1.0 } else { spp as f64 };
            sum / n
        })
        .collect()
}

fn rel_mse(estimate: &[f64], exact: &[f64]) -> f64 {
    estimate.iter().zip(exact).map(|(e, x)| (e - x).powi(2) / (x * x + 1e-6)).sum::<f64>() / exact.len() as f64
}

#[test]
fn resampling_is_unbiased_on_ten_thousand_lights_and_beats_the_light_bvh_at_equal_samples() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings::default());
    LightingPlugin::build(&mut world, &mut schedule);
    let scene = spawn_scaling_scene(&mut world, 10_000, 1);
    let points = scene.ground_points(64, 3);
    // `All` gives each light's exact (shadowed) contribution: the reference per point.
    let exact = irradiance(&mut world, &mut schedule, &points, LightSelection::All, 1);
    assert!(exact.iter().all(|&x| x > 0.0), "every point is lit");
    let ris = |world: &mut World, schedule: &mut Schedule, spp| {
        irradiance(world, schedule, &points, LightSelection::Resampled { candidates: 8 }, spp)
    };
    let (low, high) = (ris(&mut world, &mut schedule, 64), ris(&mut world, &mut schedule, 1024));
    let bvh = irradiance(&mut world, &mut schedule, &points, LightSelection::OneSampled, 64);
    let total = |v: &[f64]| v.iter().sum::<f64>();
    let mean_ratio = total(&high) / total(&exact);
    let (err_low, err_high, err_bvh) = (rel_mse(&low, &exact), rel_mse(&high, &exact), rel_mse(&bvh, &exact));
    eprintln!(
        "mean ratio {mean_ratio:.4}; relMSE RIS(8) 64 spp {err_low:.3e}, 1024 spp {err_high:.3e}; BVH 64 spp {err_bvh:.3e}"
    );
    assert!((mean_ratio - 1.0).abs() < 0.01, "RIS mean {mean_ratio}");
    // 16x the samples: 1/16 of the error (within noise of the error estimate itself).
    let fall = err_low / err_high;
    assert!((8.0..32.0).contains(&fall), "relMSE fell {fall}x for 16x spp");
    assert!(err_low < err_bvh, "RIS {err_low} vs BVH {err_bvh} at 64 spp");
    // The run report says which selection ran (the last update was the BVH's one-sampled one).
    irradiance(&mut world, &mut schedule, &points, LightSelection::Resampled { candidates: 8 }, 1);
    let report = world.resource::<kelvin::shading::RunReport>();
    let said = format!("{report:?}");
    assert!(said.contains("resampled (RIS) from 8 candidates"), "{said}");
}

/// The target (unshadowed contribution at the shading normal) is zero for a light under the
/// floor, where the floor reflects nothing of it either: no bias, and no sample of it. The
/// uniform sampler draws that light as often as the one above (the light BVH would not).
#[test]
fn a_light_behind_the_surface_has_zero_target_and_no_bias() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { light_sampler: kelvin::shading::LightSamplerKind::Uniform, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Rectangle { half_size: glam::Vec2::splat(5.0) }, up));
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.5, 2.0, 0.0))));
    world.spawn((PointLight::candela(5000.0), Transform::from_translation(Vec3::new(0.0, -1.0, 0.0))));
    let points: Vec<_> =
        (0..16).map(|i| LightSampleContext::on_surface(Vec3::new(i as f32 * 0.1, 0.0, 0.0), Vec3::Y)).collect();
    let exact = irradiance(&mut world, &mut schedule, &points, LightSelection::All, 1);
    let ris = irradiance(&mut world, &mut schedule, &points, LightSelection::Resampled { candidates: 4 }, 256);
    // Per sample the estimate is (k / M) / pmf times the light above's share, k ~ B(4, 1/2) the
    // candidates that drew it: 3.1% noise per point at 256 spp, 0.8% over the 16 points.
    let ratio = ris.iter().sum::<f64>() / exact.iter().sum::<f64>();
    eprintln!("RIS / exact with a light under the floor: {ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.03, "{ratio}");
    let lighting = world.resource::<DirectLighting>();
    assert!(lighting.wi.iter().zip(&lighting.pdf).all(|(w, &p)| p == 0.0 || w.y > 0.0), "no sample from below");
}
