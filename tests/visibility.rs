//! Visibility queries: BVH vs brute force, shadow acne, area-light endpoints, bad input.

use glam::{EulerRot, Quat, Vec2, Vec3};
use kelvin::geometry::{
    Disk, GeometryError, GeometryInstance, GeometryRef, Hit, Mesh, Ray, Rectangle, SceneBvh, Shape, Sphere,
    SurfacePoint, Transform, closest_hits, occluded, triangle_surface_point,
};
use kelvin::rng::SplitMix64;

/// A point with each coordinate uniform in [lo, hi).
fn uniform_vec3(rng: &mut SplitMix64, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi))
}

/// A rotation from three uniform Euler angles (varied, not uniform over rotations).
fn random_rotation(rng: &mut SplitMix64) -> Quat {
    let tau = std::f32::consts::TAU;
    Quat::from_euler(EulerRot::XYZ, rng.range(0.0, tau), rng.range(0.0, tau), rng.range(0.0, tau))
}

fn instance(geometry: GeometryRef<'_>, transform: Transform, entity_index: u32) -> GeometryInstance<'_> {
    GeometryInstance { geometry, transform, entity_index, material: entity_index % 5 }
}

/// 10 meshes x 100 random triangles, 20 spheres, 20 disks (some annuli), 10 rectangles, in a
/// 14 m box, with random rotations and (for all but spheres) non-uniform scales.
fn random_meshes(rng: &mut SplitMix64) -> Vec<Mesh> {
    (0..10)
        .map(|_| {
            let tris: Vec<[Vec3; 3]> = (0..100)
                .map(|_| {
                    let c = uniform_vec3(rng, -1.5, 1.5);
                    [
                        c + uniform_vec3(rng, -0.4, 0.4),
                        c + uniform_vec3(rng, -0.4, 0.4),
                        c + uniform_vec3(rng, -0.4, 0.4),
                    ]
                })
                .collect();
            Mesh::from_triangles(&tris).unwrap()
        })
        .collect()
}

fn random_scene<'a>(rng: &mut SplitMix64, meshes: &'a [Mesh]) -> Vec<GeometryInstance<'a>> {
    let mut out = Vec::new();
    for m in meshes {
        let t = Transform {
            translation: uniform_vec3(rng, -4.0, 4.0),
            rotation: random_rotation(rng),
            scale: uniform_vec3(rng, 0.5, 1.5),
            shear: glam::Vec3::ZERO,
        };
        out.push(instance(GeometryRef::Mesh(m), t, out.len() as u32));
    }
    for i in 0..50 {
        let shape: Shape = match i % 5 {
            0 | 1 => Sphere { radius: rng.range(0.1, 0.6) }.into(),
            2 | 3 => {
                let radius = rng.range(0.2, 0.8);
                let inner_radius = if i % 2 == 0 { 0.0 } else { radius * rng.f32() * 0.8 };
                Disk { radius, inner_radius }.into()
            }
            _ => Rectangle { half_size: Vec2::new(rng.range(0.1, 0.7), rng.range(0.1, 0.7)) }.into(),
        };
        let scale = if matches!(shape, Shape::Sphere(_)) {
            Vec3::splat(rng.range(0.5, 2.0))
        } else {
            uniform_vec3(rng, 0.5, 2.0)
        };
        let t = Transform {
            translation: uniform_vec3(rng, -6.0, 6.0),
            rotation: random_rotation(rng),
            scale,
            shear: glam::Vec3::ZERO,
        };
        out.push(instance(GeometryRef::Shape(shape), t, out.len() as u32));
    }
    out
}

/// Segments, rays to infinity, and rays starting exactly on surfaces (no offset).
fn random_rays(rng: &mut SplitMix64, bvh: &SceneBvh, n: usize) -> Vec<Ray> {
    let mut rays: Vec<Ray> = (0..n)
        .map(|i| {
            let p0 = uniform_vec3(rng, -7.0, 7.0);
            if i % 3 == 0 {
                Ray::new(p0, uniform_vec3(rng, -1.0, 1.0))
            } else {
                Ray::segment(p0, uniform_vec3(rng, -7.0, 7.0))
            }
        })
        .collect();
    // Replace a fifth with rays leaving hit points: t near 0 and grazing starts.
    for i in (0..n).step_by(5) {
        if let Some(h) = bvh.closest_hit(&rays[i]) {
            rays[i] = Ray::segment(h.p, uniform_vec3(rng, -7.0, 7.0));
        }
    }
    rays
}

