//! kelvin's own files (tests/data/gltf/kelvin, written by scripts/make_test_gltf.py): the IES light's
//! colour and the mirrored emitter.

use super::*;

/// Rec. 709 luminance of linear RGB, as kelvin's glTF spawner weighs a light's colour.
fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// A world with the lighting systems (every light sampled at every point) and the scene at `path` spawned.
fn spawned(path: &Path) -> (World, Schedule, SpawnReport) {
    let scene = load_ok(path);
    let mut world = World::new();
    let mut schedule = Schedule::default();
    world.insert_resource(Settings { selection: LightSelection::All, ..Default::default() });
    LightingPlugin::build(&mut world, &mut schedule);
    let report = spawn_gltf(&mut world, &scene);
    (world, schedule, report)
}

/// Photometric irradiance (lx) at each of `points` on an upward-facing floor, with its standard error: the mean
/// over `samples` light samples per point of Y(Li) cos / pdf, summed over the lights.
fn floor_irradiance(world: &mut World, schedule: &mut Schedule, points: &[Vec3], samples: u32) -> Vec<(f64, f64)> {
    {
        let mut batch = world.resource_mut::<ShadingBatch>();
        batch.clear();
        for (i, &p) in points.iter().enumerate() {
            for s in 0..samples {
                batch.push(p, Vec3::Y, i as u32, s);
            }
        }
    }
    schedule.run(world);
    let out = world.resource::<DirectLighting>();
    (0..points.len())
        .map(|i| {
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for k in 0..samples as usize {
                let mut e = 0.0f64;
                for j in out.entries(i * samples as usize + k) {
                    let r = out.radiance[j].0;
                    if out.pdf[j] > 0.0 {
                        let y = luminance(Vec3::new(r[0], r[1], r[2]));
                        e += (y * out.wi[j].dot(Vec3::Y).max(0.0) / out.pdf[j]) as f64;
                    }
                }
                sum += e;
                sum2 += e * e;
            }
            let n = samples as f64;
            let mean = sum / n;
            (mean, ((sum2 / n - mean * mean).max(0.0) / n).sqrt())
        })
        .collect()
}

/// EXT_lights_ies with a real profile (ASA_15M_R2.ies): the light's amount is the multiplier times the colour's
/// luminance, as for KHR_lights_punctual lights, so a coloured lamp is as bright as an RGB renderer multiplying
/// colour by intensity shows it, and a black one gives no light (spawned, with zero power; no warning, as for a
/// black point light).
#[test]
fn ies_light_takes_its_colour_luminance() {
    let path = test_data("gltf/kelvin/ies_light_colour.gltf");
    let (mut world, mut schedule, report) = spawned(&path);
    assert!(report.warnings.is_empty(), "{:#?}", report.warnings);
    assert_eq!(report.lights, 2);
    let profile = IesProfile::from_file(&test_data("ies/luxcore/ASA_15M_R2.ies")).unwrap();
    // The file's first candela value (vertical 0, nadir) and the one at vertical 30 degrees, plane C0, both
    // read off the file (its candela multiplier and ballast factor are 1).
    assert_eq!((profile.candela(0.0, 0.0), profile.candela(30.0, 0.0)), (1666.0, 2337.0));
    let colour = Vec3::new(1.0, 0.5, 0.25);
    let multiplier = 2.5;

    let mut lamps: Vec<(GoniometricLight, Transform)> =
        world.query::<(&GoniometricLight, &Transform)>().iter(&world).map(|(g, t)| (g.clone(), *t)).collect();
    lamps.sort_by(|a, b| a.1.translation.x.total_cmp(&b.1.translation.x));
    let [(coloured, at_coloured), (black, at_black)] = &lamps[..] else { panic!("{} IES lights", lamps.len()) };
    assert_eq!((at_coloured.translation, at_black.translation), (Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.0, 0.0)));
    let coloured = coloured.resolve(at_coloured).unwrap();
    let black = black.resolve(at_black).unwrap();
    // Candela straight down (the lamp is aimed down): photometric intensity per profile unit times the profile.
    let down = coloured.intensity.luminous() * coloured.profile_value(Vec3::NEG_Y);
    let expected = multiplier * luminance(colour) * 1666.0;
    assert!((down / expected - 1.0).abs() < 1e-3, "{down} cd down, expected {expected} (2.5 x 0.588 x 1666)");
    let black_down = black.intensity.luminous() * black.profile_value(Vec3::NEG_Y);
    assert_eq!((black_down, black.phi()), (0.0, 0.0), "a black IES light emits nothing");

    // Irradiance on the floor, 3 m below: under the coloured lamp, 30 degrees off its axis in plane C0 (local +X,
    // world +X here) and under the black lamp, where only the coloured one (at 53.13 degrees) lights the floor.
    let off_axis = Vec3::new(3.0 * 30f32.to_radians().tan(), 0.0, 0.0);
    let under_black = Vec3::new(4.0, 0.0, 0.0);
    let e = floor_irradiance(&mut world, &mut schedule, &[Vec3::ZERO, off_axis, under_black], 1);
    let scale = (multiplier * luminance(colour)) as f64;
    let cos30 = 30f64.to_radians().cos();
    let cos53 = 0.6;
    let expected = [
        scale * 1666.0 / 9.0,
        scale * 2337.0 * cos30 / (3.0 / cos30).powi(2),
        scale * profile.candela(53.130102, 0.0) * cos53 / 25.0,
    ];
    for (k, ((got, _), want)) in e.iter().zip(expected).enumerate() {
        assert!((got / want - 1.0).abs() < 2e-3, "point {k}: {got} lx, expected {want} lx");
    }
}

