//! Rays, surface points with their rounding-error bounds, and robust ray-origin offsets.
//!
//! Offsets follow pbrt-v4 (Pharr, Jakob, Humphreys, 4th ed., section 6.8.6 "Robust Spawned Ray
//! Origins"): every intersection or sampling routine returns a point `p` together with a
//! conservative per-axis bound `p_error` such that the exact surface point lies in the box
//! `p ± p_error`. [`offset_ray_origin`] moves `p` along the normal just past the far face of that
//! box (distance `dot(|n|, p_error)`), then rounds each moved component one more float away. For a
//! surface that is planar across the error box, the offset origin is therefore strictly on the
//! side of the surface that the ray leaves toward, so the ray cannot hit that surface at `t > 0`.
//!
//! The bounds used in this module:
//! - triangles (watertight intersection or barycentric sampling): `gamma(7) * sum_i |b_i p_i|`
//!   (pbrt-v4 eq. 6.34 and the text after it);
//! - analytic shapes (intersected and sampled in f64, re-projected onto the surface, then rounded
//!   to f32): half an f32 ulp per component, doubled, plus a tiny absolute term for the f64 work,
//!   see [`f64_point_error`].
//!
//! The far end of a shadow segment is offset the same way when it lies on a surface (an area
//! light), and the segment stops at `t_max = 1 - SHADOW_EPSILON` to absorb the rounding of the
//! direction `p1 - p0` itself (pbrt-v4 `SpawnRayTo`, `ShadowEpsilon`).

use glam::{DVec3, Vec3};

use crate::lanes::{F32x16, Real, Vec3x16, Vector};

/// Unit roundoff of f32 round-to-nearest: half the distance from 1 to the next float (2^-24).
pub const F32_UNIT_ROUNDOFF: f32 = f32::EPSILON * 0.5;

/// Shadow segments stop at `t = 1 - SHADOW_EPSILON` of their length, as pbrt-v4's `ShadowEpsilon`.
/// It covers the rounding of the segment direction and of `t`, which are relative to the segment
/// length, so the endpoint surface (already offset) is never reported as an occluder.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// pbrt's gamma(n) = n u / (1 - n u): the bound on the relative error of n chained f32 roundings
/// (Higham; pbrt-v4 eq. 6.21).
pub const fn gamma(n: i32) -> f32 {
    let nu = n as f32 * F32_UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// A ray `origin + t * dir` for `t` in `(0, t_max]`. `dir` need not be normalised: for a segment
/// from `p0` to `p1`, `dir = p1 - p0` and `t_max = 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point in metres (world space).
    pub origin: Vec3,
    /// Direction; its length sets the unit of `t`.
    pub dir: Vec3,
    /// Largest accepted parameter; `f32::INFINITY` for rays to infinity.
    pub t_max: f32,
}

impl Ray {
    /// A ray to infinity.
    pub const fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir, t_max: f32::INFINITY }
    }

    /// The exact segment `p0 -> p1`, both ends included, with no offsets (see
    /// [`SurfacePoint::spawn_ray_to`] for shadow rays between surfaces).
    pub fn segment(p0: Vec3, p1: Vec3) -> Self {
        Self { origin: p0, dir: p1 - p0, t_max: 1.0 }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }

    /// Whether traversal can run: finite origin and direction, non-zero direction and `t_max > 0`
    /// (NaN `t_max` fails). Queries on invalid rays report a miss.
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite() && self.dir.is_finite() && self.dir != Vec3::ZERO && self.t_max > 0.0
    }
}

/// A point on a surface with its error bound: what a hit or a light sample hands to shadow rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position in metres (world space).
    pub p: Vec3,
    /// Per-axis bound on |p - exact surface point|, in metres.
    pub p_error: Vec3,
    /// Unit geometric normal (either side; offsets pick the side from the ray direction).
    pub n: Vec3,
}

impl SurfacePoint {
    /// A point whose error bound is not known (e.g. from an app's G-buffer): assumes it came from
    /// barycentric interpolation of vertices of about its own magnitude, `gamma(7) * |p|`, with a
    /// floor of 1e-6 m * gamma(7) for points near the origin.
    pub fn from_point(p: Vec3, n: Vec3) -> Self {
        Self { p, p_error: gamma(7) * (p.abs() + Vec3::splat(1e-6)), n }
    }

