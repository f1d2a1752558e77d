//! Area lights: hard cases (grazing directions, degenerate triangles, points on and inside spheres),
//! spectral queries, textures, bounds, transforms and bad input.

mod common;

use std::sync::Arc;

use glam::{Quat, Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::area::{ShapeSample, sphere_from_point_light};
use kelvin::light::{
    Amount, AreaLight, AreaShape, ColorQuery, LightError, LightSampleContext, LightTexture, PointLight, ResolvedArea,
};
use kelvin::rng::SplitMix64;
use kelvin::sampling::sample_uniform_sphere;
use kelvin::spectrum::SampledWavelengths;

use common::area::*;
use common::{RGB, assert_mc, lum};

// -------------------------------------------------------------------------------------------
// Hard cases and bad input

#[test]
fn grazing_cos_1e_7_stays_finite_and_consistent() {
    let mut rng = SplitMix64::new(16);
    let l = light();
    for (name, light) in [
        ("rectangle", l.resolve_rectangle(1.0, 1.0, &Transform::IDENTITY).unwrap()),
        ("disk", l.resolve_disk(0.5, &Transform::IDENTITY).unwrap()),
    ] {
        // 3 m away in the plane, 3e-7 m above it: cos at the light ~ 1e-7.
        let ctx = LightSampleContext::on_surface(Vec3::new(3.0, 0.0, 3e-7), Vec3::NEG_X);
        let (worst, n) = max_pdf_mismatch(&light, &[ctx.p], 20_000, &mut rng);
        assert!(n > 0 && worst < 1e-4, "{name}: {worst}");
        let s = irradiance(&light, &ctx, 100_000, &mut rng);
        assert!(s.mean().is_finite() && s.mean() >= 0.0);
        if name == "rectangle" {
            let want = lambert(ctx.p, ctx.n, &corners(&light.shape), nits(&light));
            assert_mc("(d) irradiance rectangle at grazing cos 1e-7", &s, want);
        }
        for _ in 0..10_000 {
            assert!(light.pdf_li(&ctx, sample_uniform_sphere(rng.vec2())).is_finite());
        }
        eprintln!("(b) pdf consistency {name} grazing cos 1e-7: max rel diff {worst:.2e} over {n} samples");
    }
    // Exactly in the plane: nothing to sample, pdf 0.
    let r = l.resolve_rectangle(1.0, 1.0, &Transform::IDENTITY).unwrap();
    let ctx = LightSampleContext::at(Vec3::new(3.0, 0.2, 0.0));
    assert!(r.sample_li(&ctx, Vec2::new(0.3, 0.6), RGB).is_none());
    assert_eq!(r.pdf_li(&ctx, Vec3::NEG_X), 0.0);
}

#[test]
fn zero_area_and_collinear_triangles_are_skipped_and_safe() {
    let l = light();
    let positions = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(2.0, 2.0, 2.0),
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(0.2, 0.4, 0.6),
        Vec3::new(f32::NAN, 0.0, 0.0),
    ];
    // good, repeated vertex, collinear (exact), collinear (rounded), NaN vertex
    let indices = [0, 1, 2, 0, 0, 1, 0, 3, 3, 0, 4, 5, 6, 1, 2];
    let mesh = l.resolve_mesh(&positions, &[], &indices, &Transform::IDENTITY).unwrap();
    assert_eq!((mesh.triangles.len(), mesh.skipped_degenerate), (1, 4));
    assert!((mesh.triangles[0].area - 0.5).abs() < 1e-6);

    // Built directly, degenerate triangles sample nothing and report pdf 0, finite bounds.
    for p in [
        [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        [Vec3::ONE; 3],
        [Vec3::ZERO, Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.2, 0.4, 0.6)],
    ] {
        let t = ResolvedArea::new(
            AreaShape::Triangle { p, uv: [Vec2::ZERO; 3] },
            l.resolve_disk(1.0, &Transform::IDENTITY).unwrap().radiance,
            false,
            None,
        );
        let ctx = LightSampleContext::at(Vec3::new(0.3, 1.0, -0.2));
        let mut rng = SplitMix64::new(17);
        for _ in 0..1000 {
            assert!(t.sample_li(&ctx, rng.vec2(), RGB).is_none());
            assert_eq!(t.pdf_li(&ctx, sample_uniform_sphere(rng.vec2())), 0.0);
        }
        assert!(t.phi() == 0.0 && t.bounds().min.is_finite() && t.bounds().max.is_finite());
    }
}

