//! Point, spot and distant lights against closed forms: a point light's I cos(theta) / r^2, a
//! spot's smoothstep falloff and power, a distant light's E cos(theta), and a sun-sized disc that
//! integrates to E cos(theta). Relative errors are printed with `--nocapture`.

mod common;

use std::f64::consts::PI;

use glam::{Quat, Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::distant::SUN_ANGULAR_DIAMETER;
use kelvin::light::{Amount, DistantLight, LightSampleContext, PointLight, SceneSphere, SpotLight};
use kelvin::rng::SplitMix64;
use kelvin::sampling::sample_uniform_sphere;

use common::{RGB, Stats, assert_mc, lum};

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-30)
}

/// Receivers around `center`: positions and unit normals tilted by up to ~80 degrees from the
/// direction toward it.
fn receivers(center: Vec3, rng: &mut SplitMix64, n: usize) -> Vec<LightSampleContext> {
    (0..n)
        .map(|_| {
            let d = sample_uniform_sphere(rng.vec2());
            let p = center + d * (0.3 + 4.0 * rng.f32());
            let axis = d.any_orthonormal_vector();
            LightSampleContext::on_surface(p, Quat::from_axis_angle(axis, 1.4 * rng.f32()) * -d)
        })
        .collect()
}

#[test]
fn point_light_irradiance_is_i_cos_over_r2() {
    let center = Vec3::new(1.0, 2.0, -3.0);
    let light = PointLight::candela(150.0).resolve(&Transform::from_translation(center)).unwrap();
    let mut worst: f64 = 0.0;
    for ctx in receivers(center, &mut SplitMix64::new(1), 1000) {
        let s = light.sample_li(&ctx, RGB).unwrap();
        let e = lum(s.radiance) * ctx.n.dot(s.wi).max(0.0) as f64;
        let d = center.as_dvec3() - ctx.p.as_dvec3();
        let want = 150.0 * ctx.n.as_dvec3().dot(d.normalize()).max(0.0) / d.length_squared();
        worst = worst.max(rel(e, want));
        assert_eq!(s.pdf, 1.0);
    }
    eprintln!("point light E = I cos / r^2: max rel err {worst:.2e}");
    assert!(worst < 1e-4);
    // At the light itself: no direction.
    assert!(light.sample_li(&LightSampleContext::at(center), RGB).is_none());
}

#[test]
fn point_light_power_round_trips_lumens() {
    let light = PointLight { amount: Amount::Lumens(800.0), ..Default::default() };
    let r = light.resolve(&Transform::IDENTITY).unwrap();
    let candela = r.intensity.luminous() as f64;
    let lumens = r.phi() as f64 * light.spectrum.luminous_efficacy();
    eprintln!("point light 800 lm: {candela:.4} cd (want {:.4}), phi {lumens:.3} lm", 800.0 / (4.0 * PI));
    assert!(rel(candela, 800.0 / (4.0 * PI)) < 1e-4 && rel(lumens, 800.0) < 1e-4);
}

/// Cubic Hermite smoothstep of x between a and b.
fn smoothstep(x: f64, a: f64, b: f64) -> f64 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[test]
fn spot_light_on_axis_and_in_the_falloff_band() {
    let (inner, outer) = (0.3f32, 0.5f32);
    let dir = Vec3::new(0.2, -1.0, 0.3).normalize();
    let pos = Vec3::new(0.5, 3.0, 0.0);
    let t = Transform::from_translation(pos).looking_to(dir, Vec3::Y);
    let light =
        SpotLight { amount: Amount::Candela(500.0), inner_angle: inner, outer_angle: outer, ..Default::default() }
            .resolve(&t)
            .unwrap();
    let perp = dir.any_orthonormal_vector();
    let mut worst: f64 = 0.0;
    for angle in [0.0f32, 0.1, 0.3, 0.35, 0.4, 0.45, 0.49] {
        let w = Quat::from_axis_angle(perp, angle) * dir;
        let r = 2.5f32;
        let ctx = LightSampleContext::on_surface(pos + w * r, -w);
        let s = light.sample_li(&ctx, RGB).unwrap();
        let cos = (-s.wi).dot(dir) as f64;
        let want = 500.0 * smoothstep(cos, (outer as f64).cos(), (inner as f64).cos()) / (r as f64 * r as f64);
        let e = lum(s.radiance);
        eprintln!("spot at {angle} rad: E {e:.6e} vs {want:.6e}, rel err {:.2e}", rel(e, want));
        worst = worst.max(rel(e, want));
    }
    assert!(worst < 1e-3, "{worst}");
    let outside = LightSampleContext::at(pos + Quat::from_axis_angle(perp, 0.6) * dir);
    assert!(light.sample_li(&outside, RGB).is_none());
}

