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
        shear: glam::Vec3::ZERO,
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
    assert!(matches!(l.resolve_sphere(-1.0, &t), Err(LightError::BadSize { field: "radius", .. })));
    assert!(matches!(l.resolve_disk(f32::NAN, &t), Err(LightError::BadSize { field: "radius", .. })));
    assert!(matches!(l.resolve_rectangle(1.0, 0.0, &t), Err(LightError::BadSize { field: "height", .. })));
    // A good radius that the transform scales to nothing: the message says so (not "1 must be >= 0").
    let flat = Transform { scale: Vec3::ZERO, ..Transform::IDENTITY };
    let e = l.resolve_sphere(1.0, &flat).unwrap_err().to_string();
    assert_eq!(e, "AreaLight: radius = 1 (scaled by the transform: 0) must be finite and > 0");
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

// -------------------------------------------------------------------------------------------
// The f32 kernel (`AreaShape::sample_fast`, what `sample_li` uses) against its f64 reference
// (`AreaShape::sample`, what `sample_li_f64` uses)

/// Per kind of hard triangle: samples compared, how many took the f32 kernel, and the worst
/// relative pdf difference (to the reference and to `hit`) and direction difference (radians
/// over the triangle's angular size).
#[derive(Default)]
struct Agreement {
    samples: usize,
    kernel: usize,
    pdf_vs_reference: f64,
    pdf_vs_hit: f64,
    spherical_dir: f64,
    area_dir: f64,
    none: usize,
    reference_gave_up: usize,
}

#[test]
fn f32_kernel_agrees_with_f64_reference_on_hard_triangles() {
    use kelvin::light::area::SamplingStrategy;
    use kelvin::sampling::spherical_f32::TriangleView;
    use kelvin::sampling::{sample_spherical_triangle, triangle_solid_angle};
    let mut rng = SplitMix64::new(41);
    let mut by_kind: Vec<(&str, Agreement)> = Vec::new();
    let mut a_bound = 0.0f32;
    for (kind, v, p) in hard_triangles(&mut rng, 6000) {
        let shape = AreaShape::Triangle { p: v, uv: [Vec2::ZERO, Vec2::X, Vec2::Y] };
        let (normal, area) = (shape.plane_normal().unwrap(), shape.area());
        let (view, holds) = TriangleView::<f32>::new(v, normal * (2.0 * area), p);
        let view = holds.then_some(view);
        let kernel = view.is_some_and(|t| t.solid_angle < 3e-4 || t.spherical().1);
        if let Some(t) = view {
            // The error bound the strategy choice relies on holds (the reference is f64, rounded).
            let exact = triangle_solid_angle(v, p);
            let err = (t.solid_angle - exact).abs();
            assert!(err <= t.solid_angle_error + exact * 1.2e-7, "{kind}: {v:?} from {p}: {t:?} vs {exact}");
            a_bound = a_bound.max(err / t.solid_angle_error);
        }
        // Angular size: the largest angle between vertex directions.
        let dirs = v.map(|q| (q.as_dvec3() - p.as_dvec3()).normalize());
        let size = (0..3).map(|i| dirs[i].angle_between(dirs[(i + 1) % 3])).fold(0.0, f64::max);
        let slot = match by_kind.iter().position(|(k, _)| *k == kind) {
            Some(i) => i,
            None => {
                by_kind.push((kind, Agreement::default()));
                by_kind.len() - 1
            }
        };
        let a = &mut by_kind[slot].1;
        for _ in 0..32 {
            let u = rng.vec2();
            let (fast, reference) = (shape.sample_fast(p, u), shape.sample(p, u));
            let Some(f) = fast else {
                // Only through the reference (whose edge repair may give up), which then agrees.
                assert!(reference.is_none(), "{kind}: {v:?} from {p}, u {u}: no f32 sample");
                a.none += 1;
                continue;
            };
            a.samples += 1;
            let rel = |x: f32, y: f32| ((x - y) as f64).abs() / y as f64;
            let h =
                shape.hit(p, f.wi).unwrap_or_else(|| panic!("{kind}: {v:?} from {p}, u {u}: f32 wi {} misses", f.wi));
            a.pdf_vs_hit = a.pdf_vs_hit.max(rel(f.pdf, h.pdf));
            let Some(r) = reference else {
                a.reference_gave_up += 1; // its point, rounded to f32, fell outside
                continue;
            };
            a.pdf_vs_reference = a.pdf_vs_reference.max(rel(f.pdf, r.pdf));
            a.kernel += kernel as usize;
            if !kernel || f == r {
                continue; // the reference's own sample (its view, or per sample at an edge)
            }
            if shape.strategy(p) == SamplingStrategy::SphericalTriangle {
                // The f64 map's direction for the same u (the reference rounds its point to f32
                // before taking the direction, which costs more than f32 does here).
                let b = sample_spherical_triangle(v, p, u).unwrap().0;
                let [v0, v1, v2] = v.map(|q| q.as_dvec3() - p.as_dvec3());
                let q = v0 + (v1 - v0) * b[1] as f64 + (v2 - v0) * b[2] as f64;
                a.spherical_dir = a.spherical_dir.max(f.wi.as_dvec3().angle_between(q) / size);
            } else {
                a.area_dir = a.area_dir.max(f.wi.as_dvec3().angle_between(r.wi.as_dvec3()));
            }
        }
    }
    for (kind, a) in &by_kind {
        eprintln!(
            "{kind}: {} samples, {:.1}% by the f32 kernel; max rel pdf diff {:.1e} to the reference, {:.1e} to hit; \
             max direction diff {:.1e} of the angular size (spherical), {:.1e} rad (area); {} None, {} only from f32",
            a.samples,
            100.0 * a.kernel as f64 / a.samples.max(1) as f64,
            a.pdf_vs_reference,
            a.pdf_vs_hit,
            a.spherical_dir,
            a.area_dir,
            a.none,
            a.reference_gave_up
        );
    }
    eprintln!("solid angle: error at most {a_bound:.2} of its bound");
    for (kind, a) in &by_kind {
        assert!(a.pdf_vs_reference < 1e-4 && a.pdf_vs_hit < 1e-4, "{kind}");
        assert!(a.spherical_dir < 1e-4 && a.area_dir < 1e-6, "{kind}");
    }
}