#[test]
fn sphere_hard_points_all_outputs_finite() {
    let mut rng = SplitMix64::new(18);
    let l = two_sided();
    let s = l.resolve_sphere(1.0, &Transform::IDENTITY).unwrap();
    let points = [
        Vec3::ZERO,                            // centre
        Vec3::new(0.0, 0.0, 1.0),              // on the surface
        Vec3::new(0.0, 1.0f32.next_up(), 0.0), // 1.2e-7 r outside
        Vec3::new(0.0, 0.0, 1.0 + 1e-3),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(1e4, 0.0, 0.0), // far
    ];
    for p in points {
        let ctx = LightSampleContext::on_surface(p, Vec3::Y);
        for _ in 0..5000 {
            if let Some(ls) = s.sample_li(&ctx, rng.vec2(), RGB) {
                assert!(
                    ls.pdf.is_finite()
                        && ls.pdf > 0.0
                        && ls.radiance.is_finite()
                        && ls.p_light.is_finite()
                        && ls.n_light.is_finite()
                );
            }
            assert!(s.pdf_li(&ctx, sample_uniform_sphere(rng.vec2())).is_finite());
        }
    }
    let (worst, n) = max_pdf_mismatch(&s, &points, 5000, &mut rng);
    eprintln!("(b) pdf consistency sphere hard points: max rel diff {worst:.2e} over {n} samples");
    assert!(worst < 1e-4, "{worst}");
}

#[test]
fn spectral_query_gives_finite_spectral_radiance() {
    let lambda = SampledWavelengths::sample_visible(0.3);
    let r = rectangle(&light());
    let n = r.shape.plane_normal().unwrap();
    let ctx = LightSampleContext::at(r.shape.sample_area(Vec2::splat(0.5)).unwrap().p + n);
    let ls = r.sample_li(&ctx, Vec2::new(0.2, 0.7), ColorQuery::Spectral(&lambda)).unwrap();
    let want = lambda.eval(&r.radiance.spectrum).scale(r.radiance.scale);
    for i in 0..4 {
        assert!((ls.radiance.0[i] - want.0[i]).abs() <= 1e-6 * want.0[i].abs() && want.0[i] > 0.0);
    }
}

