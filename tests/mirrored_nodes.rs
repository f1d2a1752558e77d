//! Lights and cameras under mirrored and sheared parents aim where glTF, Bevy's
//! `GlobalTransform::forward()` and three.js aim them: along the node's world matrix applied to
//! local -Z, normalised. Blender writes such parents (a mirror modifier applied as a scale of -1,
//! a non-uniform scale above a rotated child). The expected directions are computed here from the
//! matrices alone; the lights are the crate's own, resolved from `Transform::from_affine` of that
//! matrix, as the glTF loader, animation and the Bevy placement build them. End to end: a white
//! floor lit by a 1000 lx directional light, both the light and the camera under mirrored parents,
//! reads E / pi = 318.3 nit.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Mat3, Quat, Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{
    Amount, ColorQuery, DistantLight, GoniometricLight, LightSampleContext, ProjectionLight, SceneSphere, SpotLight,
};
use kelvin::render::camera::{Camera, PinholeCamera};
use kelvin::render::job::{IntegratorChoice, RenderJob};
use kelvin::rng::SplitMix64;
use kelvin::sampling::sample_uniform_sphere;
use kelvin::scene::ies::IesProfile;
use kelvin::scene::image::RgbImage;
use serde_json::json;

use common::files::TempDir;
use common::gltf_doc::{Doc, floor};

/// The parents a file brings, each named: a mirror on every axis, two mirrors (a half turn), a
/// shear, a shear with a mirror, and a non-uniform scale over a rotated child (a shear in world
/// space), and a plain rotation as the control.
fn parents() -> Vec<(&'static str, Affine3A)> {
    let shear = Mat3::from_cols(Vec3::X, Vec3::new(0.6, 1.0, 0.0), Vec3::new(-0.4, 0.3, 1.0));
    let turned = Affine3A::from_rotation_y(0.7);
    vec![
        ("rotation only", turned),
        ("mirror x", Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0))),
        ("mirror y", Affine3A::from_scale(Vec3::new(1.0, -1.0, 1.0))),
        ("mirror z", Affine3A::from_scale(Vec3::new(1.0, 1.0, -1.0))),
        ("mirror x and z", Affine3A::from_scale(Vec3::new(-1.0, 1.0, -1.0))),
        ("mirror x, scaled", Affine3A::from_scale(Vec3::new(-2.0, 0.5, 1.5)) * turned),
        ("shear", Affine3A::from_mat3(shear)),
        ("shear and mirror z", Affine3A::from_mat3(shear * Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0)))),
        ("non-uniform scale over a rotated child", Affine3A::from_scale(Vec3::new(3.0, 1.0, 0.5))),
    ]
}

/// The light or camera node under each parent: at (0.4, 2, -0.3), turned so that its -Z points
/// down and sideways and its +Y has a part along every axis.
fn child() -> Affine3A {
    let r = Quat::from_rotation_x(-1.2) * Quat::from_rotation_z(0.4) * Quat::from_rotation_y(0.3);
    Affine3A::from_rotation_translation(r, Vec3::new(0.4, 2.0, -0.3))
}

/// The world frame the matrix says, built apart from `Transform`: forward = M (-Z), up = M (+Y)
/// made orthogonal to it, right completing a right-handed frame.
fn expected_frame(m: &Affine3A) -> (Vec3, Vec3, Vec3) {
    let forward = (m.matrix3 * Vec3::NEG_Z).normalize();
    let y = m.matrix3 * Vec3::Y;
    let up = (y - forward * forward.dot(y)).normalize();
    (forward.cross(up), up, forward)
}

fn placed() -> impl Iterator<Item = (&'static str, Affine3A, Transform)> {
    parents().into_iter().map(|(name, parent)| {
        let world = parent * child();
        (name, world, Transform::from_affine(world))
    })
}

fn assert_along(name: &str, what: &str, got: Vec3, want: Vec3) {
    let angle = got.normalize().dot(want).clamp(-1.0, 1.0).acos();
    assert!(angle < 1e-3, "{name}: {what} {got} is {angle} rad off {want}");
}

#[test]
fn forward_is_the_world_matrix_applied_to_minus_z() {
    for (name, world, t) in placed() {
        let (right, up, forward) = expected_frame(&world);
        assert_along(name, "forward()", t.forward(), forward);
        assert_along(name, "aim -Z", t.aim() * Vec3::NEG_Z, forward);
        assert_along(name, "aim +Y", t.aim() * Vec3::Y, up);
        assert_along(name, "aim +X", t.aim() * Vec3::X, right);
    }
}

#[test]
fn directional_lights_shine_along_the_world_matrix() {
    let scene = SceneSphere { center: Vec3::ZERO, radius: 10.0 };
    for (name, world, t) in placed() {
        let light = DistantLight { amount: Amount::Lux(1000.0), ..Default::default() }.resolve(&t, scene).unwrap();
        let s = light.sample_li(&LightSampleContext::at(Vec3::ZERO), Vec2::splat(0.5), ColorQuery::Rgb).unwrap();
        assert_along(name, "direction to the light", -s.wi, expected_frame(&world).2);
    }
}

