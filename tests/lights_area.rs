//! Area lights (pbrt-v4 `DiffuseAreaLight`) on spheres, disks, rectangles and triangles:
//! (a) closed-form power vs a Monte Carlo integral of the emitted radiance,
//! (b) every sample's pdf equals `pdf_li` of its direction,
//! (c) `pdf_li` integrates to 1 over directions,
//! (d) sampled irradiance vs closed forms (disk on axis, sphere, Lambert's polygon formula),
//! plus the hard cases named in the test names. Relative errors are printed with `--nocapture`.

use std::f64::consts::PI;
use std::sync::Arc;

use glam::{DVec3, Quat, Vec2, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::area::{SamplingStrategy, ShapeSample};
use kelvin::light::{
    Amount, AreaLight, AreaShape, ColorQuery, LightError, LightSampleContext, LightTexture, ResolvedArea,
};
use kelvin::sampling::{Frame, sample_uniform_cone_sin2, sample_uniform_sphere, uniform_cone_pdf_sin2};
use kelvin::spectrum::{SampledSpectrum, SampledWavelengths};

/// SplitMix64 (Steele, Lea, Flood 2014).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Self(seed)
    }
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn u2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }
}

/// Running mean and standard error.
#[derive(Default)]
struct Stats {
    n: f64,
    sum: f64,
    sum2: f64,
}

impl Stats {
    fn add(&mut self, x: f64) {
        self.n += 1.0;
        self.sum += x;
        self.sum2 += x * x;
    }
    fn mean(&self) -> f64 {
        self.sum / self.n
    }
    fn sigma(&self) -> f64 {
        let m = self.mean();
        ((self.sum2 / self.n - m * m).max(0.0) / self.n).sqrt()
    }
}

const RGB: ColorQuery<'static> = ColorQuery::Rgb;

/// Rec. 709 luminance of an RGB-mode result.
fn lum(s: SampledSpectrum) -> f64 {
    0.2126 * s.0[0] as f64 + 0.7152 * s.0[1] as f64 + 0.0722 * s.0[2] as f64
}

/// Photometric radiance (nit) of an untextured light.
fn nits(light: &ResolvedArea) -> f64 {
    lum(light.radiance.eval(RGB))
}

/// Asserts |measured - expected| <= 3 sigma (+ a 1e-5 relative floor for f32 rounding when the
/// estimator has next to no variance) and prints the relative error.
fn assert_mc(name: &str, s: &Stats, expected: f64) {
    let (m, sigma) = (s.mean(), s.sigma());
    let rel = (m - expected).abs() / expected.abs().max(1e-30);
    eprintln!(
        "{name}: measured {m:.6e}, expected {expected:.6e}, rel err {rel:.2e}, 3 sigma rel {:.2e}",
        3.0 * sigma / expected.abs().max(1e-30)
    );
    assert!((m - expected).abs() <= 3.0 * sigma + 1e-5 * expected.abs(), "{name}: {m} vs {expected} (sigma {sigma})");
}

fn light() -> AreaLight {
    AreaLight { amount: Amount::WattsPerM2Sr(2.5), ..Default::default() }
}

fn two_sided() -> AreaLight {
    AreaLight { two_sided: true, ..light() }
}

fn tilted(translation: Vec3) -> Transform {
    Transform { translation, rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.2), scale: Vec3::ONE }
}

fn sphere(l: &AreaLight) -> ResolvedArea {
    l.resolve_sphere(0.7, &Transform::from_translation(Vec3::new(0.3, -0.2, 0.5))).unwrap()
}
fn disk(l: &AreaLight) -> ResolvedArea {
    l.resolve_disk(0.5, &tilted(Vec3::new(0.1, 1.0, -0.3))).unwrap()
}
fn rectangle(l: &AreaLight) -> ResolvedArea {
    l.resolve_rectangle(1.5, 0.8, &tilted(Vec3::new(-0.2, 0.4, 0.1))).unwrap()
}
fn triangle(l: &AreaLight, p: [Vec3; 3]) -> ResolvedArea {
    let mesh = l.resolve_mesh(&p, &[], &[0, 1, 2], &Transform::IDENTITY).unwrap();
    mesh.triangles.into_iter().next().expect("non-degenerate")
}
fn moderate_triangle(l: &AreaLight) -> ResolvedArea {
    triangle(l, [Vec3::new(-0.5, 0.2, 0.1), Vec3::new(0.9, -0.1, 0.3), Vec3::new(0.1, 0.8, -0.4)])
}

