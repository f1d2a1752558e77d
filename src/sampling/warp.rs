//! Warps from the unit square to disks, triangles, spheres, hemispheres and cones, each beside its
//! pdf and its inverse; 1D/2D linear warps; spherical coordinates; the equal-area octahedral map.
//! Local frames are z-up. Formulas follow pbrt-v4 §A.4-A.5 unless another source is cited.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI, TAU};

use crate::lanes::Real;
use glam::{Vec2, Vec3};

use super::ONE_MINUS_EPSILON;

// ---------------------------------------------------------------------------------------------
// Disks and triangles
// ---------------------------------------------------------------------------------------------

/// A point uniformly distributed on the unit disk by Shirley and Chiu's (1997) concentric map,
/// which sends square strata to compact disk regions. Pdf: [`uniform_disk_pdf`].
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    // Each quarter of the square (split by its diagonals) maps to a quarter of the disk.
    let (r, theta) =
        if o.x.abs() > o.y.abs() { (o.x, FRAC_PI_4 * (o.y / o.x)) } else { (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)) };
    let (s, c) = theta.sin_cos();
    r * Vec2::new(c, s)
}

/// The unit-square point that [`sample_uniform_disk_concentric`] maps to `p` (|p| <= 1).
pub fn invert_uniform_disk_concentric(p: Vec2) -> Vec2 {
    let r = p.length();
    let mut theta = p.y.atan2(p.x);
    if theta < -FRAC_PI_4 {
        theta += TAU; // now in [-pi/4, 7pi/4): one branch per quarter
    }
    let o = if theta < FRAC_PI_4 {
        Vec2::new(r, r * theta / FRAC_PI_4)
    } else if theta < 3.0 * FRAC_PI_4 {
        Vec2::new(r * (FRAC_PI_2 - theta) / FRAC_PI_4, r)
    } else if theta < 5.0 * FRAC_PI_4 {
        Vec2::new(-r, r * (PI - theta) / FRAC_PI_4)
    } else {
        Vec2::new(r * (theta - 3.0 * FRAC_PI_2) / FRAC_PI_4, -r)
    };
    ((o + Vec2::ONE) * 0.5).clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON))
}

/// A point uniformly distributed on the unit disk in polar form (r = sqrt(u.x), phi = 2 pi u.y):
/// simpler than the concentric map but stretches strata near the centre.
pub fn sample_uniform_disk_polar(u: Vec2) -> Vec2 {
    let r = u.x.max(0.0).sqrt();
    let (s, c) = (TAU * u.y).sin_cos();
    r * Vec2::new(c, s)
}

/// The unit-square point that [`sample_uniform_disk_polar`] maps to `p`.
pub fn invert_uniform_disk_polar(p: Vec2) -> Vec2 {
    Vec2::new(p.length_squared().min(ONE_MINUS_EPSILON), spherical_phi(p.extend(0.0)) / TAU)
}

/// Pdf of either uniform disk warp, per unit area of the unit disk: 1 / pi.
pub fn uniform_disk_pdf() -> f32 {
    FRAC_1_PI
}

/// Uniform barycentrics `[b0, b1, b2]` over a triangle by Heitz's (2019) low-distortion map ("A
/// Low-Distortion Map Between Triangle and Square"), as pbrt-v4 uses. Pdf: [`uniform_triangle_pdf`].
pub fn sample_uniform_triangle(u: Vec2) -> [f32; 3] {
    sample_uniform_triangle_of(u.x, u.y)
}

/// [`sample_uniform_triangle`] over [`Real`]: one point (`f32`) or a lane each (`F32x16`).
#[inline(always)]
pub fn sample_uniform_triangle_of<F: Real>(u0: F, u1: F) -> [F; 3] {
    let below = u0.lt(u1);
    let (half0, half1) = (u0 / 2.0, u1 / 2.0);
    let b0 = F::select(below, half0, u0 - half1);
    let b1 = F::select(below, u1 - half0, half1);
    [b0, b1, F::splat(1.0) - b0 - b1]
}

/// The unit-square point that [`sample_uniform_triangle`] maps to barycentrics `b`.
pub fn invert_uniform_triangle_sample(b: [f32; 3]) -> Vec2 {
    if b[1] > b[0] { Vec2::new(2.0 * b[0], b[1] + b[0]) } else { Vec2::new(b[0] + b[1], 2.0 * b[1]) }
}