#[test]
fn spot_light_power_matches_monte_carlo_of_its_falloff() {
    let light = SpotLight { amount: Amount::Lumens(800.0), inner_angle: 0.2, outer_angle: 0.7, ..Default::default() };
    let r = light.resolve(&Transform::IDENTITY).unwrap();
    // Integrate I(w) over the sphere of directions: sample_li from points on a unit sphere.
    let mut rng = SplitMix64::new(2);
    let mut s = Stats::default();
    for _ in 0..400_000 {
        let w = sample_uniform_sphere(rng.vec2());
        let i = r.sample_li(&LightSampleContext::at(w), RGB).map_or(0.0, |ls| lum(ls.radiance));
        s.add(i * 4.0 * PI);
    }
    assert_mc("spot light power 800 lm vs MC of falloff", &s, 800.0);
    assert!(rel(r.phi() as f64 * light.spectrum.luminous_efficacy(), 800.0) < 1e-4);
}

#[test]
fn distant_light_irradiance_is_e_cos() {
    let dir = Vec3::new(-0.3, -1.0, 0.4).normalize();
    let light = DistantLight { amount: Amount::Lux(10_000.0), ..Default::default() }
        .resolve(&Transform::IDENTITY.looking_to(dir, Vec3::Y), SceneSphere::default())
        .unwrap();
    let mut worst: f64 = 0.0;
    for ctx in receivers(Vec3::ZERO, &mut SplitMix64::new(3), 1000) {
        let s = light.sample_li(&ctx, Vec2::ZERO, RGB).unwrap();
        let e = lum(s.radiance) * ctx.n.dot(s.wi).max(0.0) as f64;
        let want = 10_000.0 * ctx.n.as_dvec3().dot(-dir.as_dvec3()).max(0.0);
        worst = worst.max((e - want).abs() / 10_000.0);
        assert_eq!((s.pdf, light.pdf_li(s.wi)), (1.0, 0.0));
    }
    eprintln!("distant E cos: max error {worst:.2e} of E");
    assert!(worst < 1e-5);
}

#[test]
fn sun_sized_disc_integrates_to_e_cos() {
    let dir = Vec3::new(0.3, -1.0, -0.2).normalize();
    let light =
        DistantLight { amount: Amount::Lux(100_000.0), angular_diameter: SUN_ANGULAR_DIAMETER, ..Default::default() }
            .resolve(&Transform::IDENTITY.looking_to(dir, Vec3::Y), SceneSphere::default())
            .unwrap();
    let mut rng = SplitMix64::new(4);
    for tilt in [0.0f32, 0.7, 1.5] {
        let n = Quat::from_axis_angle(dir.any_orthonormal_vector(), tilt) * -dir;
        let ctx = LightSampleContext::on_surface(Vec3::new(0.1, 0.0, 0.2), n);
        let mut s = Stats::default();
        let mut worst_pdf: f64 = 0.0;
        for _ in 0..200_000 {
            let ls = light.sample_li(&ctx, rng.vec2(), RGB).unwrap();
            worst_pdf = worst_pdf.max(rel(light.pdf_li(ls.wi) as f64, ls.pdf as f64));
            s.add(lum(ls.radiance) * ctx.n.dot(ls.wi).max(0.0) as f64 / ls.pdf as f64);
        }
        let want = 100_000.0 * (tilt as f64).cos();
        assert_mc(&format!("sun disc E cos, tilt {tilt} rad"), &s, want);
        eprintln!("sun disc tilt {tilt}: max pdf vs pdf_li rel diff {worst_pdf:.2e}");
        assert!(worst_pdf < 1e-4);
    }
}
