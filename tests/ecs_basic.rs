//! The light system in a World: spawn lights, shade a batch, read DirectLighting.

use bevy_ecs::prelude::*;
use glam::Vec3;
use kelvin::geometry::Transform;
use kelvin::light::{Amount, LightTable, PointLight, SpotLight};
use kelvin::shading::{DirectLighting, LightSelection, RunReport, Settings, ShadingBatch};
use kelvin::systems::LightingPlugin;

fn world_and_schedule() -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    LightingPlugin::build(&mut world, &mut schedule);
    (world, schedule)
}

#[test]
fn point_light_gives_inverse_square_luminance_in_rgb_mode() {
    let (mut world, mut schedule) = world_and_schedule();
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 2.0, 0.0))));
    world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    schedule.run(&mut world);
    let out = world.resource::<DirectLighting>();
    assert_eq!(out.len(), 1);
    let y = out.radiance[0].0[1] * 0.7152 + out.radiance[0].0[0] * 0.2126 + out.radiance[0].0[2] * 0.0722;
    assert!((y - 25.0).abs() < 0.05, "Y = {y}, expected I / h^2 = 25 cd/m^2 per sr");
    assert!((out.wi[0] - Vec3::Y).length() < 1e-6 && out.delta[0] && (out.pdf[0] - 1.0).abs() < 1e-6);
    assert!(world.resource::<RunReport>().ran("sample_direct_lighting"));
}

/// Hard case: a light and an occluder spawned without a transform. Each gets its required
/// `Transform` (the identity), so the light shines from the origin and the sphere blocks it,
/// instead of both being silently ignored.
#[test]
fn lights_and_geometry_spawned_without_a_transform_sit_at_the_origin() {
    let (mut world, mut schedule) = world_and_schedule();
    let light = world.spawn(PointLight::candela(100.0)).id();
    let ball = world.spawn(kelvin::geometry::Sphere { radius: 0.5 }).id();
    assert_eq!(world.get::<Transform>(light), Some(&Transform::IDENTITY));
    assert_eq!(world.get::<Transform>(ball), Some(&Transform::IDENTITY));
    // 2 m above the light, facing it: its light passes through the ball at the origin.
    world.resource_mut::<ShadingBatch>().push(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, 0, 0);
    schedule.run(&mut world);
    assert_eq!(world.resource::<LightTable>().entity_count(), 1);
    assert!(world.resource::<DirectLighting>().occluded[0], "the ball at the origin should block the light");
    world.despawn(ball);
    schedule.run(&mut world);
    let out = world.resource::<DirectLighting>();
    let y = out.radiance[0].0[1] * 0.7152 + out.radiance[0].0[0] * 0.2126 + out.radiance[0].0[2] * 0.0722;
    assert!((y - 25.0).abs() < 0.05, "Y = {y}, expected 100 cd / (2 m)^2 from the origin");
}

#[test]
fn all_lights_mode_gives_one_entry_per_light_and_removal_keeps_the_table_dense() {
    let (mut world, mut schedule) = world_and_schedule();
    world.resource_mut::<Settings>().selection = LightSelection::All;
    let a = world.spawn((PointLight::candela(10.0), Transform::from_translation(Vec3::Y))).id();
    let _b = world.spawn((PointLight::candela(20.0), Transform::from_translation(Vec3::Y * 2.0))).id();
    let spot = SpotLight { amount: Amount::Candela(5.0), ..Default::default() };
    world.spawn((spot, Transform::from_translation(Vec3::Y).looking_to(Vec3::NEG_Y, Vec3::Z)));
    world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    schedule.run(&mut world);
    assert_eq!(world.resource::<DirectLighting>().len(), 3);
    world.despawn(a);
    schedule.run(&mut world);
    let table = world.resource::<LightTable>();
    assert_eq!(table.len(), 2);
    assert_eq!(table.points().len(), 1);
    assert_eq!(world.resource::<DirectLighting>().len(), 2);
}

#[test]
fn invalid_spot_angles_are_reported_not_panicking() {
    let (mut world, mut schedule) = world_and_schedule();
    let bad = SpotLight { inner_angle: 1.0, outer_angle: 0.5, ..Default::default() };
    world.spawn((bad, Transform::default()));
    schedule.run(&mut world);
    assert!(world.resource::<LightTable>().is_empty());
    let report = world.resource::<RunReport>();
    assert!(report.warnings.iter().any(|w| w.contains("inner_angle")), "{report}");
}

#[test]
fn occluders_block_shadow_rays_and_the_bvh_follows_moving_geometry() {
    use kelvin::geometry::{Rectangle, Sphere};
    let (mut world, mut schedule) = world_and_schedule();
    world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 4.0, 0.0))));
    let floor = Transform::from_translation(Vec3::ZERO).looking_to(Vec3::NEG_Y, Vec3::Z); // +Z (front) -> +Y
    world.spawn((Rectangle { half_size: glam::Vec2::splat(10.0) }, floor));
    let ball = world.spawn((Sphere { radius: 0.5 }, Transform::from_translation(Vec3::new(0.0, 2.0, 0.0)))).id();
    world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, 0, 0);
    world.resource_mut::<ShadingBatch>().push(Vec3::new(3.0, 0.0, 0.0), Vec3::Y, 1, 0);
    schedule.run(&mut world);
    let out = world.resource::<DirectLighting>();
    assert!(out.occluded[0] && out.radiance[0].0[1] == 0.0, "the ball shadows the point below it");
    assert!(!out.occluded[1] && out.radiance[1].0[1] > 0.0, "the floor never shadows itself");
    assert_eq!(world.resource::<kelvin::systems::ShadowRays>().blocked(), 1);
    assert!(world.resource::<RunReport>().ran("trace_shadow_rays"));

    // Move the ball away: a refit, and the shadow is gone.
    world.get_mut::<Transform>(ball).unwrap().translation.x = 5.0;
    schedule.run(&mut world);
    let report = world.resource::<RunReport>();
    assert!(report.ran("update_scene_bvh") && report.entries.iter().any(|e| e.system == "bvh_refit"), "{report}");
    assert!(!world.resource::<DirectLighting>().occluded[0]);
    assert_eq!(world.resource::<kelvin::systems::ShadowRays>().blocked(), 0);

    // Lights that cast no shadows trace no rays.
    let mut lights = world.query::<&mut PointLight>();
    for mut l in lights.iter_mut(&mut world) {
        l.casts_shadows = false;
    }
    schedule.run(&mut world);
    let report = world.resource::<RunReport>();
    assert!(!report.ran("trace_shadow_rays") && !report.ran("update_scene_bvh"), "{report}");
}