/// Pdf of [`sample_uniform_triangle`] per unit area of a triangle of `area`: 1 / area.
pub fn uniform_triangle_pdf(area: f32) -> f32 {
    1.0 / area
}

// ---------------------------------------------------------------------------------------------
// Spheres, hemispheres, cones (z-up)
// ---------------------------------------------------------------------------------------------

/// A direction uniformly distributed over the unit sphere. Pdf: [`uniform_sphere_pdf`].
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    // sin^2 = (1 - z)(1 + z) = 4 u (1 - u): no cancellation near the poles.
    let sin_theta = 2.0 * (u.x * (1.0 - u.x)).max(0.0).sqrt();
    spherical_direction(sin_theta, z, TAU * u.y)
}

/// Pdf of [`sample_uniform_sphere`] per steradian: 1 / (4 pi).
pub fn uniform_sphere_pdf() -> f32 {
    1.0 / (4.0 * PI)
}

/// The unit-square point that [`sample_uniform_sphere`] maps to unit `w`.
pub fn invert_uniform_sphere_sample(w: Vec3) -> Vec2 {
    let one_minus_z = if w.z > 0.0 { one_minus_cos(w) } else { 1.0 - w.z };
    Vec2::new((one_minus_z / 2.0).clamp(0.0, ONE_MINUS_EPSILON), spherical_phi(w) / TAU)
}

/// A direction uniformly distributed over the hemisphere z >= 0. Pdf: [`uniform_hemisphere_pdf`].
pub fn sample_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let sin_theta = ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();
    spherical_direction(sin_theta, z, TAU * u.y)
}

/// Pdf of [`sample_uniform_hemisphere`] per steradian: 1 / (2 pi).
pub fn uniform_hemisphere_pdf() -> f32 {
    1.0 / TAU
}

/// The unit-square point that [`sample_uniform_hemisphere`] maps to unit `w` (w.z >= 0).
pub fn invert_uniform_hemisphere_sample(w: Vec3) -> Vec2 {
    Vec2::new(w.z.clamp(0.0, ONE_MINUS_EPSILON), spherical_phi(w) / TAU)
}

/// A direction over the hemisphere z >= 0 with density cos(theta) / pi (Malley's method: project
/// a concentric disk sample up). Pdf: [`cosine_hemisphere_pdf`].
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    d.extend((1.0 - d.length_squared()).max(0.0).sqrt())
}

/// Pdf of [`sample_cosine_hemisphere`] per steradian: cos(theta) / pi, 0 below the horizon.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// The unit-square point that [`sample_cosine_hemisphere`] maps to unit `w` (w.z >= 0).
pub fn invert_cosine_hemisphere_sample(w: Vec3) -> Vec2 {
    invert_uniform_disk_concentric(Vec2::new(w.x, w.y))
}

/// A direction uniformly distributed in the cone of half-angle theta_max around +z.
/// Pdf: [`uniform_cone_pdf`]. `cos_theta_max` is clamped to [-1, 1]. For narrow cones prefer
/// [`sample_uniform_cone_sin2`]: an f32 cosine cannot hold a cone narrower than ~3e-4 rad.
pub fn sample_uniform_cone(u: Vec2, cos_theta_max: f32) -> Vec3 {
    // 1 - cos is exact (Sterbenz) for cos in [0.5, 1], so no precision is lost here.
    sample_cone_one_minus_cos(u, 1.0 - cos_theta_max.clamp(-1.0, 1.0))
}

/// [`sample_uniform_cone`] for a cone given by sin^2(theta_max) (clamped to [0, 1]; cones up to a
/// hemisphere). Exact for tiny cones such as the sun seen from Earth (sin^2 ~ 2e-5) or a small
/// sphere far away (sin^2 ~ 1e-9), where cos(theta_max) rounds to 1 in f32.
/// Pdf: [`uniform_cone_pdf_sin2`].
pub fn sample_uniform_cone_sin2(u: Vec2, sin2_theta_max: f32) -> Vec3 {
    sample_cone_one_minus_cos(u, one_minus_cos_from_sin2(sin2_theta_max))
}

