//! Resampled importance sampling of lights (`LightSelection::Resampled`) and reservoir reuse
//! (`LightSelection::Restir`) through the schedule: unbiased against the exact sum over every
//! light on the 10,000-light scaling scene, with error falling as 1/spp and below the light BVH's
//! (and RIS's) at equal samples; targets that are zero somewhere (a light under the floor, a
//! back-facing panel) add no bias; temporal reuse (light_resampling/temporal.rs) follows moving
//! lights, removed lights and moving points, alone and with spatial reuse; bad reuse input never
//! panics.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::{Rectangle, Transform};
use kelvin::light::{LightSampleContext, PointLight};
use kelvin::scenes::spawn_scaling_scene;
use kelvin::shading::{
    DirectLighting, ImageLayout, LightSamplerKind, LightSelection, Restir, ReuseWeights, Settings, ShadingBatch,
};
use kelvin::systems::LightingPlugin;

#[path = "light_resampling/temporal.rs"]
mod temporal;

/// Settings with independent random numbers: the error laws (1/spp) and the comparisons at equal
/// samples are the estimators', not the Sobol pattern's (which RIS alone takes and ReSTIR does not).
/// The unbiasedness tests run under the default pattern.
fn independent() -> Settings {
    Settings { pattern: kelvin::rng::Pattern::Independent, ..Default::default() }
}

/// A world with the light system's schedule and `settings`.
fn world_with(settings: Settings) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(settings);
    LightingPlugin::build(&mut world, &mut schedule);
    (world, schedule)
}

/// A 10 x 10 m floor at y = 0 facing up.
fn spawn_floor(world: &mut World) {
    let up = Transform::default().looking_to(Vec3::NEG_Y, Vec3::Z);
    world.spawn((Rectangle { half_size: glam::Vec2::splat(5.0) }, up));
}

/// No entry of the last run has a direction from under the floor (its target is zero there).
fn assert_no_sample_from_below(world: &World) {
    let lighting = world.resource::<DirectLighting>();
    assert!(lighting.wi.iter().zip(&lighting.pdf).all(|(w, &p)| p == 0.0 || w.y > 0.0), "no sample from below");
}

/// Per point, the cosine-weighted estimate sum Li cos / pdf over its entries, averaged over its
/// samples (irradiance, RGB summed over channels), with shadows.
fn irradiance(
    world: &mut World,
    schedule: &mut Schedule,
    points: &[LightSampleContext],
    selection: LightSelection,
    spp: u32,
) -> Vec<f64> {
    irradiance_of(world, schedule, points, selection, spp, Frame::default())
}

/// How a batch sits among others: its points' image width (for spatial reuse), each point's
/// index in last run's batch (temporal reuse; `SAME` for the same points in the same order), and
/// the sample index (the frame).
#[derive(Clone, Copy, Default)]
struct Frame<'a> {
    width: Option<u32>,
    previous: Option<&'a [u32]>,
    sample: u32,
}

/// `Frame::previous` for last run's points in the same order.
const SAME: &[u32] = &[];

fn irradiance_of(
    world: &mut World,
    schedule: &mut Schedule,
    points: &[LightSampleContext],
    selection: LightSelection,
    spp: u32,
    frame: Frame<'_>,
) -> Vec<f64> {
    let Settings { light_sampler, pattern, .. } = *world.resource::<Settings>();
    world.insert_resource(Settings {
        selection,
        samples_per_point: spp,
        seed: 17,
        light_sampler,
        pattern,
        ..Default::default()
    });
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, p) in points.iter().enumerate() {
            batch.push(p.p, p.n, i as u32, frame.sample);
        }
        batch.layout = frame.width.map(|width| ImageLayout { width, samples_per_pixel: 1, first: 0 });
        match frame.previous {
            Some(SAME) => batch.previous = (0..points.len() as u32).collect(),
            Some(previous) => batch.previous = previous.to_vec(),
            None => {}
        }
    }
    schedule.run(world);
    let lighting = world.resource::<DirectLighting>();
    (0..points.len())
        .map(|i| {
            // Each entry's pdf carries the spp samples: the sum is the estimate.
            lighting.irradiance(i, points[i].n).0.iter().map(|&c| c as f64).sum::<f64>()
        })
        .collect()
}

fn rel_mse(estimate: &[f64], exact: &[f64]) -> f64 {
    estimate.iter().zip(exact).map(|(e, x)| (e - x).powi(2) / (x * x + 1e-6)).sum::<f64>() / exact.len() as f64
}

