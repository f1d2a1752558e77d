//! Area lights (pbrt-v4 `DiffuseAreaLight`) on spheres, disks, rectangles and triangles:
//! (a) closed-form power vs a Monte Carlo integral of the emitted radiance,
//! (b) every sample's pdf equals `pdf_li` of its direction,
//! (c) `pdf_li` integrates to 1 over directions.
//! Irradiance (d) is in `lights_area_irradiance.rs`, hard cases in `lights_area_hard.rs`.
//! Relative errors are printed with `--nocapture`.

mod common;

use std::f64::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::area::SamplingStrategy;
use kelvin::light::{Amount, AreaLight, LightSampleContext, LightTexture, ResolvedArea};
use kelvin::rng::SplitMix64;
use kelvin::sampling::{Frame, sample_uniform_cone_sin2, sample_uniform_sphere, uniform_cone_pdf_sin2};

use common::area::*;
use common::{RGB, Stats, assert_mc, lum};

// -------------------------------------------------------------------------------------------
// (a) power

/// Monte Carlo power, W: points uniform on the surface, directions uniform on the sphere (drawn in
/// the local normal frame), both jittered-stratified on a 1000 x 1000 grid (the direction strata
/// randomly permuted).
fn mc_power(light: &ResolvedArea, rng: &mut SplitMix64) -> Stats {
    const K: usize = 1000;
    let mut perm: Vec<u32> = (0..(K * K) as u32).collect();
    for i in (1..perm.len()).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    let strat = |c: usize, j: Vec2| Vec2::new(((c % K) as f32 + j.x) / K as f32, ((c / K) as f32 + j.y) / K as f32);
    let l_rad = light.radiance.radiometric as f64 / nits(light);
    let scale = light.area as f64 * 4.0 * PI;
    let mut s = Stats::default();
    for (i, &pi) in perm.iter().enumerate() {
        let on = light.shape.sample_area(strat(i, rng.vec2()).min(Vec2::splat(0.999_999_9))).unwrap();
        // Uniform directions drawn in the normal's frame, so the strata follow cos(theta).
        let w = Frame::from_z(on.n)
            .from_local(sample_uniform_sphere(strat(pi as usize, rng.vec2()).min(Vec2::splat(0.999_999_9))));
        let l = lum(light.radiance(on.p, on.n, on.uv, w, RGB)) * l_rad;
        s.add(l * on.n.dot(w).abs() as f64 * scale);
    }
    s
}

fn check_power(name: &str, light: &ResolvedArea, seed: u64) {
    let s = mc_power(light, &mut SplitMix64::new(seed));
    let expected = light.phi() as f64;
    assert_mc(&format!("(a) power {name}"), &s, expected);
    assert!((s.mean() - expected).abs() < 1e-3 * expected, "{name}: power off by more than 1e-3");
}

#[test]
fn power_closed_form_matches_monte_carlo_for_every_shape() {
    for (i, (name, l)) in all_shapes().iter().enumerate() {
        check_power(name, l, 10 + i as u64);
        if l.two_sided {
            assert!(
                (l.phi() as f64 - 2.0 * PI * l.radiance.radiometric as f64 * l.area as f64).abs()
                    < 1e-4 * l.phi() as f64
            );
        }
    }
}

#[test]
fn power_of_textured_rectangle_uses_mean_texel_luminance() {
    let texels: Vec<Vec3> = (0..12).map(|i| Vec3::splat(0.1 + 0.37 * ((i * 7) % 12) as f32)).collect();
    let tex = Arc::new(LightTexture::new(4, 3, texels).unwrap());
    let l = AreaLight { texture: Some(tex.clone()), ..light() };
    let r = rectangle(&l);
    assert!((r.phi() / (r.radiance.radiometric * r.area * std::f32::consts::PI) - tex.mean_luminance).abs() < 1e-5);
    check_power("textured rectangle", &r, 99);
}