/// Pdf of [`sample_uniform_cone`] per steradian: 1 / (2 pi (1 - cos theta_max)); +inf for a cone
/// of zero angle (use [`uniform_cone_pdf_sin2`] for narrow cones).
pub fn uniform_cone_pdf(cos_theta_max: f32) -> f32 {
    1.0 / (TAU * (1.0 - cos_theta_max.clamp(-1.0, 1.0)))
}

/// Pdf of [`sample_uniform_cone_sin2`] per steradian, accurate for tiny cones.
pub fn uniform_cone_pdf_sin2(sin2_theta_max: f32) -> f32 {
    1.0 / (TAU * one_minus_cos_from_sin2(sin2_theta_max))
}

/// The unit-square point that [`sample_uniform_cone`] maps to unit `w` inside the cone.
pub fn invert_uniform_cone_sample(w: Vec3, cos_theta_max: f32) -> Vec2 {
    invert_cone(w, 1.0 - cos_theta_max.clamp(-1.0, 1.0))
}

/// The unit-square point that [`sample_uniform_cone_sin2`] maps to unit `w` inside the cone.
pub fn invert_uniform_cone_sample_sin2(w: Vec3, sin2_theta_max: f32) -> Vec2 {
    invert_cone(w, one_minus_cos_from_sin2(sin2_theta_max))
}

/// 1 - cos(theta) from sin^2(theta) for theta in [0, pi/2], without cancellation:
/// 1 - cos = sin^2 / (1 + cos).
fn one_minus_cos_from_sin2(sin2: f32) -> f32 {
    let s2 = if sin2.is_nan() { 0.0 } else { sin2.clamp(0.0, 1.0) };
    s2 / (1.0 + (1.0 - s2).sqrt())
}

/// 1 - w.z for unit `w` with w.z > 0, without cancellation near the pole.
fn one_minus_cos(w: Vec3) -> f32 {
    (w.x * w.x + w.y * w.y) / (1.0 + w.z)
}

/// Uniform in the cone with 1 - cos(theta_max) = `omc`: 1 - cos(theta) = u.x * omc.
fn sample_cone_one_minus_cos(u: Vec2, omc: f32) -> Vec3 {
    let t = u.x * omc;
    let sin_theta = (t * (2.0 - t)).max(0.0).sqrt(); // sin^2 = t (2 - t)
    spherical_direction(sin_theta, 1.0 - t, TAU * u.y)
}

fn invert_cone(w: Vec3, omc: f32) -> Vec2 {
    let t = if w.z > 0.0 { one_minus_cos(w) } else { 1.0 - w.z };
    let u0 = if omc > 0.0 { t / omc } else { 0.0 };
    Vec2::new(u0.clamp(0.0, ONE_MINUS_EPSILON), spherical_phi(w) / TAU)
}

// ---------------------------------------------------------------------------------------------
// Linear and bilinear warps
// ---------------------------------------------------------------------------------------------

/// x in [0, 1) with density proportional to the line from `a` at 0 to `b` at 1 (pbrt-v4 §A.4.2).
/// `a` and `b` should be >= 0 (negative or NaN count as 0); if both are 0 the warp is uniform.
/// Pdf: [`linear_pdf`].
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    let (a, b) = (non_negative(a), non_negative(b));
    if !(a + b > 0.0 && (a + b).is_finite()) {
        return u;
    }
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    // The quadratic root written as u (a + b) / (a + sqrt(lerp(u, a^2, b^2))) has no cancellation.
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).max(0.0).sqrt());
    x.min(ONE_MINUS_EPSILON)
}

/// Pdf of [`sample_linear`] on [0, 1]: 2 lerp(x, a, b) / (a + b); 0 outside [0, 1].
pub fn linear_pdf(x: f32, a: f32, b: f32) -> f32 {
    if !(0.0..=1.0).contains(&x) {
        return 0.0;
    }
    let (a, b) = (non_negative(a), non_negative(b));
    if !(a + b > 0.0 && (a + b).is_finite()) {
        return 1.0;
    }
    2.0 * ((1.0 - x) * a + x * b) / (a + b)
}

/// The u that [`sample_linear`] maps to `x`: the cdf x (a (2 - x) + b x) / (a + b).
pub fn invert_linear_sample(x: f32, a: f32, b: f32) -> f32 {
    let (a, b) = (non_negative(a), non_negative(b));
    if !(a + b > 0.0 && (a + b).is_finite()) {
        return x;
    }
    x * (a * (2.0 - x) + b * x) / (a + b)
}