fn assert_agrees(bvh: &SceneBvh, rays: &[Ray]) -> (usize, usize) {
    let mut blocked = Vec::new();
    let mut hits: Vec<Option<Hit>> = Vec::new();
    occluded(bvh, rays, &mut blocked);
    closest_hits(bvh, rays, &mut hits);
    let mut n_blocked = 0;
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(blocked[i], bvh.occluded_brute_force(r), "any-hit differs for ray {i}: {r:?}");
        let reference = bvh.closest_hit_brute_force(r);
        assert_eq!(hits[i], reference, "closest hit differs for ray {i}: {r:?}");
        // Any-hit and closest-hit agree with each other too.
        assert_eq!(blocked[i], reference.is_some(), "ray {i}");
        n_blocked += blocked[i] as usize;
    }
    (n_blocked, rays.len() - n_blocked)
}

#[test]
fn bvh_queries_equal_brute_force_on_random_scenes() {
    let mut rng = SplitMix64::new(0x5eed);
    let meshes = random_meshes(&mut rng);
    let scene = random_scene(&mut rng, &meshes);
    let mut bvh = SceneBvh::build(&scene);
    assert_eq!(bvh.primitive_count(), 1000 + 50);
    let rays = random_rays(&mut rng, &bvh, 10_000);
    let (blocked, clear) = assert_agrees(&bvh, &rays);
    assert!(blocked > 2000 && clear > 2000, "a meaningful mix: {blocked} blocked, {clear} clear");

    // After a refit (a third of the instances move) the tree still answers exactly.
    let moved: Vec<(u32, Transform)> = (0..scene.len() as u32)
        .step_by(3)
        .map(|i| {
            let mut t = scene[i as usize].transform;
            t.translation += uniform_vec3(&mut rng, -2.0, 2.0);
            t.rotation = random_rotation(&mut rng);
            (i, t)
        })
        .collect();
    bvh.refit(&moved).unwrap();
    let rays = random_rays(&mut rng, &bvh, 3_000);
    assert_agrees(&bvh, &rays);
}

/// Camera rays onto a tessellated sphere; shadow rays from each hit to a point light. Returns
/// (points facing the light, of those occluded with offsets, of those occluded without).
fn acne_counts(offset: f32) -> (usize, usize, usize) {
    let center = Vec3::splat(offset);
    let sphere = Mesh::uv_sphere(2.0, 48, 24);
    let bvh = SceneBvh::build(&[instance(GeometryRef::Mesh(&sphere), Transform::from_translation(center), 0)]);
    let eye = center + Vec3::new(0.0, 0.0, 8.0);
    let light = center + Vec3::new(7.0, 2.0, 1.0);
    let (mut facing, mut acne, mut naive_acne) = (0, 0, 0);
    for j in 0..64 {
        for i in 0..64 {
            let d = Vec3::new(-0.3 + 0.6 * (i as f32 + 0.5) / 64.0, -0.3 + 0.6 * (j as f32 + 0.5) / 64.0, -1.0);
            let Some(hit) = bvh.closest_hit(&Ray::new(eye, d)) else { continue };
            let shadow = hit.surface_point().spawn_ray_to_point(light);
            // Faces the light from p and from the offset origin (they differ near the terminator,
            // where p's error, ~4 cm at 1e5, turns the direction), by a margin above f32 error.
            let ng = hit.ng.as_dvec3();
            let cos_p = ng.dot((light.as_dvec3() - hit.p.as_dvec3()).normalize());
            let cos_o = ng.dot(shadow.dir.as_dvec3().normalize());
            if cos_p > 1e-3 && cos_o > 1e-3 {
                facing += 1;
                acne += bvh.occluded(&shadow) as usize;
                naive_acne += bvh.occluded(&Ray::segment(hit.p, light)) as usize;
            }
        }
    }
    (facing, acne, naive_acne)
}

#[test]
fn no_shadow_acne_on_a_tessellated_sphere_near_and_far_from_the_origin() {
    for offset in [0.0, 1e3, 1e5] {
        let (facing, acne, naive) = acne_report(offset);
        assert!(facing > 800, "offset {offset}: only {facing} lit points");
        assert_eq!(acne, 0, "offset {offset}: {acne} of {facing} lit points self-shadowed");
        // The test has teeth: without offsets the same points do self-shadow.
        assert!(naive > 0, "offset {offset}: expected acne without offsets");
    }
}

fn acne_report(offset: f32) -> (usize, usize, usize) {
    let r = acne_counts(offset);
    eprintln!("offset {offset:>8}: {} lit points, {} occluded with offsets, {} without", r.0, r.1, r.2);
    r
}

