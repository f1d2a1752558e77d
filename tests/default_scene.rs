//! The embedded default scene: every light kind it promises is in the light table, and it renders.

use bevy_ecs::prelude::*;
use kelvin::light::{LightKind, LightTable};
use kelvin::render::renderer::{RenderOptions, Strategy, render};
use kelvin::shading::RunReport;
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
        &RenderOptions { width: 24, height: 24, spp: 2, strategy: Strategy::Mis },
        |_| {},
    );
    let report = world.resource::<RunReport>();
    assert!(report.warnings.is_empty(), "{report}");
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