/// A point in [0, 1)^2 with density proportional to the bilinear interpolation of corner weights
/// `w = [w(0,0), w(1,0), w(0,1), w(1,1)]` (pbrt-v4 §A.4.3): y from the marginal, then x given y.
/// Lights use it to warp uniform samples toward cos(theta) at a polygon's corners.
/// Pdf: [`bilinear_pdf`].
pub fn sample_bilinear(u: Vec2, w: [f32; 4]) -> Vec2 {
    let w = w.map(non_negative);
    let y = sample_linear(u.y, w[0] + w[1], w[2] + w[3]);
    let x = sample_linear(u.x, lerp(y, w[0], w[2]), lerp(y, w[1], w[3]));
    Vec2::new(x, y)
}

/// Pdf of [`sample_bilinear`] on [0, 1]^2; 0 outside, 1 when all weights are 0.
pub fn bilinear_pdf(p: Vec2, w: [f32; 4]) -> f32 {
    if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
        return 0.0;
    }
    let w = w.map(non_negative);
    let sum = w[0] + w[1] + w[2] + w[3];
    if !(sum > 0.0 && sum.is_finite()) {
        return 1.0;
    }
    let f = (1.0 - p.x) * (1.0 - p.y) * w[0] + p.x * (1.0 - p.y) * w[1] + (1.0 - p.x) * p.y * w[2] + p.x * p.y * w[3];
    4.0 * f / sum
}

/// The unit-square point that [`sample_bilinear`] maps to `p`.
pub fn invert_bilinear_sample(p: Vec2, w: [f32; 4]) -> Vec2 {
    let w = w.map(non_negative);
    Vec2::new(
        invert_linear_sample(p.x, lerp(p.y, w[0], w[2]), lerp(p.y, w[1], w[3])),
        invert_linear_sample(p.y, w[0] + w[1], w[2] + w[3]),
    )
}

/// Hermite smooth step: 0 below `a`, 1 above `b`, 3t^2 - 2t^3 between (a step at `a` if a == b).
pub fn smooth_step(x: f32, a: f32, b: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

fn non_negative(v: f32) -> f32 {
    if v > 0.0 { v } else { 0.0 }
}

// ---------------------------------------------------------------------------------------------
// Spherical coordinates and the equal-area octahedral map
// ---------------------------------------------------------------------------------------------

/// The unit vector at polar angle theta (from +z) and azimuth phi (from +x toward +y).
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let s = sin_theta.clamp(-1.0, 1.0);
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(s * cos_phi, s * sin_phi, cos_theta.clamp(-1.0, 1.0))
}

/// Polar angle of `v` from +z in [0, pi]; `v` need not be normalised. atan2 keeps full precision
/// near the poles, where acos(z) would not.
pub fn spherical_theta(v: Vec3) -> f32 {
    (v.x * v.x + v.y * v.y).sqrt().atan2(v.z)
}

/// Azimuth of `v` about +z, from +x toward +y, in [0, 2 pi).
pub fn spherical_phi(v: Vec3) -> f32 {
    let p = v.y.atan2(v.x);
    if p >= 0.0 {
        p
    } else {
        let q = p + TAU;
        if q < TAU { q } else { 0.0 } // a tiny negative angle rounds up to 2 pi
    }
}

/// The unit square [0, 1]^2 onto the unit sphere, preserving area (Clarberg 2008, "Fast
/// Equal-Area Mapping of the (Hemi)Sphere using SIMD"; pbrt-v4 §3.8.3). The centre maps to +z, the
/// corners to -z. The pdf of a direction from a uniform square sample is 1 / (4 pi).
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    // Signed distance from the diamond |u| + |v| = 1 (the equator): > 0 inside (upper hemisphere).
    let signed_distance = 1.0 - (up + vp);
    let d = signed_distance.abs();
    let r = 1.0 - d;
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (d * (2.0 - d)).copysign(signed_distance); // 1 - r^2 without cancellation
    let (sin_phi, cos_phi) = phi.sin_cos();
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * s, sin_phi.copysign(v) * s, z)
}