    /// A ray leaving this surface along `w`, to infinity (distant and infinite lights).
    pub fn spawn_ray(&self, w: Vec3) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_error, self.n, w), w)
    }

    /// A shadow segment from this surface to the point `p` (a point light): offset at the start,
    /// stopping `SHADOW_EPSILON` short of `p`.
    pub fn spawn_ray_to_point(&self, p: Vec3) -> Ray {
        let o = offset_ray_origin(self.p, self.p_error, self.n, p - self.p);
        Ray { origin: o, dir: p - o, t_max: 1.0 - SHADOW_EPSILON }
    }

    /// A shadow segment between two surfaces (shading point to area-light sample): both ends are
    /// offset off their surfaces toward each other, and the segment stops `SHADOW_EPSILON` short.
    pub fn spawn_ray_to(&self, to: &SurfacePoint) -> Ray {
        let from = offset_ray_origin(self.p, self.p_error, self.n, to.p - self.p);
        let end = offset_ray_origin(to.p, to.p_error, to.n, from - to.p);
        Ray { origin: from, dir: end - from, t_max: 1.0 - SHADOW_EPSILON }
    }
}

/// How rays leave a surface (shadow rays, and the renderer's BSDF rays): the error-bound offset of
/// this module, or the naive fixed-distance offset many renderers use. The accuracy report prices
/// the difference: a fixed epsilon too small self-shadows ("acne"), too large leaks light.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum ShadowOffset {
    /// [`offset_ray_origin`] with the point's error bound (pbrt-v4 section 6.8.6).
    #[default]
    ErrorBound,
    /// Move each end this many metres along its normal (toward the other end); the segment still
    /// stops `SHADOW_EPSILON` short of its end.
    FixedEpsilon(f32),
}

impl ShadowOffset {
    /// `p` moved off its surface (normal `n`) to the side `w` points to.
    pub fn offset(self, p: &SurfacePoint, w: Vec3) -> Vec3 {
        match self {
            Self::ErrorBound => offset_ray_origin(p.p, p.p_error, p.n, w),
            Self::FixedEpsilon(eps) => p.p + p.n * if w.dot(p.n) < 0.0 { -eps } else { eps },
        }
    }

    /// As [`SurfacePoint::spawn_ray`] with this offset.
    pub fn spawn_ray(self, from: &SurfacePoint, w: Vec3) -> Ray {
        Ray::new(self.offset(from, w), w)
    }

    /// As [`SurfacePoint::spawn_ray_to_point`] with this offset.
    pub fn spawn_ray_to_point(self, from: &SurfacePoint, p: Vec3) -> Ray {
        let o = self.offset(from, p - from.p);
        Ray { origin: o, dir: p - o, t_max: 1.0 - SHADOW_EPSILON }
    }

    /// As [`SurfacePoint::spawn_ray_to`] with this offset at both ends.
    pub fn spawn_ray_to(self, from: &SurfacePoint, to: &SurfacePoint) -> Ray {
        let o = self.offset(from, to.p - from.p);
        let end = self.offset(to, o - to.p);
        Ray { origin: o, dir: end - o, t_max: 1.0 - SHADOW_EPSILON }
    }
}

/// pbrt-v4's `OffsetRayOrigin`: `p` moved along `n` (to the side `w` points to) by
/// `dot(|n|, p_error)`, each moved component then rounded one float further. If the exact surface
/// point is within `p ± p_error` and the surface is planar there, the result lies strictly on the
/// `w` side of the surface. `n` should be unit length; `w` only chooses the side.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let offset = if w.dot(n) < 0.0 { -d * n } else { d * n };
    let po = p + offset;
    if !po.is_finite() {
        return po;
    }
    Vec3::new(step_toward(po.x, offset.x), step_toward(po.y, offset.y), step_toward(po.z, offset.z))
}