/// Shading points on a floor, segments to points sampled on an area light (disk, rectangle,
/// sphere or triangle) that is itself in the BVH: nothing but the two end surfaces is in the
/// scene, so any blocked segment is a self-intersection at one of its ends.
#[test]
fn segments_ending_on_area_lights_are_unoccluded() {
    let floor_mesh = Mesh::from_triangles(&[
        [Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 0.0, 100.0), Vec3::new(100.0, 0.0, -100.0)],
        [Vec3::new(-100.0, 0.0, -100.0), Vec3::new(-100.0, 0.0, 100.0), Vec3::new(100.0, 0.0, 100.0)],
    ])
    .unwrap();
    let tri_light = Mesh::from_triangles(&[[Vec3::ZERO, Vec3::new(1.0, 0.0, 0.3), Vec3::new(0.2, 0.0, 1.0)]]).unwrap();
    // Flat lights face down (local +Z turned to -Y).
    let down = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    let lights: [(GeometryRef, Vec3, Quat, Vec3); 4] = [
        (GeometryRef::Shape(Disk::new(0.5).into()), Vec3::new(0.0, 3.0, 0.0), down, Vec3::ONE),
        (
            GeometryRef::Shape(Rectangle::from_size(Vec2::new(1.0, 0.5)).into()),
            Vec3::new(4.0, 2.5, -1.0),
            down * Quat::from_rotation_y(0.3),
            Vec3::new(2.0, 1.0, 1.0),
        ),
        (GeometryRef::Shape(Sphere { radius: 0.4 }.into()), Vec3::new(-3.0, 1.5, 2.0), Quat::IDENTITY, Vec3::ONE),
        (GeometryRef::Mesh(&tri_light), Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_z(3.0), Vec3::ONE),
    ];
    for offset in [Vec3::ZERO, Vec3::new(1e5, 2e3, -1e5)] {
        for (k, &(geometry, p, rotation, scale)) in lights.iter().enumerate() {
            let floor = Transform::from_translation(offset);
            let light = Transform { translation: offset + p, rotation, scale, shear: glam::Vec3::ZERO };
            let bvh =
                SceneBvh::build(&[instance(GeometryRef::Mesh(&floor_mesh), floor, 0), instance(geometry, light, 1)]);
            let mut rng = SplitMix64::new(42 + k as u64);
            let (mut tested, mut blocked, mut naive) = (0, 0, 0);
            for _ in 0..2000 {
                // Floor points up to 60 m away: light arrives at grazing angles.
                let q = offset + Vec3::new(rng.range(-60.0, 60.0), 0.0, rng.range(-60.0, 60.0));
                let from = SurfacePoint::from_point(q, Vec3::Y);
                let u = rng.vec2();
                let to = match bvh.placed_shape(1) {
                    Some(shape) => shape.sample_area(u),
                    None => {
                        let (s, v) = (u.x.sqrt(), bvh.world_triangle(1, 0).unwrap());
                        triangle_surface_point(&v, [1.0 - s, s * (1.0 - u.y), s * u.y])
                    }
                };
                // Points on the far side of the sphere are rightly hidden by the sphere itself.
                if to.n.as_dvec3().dot((from.p - to.p).as_dvec3()) <= 1e-4 && k == 2 {
                    continue;
                }
                tested += 1;
                blocked += bvh.occluded(&from.spawn_ray_to(&to)) as usize;
                naive += bvh.occluded(&Ray::segment(from.p, to.p)) as usize;
            }
            assert!(tested > 900, "light {k}: {tested}");
            // The test has teeth: exact segments without offsets do get blocked at their ends.
            assert!(naive > tested / 10, "light {k} offset {offset}: only {naive} naive segments blocked");
            assert_eq!(blocked, 0, "light {k} offset {offset}: {blocked} of {tested} segments blocked at an end");
        }
    }
}

