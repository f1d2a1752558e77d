//! The embedded default scene: every light kind it promises is in the light table, and it renders.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{LightKind, LightTable, PointLight};
use kelvin::light_sampler::LightSampler;
use kelvin::render::renderer::{RenderOptions, Strategy, render};
use kelvin::shading::{LightSamplerKind, RunReport, Settings};
use kelvin::systems::LightingPlugin;

#[test]
fn default_scene_has_area_spot_blackbody_point_and_sky_lights_and_renders() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    kelvin::scenes::default_scene::spawn_default_scene(&mut world);
    let (film, stats) = render(
        &mut world,
        &mut schedule,
        &RenderOptions { width: 24, height: 24, spp: 2, strategy: Strategy::Mis, crop: None },
        |_| {},
    );
    assert!(stats.report.warnings.is_empty(), "{}", stats.report);
    // Lights are chosen by the light BVH unless the settings say otherwise (as in pbrt-v4).
    assert_eq!(Settings::default().light_sampler, LightSamplerKind::Bvh);
    assert_eq!(world.resource::<LightSampler>().kind(), LightSamplerKind::Bvh);
    let table = world.resource::<LightTable>();
    let kinds: Vec<LightKind> = table.ids().map(|id| id.kind).collect();
    for k in [LightKind::Area, LightKind::Spot, LightKind::Point, LightKind::UniformInfinite] {
        assert!(kinds.contains(&k), "{k:?} missing from {kinds:?}");
    }
    assert!(film.pixels().iter().all(|p| p.is_finite()) && stats.shadow_rays > 0);
    // MIS traces one BSDF ray per camera sample that hit a surface (most of them, in a room).
    assert_eq!(stats.camera_samples, 24 * 24 * 2);
    assert!(stats.bsdf_rays > stats.camera_samples / 2 && stats.bsdf_rays <= stats.camera_samples, "{stats:?}");
    // Every pass took time, and together no more than the render.
    let p = stats.passes;
    assert!(p.camera > 0.0 && p.light_system > 0.0 && p.shading > 0.0, "{p:?}");
    assert!(p.camera + p.light_system + p.shading <= stats.seconds, "{stats:?}");
}

#[test]
fn table_length_counts_every_kind() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    kelvin::scenes::default_scene::spawn_default_scene(&mut world);
    schedule.run(&mut world);
    let table = world.resource::<LightTable>();
    assert_eq!(table.len(), table.ids().count());
    assert_eq!(table.len(), 4);
}

/// The render's report covers all of it: a light rejected in the first update (before any
/// batch) is still reported at the end, and the counts are summed over the batches.
#[test]
fn render_report_keeps_every_warning_and_sums_counts_over_batches() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    kelvin::scenes::default_scene::spawn_default_scene(&mut world);
    world.spawn((PointLight::candela(-5.0), Transform::from_translation(Vec3::Y)));
    // 96 x 96 x 4 = 36864 camera samples: three batches, after the update that syncs the scene.
    let opts = RenderOptions { width: 96, height: 96, spp: 4, strategy: Strategy::Mis, crop: None };
    let (_, stats) = render(&mut world, &mut schedule, &opts, |_| {});
    let report = &stats.report;
    assert_eq!(report.updates, 4, "{report}");
    assert_eq!(report.warnings.len(), 1, "{report}");
    assert!(report.warnings[0].contains("PointLight: amount = -5 must be finite and >= 0"), "{report}");
    assert_eq!(report.runs("sample_direct_lighting"), 3, "{report}");
    assert_eq!(report.count("sample_direct_lighting"), stats.camera_samples, "{report}");
    assert_eq!(report.count("trace_shadow_rays"), stats.shadow_rays, "{report}");
    assert_eq!(report.line("sample_direct_lighting", false).map(|l| l.updates), Some(1), "{report}");
    // The sampler was built once, in the first update, and left alone by the batches.
    assert_eq!(report.runs("update_light_sampler"), 1, "{report}");
    assert_eq!(report.line("update_light_sampler", false).map(|l| l.updates), Some(3), "{report}");
    let text = report.to_string();
    assert!(text.contains("36864 points in all") && text.contains("warning: light"), "{text}");
    // The world's report is the last update's alone, as an app that runs once per frame reads it.
    assert!(world.resource::<RunReport>().warnings.is_empty());
}
