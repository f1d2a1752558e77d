//! The ECS keeps an image light's sampling tables when a change leaves its image and table
//! options as they were, updates only the rewritten rows when some rows of the same-size image
//! change (equal to a fresh build), and builds anew otherwise. On the repository's real HDR.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{EnvMapTables, ImageInfiniteLight};
use kelvin::scene::image::RgbImage;
use kelvin::shading::{RunReport, Settings};
use kelvin::systems::{EnvTables, LightingPlugin};

fn why(world: &World) -> String {
    let report = world.resource::<RunReport>();
    report.entries.iter().filter(|e| e.system == "env_tables").map(|e| e.why.clone()).collect::<Vec<_>>().join("; ")
}

fn tables(world: &World, e: Entity) -> Arc<EnvMapTables> {
    world.resource::<EnvTables>().by_entity[&e].clone()
}

#[test]
fn tables_are_kept_updated_by_rows_or_rebuilt_as_the_change_calls_for() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/env/spiaggia_di_mondello_1k.hdr");
    let image = Arc::new(kelvin::scene::image::load_image(std::path::Path::new(path)).unwrap().image);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings::default());
    LightingPlugin::build(&mut world, &mut schedule);
    // No MIS compensation: row updates then equal a fresh build bit for bit.
    let light = ImageInfiniteLight { mis_compensation: false, ..ImageInfiniteLight::new(image.clone()) };
    let options = light.table_options();
    let e = world.spawn((light, Transform::default())).id();
    schedule.run(&mut world);
    assert!(why(&world).contains("tables built"), "{}", why(&world));
    let first = tables(&world, e);

    // A brighter sky of the same image: the tables stay.
    world.get_mut::<ImageInfiniteLight>(e).unwrap().scale = 3.0;
    schedule.run(&mut world);
    assert!(why(&world).contains("tables kept"), "{}", why(&world));
    assert!(Arc::ptr_eq(&first, &tables(&world, e)));

    // Rows 100..116 repainted (a cloud): only they are updated, and the tables equal a fresh build.
    let mut painted: RgbImage = (*image).clone();
    let w = painted.width;
    for y in 100..116 {
        for p in &mut painted.pixels[y * w + 40..y * w + 300] {
            *p = Vec3::new(50.0, 40.0, 30.0);
        }
    }
    let painted = Arc::new(painted);
    world.get_mut::<ImageInfiniteLight>(e).unwrap().image = painted.clone();
    schedule.run(&mut world);
    assert!(why(&world).contains(&format!("rows 100..116 of {} changed", image.height)), "{}", why(&world));
    let updated = tables(&world, e);
    assert!(*updated == EnvMapTables::build_with(&painted, options), "row update differs from a fresh build");
    assert!(*updated != *first, "the painted rows changed the tables");

    // Another size: built anew.
    let small = Arc::new(RgbImage { width: 8, height: 4, pixels: vec![Vec3::ONE; 32] });
    world.get_mut::<ImageInfiniteLight>(e).unwrap().image = small.clone();
    schedule.run(&mut world);
    assert!(why(&world).contains("tables built"), "{}", why(&world));
    assert!(*tables(&world, e) == EnvMapTables::build_with(&small, options));
}
