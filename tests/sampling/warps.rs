//! Warps: pdf == 1 / |Jacobian| at grid points, pdfs integrate to 1, inverses round-trip.

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use kelvin::rng::SplitMix64;
use kelvin::sampling::*;

use crate::common::*;

type Dir = Box<dyn Fn(Vec2) -> Vec3>;
type DirPdf = Box<dyn Fn(Vec3) -> f32>;
type Skip = fn(Vec2) -> bool;
type Disk = fn(Vec2) -> Vec2;
type SpherePdf = Box<dyn Fn(Vec3) -> f64>;

fn near_diagonals(u: Vec2) -> bool {
    let m = 3.0 * H;
    (u.x - u.y).abs() < m || (u.x + u.y - 1.0).abs() < m
}

fn near_octahedron_seams(u: Vec2) -> bool {
    let m = 3.0 * H;
    let (a, b) = ((2.0 * u.x - 1.0).abs(), (2.0 * u.y - 1.0).abs());
    (u.x - 0.5).abs() < m || (u.y - 0.5).abs() < m || (a + b - 1.0).abs() < 3.0 * m
}

fn never(_: Vec2) -> bool {
    false
}

/// (name, sample, pdf, kinks to stay away from, true if the Jacobian is taken over (x, y) / z).
fn direction_warps() -> Vec<(&'static str, Dir, DirPdf, Skip, bool)> {
    vec![
        ("uniform sphere", Box::new(sample_uniform_sphere), Box::new(|_| uniform_sphere_pdf()), never, false),
        (
            "uniform hemisphere",
            Box::new(sample_uniform_hemisphere),
            Box::new(|_| uniform_hemisphere_pdf()),
            never,
            false,
        ),
        (
            "cosine hemisphere",
            Box::new(sample_cosine_hemisphere),
            Box::new(|w| cosine_hemisphere_pdf(w.z)),
            near_diagonals,
            false,
        ),
        ("cone cos 0.3", Box::new(|u| sample_uniform_cone(u, 0.3)), Box::new(|_| uniform_cone_pdf(0.3)), never, false),
        (
            "cone sin2 0.2",
            Box::new(|u| sample_uniform_cone_sin2(u, 0.2)),
            Box::new(|_| uniform_cone_pdf_sin2(0.2)),
            never,
            false,
        ),
        (
            "tiny cone sin2 1e-9 (cos rounds to 1 in f32)",
            Box::new(|u| sample_uniform_cone_sin2(u, 1e-9)),
            Box::new(|_| uniform_cone_pdf_sin2(1e-9)),
            never,
            true,
        ),
        (
            "equal-area octahedral",
            Box::new(equal_area_square_to_sphere),
            Box::new(|_| uniform_sphere_pdf()),
            near_octahedron_seams,
            false,
        ),
    ]
}

#[test]
fn direction_warps_pdf_equals_inverse_jacobian_within_1e4() {
    for (name, sample, pdf, skip, planar) in direction_warps() {
        let mut worst = 0.0f64;
        for u in u_grid(24, 0.03, 0.97).into_iter().filter(|&u| !skip(u)) {
            let w = sample(u);
            let measured = if planar {
                // Near the pole dw = dx dy / z, and x, y keep their digits for tiny cones.
                let f = |u: Vec2| {
                    let w = sample(u);
                    [w.x as f64, w.y as f64]
                };
                w.z as f64 / jacobian_2d(&f, u)
            } else {
                let f = |u: Vec2| sample(u).as_dvec3().to_array();
                1.0 / jacobian_sphere(&f, u)
            };
            let err = rel(pdf(w) as f64, measured);
            assert!(err < 1e-4, "{name}: at u = {u} pdf {} but 1/|J| = {measured}", pdf(w));
            worst = worst.max(err);
        }
        println!("{name}: max relative pdf error {worst:.1e}");
    }
}