#[test]
fn resampling_is_unbiased_on_ten_thousand_lights_and_beats_the_light_bvh_at_equal_samples() {
    let (mut world, mut schedule) = world_with(independent());
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
    let (mut world, mut schedule) =
        world_with(Settings { light_sampler: LightSamplerKind::Uniform, ..Default::default() });
    spawn_floor(&mut world);
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
    assert_no_sample_from_below(&world);
}

/// A `width` x `width` image of ground points `spacing` m apart, centred at `centre`.
fn image(centre: Vec3, width: u32, spacing: f32) -> Vec<LightSampleContext> {
    let half = (width as f32 - 1.0) / 2.0;
    (0..width * width)
        .map(|k| {
            let (x, y) = ((k % width) as f32 - half, (k / width) as f32 - half);
            LightSampleContext::on_surface(centre + Vec3::new(x, 0.0, y) * spacing, Vec3::Y)
        })
        .collect()
}

/// Spatial reuse only (no history), `k` neighbours.
fn spatial(k: u32, weights: ReuseWeights) -> LightSelection {
    LightSelection::Restir(Restir {
        candidates: 8,
        spatial: k,
        radius: 6,
        temporal: false,
        weights,
        ..Default::default()
    })
}

/// Spatial reuse on a 16 x 16 image of the 10,000-light scene: the unbiased (balance-heuristic)
/// combination converges to the exact sum within 1% with relMSE falling as 1/spp, and at equal
/// samples beats RIS alone (the reuse brings neighbours' candidates).
#[test]
fn spatial_reuse_is_unbiased_on_ten_thousand_lights() {
    let (mut world, mut schedule) = world_with(independent());
    let scene = spawn_scaling_scene(&mut world, 10_000, 1);
    let centre = scene.ground_points(1, 5)[0].p;
    let points = image(centre, 16, 0.25);
    let exact = irradiance(&mut world, &mut schedule, &points, LightSelection::All, 1);
    assert!(exact.iter().all(|&x| x > 0.0), "every point is lit");
    let frame = Frame { width: Some(16), ..Default::default() };
    let mut run = |selection, spp| irradiance_of(&mut world, &mut schedule, &points, selection, spp, frame);
    let unbiased = spatial(4, ReuseWeights::Unbiased);
    let (low, high) = (run(unbiased, 16), run(unbiased, 256));
    let ris = run(LightSelection::Resampled { candidates: 8 }, 16);
    let biased = run(spatial(4, ReuseWeights::Biased), 256);
    let total = |v: &[f64]| v.iter().sum::<f64>();
    let (mean, mean_biased) = (total(&high) / total(&exact), total(&biased) / total(&exact));
    let (err_low, err_high, err_ris) = (rel_mse(&low, &exact), rel_mse(&high, &exact), rel_mse(&ris, &exact));
    eprintln!(
        "spatial k=4: mean {mean:.4} (biased weights {mean_biased:.4}); relMSE 16 spp {err_low:.3e}, 256 spp \
         {err_high:.3e}; RIS alone 16 spp {err_ris:.3e}"
    );
    assert!((mean - 1.0).abs() < 0.01, "spatial reuse mean {mean}");
    let fall = err_low / err_high;
    assert!((8.0..32.0).contains(&fall), "relMSE fell {fall}x for 16x spp");
    assert!(err_low < err_ris, "spatial {err_low} vs RIS {err_ris} at 16 spp");
    let report = format!("{:?}", world.resource::<kelvin::shading::RunReport>());
    assert!(report.contains("ReSTIR: RIS M=8; temporal off; spatial: k=4 within 6 px"), "{report}");
}