#[test]
fn bad_input_is_an_error_or_a_report_never_a_panic() {
    // NaN vertices and bad indices: clear errors naming the culprit.
    let nan = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 1.0)], vec![0, 1, 2]);
    let err = nan.unwrap_err();
    assert!(matches!(err, GeometryError::NonFiniteVertex { index: 2, .. }));
    assert!(err.to_string().contains("vertex 2"), "{err}");
    let range = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 3]).unwrap_err();
    assert!(range.to_string().contains("triangle 0 uses vertex 3"), "{range}");

    // Degenerate triangles (zero area, repeated vertices) are skipped and reported.
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(2.0, 0.0, 0.0)];
    let mesh = Mesh::new(p.to_vec(), vec![0, 1, 2, 0, 0, 2, 0, 1, 3, 1, 1, 1]).unwrap();
    let flat = Mesh::from_triangles(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]).unwrap();
    let squash = Transform { scale: Vec3::new(1.0, 0.0, 1.0), ..Default::default() };
    let nan_t = Transform::from_translation(Vec3::new(0.0, f32::NAN, 0.0));
    let scene = [
        instance(GeometryRef::Mesh(&mesh), Transform::IDENTITY, 0),
        instance(GeometryRef::Mesh(&flat), squash, 1),
        instance(GeometryRef::Mesh(&flat), nan_t, 2),
        instance(GeometryRef::Shape(Sphere { radius: f32::NAN }.into()), Transform::IDENTITY, 3),
        instance(
            GeometryRef::Shape(Sphere { radius: 1.0 }.into()),
            Transform { scale: Vec3::new(1.0, 2.0, 1.0), ..Default::default() },
            4,
        ),
    ];
    let mut bvh = SceneBvh::build(&scene);
    assert_eq!(bvh.primitive_count(), 1);
    let degenerate: Vec<(u32, u32)> =
        bvh.report().degenerate_triangles.iter().map(|g| (g.entity_index, g.primitive)).collect();
    assert_eq!(degenerate, vec![(0, 1), (0, 2), (0, 3), (1, 0)]);
    let skipped: Vec<String> = bvh.report().skipped_instances.iter().map(|e| e.to_string()).collect();
    assert_eq!(skipped.len(), 3, "{skipped:?}");
    assert!(skipped[0].contains("entity 2") && skipped[0].contains("not finite"), "{}", skipped[0]);
    assert!(skipped[1].contains("entity 3") && skipped[1].contains("sphere"), "{}", skipped[1]);
    assert!(skipped[2].contains("uniform scale"), "{}", skipped[2]);

    // Rays through the degenerate triangles, NaN and zero-length rays: no panic, sane answers.
    let through = Ray::new(Vec3::new(1.5, 0.0, 1.0), Vec3::NEG_Z);
    assert!(!bvh.occluded(&through) && bvh.closest_hit(&through).is_none());
    assert!(bvh.occluded(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z)));
    for bad in [
        Ray::new(Vec3::NAN, Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::segment(Vec3::ONE, Vec3::ONE),
        Ray { t_max: f32::NAN, ..through },
    ] {
        assert!(!bvh.occluded(&bad) && bvh.closest_hit(&bad).is_none());
    }

    // Refits with bad input are errors that change nothing, or lead to a rebuild.
    let before = bvh.clone().closest_hit(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z));
    assert!(matches!(bvh.refit(&[(7, Transform::IDENTITY)]), Err(GeometryError::UnknownInstance { instance: 7, .. })));
    assert!(matches!(bvh.refit(&[(0, nan_t)]), Err(GeometryError::RefitNeedsRebuild { instance: 0 })));
    assert_eq!(bvh.closest_hit(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z)), before);
    assert!(bvh.update_transforms(&[(2, Transform::IDENTITY)]).is_ok(), "instance 2 becomes valid: rebuild");
    assert_eq!(bvh.primitive_count(), 2);
}

#[test]
fn closest_hit_reports_normals_uvs_and_ids() {
    let mesh = Mesh::uv_sphere(1.0, 64, 32);
    let t = Transform {
        translation: Vec3::new(0.0, 0.0, -5.0),
        rotation: Quat::from_rotation_y(0.5),
        scale: Vec3::splat(2.0),
        shear: glam::Vec3::ZERO,
    };
    let disk_t = Transform::from_translation(Vec3::new(10.0, 0.0, 0.0)).looking_to(Vec3::X, Vec3::Y);
    let bvh = SceneBvh::build(&[
        GeometryInstance { geometry: GeometryRef::Mesh(&mesh), transform: t, entity_index: 7, material: 3 },
        GeometryInstance {
            geometry: GeometryRef::Shape(Disk::new(1.0).into()),
            transform: disk_t,
            entity_index: 8,
            material: 4,
        },
    ]);
    let mut rng = SplitMix64::new(3);
    for _ in 0..200 {
        let d = Vec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), -1.0);
        let Some(h) = bvh.closest_hit(&Ray::new(Vec3::ZERO, d)) else { continue };
        let radial = (h.p - t.translation).normalize();
        // Facets deviate from the sphere by at most half the angular step (pi / 32).
        assert!(h.ns.dot(radial) > 0.999 && h.ng.dot(radial) > 0.99, "{h:?}");
        assert!((h.p - t.translation).length() > 1.99 && (h.p - t.translation).length() <= 2.0 + 1e-5);
        assert!(h.uv.cmpge(Vec2::ZERO).all() && h.uv.cmple(Vec2::ONE).all());
        assert_eq!((h.id.entity_index, h.material, h.instance), (7, 3, 0));
        assert!((h.t * d.length() - h.p.length()).abs() < 1e-4);
    }
    // looking_to turns the disk's local -Z to +X, so its front (+Z) faces -X, toward the ray.
    let h = bvh.closest_hit(&Ray::new(Vec3::new(9.0, 0.2, 0.3), Vec3::X)).unwrap();
    assert_eq!((h.id, h.material, h.instance), (kelvin::geometry::GeometryId { entity_index: 8, primitive: 0 }, 4, 1));
    assert!(h.ng.abs_diff_eq(Vec3::NEG_X, 1e-6) && (h.t - 1.0).abs() < 1e-6 && h.p_error.max_element() < 1e-5);
}