fn all_shapes() -> Vec<(&'static str, ResolvedArea)> {
    let mut v = Vec::new();
    for l in [light(), two_sided()] {
        v.push((if l.two_sided { "sphere two-sided" } else { "sphere one-sided" }, sphere(&l)));
        v.push((if l.two_sided { "disk two-sided" } else { "disk one-sided" }, disk(&l)));
        v.push((if l.two_sided { "rectangle two-sided" } else { "rectangle one-sided" }, rectangle(&l)));
        v.push((if l.two_sided { "triangle two-sided" } else { "triangle one-sided" }, moderate_triangle(&l)));
    }
    v
}

// -------------------------------------------------------------------------------------------
// (a) power

/// Monte Carlo power, W: points uniform on the surface, directions uniform on the sphere (drawn in
/// the local normal frame), both jittered-stratified on a 1000 x 1000 grid (the direction strata
/// randomly permuted).
fn mc_power(light: &ResolvedArea, rng: &mut Rng) -> Stats {
    const K: usize = 1000;
    let mut perm: Vec<u32> = (0..(K * K) as u32).collect();
    for i in (1..perm.len()).rev() {
        perm.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let strat = |c: usize, j: Vec2| Vec2::new(((c % K) as f32 + j.x) / K as f32, ((c / K) as f32 + j.y) / K as f32);
    let l_rad = light.radiance.radiometric as f64 / nits(light);
    let scale = light.area as f64 * 4.0 * PI;
    let mut s = Stats::default();
    for (i, &pi) in perm.iter().enumerate() {
        let on = light.shape.sample_area(strat(i, rng.u2()).min(Vec2::splat(0.999_999_9))).unwrap();
        // Uniform directions drawn in the normal's frame, so the strata follow cos(theta).
        let w = Frame::from_z(on.n)
            .from_local(sample_uniform_sphere(strat(pi as usize, rng.u2()).min(Vec2::splat(0.999_999_9))));
        let l = lum(light.radiance(on.p, on.n, on.uv, w, RGB)) * l_rad;
        s.add(l * on.n.dot(w).abs() as f64 * scale);
    }
    s
}

fn check_power(name: &str, light: &ResolvedArea, seed: u64) {
    let s = mc_power(light, &mut Rng::new(seed));
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

/// Reference points around a light (in a box 3x its size around its centre).
fn points_around(light: &ResolvedArea, rng: &mut Rng, n: usize) -> Vec<Vec3> {
    let (min, max) = light.shape.bounds();
    let (c, half) = ((min + max) * 0.5, ((max - min) * 0.5).max_element() * 3.0 + 0.1);
    (0..n).map(|_| c + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0) * half).collect()
}

/// Max relative difference between sample pdfs and `pdf_li` (of both `shape.sample`, which
/// includes directions toward a light's back, and `sample_li`).
fn max_pdf_mismatch(light: &ResolvedArea, points: &[Vec3], per_point: usize, rng: &mut Rng) -> (f64, usize) {
    let (mut worst, mut count) = (0.0f64, 0);
    for &p in points {
        let ctx = LightSampleContext::at(p);
        for _ in 0..per_point {
            let u = rng.u2();
            let mut check = |pdf: f32, wi: Vec3| {
                let other = light.pdf_li(&ctx, wi);
                assert!(pdf.is_finite() && pdf > 0.0 && other.is_finite(), "pdf {pdf} / pdf_li {other} at {p}");
                worst = worst.max(((pdf - other) as f64).abs() / pdf as f64);
                count += 1;
            };
            if let Some(s) = light.shape.sample(p, u) {
                check(s.pdf, s.wi);
            }
            if let Some(s) = light.sample_li(&ctx, u, RGB) {
                assert!(s.radiance.is_finite() && s.p_light.is_finite() && s.wi.is_normalized());
                check(s.pdf, s.wi);
            }
        }
    }
    (worst, count)
}

#[test]
fn sample_pdf_equals_pdf_li_for_every_shape() {
    let mut rng = Rng::new(2);
    for (name, l) in all_shapes() {
        let points = points_around(&l, &mut rng, 200);
        let (worst, n) = max_pdf_mismatch(&l, &points, 200, &mut rng);
        eprintln!("(b) pdf consistency {name}: max rel diff {worst:.2e} over {n} samples");
        assert!(worst < 1e-4, "{name}: {worst}");
    }
}

#[test]
fn sample_pdf_equals_pdf_li_across_strategy_bands() {
    let mut rng = Rng::new(3);
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
fn pdf_integral(light: &ResolvedArea, p: Vec3, cone: Option<(Vec3, f32)>, n: usize, rng: &mut Rng) -> Stats {
    let ctx = LightSampleContext::at(p);
    let mut s = Stats::default();
    for _ in 0..n {
        let (w, density) = match cone {
            None => (sample_uniform_sphere(rng.u2()), 1.0 / (4.0 * PI)),
            Some((axis, sin2)) => {
                let w = Frame::from_z(axis).from_local(sample_uniform_cone_sin2(rng.u2(), sin2));
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
    let mut rng = Rng::new(4);
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
    let mut rng = Rng::new(5);
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

/// Mean of L cos / pdf over `sample_li` samples (cos clamped to the receiving hemisphere).
fn irradiance(light: &ResolvedArea, ctx: &LightSampleContext, n: usize, rng: &mut Rng) -> Stats {
    let mut s = Stats::default();
    for _ in 0..n {
        let x = match light.sample_li(ctx, rng.u2(), RGB) {
            Some(ls) => {
                assert!(ls.pdf.is_finite() && ls.pdf > 0.0 && ls.radiance.is_finite());
                lum(ls.radiance) * ctx.n.dot(ls.wi).max(0.0) as f64 / ls.pdf as f64
            }
            None => 0.0,
        };
        s.add(x);
    }
    s
}

/// Lambert's formula for a uniform polygon wholly above the receiver's horizon:
/// E = L/2 sum_i beta_i n . (r_i x r_{i+1}) / |r_i x r_{i+1}|, r_i unit vectors to the vertices.
fn lambert(p: Vec3, n: Vec3, verts: &[Vec3], l: f64) -> f64 {
    let (p, n) = (p.as_dvec3(), n.as_dvec3());
    let r: Vec<DVec3> = verts.iter().map(|v| (v.as_dvec3() - p).normalize()).collect();
    for v in &r {
        assert!(n.dot(*v) >= 0.0, "polygon crosses the horizon");
    }
    let mut sum = 0.0;
    for i in 0..r.len() {
        let (a, b) = (r[i], r[(i + 1) % r.len()]);
        let c = a.cross(b);
        sum += c.length().atan2(a.dot(b)) * n.dot(c.normalize());
    }
    0.5 * l * sum.abs()
}

fn corners(shape: &AreaShape) -> Vec<Vec3> {
    match *shape {
        AreaShape::Rectangle { corner, ex, ey } => vec![corner, corner + ex, corner + ex + ey, corner + ey],
        AreaShape::Triangle { p, .. } => p.to_vec(),
        _ => unreachable!(),
    }
}

/// A 2 x 2 square at z = 0 facing +z, and a point at height h over its centre facing down.
fn unit_rectangle_above(l: &AreaLight, h: f32) -> (ResolvedArea, LightSampleContext) {
    let r = l.resolve_rectangle(2.0, 2.0, &Transform::IDENTITY).unwrap();
    (r, LightSampleContext::on_surface(Vec3::new(0.1, -0.05, h), Vec3::NEG_Z))
}

/// A 1 cm square 1 m away (1e-4 sr), facing the receiver.
fn far_tiny_rectangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let t = Transform::from_translation(Vec3::new(0.0, 0.0, 1.0)).looking_to(Vec3::Z, Vec3::Y);
    let r = l.resolve_rectangle(0.01, 0.01, &t).unwrap();
    (r, LightSampleContext::on_surface(Vec3::new(0.02, 0.01, 0.0), Vec3::new(0.1, 0.0, 1.0).normalize()))
}

/// A triangle of 1e-8 sr seen from the origin.
fn tiny_triangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let s = 1.4142e-4;
    let t = triangle(l, [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, s, 1.0), Vec3::new(s, 0.0, 1.0)]);
    (t, LightSampleContext::on_surface(Vec3::ZERO, Vec3::new(0.3, 0.0, 1.0).normalize()))
}

/// An equilateral triangle (inradius 1) 1 cm below a receiver facing it: about 6.23 sr.
fn near_hemisphere_triangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let v = |a: f32| Vec3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0);
    let t = triangle(l, [v(0.0), v(2.0 * std::f32::consts::FRAC_PI_3), v(4.0 * std::f32::consts::FRAC_PI_3)]);
    (t, LightSampleContext::on_surface(Vec3::new(0.0, 0.0, 0.01), Vec3::NEG_Z))
}

/// A unit sphere at the origin and a point on +z at distance `d` (rounded to f32) facing it.
fn sphere_at_origin(l: &AreaLight, d: f64) -> (ResolvedArea, LightSampleContext) {
    let s = l.resolve_sphere(1.0, &Transform::IDENTITY).unwrap();
    let z = if d > 1.0 { (d as f32).max(1.0f32.next_up()) } else { d as f32 };
    (s, LightSampleContext::on_surface(Vec3::new(0.0, 0.0, z), Vec3::NEG_Z))
}

/// A 1 mm sphere 10 m away: sin^2(theta_max) = 1e-8, far below pbrt's Taylor threshold.
fn tiny_sphere(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let s = l.resolve_sphere(1e-3, &Transform::from_translation(Vec3::new(1.0, 2.0, 3.0))).unwrap();
    let p = Vec3::new(1.0, 2.0, 3.0) + Vec3::new(6.0, 0.0, 8.0);
    (s, LightSampleContext::on_surface(p, Vec3::new(-0.6, 0.3, -0.8).normalize()))
}

/// E = pi L (r/d)^2 cos(theta) for a sphere wholly above the horizon.
fn sphere_irradiance(s: &ResolvedArea, ctx: &LightSampleContext) -> f64 {
    let AreaShape::Sphere { center, radius } = s.shape else { unreachable!() };
    let to_c = center.as_dvec3() - ctx.p.as_dvec3();
    let (d, r) = (to_c.length(), radius as f64);
    let cos = ctx.n.as_dvec3().dot(to_c / d);
    assert!(cos.acos() + (r / d).asin() <= PI / 2.0 + 1e-9, "sphere crosses the horizon");
    PI * nits(s) * (r / d).powi(2) * cos
}

#[test]
fn irradiance_of_disk_on_axis() {
    let mut rng = Rng::new(6);
    for l in [light(), two_sided()] {
        let d = disk(&l);
        let AreaShape::Disk { center, normal, radius } = d.shape else { unreachable!() };
        for h in [0.05f32, 0.7, 4.0] {
            let ctx = LightSampleContext::on_surface(center + normal * h, -normal);
            let sin2 = (radius * radius / (radius * radius + h * h)) as f64;
            let name = format!("(d) irradiance disk on axis h = {h} two_sided = {}", l.two_sided);
            assert_mc(&name, &irradiance(&d, &ctx, 500_000, &mut rng), PI * nits(&d) * sin2);
        }
        // Behind a one-sided disk: nothing.
        let ctx = LightSampleContext::on_surface(center - normal * 0.5, normal);
        let e = irradiance(&d, &ctx, 10_000, &mut rng).mean();
        if l.two_sided { assert!(e > 0.0) } else { assert_eq!(e, 0.0) }
    }
}

#[test]
fn irradiance_of_sphere_from_outside() {
    let mut rng = Rng::new(7);
    let s = sphere(&light());
    let AreaShape::Sphere { center, .. } = s.shape else { unreachable!() };
    for (k, (offset, tilt)) in
        [(Vec3::new(2.0, 0.5, -1.0), 0.3f32), (Vec3::new(0.0, -0.9, 0.2), 0.1), (Vec3::new(-5.0, 3.0, 1.0), 1.2)]
            .into_iter()
            .enumerate()
    {
        let p = center + offset;
        let n = Quat::from_axis_angle(offset.normalize().any_orthonormal_vector(), tilt) * (-offset.normalize());
        let ctx = LightSampleContext::on_surface(p, n);
        let name = format!("(d) irradiance sphere point {k} ({:?})", s.strategy(p));
        assert_mc(&name, &irradiance(&s, &ctx, 500_000, &mut rng), sphere_irradiance(&s, &ctx));
    }
}

#[test]
fn irradiance_of_tiny_sphere_below_taylor_threshold() {
    let (s, ctx) = tiny_sphere(&light());
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Cone);
    assert_mc(
        "(d) irradiance tiny sphere sin^2 = 1e-8",
        &irradiance(&s, &ctx, 200_000, &mut Rng::new(8)),
        sphere_irradiance(&s, &ctx),
    );
    // Near pbrt's Taylor threshold sin^2 = 6.85e-4.
    let s = light().resolve_sphere(0.0262, &Transform::IDENTITY).unwrap();
    let ctx = LightSampleContext::on_surface(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y);
    assert_mc(
        "(d) irradiance sphere sin^2 = 6.86e-4",
        &irradiance(&s, &ctx, 200_000, &mut Rng::new(9)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_of_sphere_at_1e_3_r_outside() {
    let (s, ctx) = sphere_at_origin(&light(), 1.0 + 1e-3);
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Cone);
    assert_mc(
        "(d) irradiance sphere d = r (1 + 1e-3)",
        &irradiance(&s, &ctx, 1_000_000, &mut Rng::new(10)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_of_sphere_at_1e_7_r_outside() {
    let (s, ctx) = sphere_at_origin(&light(), 1.0 + 1e-7);
    assert_eq!(s.strategy(ctx.p), SamplingStrategy::Area);
    assert_mc(
        "(d) irradiance sphere d = r (1 + 1.2e-7)",
        &irradiance(&s, &ctx, 1_000_000, &mut Rng::new(11)),
        sphere_irradiance(&s, &ctx),
    );
}

#[test]
fn irradiance_at_shading_point_on_sphere_surface() {
    let mut rng = Rng::new(12);
    for l in [light(), two_sided()] {
        let (s, _) = sphere_at_origin(&l, 1.0);
        let p = Vec3::new(0.0, 0.0, 1.0); // exactly on the surface
        let inward = LightSampleContext::on_surface(p, -p.normalize());
        let outward = LightSampleContext::on_surface(p, p.normalize());
        // Facing in, a two-sided sphere fills the hemisphere (E = pi L); a one-sided one shows
        // only its unlit inside. Facing out, the sphere is below the horizon.
        let want_in = if l.two_sided { PI * nits(&s) } else { 0.0 };
        assert_mc(
            &format!("(d) irradiance on sphere surface, facing in, two_sided = {}", l.two_sided),
            &irradiance(&s, &inward, 500_000, &mut rng),
            want_in,
        );
        let e_out = irradiance(&s, &outward, 100_000, &mut rng).mean();
        assert!(e_out.abs() <= 1e-3 * nits(&s), "facing out: {e_out}");
    }
}

#[test]
fn irradiance_inside_sphere() {
    let mut rng = Rng::new(13);
    for l in [light(), two_sided()] {
        let (s, _) = sphere_at_origin(&l, 1.0);
        let ctx = LightSampleContext::on_surface(Vec3::new(0.3, -0.4, 0.2), Vec3::new(1.0, 2.0, -0.5).normalize());
        assert_eq!(s.strategy(ctx.p), SamplingStrategy::Area);
        let want = if l.two_sided { PI * nits(&s) } else { 0.0 };
        assert_mc(
            &format!("(d) irradiance inside sphere, two_sided = {}", l.two_sided),
            &irradiance(&s, &ctx, 500_000, &mut rng),
            want,
        );
    }
}

#[test]
fn irradiance_of_rectangle_in_both_strategy_bands() {
    let mut rng = Rng::new(14);
    let l = light();
    let (r, ctx) = far_tiny_rectangle(&l);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle far tiny 1e-4 sr (Area)", &irradiance(&r, &ctx, 200_000, &mut rng), want);

    let (r, ctx) = unit_rectangle_above(&l, 1.0);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::SphericalRectangle);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle moderate (Spherical)", &irradiance(&r, &ctx, 500_000, &mut rng), want);

    let (r, ctx) = unit_rectangle_above(&l, 0.01);
    assert_eq!(r.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc("(d) irradiance rectangle near huge 6.23 sr (Area)", &irradiance(&r, &ctx, 2_000_000, &mut rng), want);

    // A tilted rectangle and a tilted receiver, two-sided, seen from behind.
    let r = rectangle(&two_sided());
    let n = r.shape.plane_normal().unwrap();
    let AreaShape::Rectangle { corner, ex, ey } = r.shape else { unreachable!() };
    let p = corner + 0.3 * ex + 0.6 * ey - 0.8 * n;
    let ctx = LightSampleContext::on_surface(p, Quat::from_axis_angle(ex.normalize(), 0.2) * n);
    let want = lambert(ctx.p, ctx.n, &corners(&r.shape), nits(&r));
    assert_mc(
        &format!("(d) irradiance tilted rectangle from behind two-sided ({:?})", r.strategy(p)),
        &irradiance(&r, &ctx, 500_000, &mut rng),
        want,
    );
}

#[test]
fn irradiance_of_triangles_1e_8_sr_moderate_and_nearly_2_pi_sr() {
    let mut rng = Rng::new(15);
    let l = light();
    let (t, ctx) = tiny_triangle(&l);
    let omega = kelvin::sampling::triangle_solid_angle(corners(&t.shape).try_into().unwrap(), ctx.p);
    assert!((omega - 1e-8).abs() < 1e-11, "{omega}");
    assert_eq!(t.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle 1e-8 sr (Area)", &irradiance(&t, &ctx, 100_000, &mut rng), want);

    let t = moderate_triangle(&l);
    let n = t.shape.plane_normal().unwrap();
    let p = corners(&t.shape).iter().sum::<Vec3>() / 3.0 + 0.7 * n;
    let ctx = LightSampleContext::on_surface(p, Quat::from_axis_angle(n.any_orthonormal_vector(), 0.15) * -n);
    assert_eq!(t.strategy(p), SamplingStrategy::SphericalTriangle);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle moderate (Spherical)", &irradiance(&t, &ctx, 500_000, &mut rng), want);

    let (t, ctx) = near_hemisphere_triangle(&l);
    let omega = kelvin::sampling::triangle_solid_angle(corners(&t.shape).try_into().unwrap(), ctx.p);
    assert!(omega > 6.22 && omega < 2.0 * std::f32::consts::PI, "{omega}");
    assert_eq!(t.strategy(ctx.p), SamplingStrategy::Area);
    let want = lambert(ctx.p, ctx.n, &corners(&t.shape), nits(&t));
    assert_mc("(d) irradiance triangle nearly 2 pi sr (Area)", &irradiance(&t, &ctx, 2_000_000, &mut rng), want);
}

// -------------------------------------------------------------------------------------------
// Hard cases and bad input

#[test]
fn grazing_cos_1e_7_stays_finite_and_consistent() {
    let mut rng = Rng::new(16);
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
            assert!(light.pdf_li(&ctx, sample_uniform_sphere(rng.u2())).is_finite());
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
        let mut rng = Rng::new(17);
        for _ in 0..1000 {
            assert!(t.sample_li(&ctx, rng.u2(), RGB).is_none());
            assert_eq!(t.pdf_li(&ctx, sample_uniform_sphere(rng.u2())), 0.0);
        }
        assert!(t.phi() == 0.0 && t.bounds().min.is_finite() && t.bounds().max.is_finite());
    }
}

#[test]
fn sphere_hard_points_all_outputs_finite() {
    let mut rng = Rng::new(18);
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
            if let Some(ls) = s.sample_li(&ctx, rng.u2(), RGB) {
                assert!(
                    ls.pdf.is_finite()
                        && ls.pdf > 0.0
                        && ls.radiance.is_finite()
                        && ls.p_light.is_finite()
                        && ls.n_light.is_finite()
                );
            }
            assert!(s.pdf_li(&ctx, sample_uniform_sphere(rng.u2())).is_finite());
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
    let mut rng = Rng::new(19);
    for _ in 0..1000 {
        if let Some(ls) = r.sample_li(&ctx, rng.u2(), RGB) {
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
        let mut rng = Rng::new(20);
        for _ in 0..1000 {
            let p = r.shape.sample_area(rng.u2()).unwrap().p;
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