/// The hard case for combining reservoirs: a target that is zero at some points and not at
/// others. A one-sided panel stands upright across the middle of a floor image, facing +x: for
/// the half of the image behind it the panel's target is zero, so a neighbour from that half
/// could never have produced the panel samples it is combined with. A light under the floor has
/// zero target everywhere. The balance-heuristic weights count only reservoirs that could have
/// produced the sample (no bias); 1/sum M counts them all, and is darker in front of the panel.
#[test]
fn a_back_facing_light_gives_spatial_reuse_no_bias() {
    // The uniform sampler draws the light under the floor as often as any (the light BVH would not).
    let (mut world, mut schedule) =
        world_with(Settings { light_sampler: LightSamplerKind::Uniform, ..Default::default() });
    spawn_floor(&mut world);
    let facing_x = Transform::from_translation(Vec3::new(0.0, 0.35, 0.0)).looking_to(Vec3::NEG_X, Vec3::Y);
    world.spawn((kelvin::light::AreaLight::default(), Rectangle { half_size: glam::Vec2::splat(0.3) }, facing_x));
    world.spawn((PointLight::candela(20.0), Transform::from_translation(Vec3::new(-0.5, 2.0, 0.0))));
    world.spawn((PointLight::candela(5000.0), Transform::from_translation(Vec3::new(0.0, -1.0, 0.0))));
    let points = image(Vec3::ZERO, 16, 0.1);
    let exact = irradiance(&mut world, &mut schedule, &points, LightSelection::All, 256);
    let front: Vec<usize> = (0..points.len()).filter(|&i| points[i].p.x > 0.0).collect();
    let behind = |v: &[f64]| (0..points.len()).filter(|&i| points[i].p.x < 0.0).map(|i| v[i]).sum::<f64>();
    let ahead = |v: &[f64]| front.iter().map(|&i| v[i]).sum::<f64>();
    assert!(ahead(&exact) > 5.0 * behind(&exact), "the panel lights the front half: {exact:?}");
    let frame = Frame { width: Some(16), ..Default::default() };
    let mut run = |weights| irradiance_of(&mut world, &mut schedule, &points, spatial(4, weights), 512, frame);
    let (unbiased, biased) = (run(ReuseWeights::Unbiased), run(ReuseWeights::Biased));
    let (ratio, ratio_biased) = (ahead(&unbiased) / ahead(&exact), ahead(&biased) / ahead(&exact));
    let ratio_behind = behind(&unbiased) / behind(&exact);
    eprintln!("in front of the panel: unbiased {ratio:.4}, biased {ratio_biased:.4}; behind: {ratio_behind:.4}");
    assert!((ratio - 1.0).abs() < 0.02, "unbiased weights in front of the panel: {ratio}");
    assert!((ratio_behind - 1.0).abs() < 0.02, "unbiased weights behind the panel: {ratio_behind}");
    assert!(ratio_biased < ratio - 0.02, "the case is hard: 1/sum M is biased here ({ratio_biased} vs {ratio})");
    assert_no_sample_from_below(&world);
}

/// Bad input to reuse never panics and never makes a non-finite entry: previous indices out of
/// range (and past the end of u32), an image layout whose `first` is near u64::MAX or whose
/// width is 0, NaN positions, a batch that shrinks to empty and grows again, and samples per
/// point changing between runs (the history no longer fits).
#[test]
fn bad_reuse_input_never_panics() {
    let (mut world, mut schedule) = world_with(Settings::default());
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
    let selection = LightSelection::Restir(Restir { spatial: 16, radius: 1000, ..Default::default() });
    let layouts = [
        Some(ImageLayout { width: 0, samples_per_pixel: 0, first: 0 }),
        Some(ImageLayout { width: 3, samples_per_pixel: 2, first: u64::MAX - 1 }),
        Some(ImageLayout { width: u32::MAX, samples_per_pixel: u32::MAX, first: 5 }),
        Some(ImageLayout { width: 1, samples_per_pixel: 1, first: 0 }),
        None,
    ];
    for (run, layout) in layouts.into_iter().enumerate() {
        let spp = 1 + run as u32 % 2;
        world.insert_resource(Settings { selection, samples_per_point: spp, ..Default::default() });
        {
            let mut batch = world.resource_mut::<ShadingBatch>();
            batch.clear();
            let n = if run == 3 { 0 } else { 20 };
            for i in 0..n {
                let x = if i % 7 == 3 { f32::NAN } else { i as f32 * 0.1 };
                batch.push(Vec3::new(x, 0.0, 0.0), Vec3::Y, i, run as u32);
            }
            batch.previous = (0..n).map(|i| [i, i + 1000, u32::MAX, u32::MAX - 1][i as usize % 4]).collect();
            batch.layout = layout;
        }
        schedule.run(&mut world);
        let lighting = world.resource::<DirectLighting>();
        assert!(lighting.radiance.iter().all(|r| r.is_finite()), "run {run}");
        assert!(lighting.pdf.iter().all(|p| p.is_finite() && *p >= 0.0), "run {run}");
        assert!(run == 3 || lighting.pdf.iter().any(|&p| p > 0.0), "run {run}: some entry is lit");
    }
}
