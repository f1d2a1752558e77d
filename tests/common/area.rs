//! Area-light fixtures: lights, shapes and reference points, plus the closed forms and estimators
//! the area tests share.

use std::f64::consts::PI;

use glam::{DVec3, Quat, Vec3};
use kelvin::geometry::Transform;
use kelvin::light::{Amount, AreaLight, AreaShape, LightSampleContext, ResolvedArea};
use kelvin::rng::SplitMix64;

use super::{RGB, Stats, lum};

/// Photometric radiance (nit) of an untextured light.
pub fn nits(light: &ResolvedArea) -> f64 {
    lum(light.radiance.eval(RGB))
}

pub fn light() -> AreaLight {
    AreaLight { amount: Amount::WattsPerM2Sr(2.5), ..Default::default() }
}

pub fn two_sided() -> AreaLight {
    AreaLight { two_sided: true, ..light() }
}

pub fn tilted(translation: Vec3) -> Transform {
    Transform {
        translation,
        rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.2),
        scale: Vec3::ONE,
        shear: glam::Vec3::ZERO,
    }
}

pub fn sphere(l: &AreaLight) -> ResolvedArea {
    l.resolve_sphere(0.7, &Transform::from_translation(Vec3::new(0.3, -0.2, 0.5))).unwrap()
}
pub fn disk(l: &AreaLight) -> ResolvedArea {
    l.resolve_disk(0.5, &tilted(Vec3::new(0.1, 1.0, -0.3))).unwrap()
}
pub fn rectangle(l: &AreaLight) -> ResolvedArea {
    l.resolve_rectangle(1.5, 0.8, &tilted(Vec3::new(-0.2, 0.4, 0.1))).unwrap()
}
pub fn triangle(l: &AreaLight, p: [Vec3; 3]) -> ResolvedArea {
    let mesh = l.resolve_mesh(&p, &[], &[0, 1, 2], &Transform::IDENTITY).unwrap();
    mesh.triangles.into_iter().next().expect("non-degenerate")
}
pub fn moderate_triangle(l: &AreaLight) -> ResolvedArea {
    triangle(l, [Vec3::new(-0.5, 0.2, 0.1), Vec3::new(0.9, -0.1, 0.3), Vec3::new(0.1, 0.8, -0.4)])
}

pub fn all_shapes() -> Vec<(&'static str, ResolvedArea)> {
    let mut v = Vec::new();
    for l in [light(), two_sided()] {
        v.push((if l.two_sided { "sphere two-sided" } else { "sphere one-sided" }, sphere(&l)));
        v.push((if l.two_sided { "disk two-sided" } else { "disk one-sided" }, disk(&l)));
        v.push((if l.two_sided { "rectangle two-sided" } else { "rectangle one-sided" }, rectangle(&l)));
        v.push((if l.two_sided { "triangle two-sided" } else { "triangle one-sided" }, moderate_triangle(&l)));
    }
    v
}

/// Reference points around a light (in a box 3x its size around its centre).
pub fn points_around(light: &ResolvedArea, rng: &mut SplitMix64, n: usize) -> Vec<Vec3> {
    let (min, max) = light.shape.bounds();
    let (c, half) = ((min + max) * 0.5, ((max - min) * 0.5).max_element() * 3.0 + 0.1);
    (0..n).map(|_| c + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0) * half).collect()
}

