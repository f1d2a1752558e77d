//! The game loop: 10k lights of mixed kinds for 1,000 frames; lights move, appear, disappear and
//! change intensity. After every frame the `LightTable` must equal one rebuilt from scratch, and
//! `DirectLighting` must equal a scalar per-light reference, bit for bit for delta lights.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{
    Amount, ColorQuery, DistantLight, LightKind, LightSampleContext, LightTable, PointLight, SpotLight,
};
use kelvin::rng::SplitMix64;
use kelvin::shading::{
    DirectLighting, LightSamplerKind, LightSelection, RunReport, SceneBounds, Settings, ShadingBatch,
};
use kelvin::spectrum::{SampledSpectrum, Spectrum};
use kelvin::systems::LightingPlugin;

/// A uniform point in the cube [-r, r)^3.
fn in_cube(rng: &mut SplitMix64, r: f32) -> Vec3 {
    Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 2.0 * r
}

fn spawn_random(world: &mut World, rng: &mut SplitMix64) -> Entity {
    let t = Transform::from_translation(in_cube(rng, 50.0) + Vec3::Y * 60.0).looking_to(in_cube(rng, 1.0), Vec3::Y);
    let temp = 2000.0 + 100.0 * rng.below(40) as f64;
    let spectrum = Spectrum::blackbody(temp).unwrap();
    match rng.below(10) {
        0..=5 => world
            .spawn((PointLight { amount: Amount::Candela(1.0 + 100.0 * rng.f32()), spectrum, ..Default::default() }, t))
            .id(),
        6..=8 => {
            let outer = 0.2 + 1.2 * rng.f32();
            let spot = SpotLight {
                amount: Amount::Lumens(500.0 * rng.f32()),
                spectrum,
                inner_angle: outer * rng.f32(),
                outer_angle: outer,
                ..Default::default()
            };
            world.spawn((spot, t)).id()
        }
        _ => world
            .spawn((DistantLight { amount: Amount::Lux(100.0 * rng.f32()), spectrum, ..Default::default() }, t))
            .id(),
    }
}

/// Every light entity's rows hold exactly what resolving it from scratch gives.
fn assert_table_matches_world(world: &mut World, frame: usize) {
    let bounds = world.resource::<SceneBounds>().sphere;
    let mut entities = 0;
    let mut points = world.query::<(Entity, &PointLight, &Transform)>();
    let fresh: Vec<_> = points.iter(world).map(|(e, l, t)| (e, l.resolve(t).unwrap())).collect();
    let table = world.resource::<LightTable>();
    for (e, want) in fresh {
        let rows = table.rows_of(e);
        assert!(rows.len() == 1 && rows[0].kind == LightKind::Point, "frame {frame}: {e} rows {rows:?}");
        assert_eq!(table.points().get(rows[0].row as usize), want, "frame {frame}: point {e}");
        entities += 1;
    }
    let mut spots = world.query::<(Entity, &SpotLight, &Transform)>();
    let fresh: Vec<_> = spots.iter(world).map(|(e, l, t)| (e, l.resolve(t).unwrap())).collect();
    let table = world.resource::<LightTable>();
    for (e, want) in fresh {
        let rows = table.rows_of(e);
        assert!(rows.len() == 1 && rows[0].kind == LightKind::Spot, "frame {frame}: {e}");
        assert_eq!(table.spots().get(rows[0].row as usize), want, "frame {frame}: spot {e}");
        entities += 1;
    }
    let mut distant = world.query::<(Entity, &DistantLight, &Transform)>();
    let fresh: Vec<_> = distant.iter(world).map(|(e, l, t)| (e, l.resolve(t, bounds).unwrap())).collect();
    let table = world.resource::<LightTable>();
    for (e, want) in fresh {
        let rows = table.rows_of(e);
        assert!(rows.len() == 1 && rows[0].kind == LightKind::Distant, "frame {frame}: {e}");
        assert_eq!(table.distant().items[rows[0].row as usize], want, "frame {frame}: distant {e}");
        entities += 1;
    }
    assert_eq!(table.entity_count(), entities, "frame {frame}: no stale rows");
    assert_eq!(table.len(), entities, "frame {frame}: one row per light");
}