/// [`ShadowOffset::ErrorBound`]'s [`ShadowOffset::spawn_ray_to_point`] from `LANES` surface
/// points (lane columns x, y, z of position, error bound and normal) to `target`: the segments'
/// origins and directions (each t_max is `1 - SHADOW_EPSILON`). The operations of
/// [`offset_ray_origin`] in the same order, so the rays are the same bit for bit.
#[inline(always)]
pub fn spawn_rays_to_points_lanes(from: [&Vec3x16; 3], target: &Vec3x16) -> [Vec3x16; 2] {
    let [&p, &e, &n] = from;
    let d = n.map(F32x16::abs).dot(e);
    let side = (*target - p).dot(n);
    let d = F32x16::select(side.lt(F32x16::ZERO), -d, d);
    let offset = n * d;
    let po = p + offset;
    let stepped = Vec3x16 {
        x: po.x.zip(offset.x, step_toward),
        y: po.y.zip(offset.y, step_toward),
        z: po.z.zip(offset.z, step_toward),
    };
    let origin = Vec3x16::select(po.is_finite(), stepped, po);
    [origin, *target - origin]
}

/// Finite `v` moved one float in the direction of `towards` (`next_up` for positive `towards`,
/// `next_down` for negative), unchanged for zero `towards`. Integer steps on the bit pattern
/// instead of std's checks for NaN and infinities, which the caller has ruled out.
#[inline(always)]
fn step_toward(v: f32, towards: f32) -> f32 {
    // A zero takes the side it moves to, so that one step up in magnitude is the right tiny value.
    let from = if v == 0.0 { 0.0f32.copysign(towards) } else { v };
    // Moving toward the value's own sign grows the magnitude (bits + 1); the other way shrinks it.
    let grows = (from.to_bits() ^ towards.to_bits()) >> 31 == 0;
    let bits = if grows { from.to_bits().wrapping_add(1) } else { from.to_bits().wrapping_sub(1) };
    if towards == 0.0 { v } else { f32::from_bits(bits) }
}

/// Error bound of a point that was computed in f64 (`p64`, from `abs_terms` = the sum of the
/// absolute values of the terms that produced it, e.g. `|M| |p_obj| + |t|` for an affine map) and
/// then rounded to f32. Rounding to nearest is off by at most 2^-24 |p|; we allow 2^-23 |p|, plus
/// 2^-40 * abs_terms, which dwarfs the f64 roundings (a few 2^-53 each).
pub fn f64_point_error(p64: DVec3, abs_terms: DVec3) -> Vec3 {
    let e = p64.abs() * 2f64.powi(-23) + abs_terms * 2f64.powi(-40);
    (e * (1.0 + 2f64.powi(-20)) + DVec3::splat(f32::MIN_POSITIVE as f64)).as_vec3()
}

/// The bound pbrt-v4 uses for a point interpolated from triangle vertices with barycentrics
/// `b` (from the watertight test or from sampling): `gamma(7) * sum_i |b_i v_i|`. For one point
/// (`Vec3`) or a lane of them (`Vec3x16`).
#[inline(always)]
pub fn triangle_point_error<V: Vector>(v: &[V; 3], b: [V::Real; 3]) -> V {
    ((v[0] * b[0]).abs() + (v[1] * b[1]).abs() + (v[2] * b[2]).abs()) * V::Real::splat(gamma(7))
}