#[test]
fn power_amounts_round_trip_for_every_shape() {
    let watts = |two_sided| AreaLight { amount: Amount::Watts(60.0), two_sided, ..Default::default() };
    let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    for two in [false, true] {
        let l = watts(two);
        let t = tilted(Vec3::ONE);
        let mesh = l.resolve_mesh(&quad, &[], &[0, 1, 2, 0, 2, 3], &t).unwrap();
        let mesh_phi: f32 = mesh.triangles.iter().map(|t| t.phi()).sum();
        for phi in [
            l.resolve_sphere(0.3, &t).unwrap().phi(),
            l.resolve_disk(0.3, &t).unwrap().phi(),
            l.resolve_rectangle(2.0, 0.5, &t).unwrap().phi(),
            mesh_phi,
        ] {
            assert!((phi - 60.0).abs() < 60.0 * 1e-5, "phi {phi} W, want 60 W");
        }
    }
    // Lumens: the photometric power is the luminance-weighted power.
    let lm = AreaLight { amount: Amount::Lumens(800.0), ..Default::default() }
        .resolve_disk(0.1, &Transform::IDENTITY)
        .unwrap();
    let photometric = nits(&lm) * PI * lm.area as f64;
    assert!((photometric - 800.0).abs() < 800.0 * 1e-4, "{photometric} lm");
}

// -------------------------------------------------------------------------------------------
// (b) pdf of samples == pdf_li

#[test]
fn sample_pdf_equals_pdf_li_for_every_shape() {
    let mut rng = SplitMix64::new(2);
    for (name, l) in all_shapes() {
        let points = points_around(&l, &mut rng, 200);
        let (worst, n) = max_pdf_mismatch(&l, &points, 200, &mut rng);
        eprintln!("(b) pdf consistency {name}: max rel diff {worst:.2e} over {n} samples");
        assert!(worst < 1e-4, "{name}: {worst}");
    }
}

#[test]
fn sample_pdf_equals_pdf_li_across_strategy_bands() {
    let mut rng = SplitMix64::new(3);
    let l = light();
    let cases = [
        ("rectangle far tiny", far_tiny_rectangle(&l).0, far_tiny_rectangle(&l).1, SamplingStrategy::Area),
        (
            "rectangle moderate",
            unit_rectangle_above(&l, 1.0).0,
            unit_rectangle_above(&l, 1.0).1,
            SamplingStrategy::SphericalRectangle,
        ),
        (
            "rectangle near huge",
            unit_rectangle_above(&l, 0.01).0,
            unit_rectangle_above(&l, 0.01).1,
            SamplingStrategy::Area,
        ),
        ("triangle 1e-8 sr", tiny_triangle(&l).0, tiny_triangle(&l).1, SamplingStrategy::Area),
        (
            "triangle nearly 2 pi sr",
            near_hemisphere_triangle(&l).0,
            near_hemisphere_triangle(&l).1,
            SamplingStrategy::Area,
        ),
        (
            "sphere 1e-3 r outside",
            sphere_at_origin(&l, 1.0 + 1e-3).0,
            sphere_at_origin(&l, 1.0 + 1e-3).1,
            SamplingStrategy::Cone,
        ),
        (
            "sphere 1e-7 r outside",
            sphere_at_origin(&l, 1.0 + 1e-7).0,
            sphere_at_origin(&l, 1.0 + 1e-7).1,
            SamplingStrategy::Area,
        ),
    ];
    for (name, light, ctx, strategy) in cases {
        assert_eq!(light.strategy(ctx.p), strategy, "{name}");
        let (worst, n) = max_pdf_mismatch(&light, &[ctx.p], 20_000, &mut rng);
        eprintln!("(b) pdf consistency {name} ({strategy:?}): max rel diff {worst:.2e} over {n} samples");
        assert!(worst < 1e-4, "{name}: {worst}");
    }
}

// -------------------------------------------------------------------------------------------
// (c) pdf_li integrates to 1