/// Each entry of each point equals the light's own resolved Sample_Li, bit for bit.
fn assert_lighting_matches_reference(world: &mut World, points: &[Vec3], frame: usize) {
    let bounds = world.resource::<SceneBounds>().sphere;
    let out = world.resource::<DirectLighting>().clone();
    let table = world.resource::<LightTable>().clone();
    assert_eq!(out.offsets.len(), points.len() + 1);
    for (i, &p) in points.iter().enumerate() {
        let ctx = LightSampleContext::on_surface(p, Vec3::Y);
        assert_eq!(out.entries(i).len(), table.len(), "frame {frame}: one entry per light");
        for e in out.entries(i) {
            let owner = table.owner(out.light[e]);
            let entity = world.entity(owner);
            let t = entity.get::<Transform>().unwrap();
            let reference = if let Some(l) = entity.get::<PointLight>() {
                l.resolve(t).unwrap().sample_li(&ctx, ColorQuery::Rgb)
            } else if let Some(l) = entity.get::<SpotLight>() {
                l.resolve(t).unwrap().sample_li(&ctx, ColorQuery::Rgb)
            } else {
                let l = entity.get::<DistantLight>().unwrap();
                l.resolve(t, bounds).unwrap().sample_li(&ctx, glam::Vec2::ZERO, ColorQuery::Rgb)
            };
            match reference {
                Some(r) => {
                    assert_eq!(out.radiance[e], r.radiance, "frame {frame}: point {i} light {owner}");
                    assert_eq!(out.wi[e], r.wi, "frame {frame}: point {i} light {owner}");
                }
                None => assert_eq!(out.radiance[e], SampledSpectrum::default()),
            }
        }
    }
}

#[test]
fn ten_thousand_lights_over_a_thousand_frames_stay_consistent() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    // Every light is sampled, so the sampler only follows the table, rebuilt each frame (lights
    // come and go): the power sampler's alias table, several times cheaper than the light BVH.
    let settings = Settings {
        light_sampler: LightSamplerKind::Power,
        selection: LightSelection::All,
        shadows: false,
        ..Default::default()
    };
    world.insert_resource(settings);
    LightingPlugin::build(&mut world, &mut schedule);
    let mut rng = SplitMix64::new(7);
    let mut lights: Vec<Entity> = (0..10_000).map(|_| spawn_random(&mut world, &mut rng)).collect();
    let points = [Vec3::ZERO, Vec3::new(10.0, 0.0, -5.0), Vec3::new(-20.0, 1.0, 30.0)];
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        for (i, &p) in points.iter().enumerate() {
            batch.push(p, Vec3::Y, i as u32, 0);
        }
    }
    let frames = 1000;
    for frame in 0..frames {
        schedule.run(&mut world);
        assert!(world.resource::<RunReport>().warnings.is_empty());
        assert_table_matches_world(&mut world, frame);
        assert_lighting_matches_reference(&mut world, &points, frame);
        // 1% move, 0.5% change intensity, 0.5% disappear, 0.5% appear.
        for _ in 0..100 {
            let e = lights[rng.below(lights.len())];
            let delta = in_cube(&mut rng, 1.0);
            world.get_mut::<Transform>(e).unwrap().translation += delta;
        }
        for _ in 0..50 {
            let e = lights[rng.below(lights.len())];
            let s = 0.5 + rng.f32();
            if let Some(mut l) = world.get_mut::<PointLight>(e) {
                l.amount = Amount::Candela(l.amount.value() * s);
            } else if let Some(mut l) = world.get_mut::<SpotLight>(e) {
                l.amount = Amount::Lumens(l.amount.value() * s);
            } else if let Some(mut l) = world.get_mut::<DistantLight>(e) {
                l.amount = Amount::Lux(l.amount.value() * s);
            }
        }
        for _ in 0..50 {
            let i = rng.below(lights.len());
            world.despawn(lights.swap_remove(i));
        }
        for _ in 0..50 {
            lights.push(spawn_random(&mut world, &mut rng));
        }
    }
}

#[test]
fn skip_conditions_are_recorded() {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    schedule.run(&mut world);
    let report = world.resource::<RunReport>();
    assert!(!report.ran("sample_direct_lighting"), "empty batch: {report}");
    assert!(!report.ran("trace_shadow_rays"), "{report}");

    world.spawn((PointLight::default(), Transform::default()));
    world.resource_mut::<ShadingBatch>().push(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, 0, 0);
    schedule.run(&mut world);
    let report = world.resource::<RunReport>();
    assert!(report.ran("update_light_sampler") && report.ran("sample_direct_lighting"), "{report}");
    assert!(!report.ran("trace_shadow_rays"), "no geometry, nothing can occlude: {report}");

    schedule.run(&mut world);
    let report = world.resource::<RunReport>();
    assert!(!report.ran("update_light_sampler"), "nothing changed: {report}");
}