/// A narrow spot light and a projector light a point 2 m along the expected forward as the same
/// lights unturned light a point 2 m along -Z, and leave dark the point along the flipped forward.
#[test]
fn spot_and_projection_lights_light_what_the_world_matrix_faces() {
    let white = Arc::new(RgbImage { width: 4, height: 4, pixels: vec![Vec3::ONE; 16] });
    let spot = SpotLight {
        amount: Amount::Candela(100.0),
        inner_angle: 5f32.to_radians(),
        outer_angle: 10f32.to_radians(),
        ..Default::default()
    };
    let projector = ProjectionLight { amount: Amount::Candela(100.0), ..ProjectionLight::new(white, 0.3) };
    let at = |t: &Transform, p: Vec3| {
        let ctx = LightSampleContext::at(p);
        let spot = spot.resolve(t).unwrap().sample_li(&ctx, ColorQuery::Rgb).map(|s| s.radiance.0);
        let projection = projector.resolve(t).unwrap().sample_li(&ctx, ColorQuery::Rgb).map(|s| s.radiance.0);
        [("spot", spot), ("projection", projection)]
    };
    let reference = at(&Transform::IDENTITY, 2.0 * Vec3::NEG_Z);
    for (name, world, t) in placed() {
        let forward = expected_frame(&world).2;
        for ((kind, got), (_, want)) in at(&t, t.translation + 2.0 * forward).into_iter().zip(&reference) {
            let (got, want) = (got.unwrap_or_default(), want.unwrap());
            let worst = got.iter().zip(&want).map(|(g, w)| (g - w).abs() / w).fold(0.0, f32::max);
            assert!(worst < 1e-3, "{name}: the {kind} light gives {got:?} ahead, unturned {want:?}");
        }
        for (kind, dark) in at(&t, t.translation - 2.0 * forward) {
            assert!(dark.is_none_or(|r| r.iter().all(|&v| v == 0.0)), "{name}: the {kind} light lights behind");
        }
    }
}

/// An IES profile (asymmetric in azimuth) seen from every direction: the light's intensity over
/// the file's candela at the direction in the expected frame is one constant.
#[test]
fn goniometric_profiles_turn_with_the_world_frame() {
    let path = common::files::test_data("ies/luxcore/ASA_15M_R2.ies");
    let ies = Arc::new(IesProfile::from_file(&path).unwrap());
    for (name, world, t) in placed() {
        let light = GoniometricLight::from_ies(ies.clone()).resolve(&t).unwrap();
        let (right, up, forward) = expected_frame(&world);
        let to_local = Mat3::from_cols(right, up, -forward).transpose();
        let mut rng = SplitMix64::new(7);
        let ratios: Vec<f64> = (0..400)
            .map(|_| sample_uniform_sphere(Vec2::new(rng.f32(), rng.f32())))
            .filter_map(|w| {
                let file = ies.candela_dir(to_local * w);
                (file > 1e-3 * ies.max_candela()).then(|| light.intensity_toward(w) as f64 / file)
            })
            .collect();
        assert!(ratios.len() > 50, "{name}: {} lit directions", ratios.len());
        let (lo, hi) = ratios.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
        assert!(hi / lo < 1.0 + 1e-3, "{name}: intensity / file candela spans {lo}..{hi}");
    }
}

/// The centre ray looks along the expected forward, and the top row leans to the expected up.
#[test]
fn cameras_look_along_the_world_matrix() {
    for (name, world, t) in placed() {
        let (_, up, forward) = expected_frame(&world);
        let camera = PinholeCamera::new(&Camera::default(), &t, 64, 64);
        assert_along(name, "centre ray", camera.ray(32, 32, Vec2::ZERO).dir, forward);
        let top = camera.ray(32, 0, Vec2::splat(0.5)).dir;
        assert!(top.dot(up) > 0.3, "{name}: the top row looks {top}, up is {up}");
    }
}

/// The user's case: a white floor, a 1000 lx directional light aimed straight down and a camera
/// looking straight down, each under a mirrored (or sheared) parent node of a glTF file. Every
/// pixel reads 1000 / pi nit; a light aimed up or a camera looking up gives black.
#[test]
fn a_floor_lit_and_seen_through_mirrored_parents_reads_e_over_pi() {
    let dir = TempDir::new("mirrored_nodes", "floor");
    let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2).to_array();
    let up = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2).to_array();
    for (name, parent) in [
        ("mirror x", [-1.0, 1.0, 1.0]),
        ("mirror y", [1.0, -1.0, 1.0]),
        ("mirror z", [1.0, 1.0, -1.0]),
        ("mirror x and z, scaled", [-2.0, 1.0, -0.5]),
    ] {
        let mut doc = Doc::default();
        let m = doc.material(1.0, 0.0);
        doc.mesh("floor", &[floor([-50.0, 50.0], [-50.0, 50.0], 0.0, m)]);
        // A mirror in y sends the child's height and its "down" to the other side: the child is
        // placed and turned so that in the world it sits 2 m up and faces down.
        let (height, child_down) = if parent[1] < 0.0 { (-2.0, up) } else { (2.0, down) };
        let light = doc.light(json!({ "type": "directional", "intensity": 1000.0 }), Vec3::Y * height, child_down);
        let camera = doc.camera(0.5, Vec3::Y * height, child_down);
        let scale = Affine3A::from_scale(Vec3::from(parent));
        doc.parent(light, scale);
        doc.parent(camera, scale);
        let path = dir.join(format!("{}.gltf", name.replace([' ', ','], "_")));
        doc.write(&path);
        let job = RenderJob {
            scene: Some(path),
            width: 8,
            height: 8,
            spp: 1,
            integrator: IntegratorChoice::Direct,
            ..RenderJob::default()
        };
        let mut loaded = job.load().unwrap();
        let film = kelvin::render::renderer::render_with(
            &mut loaded.world,
            &mut loaded.schedule,
            &job.options(),
            job.camera(),
            |_| {},
        )
        .0;
        let want = 1000.0 / std::f32::consts::PI;
        for (k, p) in film.pixels().iter().enumerate() {
            let y = kelvin::scene::image::LUMINANCE_WEIGHTS.dot(*p);
            assert!((y - want).abs() < 1e-3 * want, "{name}: pixel {k} reads {y} nit, want {want}");
        }
    }
}