#[test]
fn f32_area_sampling_density_integrates_to_the_solid_angle() {
    // E[1 / pdf] over the samples is the solid angle; exact for solid-angle sampling, a Monte
    // Carlo integral for area sampling (tiny or far triangles), which the kernel does too.
    use kelvin::sampling::spherical_f32::TriangleView;
    use kelvin::sampling::triangle_solid_angle;
    let mut rng = SplitMix64::new(43);
    let mut checked = 0;
    for (kind, v, p) in hard_triangles(&mut rng, 600) {
        let shape = AreaShape::Triangle { p: v, uv: [Vec2::ZERO; 3] };
        let omega = triangle_solid_angle(v, p) as f64;
        let (normal, area) = (shape.plane_normal().unwrap(), shape.area());
        if !TriangleView::<f32>::new(v, normal * (2.0 * area), p).1 {
            continue; // the reference's (which at grazing angles drops the samples it cannot repair)
        }
        let mut s = common::Stats::default();
        for _ in 0..4000 {
            s.add(shape.sample_fast(p, rng.vec2()).map_or(0.0, |f| 1.0 / f.pdf as f64));
        }
        let err = (s.mean() - omega).abs();
        assert!(err <= 5.0 * s.sigma() + 1e-4 * omega, "{kind}: {v:?} from {p}: {} vs {omega}", s.mean());
        checked += (shape.strategy(p) == kelvin::light::area::SamplingStrategy::Area) as usize;
    }
    assert!(checked > 100, "{checked} area-sampled triangles");
}

// -------------------------------------------------------------------------------------------
// The f32 hit (`AreaShape::hit_fast`, what `pdf_li` and `li` use) against its f64 reference
// (`AreaShape::hit`, what `pdf_li_f64` uses)

