//! Spherical triangles and rectangles: pdf == 1 / |Jacobian|, chi-square uniformity over
//! sub-polygons, solid angles against closed forms and Monte Carlo, inverses; each for an ordinary,
//! a tiny (~1e-8 sr), a near-2-pi and a grazing configuration.

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};
use kelvin::rng::SplitMix64;
use kelvin::sampling::*;

use crate::common::*;

fn triangles() -> Vec<(&'static str, [Vec3; 3], Vec3)> {
    vec![
        ("ordinary", [Vec3::ZERO, Vec3::X, Vec3::new(0.3, 1.0, 0.0)], Vec3::new(0.4, 0.2, 0.8)),
        ("ordinary clockwise", [Vec3::ZERO, Vec3::new(0.3, 1.0, 0.0), Vec3::X], Vec3::new(0.4, 0.2, 0.8)),
        (
            "tiny ~1e-8 sr",
            [Vec3::ZERO, Vec3::new(1.4e-4, 0.0, 0.0), Vec3::new(0.3e-4, 1.4e-4, 0.0)],
            Vec3::new(0.5e-4, 0.3e-4, 1.0),
        ),
        (
            "near 2 pi sr",
            [Vec3::new(-1.0, -0.6, 0.0), Vec3::new(1.0, -0.6, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            Vec3::new(0.0, 0.0, 1e-3),
        ),
        (
            "large ~5 sr",
            [Vec3::new(-1.0, -0.6, 0.0), Vec3::new(1.0, -0.6, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            Vec3::new(0.0, 0.0, 0.1),
        ),
        ("grazing", [Vec3::ZERO, Vec3::X, Vec3::new(0.3, 1.0, 0.0)], Vec3::new(5.0, 0.5, 0.05)),
        ("sliver", [Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.01, 0.0)], Vec3::new(0.5, 0.3, 0.2)),
    ]
}

fn point(v: [Vec3; 3], b: [f32; 3]) -> DVec3 {
    v[0].as_dvec3() * b[0] as f64 + v[1].as_dvec3() * b[1] as f64 + v[2].as_dvec3() * b[2] as f64
}

/// dA -> dw factor |cos| / r^2 at `q` seen from `p` for a surface with normal `n`.
fn area_to_solid_angle(q: DVec3, p: DVec3, n: DVec3) -> f64 {
    let r = q - p;
    n.dot(r).abs() / (r.length_squared() * r.length())
}

/// Near the foot of a viewpoint at height h over the plane, dw/dA ~ h / r^3 changes faster than
/// finite differences of f32 points can follow; for the near-2-pi cases that is nearly every
/// sample (most of their solid angle lies there). Those points are checked by the unit test
/// `f64_maps_have_constant_jacobian_near_2pi_and_tiny` (f64 internals, 1e-5) and by the chi-square
/// tests here. Only when h is under 1% of the polygon's `size`.
fn steep(q: DVec3, p: DVec3, on_plane: DVec3, n: DVec3, size: f64) -> bool {
    let h = (p - on_plane).dot(n).abs();
    h < 0.01 * size && (q - p).length() < 30.0 * h
}

#[test]
fn spherical_triangle_pdf_equals_inverse_jacobian_ordinary_tiny_near_2pi_grazing_sliver() {
    for (name, v, p) in triangles() {
        let [v0, v1, v2] = v.map(|q| q.as_dvec3());
        let cross = (v1 - v0).cross(v2 - v0);
        let (two_area, n) = (cross.length(), cross.normalize());
        let f = |u: Vec2| {
            let (b, _) = sample_spherical_triangle(v, p, u).unwrap();
            [b[1] as f64, b[2] as f64]
        };
        let (mut worst, mut steep_points) = (0.0f64, 0);
        for u in u_grid(16, 0.05, 0.95) {
            let (b, pdf) = sample_spherical_triangle(v, p, u).unwrap();
            if steep(point(v, b), p.as_dvec3(), v0, n, (v1 - v0).length()) {
                steep_points += 1;
                continue;
            }
            let jac = jacobian_2d(&f, u) * two_area * area_to_solid_angle(point(v, b), p.as_dvec3(), n);
            let err = rel(pdf as f64, 1.0 / jac);
            assert!(err < 1e-4, "{name}: at u = {u} pdf {pdf} but 1/|J| = {}", 1.0 / jac);
            worst = worst.max(err);
        }
        println!(
            "triangle {name}: solid angle {:.6e} sr, max relative pdf error {worst:.1e} ({steep_points} of 256 points too steep)",
            triangle_solid_angle(v, p)
        );
    }
}

/// Cell index of barycentrics (b1, b2) in the k^2-triangle midpoint subdivision, and the cells'
/// corner barycentrics.
fn sub_triangles(k: usize) -> Vec<[(f64, f64); 3]> {
    let s = 1.0 / k as f64;
    let mut cells = Vec::new();
    for i in 0..k {
        for j in 0..k - i {
            let (a, b) = (i as f64 * s, j as f64 * s);
            cells.push([(a, b), (a + s, b), (a, b + s)]);
            if i + j + 1 < k {
                cells.push([(a + s, b), (a + s, b + s), (a, b + s)]);
            }
        }
    }
    cells
}

fn cell_of(cells: &[[(f64, f64); 3]], b1: f64, b2: f64) -> usize {
    // The cell containing (b1, b2), or the nearest on rounding.
    let inside = |c: &[(f64, f64); 3]| {
        let d = |(x0, y0): (f64, f64), (x1, y1): (f64, f64)| (x1 - x0) * (b2 - y0) - (y1 - y0) * (b1 - x0);
        let (e0, e1, e2) = (d(c[0], c[1]), d(c[1], c[2]), d(c[2], c[0]));
        e0.min(e1).min(e2)
    };
    (0..cells.len()).max_by(|&a, &b| inside(&cells[a]).total_cmp(&inside(&cells[b]))).unwrap()
}

#[test]
fn spherical_triangle_samples_are_uniform_chi_square_ordinary_tiny_near_2pi_grazing_sliver() {
    let cells = sub_triangles(8);
    let mut rng = SplitMix64::new(21);
    for (name, v, p) in triangles() {
        let at = |(b1, b2): (f64, f64)| (point(v, [(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32])).as_vec3();
        let omegas: Vec<f64> =
            cells.iter().map(|c| triangle_solid_angle([at(c[0]), at(c[1]), at(c[2])], p) as f64).collect();
        let total: f64 = omegas.iter().sum();
        assert!(rel(total, triangle_solid_angle(v, p) as f64) < 1e-5, "{name}: cells sum to {total}");
        let probs: Vec<f64> = omegas.iter().map(|o| o / total).collect();
        let mut counts = vec![0u64; cells.len()];
        for _ in 0..200_000 {
            let (b, _) = sample_spherical_triangle(v, p, rng.vec2()).unwrap();
            counts[cell_of(&cells, b[1] as f64, b[2] as f64)] += 1;
        }
        let stat = assert_chi_square(name, &counts, &probs);
        println!("triangle {name}: chi-square {stat:.1} over {} cells", cells.len());
    }
}

/// Does the ray p + t w (t > 0) hit triangle v? (Möller-Trumbore in f64.)
fn hits(v: [DVec3; 3], p: DVec3, w: DVec3) -> bool {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let s1 = w.cross(e2);
    let div = s1.dot(e1);
    let s = p - v[0];
    let (b1, b2) = (s.dot(s1) / div, w.dot(s.cross(e1)) / div);
    let t = e2.dot(s.cross(e1)) / div;
    b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 && t > 0.0
}

#[test]
fn spherical_triangle_solid_angle_matches_monte_carlo_ordinary_tiny_1e8_near_2pi() {
    let mut rng = SplitMix64::new(33);
    for (name, v, p) in triangles() {
        let [v0, v1, v2] = v.map(|q| q.as_dvec3());
        let (pd, cross) = (p.as_dvec3(), (v1 - v0).cross(v2 - v0));
        let exact = triangle_solid_angle(v, p) as f64;
        let (estimate, err) = if name.starts_with("near 2 pi") {
            // Area sampling has huge variance under a low viewpoint: count uniform-sphere hits.
            mean_and_error(400_000, || {
                let w = sample_uniform_sphere(rng.vec2()).as_dvec3();
                if hits([v0, v1, v2], pd, w) { 4.0 * PI } else { 0.0 }
            })
        } else {
            mean_and_error(200_000, || {
                let u = Vec2::new(rng.f64() as f32, rng.f64() as f32);
                let b = sample_uniform_triangle(u);
                0.5 * cross.length() * area_to_solid_angle(point(v, b), pd, cross.normalize())
            })
        };
        println!("triangle {name}: Van Oosterom-Strackee {exact:.9e} sr, Monte Carlo {estimate:.9e} +- {err:.1e}");
        assert!((estimate - exact).abs() < 3.0 * err + 1e-7 * exact, "{name}: {exact} vs {estimate} +- {err}");
    }
    // Spherical-triangle area from unit vertices: the octant, and a tiny cap-like triangle.
    assert!((spherical_triangle_area(Vec3::X, Vec3::Y, Vec3::Z) as f64 - PI / 2.0).abs() < 1e-6);
}

#[test]
fn spherical_triangle_inverse_round_trips_ordinary_tiny_near_2pi_grazing_sliver() {
    let mut rng = SplitMix64::new(4);
    for (name, v, p) in triangles() {
        let mut worst = 0.0f32;
        for _ in 0..5000 {
            let u = rng.vec2();
            let (b, _) = sample_spherical_triangle(v, p, u).unwrap();
            let w = (point(v, b) - p.as_dvec3()).as_vec3();
            let back = invert_spherical_triangle_sample(v, p, w).unwrap();
            worst = worst.max((back - u).abs().max_element());
        }
        println!("triangle {name}: inverse round trip max error {worst:.1e}");
        assert!(worst < 2e-4, "{name}: round trip error {worst}");
    }
}

fn rectangles() -> Vec<(&'static str, Vec3, Vec3, Vec3, Vec3)> {
    let (ex, ey) = (Vec3::new(0.8, 0.6, 0.0) * 1.5, Vec3::new(-0.6, 0.8, 0.0) * 0.7);
    vec![
        ("ordinary rotated", Vec3::new(0.3, 0.2, 0.9), Vec3::new(0.5, 0.0, 0.0), ex, ey),
        ("head-on", Vec3::new(0.0, 0.0, 1.0), Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0),
        ("tiny ~1e-8 sr", Vec3::new(0.3e-4, -0.2e-4, 1.0), Vec3::ZERO, Vec3::X * 1e-4, Vec3::Y * 1e-4),
        ("tiny 1e-12 sr (planar fallback)", Vec3::new(3e-6, -2e-6, 1.0), Vec3::ZERO, Vec3::X * 1e-6, Vec3::Y * 1e-6),
        ("near 2 pi sr", Vec3::new(0.1, 0.2, 1e-3), Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0),
        ("large ~5 sr", Vec3::new(0.1, 0.2, 0.1), Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0),
        ("grazing far", Vec3::new(30.0, 0.5, 0.2), Vec3::ZERO, Vec3::X, Vec3::Y),
        ("behind the plane", Vec3::new(0.7, 0.1, -0.4), Vec3::ZERO, Vec3::X, Vec3::Y * 0.5),
    ]
}

fn st(q: DVec3, corner: Vec3, ex: Vec3, ey: Vec3) -> [f64; 2] {
    let d = q - corner.as_dvec3();
    let (ex, ey) = (ex.as_dvec3(), ey.as_dvec3());
    [d.dot(ex) / ex.length_squared(), d.dot(ey) / ey.length_squared()]
}

#[test]
fn spherical_rectangle_pdf_equals_inverse_jacobian_ordinary_tiny_near_2pi_grazing() {
    for (name, p, corner, ex, ey) in rectangles() {
        let f = |u: Vec2| st(sample_spherical_rectangle(p, corner, ex, ey, u).unwrap().0.as_dvec3(), corner, ex, ey);
        let cross = ex.as_dvec3().cross(ey.as_dvec3());
        let (mut worst, mut steep_points) = (0.0f64, 0);
        for u in u_grid(16, 0.05, 0.95) {
            let (q, pdf) = sample_spherical_rectangle(p, corner, ex, ey, u).unwrap();
            if steep(q.as_dvec3(), p.as_dvec3(), corner.as_dvec3(), cross.normalize(), ex.length() as f64) {
                steep_points += 1;
                continue;
            }
            let jac = jacobian_2d(&f, u)
                * cross.length()
                * area_to_solid_angle(q.as_dvec3(), p.as_dvec3(), cross.normalize());
            let err = rel(pdf as f64, 1.0 / jac);
            assert!(err < 1e-4, "{name}: at u = {u} pdf {pdf} but 1/|J| = {}", 1.0 / jac);
            worst = worst.max(err);
        }
        let omega = spherical_rectangle_solid_angle(p, corner, ex, ey);
        println!(
            "rectangle {name}: solid angle {omega:.6e} sr, max relative pdf error {worst:.1e} ({steep_points} of 256 points too steep)"
        );
    }
}

#[test]
fn spherical_rectangle_samples_are_uniform_chi_square_ordinary_tiny_near_2pi_grazing() {
    let mut rng = SplitMix64::new(8);
    let k = 8;
    for (name, p, corner, ex, ey) in rectangles() {
        let (cx, cy) = (ex / k as f32, ey / k as f32);
        let probs: Vec<f64> = (0..k * k)
            .map(|c| {
                let c0 = corner + cx * (c % k) as f32 + cy * (c / k) as f32;
                spherical_rectangle_solid_angle(p, c0, cx, cy) as f64
            })
            .collect();
        let total: f64 = probs.iter().sum();
        assert!(rel(total, spherical_rectangle_solid_angle(p, corner, ex, ey) as f64) < 1e-5, "{name}");
        let probs: Vec<f64> = probs.iter().map(|o| o / total).collect();
        let mut counts = vec![0u64; k * k];
        for _ in 0..200_000 {
            let (q, _) = sample_spherical_rectangle(p, corner, ex, ey, rng.vec2()).unwrap();
            let [s, t] = st(q.as_dvec3(), corner, ex, ey);
            let (i, j) = (((s * k as f64) as usize).min(k - 1), ((t * k as f64) as usize).min(k - 1));
            counts[j * k + i] += 1;
        }
        let stat = assert_chi_square(name, &counts, &probs);
        println!("rectangle {name}: chi-square {stat:.1} over {} cells", k * k);
    }
}

/// Solid angle of the axis-aligned rectangle [x0, x1] x [y0, y1] at distance h below the
/// viewpoint: sum over corners of +-atan(x y / (h r)) (e.g. Ureña et al. 2013, eq. 5).
fn rectangle_closed_form(x0: f64, x1: f64, y0: f64, y1: f64, h: f64) -> f64 {
    let f = |x: f64, y: f64| (x * y / (h * (x * x + y * y + h * h).sqrt())).atan();
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

#[test]
fn spherical_rectangle_solid_angle_matches_closed_form_and_monte_carlo() {
    for (name, p, corner, ex, ey) in rectangles() {
        if ex.y != 0.0 {
            continue;
        }
        let (pd, c) = (p.as_dvec3(), corner.as_dvec3());
        let exact = rectangle_closed_form(
            c.x - pd.x,
            c.x - pd.x + ex.x as f64,
            c.y - pd.y,
            c.y - pd.y + ey.y as f64,
            pd.z.abs(),
        );
        let omega = spherical_rectangle_solid_angle(p, corner, ex, ey) as f64;
        println!("rectangle {name}: closed form {exact:.9e}, Van Oosterom-Strackee {omega:.9e}");
        assert!(rel(omega, exact) < 1e-6, "{name}: {omega} vs {exact}");
    }
    let mut rng = SplitMix64::new(12);
    for (name, p, corner, ex, ey) in rectangles().into_iter().filter(|r| !r.0.starts_with("near 2 pi")) {
        let cross = ex.as_dvec3().cross(ey.as_dvec3());
        let (m, e) = mean_and_error(200_000, || {
            let q = corner.as_dvec3() + ex.as_dvec3() * rng.f64() + ey.as_dvec3() * rng.f64();
            cross.length() * area_to_solid_angle(q, p.as_dvec3(), cross.normalize())
        });
        let omega = spherical_rectangle_solid_angle(p, corner, ex, ey) as f64;
        println!("rectangle {name}: Monte Carlo {m:.9e} +- {e:.1e}");
        assert!((m - omega).abs() < 3.0 * e + 1e-7 * omega, "{name}: {omega} vs {m} +- {e}");
    }
}

#[test]
fn spherical_rectangle_inverse_round_trips_ordinary_tiny_near_2pi_grazing() {
    let mut rng = SplitMix64::new(6);
    for (name, p, corner, ex, ey) in rectangles() {
        let mut worst = 0.0f32;
        for _ in 0..5000 {
            let u = rng.vec2();
            let (q, _) = sample_spherical_rectangle(p, corner, ex, ey, u).unwrap();
            let back = invert_spherical_rectangle_sample(p, corner, ex, ey, q).unwrap();
            worst = worst.max((back - u).abs().max_element());
        }
        println!("rectangle {name}: inverse round trip max error {worst:.1e}");
        assert!(worst < 2e-4, "{name}: round trip error {worst}");
    }
}
