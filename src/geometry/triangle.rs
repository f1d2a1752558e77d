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
use crate::lanes::Real;

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
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        let (kz, shear) = shear_of(ray.dir);
        Self { origin: ray.origin, kz, shear }
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
        let p = v.map(|v| {
            let q = self.permute(v);
            sheared_xy([q.x, q.y, q.z], [s.x, s.y])
        });
        let mut e = edges(&p);
        if e.contains(&0.0) {
            // Exact for products of f32, so a ray through a shared edge or vertex meets one side.
            let edge = |a: [f32; 3], b: [f32; 3]| (a[0] as f64 * b[1] as f64 - a[1] as f64 * b[0] as f64) as f32;
            e = [edge(p[1], p[2]), edge(p[2], p[0]), edge(p[0], p[1])];
        }
        let (hit, t, b) = decide(&p, e, s.z, t_max);
        hit.then_some(TriangleHit { t, b })
    }
}

/// A vertex translated to the ray origin and permuted (`q`, the ray's dominant axis last), sheared
/// in x and y by `s` (Sx, Sy) so the ray runs along +z; z is scaled later, in [`decide`].
#[inline(always)]
pub(crate) fn sheared_xy<R: Real>(q: [R; 3], s: [R; 2]) -> [R; 3] {
    [q[0] + s[0] * q[2], q[1] + s[1] * q[2], q[2]]
}

/// The watertight test's three edge functions of sheared vertices `p`.
#[inline(always)]
pub(crate) fn edges<R: Real>(p: &[[R; 3]; 3]) -> [R; 3] {
    [
        p[1][0] * p[2][1] - p[1][1] * p[2][0],
        p[2][0] * p[0][1] - p[2][1] * p[0][0],
        p[0][0] * p[1][1] - p[0][1] * p[1][0],
    ]
}

/// Lanes where an edge function is exactly zero: there the f32 test cannot decide which side of an
/// edge the ray passes, and the scalar test recomputes the edges in f64.
#[inline(always)]
pub(crate) fn any_edge_zero<R: Real>(e: [R; 3]) -> R::Mask {
    let zero = R::splat(0.0);
    let is_zero = |v: R| v.le(zero) & v.ge(zero);
    is_zero(e[0]) | is_zero(e[1]) | is_zero(e[2])
}

/// The watertight test after its edge functions `e` of sheared vertices `p` (z unscaled) with
/// the ray's z shear `sz`: whether each lane hits over (delta_t, t_max], its t and barycentrics.
/// Written once over [`Real`], so the scalar test and a leaf's triangles against one ray
/// (`wide::triangle_block_hits`) decide alike; the packet kernel (`wide::packet`) runs these steps
/// fused per lane, and its tests hold it to the same bits.
#[inline(always)]
pub(crate) fn decide<R: Real>(p: &[[R; 3]; 3], e: [R; 3], sz: R, t_max: R) -> (R::Mask, R, [R; 3]) {
    let zero = R::splat(0.0);
    let [e0, e1, e2] = e;
    let mixed = (e0.lt(zero) | e1.lt(zero) | e2.lt(zero)) & (e0.gt(zero) | e1.gt(zero) | e2.gt(zero));
    let det = e0 + e1 + e2;
    let z = [p[0][2] * sz, p[1][2] * sz, p[2][2] * sz];
    let t_scaled = e0 * z[0] + e1 * z[1] + e2 * z[2];
    // t in (0, t_max] before the division, loose by EARLY_REJECT_SLACK; det = 0 (the ray in the
    // triangle's plane, or a degenerate triangle) and NaN fail both sides.
    let t_reject = (t_max * EARLY_REJECT_SLACK) * det;
    let negative = det.lt(zero);
    let in_range = (negative & t_scaled.lt(zero) & t_scaled.ge(t_reject))
        | (det.gt(zero) & t_scaled.gt(zero) & t_scaled.le(t_reject));
    let inv_det = R::splat(1.0) / det;
    let t = t_scaled * inv_det;
    let max_x = p[0][0].abs().max(p[1][0].abs()).max(p[2][0].abs());
    let max_y = p[0][1].abs().max(p[1][1].abs()).max(p[2][1].abs());
    let max_z = z[0].abs().max(z[1].abs()).max(z[2].abs());
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let beyond_error = !t.le(t_error_bound([max_x, max_y, max_z], max_e, inv_det));
    let hit = !mixed & in_range & t.le(t_max) & beyond_error;
    (hit, t, [e0 * inv_det, e1 * inv_det, e2 * inv_det])
}