#[test]
fn planar_warps_pdf_equals_inverse_jacobian_within_1e4() {
    let disks: [(&str, Disk, Skip); 2] = [
        ("concentric disk", sample_uniform_disk_concentric, near_diagonals),
        ("polar disk", sample_uniform_disk_polar, never),
    ];
    for (name, sample, skip) in disks {
        for u in u_grid(24, 0.03, 0.97).into_iter().filter(|&u| !skip(u)) {
            let j = jacobian_2d(&|u: Vec2| sample(u).as_dvec2().to_array(), u);
            assert!(rel(uniform_disk_pdf() as f64, 1.0 / j) < 1e-4, "{name} at {u}: 1/|J| = {}", 1.0 / j);
        }
    }
    // Triangle: barycentric area is half the unit square's, so |J| = 1/2 and pdf = 1 / area.
    let (v0, v1, v2) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(3.0, 0.5, 0.0), Vec3::new(1.0, 2.0, 1.0));
    let area = 0.5 * (v1 - v0).cross(v2 - v0).length() as f64;
    for u in u_grid(24, 0.03, 0.97).into_iter().filter(|u| (u.x - u.y).abs() > 3.0 * H) {
        let f = |u: Vec2| {
            let b = sample_uniform_triangle(u);
            [b[1] as f64, b[2] as f64]
        };
        let pdf = 1.0 / (2.0 * area * jacobian_2d(&f, u));
        assert!(rel(uniform_triangle_pdf(area as f32) as f64, pdf) < 1e-4, "triangle at {u}: {pdf}");
    }
    // Linear and bilinear, including a zero end and a zero corner.
    for (a, b) in [(1.0, 3.0), (0.0, 2.0), (5.0, 0.5)] {
        for i in 0..40 {
            let u = (i as f32 * 24.0 + 40.0) / 1024.0;
            let f = |u: Vec2| [sample_linear(u.x, a, b) as f64, u.y as f64];
            let x = sample_linear(u, a, b);
            let pdf = 1.0 / jacobian_2d(&f, Vec2::new(u, 0.5));
            assert!(rel(linear_pdf(x, a, b) as f64, pdf) < 1e-4, "linear({a}, {b}) at u = {u}: {pdf}");
        }
    }
    for w in [[1.0, 2.0, 3.0, 4.0], [0.0, 1.0, 0.5, 2.0], [0.2, 0.2, 0.2, 0.2]] {
        for u in u_grid(16, 0.05, 0.95) {
            let f = |u: Vec2| sample_bilinear(u, w).as_dvec2().to_array();
            let pdf = 1.0 / jacobian_2d(&f, u);
            let p = sample_bilinear(u, w);
            assert!(rel(bilinear_pdf(p, w) as f64, pdf) < 1e-4, "bilinear {w:?} at {u}: {pdf}");
        }
    }
}

#[test]
fn pdfs_integrate_to_one_monte_carlo_within_3_sigma() {
    let mut rng = SplitMix64::new(11);
    let n = 400_000;
    let four_pi = 4.0 * PI;
    // Directions: integrate each pdf over the sphere with uniform-sphere samples.
    let sphere_pdfs: [(&str, SpherePdf); 5] = [
        ("uniform sphere", Box::new(|_| uniform_sphere_pdf() as f64)),
        ("uniform hemisphere", Box::new(|w| if w.z >= 0.0 { uniform_hemisphere_pdf() as f64 } else { 0.0 })),
        ("cosine hemisphere", Box::new(|w| cosine_hemisphere_pdf(w.z) as f64)),
        ("cone cos 0.5", Box::new(|w| if w.z >= 0.5 { uniform_cone_pdf(0.5) as f64 } else { 0.0 })),
        ("cone sin2 0.75", Box::new(|w| if w.z >= 0.5 { uniform_cone_pdf_sin2(0.75) as f64 } else { 0.0 })),
    ];
    for (name, pdf) in sphere_pdfs {
        let (m, e) = mean_and_error(n, || pdf(sample_uniform_sphere(rng.vec2())) * four_pi);
        assert!((m - 1.0).abs() < 3.0 * e + 1e-6, "{name}: integral {m} +- {e}");
    }
    let (m, e) = mean_and_error(n, || {
        let p = 2.0 * rng.vec2() - Vec2::ONE;
        if p.length_squared() <= 1.0 { uniform_disk_pdf() as f64 * 4.0 } else { 0.0 }
    });
    assert!((m - 1.0).abs() < 3.0 * e, "disk: {m} +- {e}");
    for (a, b) in [(1.0, 3.0), (0.0, 2.0)] {
        let (m, e) = mean_and_error(n, || linear_pdf(rng.f32(), a, b) as f64);
        assert!((m - 1.0).abs() < 3.0 * e, "linear({a}, {b}): {m} +- {e}");
    }
    let w = [0.0, 1.0, 0.5, 2.0];
    let (m, e) = mean_and_error(n, || bilinear_pdf(rng.vec2(), w) as f64);
    assert!((m - 1.0).abs() < 3.0 * e, "bilinear: {m} +- {e}");
}