#[test]
fn texture_lookup_is_bilinear_with_wrap() {
    let t = LightTexture::new(2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap();
    assert_eq!(t.lookup(Vec2::new(0.25, 0.5)), Vec3::ZERO);
    assert_eq!(t.lookup(Vec2::new(0.75, 0.5)), Vec3::ONE);
    assert!((t.lookup(Vec2::new(0.5, 0.5)) - Vec3::splat(0.5)).length() < 1e-6);
    assert!((t.lookup(Vec2::new(0.0, 0.5)) - Vec3::splat(0.5)).length() < 1e-6); // wraps
    assert!(LightTexture::new(2, 2, vec![Vec3::ONE; 3]).is_err());
    assert!(LightTexture::new(1, 1, vec![Vec3::new(-1.0, 0.0, 0.0)]).is_err());
    // A textured light is tinted by the texel under the sample.
    let l = AreaLight {
        texture: Some(Arc::new(LightTexture::new(2, 1, vec![Vec3::ZERO, Vec3::splat(2.0)]).unwrap())),
        ..light()
    };
    let r = l.resolve_rectangle(1.0, 1.0, &Transform::IDENTITY).unwrap();
    let ctx = LightSampleContext::at(Vec3::new(0.0, 0.0, 1.0));
    let mut rng = SplitMix64::new(19);
    for _ in 0..1000 {
        if let Some(ls) = r.sample_li(&ctx, rng.vec2(), RGB) {
            let h: ShapeSample = r.shape.hit(ctx.p, ls.wi).unwrap();
            let want = 2.0 * nits(&r) * r.texture.as_ref().unwrap().lookup(h.point.uv).x as f64 / 2.0;
            assert!((lum(ls.radiance) - want).abs() <= 1e-4 * nits(&r));
        }
    }
}

#[test]
fn bounds_follow_pbrt_diffuse_area_light() {
    let l = light();
    let s = sphere(&l).bounds();
    assert_eq!((s.cos_theta_o, s.cos_theta_e), (-1.0, 0.0));
    assert!(
        (s.min - Vec3::new(-0.4, -0.9, -0.2)).length() < 1e-6 && (s.max - Vec3::new(1.0, 0.5, 1.2)).length() < 1e-6
    );
    for r in [disk(&l), rectangle(&l), moderate_triangle(&l), rectangle(&two_sided())] {
        let b = r.bounds();
        assert_eq!((b.cos_theta_o, b.cos_theta_e, b.two_sided), (1.0, 0.0, r.two_sided));
        assert!((b.w - r.shape.plane_normal().unwrap()).length() < 1e-6 && (b.phi - r.phi()).abs() <= 1e-6 * r.phi());
        let mut rng = SplitMix64::new(20);
        for _ in 0..1000 {
            let p = r.shape.sample_area(rng.vec2()).unwrap().p;
            assert!(p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all(), "{p} outside {b:?}");
        }
    }
}

#[test]
fn transforms_place_shapes_and_mirrors_keep_the_emitting_side() {
    let l = light();
    let t = Transform {
        translation: Vec3::new(1.0, 2.0, 3.0),
        rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        scale: Vec3::new(2.0, 3.0, 1.0),
    };
    // Local +Z turned to world +Y.
    let r = l.resolve_rectangle(1.0, 1.0, &t).unwrap();
    assert!((r.shape.plane_normal().unwrap() - Vec3::Y).length() < 1e-6 && (r.area - 6.0).abs() < 1e-5);
    let d = l.resolve_disk(1.0, &t).unwrap();
    assert!(
        (d.shape.plane_normal().unwrap() - Vec3::Y).length() < 1e-6
            && (d.area - 9.0 * std::f32::consts::PI).abs() < 1e-4
    );
    let s = l.resolve_sphere(0.5, &t).unwrap();
    assert_eq!(s.shape, AreaShape::Sphere { center: Vec3::new(1.0, 2.0, 3.0), radius: 1.5 });
    // Mirroring X keeps the rectangle emitting toward local +Z.
    let m = Transform { scale: Vec3::new(-1.0, 1.0, 1.0), ..Transform::IDENTITY };
    assert!((l.resolve_rectangle(1.0, 1.0, &m).unwrap().shape.plane_normal().unwrap() - Vec3::Z).length() < 1e-6);
    let tri = l.resolve_mesh(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[], &[0, 1, 2], &m).unwrap();
    assert!((tri.triangles[0].shape.plane_normal().unwrap() - Vec3::Z).length() < 1e-6);
}

#[test]
fn bad_input_gives_clear_errors() {
    let l = light();
    let t = Transform::IDENTITY;
    assert!(matches!(l.resolve_sphere(-1.0, &t), Err(LightError::BadAmount { field: "radius", .. })));
    assert!(matches!(l.resolve_disk(f32::NAN, &t), Err(LightError::BadAmount { field: "radius", .. })));
    assert!(matches!(l.resolve_rectangle(1.0, 0.0, &t), Err(LightError::BadAmount { field: "height", .. })));
    let cd = AreaLight { amount: Amount::Candela(10.0), ..Default::default() };
    assert!(matches!(cd.resolve_sphere(1.0, &t), Err(LightError::WrongUnit { given: "cd", .. })));
    let neg = AreaLight { amount: Amount::Nits(-1.0), ..Default::default() };
    assert!(matches!(neg.resolve_sphere(1.0, &t), Err(LightError::BadAmount { .. })));
    let e = l.resolve_mesh(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[], &[0, 1, 5], &t).unwrap_err();
    assert!(e.to_string().contains("triangle 0: index 5 out of range"), "{e}");
    assert!(l.resolve_mesh(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[Vec2::ZERO], &[0, 1, 2], &t).is_err());
    assert!(l.resolve_mesh(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[], &[0, 1], &t).is_err());
    let flat = Transform { scale: Vec3::new(0.0, 1.0, 1.0), ..t };
    assert!(l.resolve_rectangle(1.0, 1.0, &flat).is_err());
    let nan = Transform { translation: Vec3::NAN, ..t };
    assert!(l.resolve_sphere(1.0, &nan).is_err());
}

#[test]
fn point_light_with_radius_is_a_sphere_of_the_same_power_and_far_intensity() {
    let p = PointLight { radius: 0.05, ..PointLight::candela(200.0) };
    let t = Transform::from_translation(Vec3::new(1.0, 2.0, 3.0));
    let s = sphere_from_point_light(&p, &t).unwrap().unwrap();
    let point = p.resolve(&t).unwrap();
    assert!((s.phi() - point.phi()).abs() <= 1e-5 * point.phi());
    // 10 m away, facing it: E = pi L (r/d)^2 = I / d^2.
    let ctx = LightSampleContext::on_surface(Vec3::new(1.0, 12.0, 3.0), Vec3::NEG_Y);
    let mut rng = SplitMix64::new(21);
    assert_mc(
        "(d) point light with radius 5 cm at 10 m vs I/d^2",
        &irradiance(&s, &ctx, 10_000, &mut rng),
        200.0 / 100.0,
    );
    assert!(sphere_from_point_light(&PointLight::candela(1.0), &t).unwrap().is_none());
}
