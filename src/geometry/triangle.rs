//! Watertight ray-triangle intersection with a conservative `t > 0` test.
//!
//! The method of Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013), as
//! described in pbrt-v4 section 6.5.3: translate the vertices to the ray origin, permute axes so
//! the ray's largest direction component is z, shear so the ray becomes +z, then evaluate the 2D
//! edge functions. Edge values that round to exactly zero are recomputed in f64 (exact for
//! products of f32), so rays through shared edges and vertices hit exactly one side.
//!
//! The hit distance carries pbrt-v4's error bound (section 6.8.6, "Conservative Ray-Triangle t
//! Tests"): hits with `t <= delta_t` are rejected, so a reported hit is truly in front of the
//! origin. That is what lets an offset origin (see `ray.rs`) never re-hit its own triangle.

use glam::Vec3;

use super::ray::{Ray, gamma};

/// Per-ray constants of the watertight test: the axis permutation and the shear.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShearedRay {
    origin: Vec3,
    /// Axis of the largest |dir| component, which becomes z (x and y follow cyclically).
    kz: u8,
    /// Shear (Sx, Sy, Sz) = (-dx/dz, -dy/dz, 1/dz) in permuted axes.
    shear: Vec3,
}

/// Barycentrics and distance of a ray-triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangleHit {
    pub t: f32,
    pub b: [f32; 3],
}

/// Ray parameter range check slack for the early `t_scaled` rejection: loose by 2^-20 so it only
/// rejects hits that the exact `t <= t_max` test on the computed `t` would reject too.
pub(crate) const EARLY_REJECT_SLACK: f32 = 1.0 + 1.0 / (1u32 << 20) as f32;

impl ShearedRay {
    /// Precomputes the permutation and shear. The ray must be valid ([`Ray::is_valid`]).
    pub(crate) fn new(ray: &Ray) -> Self {
        let a = ray.dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let d = swizzle(ray.dir, kz);
        Self { origin: ray.origin, kz, shear: Vec3::new(-d.x / d.z, -d.y / d.z, 1.0 / d.z) }
    }

    /// The ray origin, the axis that became z, and the shear: what a lane kernel of the same
    /// test needs (`wide::triangle_block_hits`).
    #[inline(always)]
    pub(crate) fn parts(&self) -> (Vec3, u8, Vec3) {
        (self.origin, self.kz, self.shear)
    }

    #[inline(always)]
    fn permute(&self, v: Vec3) -> Vec3 {
        swizzle(v - self.origin, self.kz)
    }

    /// The hit with triangle `v` if its computed `t` satisfies `delta_t < t <= t_max`.
    #[inline(always)]
    pub(crate) fn intersect(&self, v: &[Vec3; 3], t_max: f32) -> Option<TriangleHit> {
        let s = self.shear;
        let mut p0 = self.permute(v[0]);
        let mut p1 = self.permute(v[1]);
        let mut p2 = self.permute(v[2]);
        p0.x += s.x * p0.z;
        p0.y += s.y * p0.z;
        p1.x += s.x * p1.z;
        p1.y += s.y * p1.z;
        p2.x += s.x * p2.z;
        p2.y += s.y * p2.z;

        let mut e0 = p1.x * p2.y - p1.y * p2.x;
        let mut e1 = p2.x * p0.y - p2.y * p0.x;
        let mut e2 = p0.x * p1.y - p0.y * p1.x;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            let edge = |a: Vec3, b: Vec3| (a.x as f64 * b.y as f64 - a.y as f64 * b.x as f64) as f32;
            e0 = edge(p1, p2);
            e1 = edge(p2, p0);
            e2 = edge(p0, p1);
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            return None; // Ray in the triangle's plane, or a degenerate triangle.
        }

        p0.z *= s.z;
        p1.z *= s.z;
        p2.z *= s.z;
        let t_scaled = e0 * p0.z + e1 * p1.z + e2 * p2.z;
        let t_reject = t_max * EARLY_REJECT_SLACK;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_reject * det) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_reject * det) {
            return None;
        }

        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if t.is_nan() || t > t_max {
            return None;
        }

        let max_x = p0.x.abs().max(p1.x.abs()).max(p2.x.abs());
        let max_y = p0.y.abs().max(p1.y.abs()).max(p2.y.abs());
        let max_z = p0.z.abs().max(p1.z.abs()).max(p2.z.abs());
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        if t <= t_error_bound([max_x, max_y, max_z], max_e, inv_det) {
            return None;
        }
        Some(TriangleHit { t, b: [e0 * inv_det, e1 * inv_det, e2 * inv_det] })
    }
}

