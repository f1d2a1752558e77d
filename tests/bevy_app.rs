//! The `bevy` feature end to end: `examples/bevy_app.rs` (1,000 moving point and spot lights in a
//! headless Bevy `App`) against the closed form per frame, and geometry placed by Bevy's
//! propagated `GlobalTransform` casting shadows.

#[path = "../examples/bevy_app.rs"]
mod demo;

use bevy_app::{App, TaskPoolPlugin};
use bevy_ecs::prelude::*;
use bevy_transform::TransformPlugin;
use bevy_transform::components::{GlobalTransform, Transform};
use glam::Vec3;
use kelvin::geometry::Sphere;
use kelvin::light::PointLight;
use kelvin::prelude::{DirectLighting, LightingPlugin, Settings, ShadingBatch};
use kelvin::shading::LightSelection;

/// With every light sampled at every point, the light system's illuminance is exact (delta lights,
/// no occluders): it must equal the closed form at each frame while the lights move.
#[test]
fn example_lux_matches_the_closed_form_every_frame() {
    let demo = demo::Demo { grid: 10, selection: LightSelection::All, samples_per_point: 1, ..Default::default() };
    let mut app = demo::app(&demo);
    let points = demo::grid_points(demo.grid);
    let mut previous = Vec::new();
    for frame in 1..=3 {
        app.update();
        let world = app.world_mut();
        assert_eq!(world.resource::<DirectLighting>().len(), demo.lights * points.len(), "frame {frame}");
        let mut now = Vec::new();
        for k in [0, 45, 99] {
            let estimate = demo::estimated_lux(world.resource::<DirectLighting>(), k, Vec3::Y);
            let exact = demo::exact_lux(world, points[k], Vec3::Y);
            assert!(exact > 1.0, "frame {frame}, point {k}: only {exact} lx reaches the floor");
            let err = (estimate - exact).abs() / exact;
            assert!(err < 2e-3, "frame {frame}, point {k}: {estimate} lx vs closed form {exact} lx");
            now.push(exact);
        }
        // The lights move each frame, so the light system must follow them.
        assert_ne!(now, previous, "frame {frame}: nothing moved");
        previous = now;
    }
}

/// The demo's default (one light per point from the light BVH) is an unbiased estimate: over the
/// 10,000 points its mean illuminance agrees with the mean closed form.
#[test]
fn example_light_bvh_estimate_is_unbiased_over_the_grid() {
    let demo = demo::Demo { grid: 100, ..Default::default() };
    let mut app = demo::app(&demo);
    app.update();
    let points = demo::grid_points(demo.grid);
    let world = app.world_mut();
    let (mut estimate, mut exact) = (0.0f64, 0.0f64);
    for (k, &p) in points.iter().enumerate().step_by(7) {
        estimate += f64::from(demo::estimated_lux(world.resource::<DirectLighting>(), k, Vec3::Y));
        exact += f64::from(demo::exact_lux(world, p, Vec3::Y));
    }
    let err = (estimate - exact).abs() / exact;
    assert!(err < 0.03, "mean estimate {estimate} vs closed form {exact} (rel. error {err})");
}

/// Hard case: a sphere whose place comes only from its parent's transform (Bevy propagation) is
/// where it shadows; moving the parent moves the shadow. A light spawned without a transform is
/// placed at the origin (its required transform), not ignored.
#[test]
fn geometry_placed_by_a_propagated_parent_transform_casts_its_shadow() {
    let mut app = App::new();
    app.add_plugins((TaskPoolPlugin::default(), TransformPlugin, LightingPlugin::default()));
    app.insert_resource(Settings { selection: LightSelection::All, ..Default::default() });
    let world = app.world_mut();
    let light = world.spawn(PointLight::candela(100.0)).id();
    let parent = world.spawn(Transform::from_xyz(0.0, -2.0, 0.0)).id();
    world.spawn((Sphere { radius: 0.5 }, Transform::default(), ChildOf(parent)));
    // Below the light, 4 m down, with the sphere between them.
    world.resource_mut::<ShadingBatch>().push(Vec3::new(0.0, -4.0, 0.0), Vec3::Y, 0, 0);

    let lux = |app: &mut App| {
        app.update();
        demo::estimated_lux(app.world().resource::<DirectLighting>(), 0, Vec3::Y)
    };
    assert!(app.world().get::<Transform>(light).is_some(), "the light got no required Transform");
    assert_eq!(lux(&mut app), 0.0, "the sphere at the parent's place should block the light");
    let placed = app.world().get::<GlobalTransform>(light).unwrap().translation();
    assert_eq!(placed, bevy_math::Vec3::ZERO, "required transform is not the origin");

    app.world_mut().get_mut::<Transform>(parent).unwrap().translation = demo::to_bevy(Vec3::new(5.0, -2.0, 0.0));
    let lit = lux(&mut app);
    assert!((lit - 100.0 / 16.0).abs() < 1e-3, "after the parent moved: {lit} lx, expected 100 cd / (4 m)^2");
}

/// kelvin's prelude glob-imports next to the Bevy preludes a plugin build has (ecs, app, math,
/// transform): `Transform` and `Vec3` still mean Bevy's, and an app reaches kelvin's same-named types
/// through the modules the prelude brings in. A name in both preludes would make
/// these uses ambiguous, a compile error.
mod preludes_side_by_side {
    use bevy_app::prelude::*;
    use bevy_ecs::prelude::*;
    use bevy_math::prelude::*;
    use bevy_transform::prelude::*;
    use kelvin::prelude::*;

    #[test]
    fn every_prelude_name_means_one_thing() {
        let mut app = App::new();
        app.add_plugins((
            bevy_app::TaskPoolPlugin::default(),
            bevy_transform::TransformPlugin,
            LightingPlugin::default(),
        ));
        let bevy_side = (Transform::from_xyz(0.0, 2.0, 0.0), Vec3::Y, Quat::IDENTITY);
        let kelvin_side =
            (light::PointLight::candela(100.0), geometry::Transform::IDENTITY, render::material::Material::default());
        app.world_mut().spawn((kelvin_side.0, bevy_side.0));
        app.world_mut().resource_mut::<ShadingBatch>().push(Vec3::ZERO, bevy_side.1, 0, 0);
        app.update();
        let world: &World = app.world();
        let lighting = world.resource::<DirectLighting>();
        // 100 cd, 2 m straight above: 25 lx.
        let e = lighting.irradiance(0, Vec3::Y).0[1];
        assert!((e - 25.0).abs() < 1e-3, "{e}");
        let _ = (bevy_side.1, bevy_side.2, kelvin_side.1, kelvin_side.2);
        let _: (Settings, LightSelection, ColorMode, LightSamplerKind) = Default::default();
        let _: Option<(Amount, Disk, Restir, ReuseWeights, LightingSet, ImageInfiniteLight)> = None;
        let _: Option<(GoniometricLight, ProjectionLight)> = None;
        let _ = (SunSkyLight::default(), AreaLight::default(), DistantLight::default(), RenderJob::default());
        let _ = (Spectrum::d65(), UniformInfiniteLight::default(), RunReport::default());
    }
}