/// A point on triangle `v` at barycentrics `b` (b0 + b1 + b2 = 1), with its error bound and unit
/// geometric normal (counter-clockwise winding is the front, as glTF). For triangle area lights.
pub fn triangle_surface_point(v: &[Vec3; 3], b: [f32; 3]) -> SurfacePoint {
    let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    SurfacePoint { p, p_error: triangle_point_error(v, b), n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::LANES;

    /// Hard cases among random points: a point at the origin (steps from zero), a zero error
    /// bound, a light behind the surface, a light at the point, and an overflowing offset.
    #[test]
    fn lane_segments_match_one_at_a_time() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let mut v = |s: f32| Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * s;
        let mut cases: Vec<(SurfacePoint, Vec3)> = (0..60)
            .map(|_| (SurfacePoint { p: v(20.0), p_error: v(1e-4).abs(), n: v(2.0).normalize() }, v(20.0)))
            .collect();
        let up = SurfacePoint { p: Vec3::ZERO, p_error: Vec3::ZERO, n: Vec3::Y };
        cases.extend([
            (up, Vec3::new(0.0, 2.0, 0.0)),
            (up, Vec3::new(1.0, -2.0, 0.0)),
            (SurfacePoint { p_error: Vec3::splat(1e-6), ..up }, Vec3::ZERO),
            (SurfacePoint { p: Vec3::splat(f32::MAX), p_error: Vec3::splat(f32::MAX), n: Vec3::X }, Vec3::ONE),
        ]);
        for block in cases.chunks(LANES) {
            let column = |f: &dyn Fn(usize) -> Vec3| {
                let mut c = Vec3x16::ZERO;
                for l in 0..LANES {
                    c.set_lane(l, f(l.min(block.len() - 1)));
                }
                c
            };
            let from = [column(&|l| block[l].0.p), column(&|l| block[l].0.p_error), column(&|l| block[l].0.n)];
            let [origin, dir] = spawn_rays_to_points_lanes([&from[0], &from[1], &from[2]], &column(&|l| block[l].1));
            for (l, (sp, target)) in block.iter().enumerate() {
                let one = ShadowOffset::ErrorBound.spawn_ray_to_point(sp, *target);
                let lane = [0, 1, 2].map(|a| (origin[a][l].to_bits(), dir[a][l].to_bits()));
                let want = [0, 1, 2].map(|a| (one.origin[a].to_bits(), one.dir[a].to_bits()));
                assert_eq!(lane, want, "{sp:?} -> {target}");
            }
        }
    }

    #[test]
    fn gamma_matches_definition() {
        assert!((gamma(1) - 2f32.powi(-24) / (1.0 - 2f32.powi(-24))).abs() < 1e-14);
        assert!(gamma(7) > 7.0 * 2f32.powi(-24));
    }

    #[test]
    fn offset_lands_on_the_side_of_w() {
        let p = Vec3::new(1e5, 2.0, -3e3);
        let n = Vec3::new(0.3, 0.9, 0.1).normalize();
        let err = Vec3::splat(0.01);
        let out = offset_ray_origin(p, err, n, n);
        let inn = offset_ray_origin(p, err, n, -n);
        // Past the error box: the plane through any point of p ± err stays behind.
        let reach = n.abs().dot(err) as f64;
        let dist = |q: Vec3| (q.as_dvec3() - p.as_dvec3()).dot(n.as_dvec3());
        assert!(dist(out) > reach && dist(inn) < -reach);
    }

    #[test]
    fn step_toward_matches_next_up_and_next_down() {
        for v in [0.0f32, -0.0, 1.0, -1.0, 3.5e-42, -3.5e-42, f32::MIN_POSITIVE, -f32::MAX, 123.456] {
            assert_eq!(step_toward(v, 1.0).to_bits(), v.next_up().to_bits(), "{v} up");
            assert_eq!(step_toward(v, -2.0).to_bits(), v.next_down().to_bits(), "{v} down");
            assert_eq!(step_toward(v, 0.0).to_bits(), v.to_bits(), "{v} still");
        }
    }

    #[test]
    fn zero_error_still_moves_one_float_where_n_has_weight() {
        let p = Vec3::new(1.0, 1.0, 1.0);
        let q = offset_ray_origin(p, Vec3::splat(1e-7), Vec3::Y, Vec3::Y);
        assert!(q.y > p.y && q.x == p.x && q.z == p.z);
    }

    #[test]
    fn shadow_offsets_agree_with_surface_point_and_fixed_epsilon_moves_along_n() {
        let sp = SurfacePoint { p: Vec3::new(0.5, 1.0, -2.0), p_error: Vec3::splat(1e-6), n: Vec3::Y };
        let target = Vec3::new(1.0, 3.0, 0.0);
        assert_eq!(ShadowOffset::ErrorBound.spawn_ray_to_point(&sp, target), sp.spawn_ray_to_point(target));
        let r = ShadowOffset::FixedEpsilon(1e-3).spawn_ray(&sp, -Vec3::Y);
        assert!((r.origin - (sp.p - Vec3::new(0.0, 1e-3, 0.0))).length() < 1e-6);
    }

    #[test]
    fn segment_spans_unit_parameter() {
        let r = Ray::segment(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(r.at(r.t_max), Vec3::new(2.0, 0.0, 0.0));
        assert!(!Ray::segment(Vec3::ONE, Vec3::ONE).is_valid());
    }
}