/// Integral of pdf_li over directions from `p`: uniform over the sphere, or over a cone around
/// `axis` (sin^2 of its half-angle given) that contains the light.
fn pdf_integral(light: &ResolvedArea, p: Vec3, cone: Option<(Vec3, f32)>, n: usize, rng: &mut SplitMix64) -> Stats {
    let ctx = LightSampleContext::at(p);
    let mut s = Stats::default();
    for _ in 0..n {
        let (w, density) = match cone {
            None => (sample_uniform_sphere(rng.vec2()), 1.0 / (4.0 * PI)),
            Some((axis, sin2)) => {
                let w = Frame::from_z(axis).from_local(sample_uniform_cone_sin2(rng.vec2(), sin2));
                (w, uniform_cone_pdf_sin2(sin2) as f64)
            }
        };
        let pdf = light.pdf_li(&ctx, w);
        assert!(pdf.is_finite() && pdf >= 0.0);
        s.add(pdf as f64 / density);
    }
    s
}

#[test]
fn pdf_li_integrates_to_one_for_every_shape() {
    let mut rng = SplitMix64::new(4);
    for (name, l) in all_shapes() {
        for (k, p) in points_around(&l, &mut rng, 3).into_iter().enumerate() {
            let s = pdf_integral(&l, p, None, 400_000, &mut rng);
            if s.mean() == 0.0 {
                continue; // a point in a planar light's plane sees nothing.
            }
            assert_mc(&format!("(c) pdf integral {name} point {k} ({:?})", l.strategy(p)), &s, 1.0);
        }
    }
}

#[test]
fn pdf_li_integrates_to_one_across_strategy_bands() {
    let mut rng = SplitMix64::new(5);
    let l = light();
    let (r, ctx) = unit_rectangle_above(&l, 0.01);
    assert_mc("(c) pdf integral rectangle near huge (Area)", &pdf_integral(&r, ctx.p, None, 1_000_000, &mut rng), 1.0);
    let (r, ctx) = unit_rectangle_above(&l, 1.0);
    assert_mc(
        "(c) pdf integral rectangle moderate (Spherical)",
        &pdf_integral(&r, ctx.p, None, 1_000_000, &mut rng),
        1.0,
    );
    let (t, ctx) = near_hemisphere_triangle(&l);
    assert_mc("(c) pdf integral triangle nearly 2 pi sr", &pdf_integral(&t, ctx.p, None, 1_000_000, &mut rng), 1.0);
    // Tiny lights: directions in a cone around them (pdf_li is 0 outside it).
    let (r, ctx) = far_tiny_rectangle(&l);
    let axis = (Vec3::new(0.0, 0.0, 1.0) - ctx.p).normalize();
    assert_mc(
        "(c) pdf integral rectangle far tiny (Area)",
        &pdf_integral(&r, ctx.p, Some((axis, 1e-4)), 1_000_000, &mut rng),
        1.0,
    );
    let (t, ctx) = tiny_triangle(&l);
    assert_mc(
        "(c) pdf integral triangle 1e-8 sr",
        &pdf_integral(&t, ctx.p, Some((Vec3::Z, 1e-7)), 1_000_000, &mut rng),
        1.0,
    );
    for (name, d) in [
        ("sphere 1e-3 r outside (Cone)", 1.0 + 1e-3),
        ("sphere 1e-7 r outside (Area)", 1.0 + 1e-7),
        ("sphere inside (Area)", 0.4),
    ] {
        let (s, ctx) = sphere_at_origin(&l, d);
        assert_mc(&format!("(c) pdf integral {name}"), &pdf_integral(&s, ctx.p, None, 1_000_000, &mut rng), 1.0);
    }
    let (s, ctx) = tiny_sphere(&l);
    let axis = (Vec3::new(1.0, 2.0, 3.0) - ctx.p).normalize();
    assert_mc(
        "(c) pdf integral tiny sphere sin^2 = 1e-8",
        &pdf_integral(&s, ctx.p, Some((axis, 4e-8)), 1_000_000, &mut rng),
        1.0,
    );
}

// -------------------------------------------------------------------------------------------
// (d) irradiance