/// Max relative difference between sample pdfs and `pdf_li` (of both `shape.sample`, which
/// includes directions toward a light's back, and `sample_li`).
pub fn max_pdf_mismatch(light: &ResolvedArea, points: &[Vec3], per_point: usize, rng: &mut SplitMix64) -> (f64, usize) {
    let (mut worst, mut count) = (0.0f64, 0);
    for &p in points {
        let ctx = LightSampleContext::at(p);
        for _ in 0..per_point {
            let u = rng.vec2();
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

/// Mean of L cos / pdf over `sample_li` samples (cos clamped to the receiving hemisphere).
pub fn irradiance(light: &ResolvedArea, ctx: &LightSampleContext, n: usize, rng: &mut SplitMix64) -> Stats {
    let mut s = Stats::default();
    for _ in 0..n {
        let x = match light.sample_li(ctx, rng.vec2(), RGB) {
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
pub fn lambert(p: Vec3, n: Vec3, verts: &[Vec3], l: f64) -> f64 {
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

pub fn corners(shape: &AreaShape) -> Vec<Vec3> {
    match *shape {
        AreaShape::Rectangle { corner, ex, ey } => vec![corner, corner + ex, corner + ex + ey, corner + ey],
        AreaShape::Triangle { p, .. } => p.to_vec(),
        _ => unreachable!(),
    }
}

/// A 2 x 2 square at z = 0 facing +z, and a point at height h over its centre facing down.
pub fn unit_rectangle_above(l: &AreaLight, h: f32) -> (ResolvedArea, LightSampleContext) {
    let r = l.resolve_rectangle(2.0, 2.0, &Transform::IDENTITY).unwrap();
    (r, LightSampleContext::on_surface(Vec3::new(0.1, -0.05, h), Vec3::NEG_Z))
}

/// A 1 cm square 1 m away (1e-4 sr), facing the receiver.
pub fn far_tiny_rectangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let t = Transform::from_translation(Vec3::new(0.0, 0.0, 1.0)).looking_to(Vec3::Z, Vec3::Y);
    let r = l.resolve_rectangle(0.01, 0.01, &t).unwrap();
    (r, LightSampleContext::on_surface(Vec3::new(0.02, 0.01, 0.0), Vec3::new(0.1, 0.0, 1.0).normalize()))
}

/// A triangle of 1e-8 sr seen from the origin.
pub fn tiny_triangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let s = 1.4142e-4;
    let t = triangle(l, [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, s, 1.0), Vec3::new(s, 0.0, 1.0)]);
    (t, LightSampleContext::on_surface(Vec3::ZERO, Vec3::new(0.3, 0.0, 1.0).normalize()))
}

/// An equilateral triangle (inradius 1) 1 cm below a receiver facing it: about 6.23 sr.
pub fn near_hemisphere_triangle(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let v = |a: f32| Vec3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0);
    let t = triangle(l, [v(0.0), v(2.0 * std::f32::consts::FRAC_PI_3), v(4.0 * std::f32::consts::FRAC_PI_3)]);
    (t, LightSampleContext::on_surface(Vec3::new(0.0, 0.0, 0.01), Vec3::NEG_Z))
}

/// A unit sphere at the origin and a point on +z at distance `d` (rounded to f32) facing it.
pub fn sphere_at_origin(l: &AreaLight, d: f64) -> (ResolvedArea, LightSampleContext) {
    let s = l.resolve_sphere(1.0, &Transform::IDENTITY).unwrap();
    let z = if d > 1.0 { (d as f32).max(1.0f32.next_up()) } else { d as f32 };
    (s, LightSampleContext::on_surface(Vec3::new(0.0, 0.0, z), Vec3::NEG_Z))
}

/// A 1 mm sphere 10 m away: sin^2(theta_max) = 1e-8, far below pbrt's Taylor threshold.
pub fn tiny_sphere(l: &AreaLight) -> (ResolvedArea, LightSampleContext) {
    let s = l.resolve_sphere(1e-3, &Transform::from_translation(Vec3::new(1.0, 2.0, 3.0))).unwrap();
    let p = Vec3::new(1.0, 2.0, 3.0) + Vec3::new(6.0, 0.0, 8.0);
    (s, LightSampleContext::on_surface(p, Vec3::new(-0.6, 0.3, -0.8).normalize()))
}

/// E = pi L (r/d)^2 cos(theta) for a sphere wholly above the horizon.
pub fn sphere_irradiance(s: &ResolvedArea, ctx: &LightSampleContext) -> f64 {
    let AreaShape::Sphere { center, radius } = s.shape else { unreachable!() };
    let to_c = center.as_dvec3() - ctx.p.as_dvec3();
    let (d, r) = (to_c.length(), radius as f64);
    let cos = ctx.n.as_dvec3().dot(to_c / d);
    assert!(cos.acos() + (r / d).asin() <= PI / 2.0 + 1e-9, "sphere crosses the horizon");
    PI * nits(s) * (r / d).powi(2) * cos
}

/// Triangles and reference points where f32 is hard, for the f32 kernel against its f64
/// reference: (kind, vertices, point). Kinds cycle through ordinary, tiny and far (down to
/// ~1e-8 sr), nearly in the plane (heights 1e-6 to 0.1 of the size), over the inside (close to
/// 2 pi sr), slivers (thickness 1e-5 to 1e-2) and ordinary ones 1 km from the origin.
pub fn hard_triangles(rng: &mut SplitMix64, n: usize) -> Vec<(&'static str, [Vec3; 3], Vec3)> {
    const KINDS: [&str; 6] = ["ordinary", "tiny far", "near plane", "near 2 pi", "sliver", "far from origin"];
    let mut rng2 = SplitMix64::new(rng.next_u64());
    let mut unit = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let kind = KINDS[i % KINDS.len()];
        let size = rng2.log_range(1e-3, 1e2);
        let origin = if kind == "far from origin" { Vec3::new(1e3, -700.0, 400.0) } else { Vec3::ZERO };
        let mut v = [unit(), unit(), unit()].map(|q| origin + q * size);
        if kind == "sliver" {
            let t = rng2.range(0.1, 0.9);
            let e = v[1] - v[0];
            let perp = e.cross(unit()).normalize() * e.length() * rng2.log_range(1e-5, 1e-2);
            v[2] = v[0] + e * t + perp;
        }
        let centroid = (v[0] + v[1] + v[2]) / 3.0;
        let cross = (v[1] - v[0]).cross(v[2] - v[0]);
        if !(cross.length() > 1e-5 * (v[1] - v[0]).length() * (v[2] - v[0]).length()) {
            continue;
        }
        let n = cross.normalize();
        let side = if rng2.f32() < 0.5 { 1.0 } else { -1.0 };
        let dir = unit().normalize();
        let p = match kind {
            "tiny far" => centroid + dir * size * rng2.log_range(10.0, 1e4),
            "near plane" => {
                let w = unit();
                let in_plane = (w - n * n.dot(w)) * size * 2.0;
                centroid + in_plane + n * side * size * rng2.log_range(1e-6, 0.1)
            }
            "near 2 pi" => {
                let (a, b) = (rng2.f32(), rng2.f32());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b + n * side * size * rng2.log_range(1e-5, 0.1)
            }
            _ => centroid + dir * size * rng2.log_range(0.2, 10.0),
        };
        out.push((kind, v, p));
    }
    out
}