#[test]
fn inverses_round_trip() {
    let close =
        |a: Vec2, b: Vec2, tol: f32, what: &str| assert!((a - b).abs().max_element() < tol, "{what}: {a} -> {b}");
    for u in u_grid(40, 0.001, 0.999) {
        close(u, invert_uniform_disk_concentric(sample_uniform_disk_concentric(u)), 2e-5, "concentric");
        close(u, invert_uniform_disk_polar(sample_uniform_disk_polar(u)), 2e-5, "polar");
        close(u, invert_uniform_triangle_sample(sample_uniform_triangle(u)), 2e-6, "triangle");
        close(u, invert_uniform_sphere_sample(sample_uniform_sphere(u)), 2e-5, "sphere");
        close(u, invert_uniform_hemisphere_sample(sample_uniform_hemisphere(u)), 2e-5, "hemisphere");
        close(u, invert_cosine_hemisphere_sample(sample_cosine_hemisphere(u)), 2e-5, "cosine");
        close(u, invert_uniform_cone_sample(sample_uniform_cone(u, 0.3), 0.3), 2e-5, "cone");
        close(u, invert_uniform_cone_sample_sin2(sample_uniform_cone_sin2(u, 1e-9), 1e-9), 1e-4, "tiny cone");
        close(u, equal_area_sphere_to_square(equal_area_square_to_sphere(u)), 2e-5, "equal-area");
        let w = [0.0, 1.0, 0.5, 2.0];
        close(u, invert_bilinear_sample(sample_bilinear(u, w), w), 2e-5, "bilinear");
        let x = sample_linear(u.x, 0.0, 2.0);
        assert!((invert_linear_sample(x, 0.0, 2.0) - u.x).abs() < 2e-5, "linear at {u}");
    }
}

#[test]
fn equal_area_sphere_to_square_round_trips_near_poles_and_equator() {
    let mut rng = SplitMix64::new(5);
    let mut dirs: Vec<Vec3> = (0..20_000).map(|_| sample_uniform_sphere(rng.vec2())).collect();
    dirs.extend([
        Vec3::new(1e-4, 2e-4, 1.0).normalize(),
        Vec3::new(-3e-5, 1e-5, -1.0).normalize(),
        Vec3::new(0.6, -0.8, 1e-6).normalize(),
        Vec3::new(-0.6, 0.8, -1e-6).normalize(),
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::X,
        Vec3::NEG_Y,
    ]);
    let mut worst = 0.0f32;
    for d in dirs {
        let back = equal_area_square_to_sphere(equal_area_sphere_to_square(d));
        let err = (back - d).length();
        assert!(err < 2e-6, "{d} -> {back}");
        worst = worst.max(err);
    }
    println!("equal-area sphere -> square -> sphere: max error {worst:.1e}");
}

#[test]
fn spherical_coordinates_round_trip() {
    let mut rng = SplitMix64::new(9);
    for _ in 0..10_000 {
        let w = sample_uniform_sphere(rng.vec2());
        let (theta, phi) = (spherical_theta(w), spherical_phi(w));
        assert!((0.0..std::f32::consts::TAU).contains(&phi));
        let back = spherical_direction(theta.sin(), theta.cos(), phi);
        assert!((back - w).length() < 1e-5, "{w} -> {back}");
    }
}