/// The inverse of [`equal_area_square_to_sphere`]; `d` need not be normalised (zero maps to the
/// centre).
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let d = d.normalize_or(Vec3::Z);
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    // r = sqrt(1 - |z|), written so it keeps its digits near the poles.
    let r = ((x * x + y * y) / (1.0 + z)).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let t = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = t.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u); // fold the lower hemisphere into the square's corners
    }
    Vec2::new((u.copysign(d.x) + 1.0) * 0.5, (v.copysign(d.y) + 1.0) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_maps_square_corners_and_centre() {
        assert_eq!(sample_uniform_disk_concentric(Vec2::splat(0.5)), Vec2::ZERO);
        let p = sample_uniform_disk_concentric(Vec2::new(1.0, 0.5));
        assert!((p - Vec2::X).length() < 1e-6);
        let c = sample_uniform_disk_concentric(Vec2::ONE);
        assert!((c.length() - 1.0).abs() < 1e-6 && (c.x - c.y).abs() < 1e-6);
    }

    #[test]
    fn triangle_map_covers_vertices() {
        assert_eq!(sample_uniform_triangle(Vec2::ZERO), [0.0, 0.0, 1.0]);
        assert_eq!(sample_uniform_triangle(Vec2::new(1.0, 0.0)), [1.0, 0.0, 0.0]);
        assert_eq!(sample_uniform_triangle(Vec2::new(0.0, 1.0)), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn narrow_cone_sin2_keeps_its_angle_where_cos_rounds_to_one() {
        let sin2 = 1e-9f32;
        assert_eq!(1.0 - sin2, 1.0, "the cosine form cannot hold this cone in f32");
        let expected_pdf = 1.0 / (TAU as f64 * (sin2 as f64 / (1.0 + (1.0 - sin2 as f64).sqrt())));
        let pdf = uniform_cone_pdf_sin2(sin2) as f64;
        assert!((pdf / expected_pdf - 1.0).abs() < 1e-6, "{pdf} vs {expected_pdf}");
        // The edge of the cone is at sin(theta) = sqrt(sin2).
        let w = sample_uniform_cone_sin2(Vec2::new(1.0, 0.3), sin2);
        let sin_theta = (w.x * w.x + w.y * w.y).sqrt();
        assert!((sin_theta / sin2.sqrt() - 1.0).abs() < 1e-5, "{sin_theta}");
        let u = invert_uniform_cone_sample_sin2(sample_uniform_cone_sin2(Vec2::new(0.37, 0.6), sin2), sin2);
        assert!((u - Vec2::new(0.37, 0.6)).abs().max_element() < 1e-5, "{u}");
    }

    #[test]
    fn spherical_phi_stays_below_two_pi() {
        assert_eq!(spherical_phi(Vec3::new(1.0, -1e-30, 0.0)), 0.0);
        assert!(spherical_phi(Vec3::new(1.0, -1e-3, 0.0)) < TAU);
        assert!((spherical_phi(Vec3::NEG_Y) - 1.5 * PI).abs() < 1e-6);
    }

    #[test]
    fn spherical_theta_is_accurate_near_the_pole() {
        let theta = spherical_theta(Vec3::new(1e-5, 0.0, 1.0));
        assert!((theta / 1e-5 - 1.0).abs() < 1e-6, "{theta}");
    }

    #[test]
    fn equal_area_map_sends_centre_up_and_corners_down() {
        assert!((equal_area_square_to_sphere(Vec2::splat(0.5)) - Vec3::Z).length() < 1e-6);
        assert!((equal_area_square_to_sphere(Vec2::ZERO) + Vec3::Z).length() < 1e-6);
        assert!((equal_area_square_to_sphere(Vec2::new(1.0, 0.5)) - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn smooth_step_ends_and_middle() {
        assert_eq!(smooth_step(-1.0, 0.0, 1.0), 0.0);
        assert_eq!(smooth_step(2.0, 0.0, 1.0), 1.0);
        assert_eq!(smooth_step(0.5, 0.0, 1.0), 0.5);
        assert_eq!(smooth_step(0.5, 1.0, 1.0), 0.0);
    }

    #[test]
    fn linear_with_zero_weights_is_uniform() {
        assert_eq!(sample_linear(0.3, 0.0, 0.0), 0.3);
        assert_eq!(linear_pdf(0.3, 0.0, 0.0), 1.0);
        assert_eq!(sample_linear(0.0, 0.0, 1.0), 0.0);
        assert_eq!(bilinear_pdf(Vec2::splat(0.5), [0.0; 4]), 1.0);
    }
}