/// glTF 2.0 spec 3.7.4: a node whose world transform has a negative determinant reverses its triangles' winding.
/// mirrored_emitter.gltf has a one-sided emissive quad without NORMAL data and an occluder under scale
/// [-1, 1, 1]; its twin has the same world-space surfaces unmirrored. The emitter faces down and the floor gets the
/// same light from both (the occluder's shadow included).
#[test]
fn mirrored_emitter_faces_and_lights_as_its_unmirrored_twin() {
    let points = [Vec3::new(-0.3, 0.0, 0.0), Vec3::ZERO, Vec3::new(0.4, 0.0, 0.0)];
    let samples = 4096;
    let mut lit = Vec::new();
    for file in ["mirrored_emitter.gltf", "unmirrored_emitter.gltf"] {
        let (mut world, mut schedule, report) = spawned(&test_data("gltf/kelvin").join(file));
        assert!(report.warnings.is_empty(), "{file}: {:#?}", report.warnings);
        assert_eq!((report.meshes, report.emissive_meshes), (3, 1), "{file}");
        let normals: Vec<Vec3> = world
            .query_filtered::<&Mesh, With<AreaLight>>()
            .iter(&world)
            .flat_map(|m| {
                (0..m.triangle_count()).map(|t| {
                    let [a, b, c] = m.triangle(t);
                    (b - a).cross(c - a).normalize()
                })
            })
            .collect();
        assert_eq!(normals.len(), 2, "{file}");
        assert!(normals.iter().all(|n| n.abs_diff_eq(Vec3::NEG_Y, 1e-6)), "{file}: emitter normals {normals:?}");
        lit.push(floor_irradiance(&mut world, &mut schedule, &points, samples));
    }
    // 4 nits over the quad at y = 1; x = 0.4 is outside the occluder's shadow, the others are in part of it.
    let emitter =
        [Vec3::new(-0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, 0.5), Vec3::new(-0.5, 1.0, 0.5)];
    for (k, &p) in points.iter().enumerate() {
        let ((m, m_err), (u, u_err)) = (lit[0][k], lit[1][k]);
        let unoccluded = common::area::lambert(p, Vec3::Y, &emitter, 4.0);
        println!(
            "x = {}: mirrored {m:.4} +- {m_err:.4}, unmirrored {u:.4} +- {u_err:.4}, unoccluded {unoccluded:.4} lx",
            p.x
        );
        assert!((m - u).abs() < 5.0 * (m_err * m_err + u_err * u_err).sqrt() + 1e-3 * u, "x = {}: {m} vs {u} lx", p.x);
        if k == 2 {
            assert!((m - unoccluded).abs() < 5.0 * m_err + 1e-3 * unoccluded, "x = 0.4: {m} lx, Lambert {unoccluded}");
        } else {
            assert!(m < 0.9 * unoccluded, "x = {}: {m} lx, not shadowed (unoccluded {unoccluded})", p.x);
        }
    }
}