/// pbrt-v4 eqs. 6.27-6.32: a bound on the rounding error of the watertight test's t, from the
/// largest |x|, |y| and (scaled) |z| of the sheared vertices, the largest |edge function| and
/// 1 / det. A hit counts only if its t exceeds this bound. (The scalar test and its lane kernel,
/// `wide::triangle_block_hits`, both call it.)
#[inline(always)]
pub(crate) fn t_error_bound(max: [f32; 3], max_e: f32, inv_det: f32) -> f32 {
    let [max_x, max_y, max_z] = max;
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + max_z);
    let delta_y = gamma(5) * (max_y + max_z);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs()
}

/// `v` with its axes rotated so that axis `kz` becomes z (static swizzles: runtime indexing
/// into a `Vec3` is slower).
#[inline(always)]
fn swizzle(v: Vec3, kz: u8) -> Vec3 {
    match kz {
        0 => Vec3::new(v.y, v.z, v.x),
        1 => Vec3::new(v.z, v.x, v.y),
        _ => v,
    }
}

/// Largest usable world coordinate, metres (1e9 km). Beyond about 1e19 the BVH builder's surface
/// areas overflow f32 and obvhs breaks (found by fuzzing the glTF import); 1e12 leaves room for
/// sums over millions of nodes.
pub const MAX_COORDINATE: f32 = 1e12;

/// Whether a triangle has zero area in f32 (repeated or collinear vertices), or a vertex that is
/// not finite or lies beyond [`MAX_COORDINATE`] on some axis. Such triangles are left out of the
/// scene BVH and of area lights.
pub(crate) fn is_degenerate(v: &[Vec3; 3]) -> bool {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let in_range = v.iter().all(|p| p.abs().max_element() <= MAX_COORDINATE);
    let proper = n.length_squared() > 0.0 && n.is_finite() && in_range;
    !proper
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [Vec3; 3] = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];

    #[test]
    fn hits_the_middle_with_barycentrics_summing_to_one() {
        let ray = Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let hit = ShearedRay::new(&ray).intersect(&TRI, f32::INFINITY).unwrap();
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!((hit.b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let p = hit.b[0] * TRI[0] + hit.b[1] * TRI[1] + hit.b[2] * TRI[2];
        assert!(p.distance(ray.at(hit.t)) < 1e-6);
    }

    #[test]
    fn respects_t_max_and_origin() {
        let ray = Ray { origin: Vec3::new(0.0, 0.0, 2.0), dir: Vec3::new(0.0, 0.0, -1.0), t_max: 1.5 };
        assert!(ShearedRay::new(&ray).intersect(&TRI, ray.t_max).is_none());
        let behind = Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(ShearedRay::new(&behind).intersect(&TRI, f32::INFINITY).is_none());
    }

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles sharing the edge x = 0; rays straight through the edge hit exactly one.
        let a = [Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)];
        let b = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        for i in 0..100 {
            let y = -0.9 + 0.018 * i as f32;
            let ray = Ray::new(Vec3::new(0.0, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
            let s = ShearedRay::new(&ray);
            let hits =
                s.intersect(&a, f32::INFINITY).is_some() as u32 + s.intersect(&b, f32::INFINITY).is_some() as u32;
            assert!(hits >= 1, "ray at y = {y} slipped through the shared edge");
        }
    }

    #[test]
    fn degenerate_triangles_are_detected() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        assert!(is_degenerate(&[p, p, Vec3::ZERO]));
        assert!(is_degenerate(&[Vec3::ZERO, p, 2.0 * p]));
        assert!(is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)]));
        // Finite normal, but a vertex far beyond MAX_COORDINATE (BVH areas would overflow).
        assert!(is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 1e38)]));
        assert!(!is_degenerate(&TRI));
    }
}