#[test]
fn shadow_rays_pass_the_flat_surface_the_batch_says_they_leave() {
    use kelvin::geometry::{GeometryId, Rectangle, Sphere};
    // Hard case: points rounded to just below the floor with no error bound, so that no offset
    // lifts their shadow rays above it; only the batch's geometry column says where they lie.
    let below = Vec3::new(0.5, -1e-5, 0.25);
    let occluded = |points: usize, ball: bool, on_floor: bool| {
        let (mut world, mut schedule) = world_and_schedule();
        world.spawn((PointLight::candela(100.0), Transform::from_translation(Vec3::new(0.0, 4.0, 0.0))));
        let floor = Transform::from_translation(Vec3::ZERO).looking_to(Vec3::NEG_Y, Vec3::Z);
        let floor = world.spawn((Rectangle { half_size: glam::Vec2::splat(10.0) }, floor)).id();
        if ball {
            // Off to the side: a curved shape puts the scene off the flat-shape lane path.
            world.spawn((Sphere { radius: 0.5 }, Transform::from_translation(Vec3::new(6.0, 2.0, 0.0))));
        }
        let mut batch = world.resource_mut::<ShadingBatch>();
        for i in 0..points {
            batch.push_with_error(below, Vec3::ZERO, Vec3::Y, Vec3::Y, i as u32, 0);
        }
        let id = GeometryId { entity_index: floor.index_u32(), primitive: 0 };
        batch.geometry = vec![if on_floor { id } else { GeometryId::NONE }; points];
        schedule.run(&mut world);
        world.resource::<DirectLighting>().occluded.clone()
    };
    for (points, ball) in [(1, false), (16, false), (3, true)] {
        assert_eq!(occluded(points, ball, false), vec![true; points], "{points} points, ball {ball}: unknown surface");
        assert_eq!(occluded(points, ball, true), vec![false; points], "{points} points, ball {ball}: on the floor");
    }
}

/// Hard case: the estimator the README shows (`DirectLighting::irradiance`, light samples alone)
/// under a real HDR map with a sun, on default `Settings`. The MIS-compensated table that an
/// integrator weighing BSDF samples may use never samples texels below the map's mean; by
/// default it must not be used, so the mean estimate equals the irradiance integrated here from
/// the map's radiance (a midpoint rule over the upper hemisphere at 4x the map's resolution).
#[test]
fn default_settings_give_the_closed_form_irradiance_under_an_hdr_map() {
    use kelvin::light::{ImageInfiniteLight, SceneSphere};
    use kelvin::scene::image::{LUMINANCE_WEIGHTS, load_image};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/spiaggia_di_mondello_1k.hdr");
    let image = std::sync::Arc::new(load_image(&path).expect("tests/data/env/spiaggia_di_mondello_1k.hdr").image);
    let light = ImageInfiniteLight::new(image.clone());

    let resolved = light.resolve(&Transform::IDENTITY, SceneSphere { center: Vec3::ZERO, radius: 1.0 }).unwrap();
    let (rows, cols) = (4 * image.height / 2, 4 * image.width);
    let (d_theta, d_phi) = (std::f64::consts::FRAC_PI_2 / rows as f64, std::f64::consts::TAU / cols as f64);
    let mut closed_form = 0.0f64;
    for i in 0..rows {
        let theta = (i as f64 + 0.5) * d_theta;
        for j in 0..cols {
            let phi = (j as f64 + 0.5) * d_phi;
            let w = glam::DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()).as_vec3();
            let le = resolved.le(w, kelvin::light::ColorQuery::Rgb).0;
            let y = LUMINANCE_WEIGHTS.dot(Vec3::new(le[0], le[1], le[2])) as f64;
            closed_form += y * theta.cos() * theta.sin() * d_theta * d_phi;
        }
    }

    let (mut world, mut schedule) = world_and_schedule();
    world.spawn((light, Transform::IDENTITY));
    let n = 1 << 15;
    for pixel in 0..n {
        world.resource_mut::<ShadingBatch>().push(Vec3::ZERO, Vec3::Y, pixel as u32, 0);
    }
    schedule.run(&mut world);
    let out = world.resource::<DirectLighting>();
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for i in 0..n {
        let e = out.irradiance(i, Vec3::Y).0;
        let y = LUMINANCE_WEIGHTS.dot(Vec3::new(e[0], e[1], e[2])) as f64;
        sum += y;
        sum2 += y * y;
    }
    let mean = sum / n as f64;
    let sigma = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    eprintln!("irradiance under mondello: estimate {mean:.4} +- {sigma:.4} lx, closed form {closed_form:.4} lx");
    assert!(
        (mean - closed_form).abs() < 4.0 * sigma + 2e-3 * closed_form,
        "estimate {mean} +- {sigma} lx, closed form {closed_form} lx"
    );
    assert!(!world.resource::<Settings>().mis, "the library default is light samples alone");
}