#[test]
fn f32_hit_agrees_with_f64_reference_on_hard_triangles() {
    use kelvin::sampling::spherical_f32::TriangleView;
    let mut rng = SplitMix64::new(47);
    let rel = |x: f32, y: f32| ((x - y) as f64).abs() / y as f64;
    let (mut by_f32, mut total, mut hits, mut sampled) = (0usize, 0usize, 0usize, 0usize);
    let (mut worst_pdf, mut worst_sampled, mut worst_point) = (0.0f64, 0.0f64, 0.0f64);
    for (kind, v, p) in hard_triangles(&mut rng, 6000) {
        let shape = AreaShape::Triangle { p: v, uv: [Vec2::ZERO, Vec2::X, Vec2::Y] };
        let (normal, area) = (shape.plane_normal().unwrap(), shape.area());
        let (view, holds) = TriangleView::<f32>::new(v, normal * (2.0 * area), p);
        let view = holds.then_some(view);
        let size = (v[1] - v[0]).length().max((v[2] - v[0]).length()).max((v[2] - v[1]).length());
        for _ in 0..32 {
            // Toward points of the plane around the triangle (half of them outside it, some
            // within rounding of an edge), and a few directions from anywhere.
            let (a, b) = (rng.f32() * 1.4 - 0.2, rng.f32() * 1.4 - 0.2);
            let wi = if rng.f32() < 0.9 {
                ((v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b) - p).normalize()
            } else {
                sample_uniform_sphere(rng.vec2())
            };
            let (fast, reference) = (shape.hit_fast(p, wi), shape.hit(p, wi));
            total += 1;
            by_f32 += view.map(|t| t.edge_test(wi)).is_some_and(|e| e.inside || e.outside) as usize;
            match (fast, reference) {
                (Some(f), Some(r)) => {
                    hits += 1;
                    worst_pdf = worst_pdf.max(rel(f.pdf, r.pdf));
                    // f32 differences v - p and the interpolated point round by eps |p|, and an
                    // ulp of the direction moves the point by eps t / |cos|; the barycentrics
                    // carry that over the triangle's least height h, the point that times its
                    // size (a sliver's point slides along its long edge).
                    let height = 2.0 * area / size;
                    let scale = (r.point.p - p).length() / normal.dot(wi).abs() + p.length().max(r.point.p.length());
                    let d = ((f.point.p - r.point.p).length() * height / (scale * size)) as f64;
                    worst_point = worst_point.max(d);
                    assert!(f.point.n == r.point.n, "{kind}");
                    assert!(
                        (f.point.uv - r.point.uv).length() <= 1e-6 * scale / height + 1e-5,
                        "{kind}: {f:?} vs {r:?}"
                    );
                }
                (None, None) => {}
                (f, r) => panic!("{kind}: {v:?} from {p} along {wi}: f32 {f:?}, f64 {r:?}"),
            }
        }
        // A sampled direction's density is the one `hit_fast` gives it.
        for _ in 0..8 {
            if let Some(s) = shape.sample_fast(p, rng.vec2()) {
                let h = shape.hit_fast(p, s.wi).unwrap_or_else(|| panic!("{kind}: {v:?} from {p}: {} misses", s.wi));
                worst_sampled = worst_sampled.max(rel(s.pdf, h.pdf));
                sampled += 1;
            }
        }
    }
    eprintln!(
        "f32 hit: {total} directions ({:.1}% decided in f32), {hits} hits: max rel pdf diff {worst_pdf:.1e} to the \
         reference, max point diff {worst_point:.1e} of (t / |cos| + |p|) size / h; {sampled} samples: max rel diff {worst_sampled:.1e} \
         to their own density",
        100.0 * by_f32 as f64 / total as f64
    );
    assert!(hits > total / 5 && by_f32 > total / 2);
    assert!(worst_pdf <= 2e-5 && worst_sampled <= 2e-5, "{worst_pdf} {worst_sampled}");
    assert!(worst_point < 1e-6);
}

#[test]
fn sample_li_density_is_pdf_li_for_its_own_direction() {
    // Through the light (and the table's dispatch): the f32 kernels on both sides, the f64
    // reference pair, and each against the other.
    let mut rng = SplitMix64::new(53);
    let l = light();
    let mut worst = [0.0f64; 3];
    let mut n = 0;
    for (_, v, p) in hard_triangles(&mut rng, 1200) {
        let Ok(mesh) = l.resolve_mesh(&v, &[], &[0, 1, 2], &Transform::IDENTITY) else { continue };
        let Some(light) = mesh.triangles.first() else { continue };
        let ctx = LightSampleContext::at(p);
        for _ in 0..16 {
            let u = rng.vec2();
            let rel = |x: f32, y: f32| ((x - y) as f64).abs() / y as f64;
            if let Some(s) = light.sample_li(&ctx, u, RGB) {
                assert!(
                    light
                        .li(&ctx, s.wi, RGB)
                        .is_some_and(|(h, le)| h.pdf == light.pdf_li(&ctx, s.wi) && le.0 == s.radiance.0)
                );
                worst[0] = worst[0].max(rel(s.pdf, light.pdf_li(&ctx, s.wi)));
                worst[2] = worst[2].max(rel(s.pdf, light.pdf_li_f64(&ctx, s.wi)));
                n += 1;
            }
            if let Some(s) = light.sample_li_f64(&ctx, u, RGB) {
                worst[1] = worst[1].max(rel(s.pdf, light.pdf_li_f64(&ctx, s.wi)));
            }
        }
    }
    eprintln!(
        "sample_li vs pdf_li over {n} samples: f32 {:.1e}, f64 {:.1e}, f32 vs f64 {:.1e}",
        worst[0], worst[1], worst[2]
    );
    assert!(n > 5000 && worst[0] <= 2e-5 && worst[1] <= 2e-5 && worst[2] <= 1e-4, "{worst:?}");
}