/// pbrt-v4 eqs. 6.27-6.32: a bound on the rounding error of the watertight test's t, from the
/// largest |x|, |y| and (scaled) |z| of the sheared vertices, the largest |edge function| and
/// 1 / det. A hit counts only if its t exceeds this bound.
#[inline(always)]
pub(crate) fn t_error_bound<R: Real>(max: [R; 3], max_e: R, inv_det: R) -> R {
    let [max_x, max_y, max_z] = max;
    let delta_z = max_z * gamma(3);
    let delta_x = (max_x + max_z) * gamma(5);
    let delta_y = (max_y + max_z) * gamma(5);
    // The order of pbrt's products, so that every caller rounds alike.
    let delta_e = (max_x * gamma(2) * max_y + delta_y * max_x + delta_x * max_y) * 2.0;
    (max_e * gamma(3) * max_z + delta_e * max_z + delta_z * max_e) * 3.0 * inv_det.abs()
}

/// The watertight test's axis permutation and shear for direction `d`: the axis of its largest
/// component (x if it beats y and z, else y if it beats z, else z), which becomes z, and (Sx, Sy,
/// Sz) = (-dx/dz, -dy/dz, 1/dz) in the permuted axes.
#[inline(always)]
pub(crate) fn shear_of(d: Vec3) -> (u8, Vec3) {
    let (x_largest, y_largest, shear) = shear_lanes(d.to_array());
    (2 - 2 * u8::from(x_largest) - u8::from(y_largest), Vec3::from_array(shear))
}

/// [`shear_of`] over [`Real`] lanes: whether x, or else y, is the largest axis, and the shear.
/// Branch-free, since the directions of incoherent rays mispredict the comparisons.
#[inline(always)]
pub(crate) fn shear_lanes<R: Real>(d: [R; 3]) -> (R::Mask, R::Mask, [R; 3]) {
    let a = d.map(R::abs);
    let x_beats_y = a[0].gt(a[1]);
    let x_largest = x_beats_y & a[0].gt(a[2]);
    let y_largest = !x_beats_y & a[1].gt(a[2]);
    // The components that become x, y and z (`PERMUTED`).
    let pick = |if_x: R, if_y: R, if_z: R| R::select(x_largest, if_x, R::select(y_largest, if_y, if_z));
    let (dx, dy, dz) = (pick(d[1], d[2], d[0]), pick(d[2], d[0], d[1]), pick(d[0], d[1], d[2]));
    (x_largest, y_largest, [-dx / dz, -dy / dz, R::splat(1.0) / dz])
}

/// The original axes that become x, y and z when axis `kz` is rotated to z (as [`swizzle`]).
pub(crate) const PERMUTED: [[usize; 3]; 3] = [[1, 2, 0], [2, 0, 1], [0, 1, 2]];

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
    fn the_largest_axis_becomes_z_and_ties_go_as_nested_comparisons() {
        // pbrt-v4's rule: x if |dx| beats |dy| and |dz|, else y if |dy| beats |dz|, else z; ties
        // (diagonal rays) go to the later axis. Written out here as the nested comparisons.
        let nested = |a: Vec3| {
            if a.x > a.y {
                if a.x > a.z { 0 } else { 2 }
            } else if a.y > a.z {
                1
            } else {
                2
            }
        };
        let values = [-2.0f32, -1.0, -0.0, 0.0, 0.5, 1.0, 2.0];
        for x in values {
            for y in values {
                for z in values {
                    let d = Vec3::new(x, y, z);
                    let (kz, shear) = shear_of(d);
                    assert_eq!(kz, nested(d.abs()), "{d}");
                    if d.to_array()[kz as usize] != 0.0 {
                        let [px, py, pz] = PERMUTED[kz as usize].map(|a| d.to_array()[a]);
                        assert_eq!(
                            shear.to_array().map(f32::to_bits),
                            [-px / pz, -py / pz, 1.0 / pz].map(f32::to_bits)
                        );
                    }
                }
            }
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
