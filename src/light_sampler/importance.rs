//! The bounds algebra of a light BVH: unions of light bounds (box, orientation cone, power), the
//! cost that guides splits, and the importance of a cluster seen from a shading point.
//!
//! After Conty Estevez & Kulla 2018, "Importance Sampling of Many Lights with Adaptive Tree
//! Splitting" (orientation cones, the SAOH cost) and pbrt-v4 section 12.6.3 (`LightBounds`,
//! `Importance`). Pure math over [`LightBounds`]; bounds with `phi <= 0` mean "no light".

use std::f32::consts::PI;

use glam::{Quat, Vec3};

use crate::light::LightBounds;

/// Bounds of no light: zero power; unions skip it and its importance is 0.
pub const EMPTY_BOUNDS: LightBounds = LightBounds {
    min: Vec3::ZERO,
    max: Vec3::ZERO,
    phi: 0.0,
    w: Vec3::Z,
    cos_theta_o: 1.0,
    cos_theta_e: 1.0,
    two_sided: false,
};

/// Squared distances below this (m^2) are clamped, so a point on a point light gives a large,
/// finite importance rather than infinity.
pub(super) const MIN_DISTANCE_SQUARED: f32 = 1e-8;

/// Importances are clamped here so the sum of two stays finite.
pub(super) const MAX_IMPORTANCE: f32 = f32::MAX / 4.0;

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// cos(max(0, a - b)) from the sines and cosines of angles a, b in [0, pi].
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// sin(max(0, a - b)) from the sines and cosines of angles a, b in [0, pi].
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

/// Angle between unit vectors, accurate for small and large angles.
#[inline]
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The smallest cone (axis, cosine of half-angle) containing cones `a` and `b`
/// (pbrt-v4 section 3.8.4, `Union(DirectionCone, DirectionCone)`).
pub fn cone_union(wa: Vec3, cos_a: f32, wb: Vec3, cos_b: f32) -> (Vec3, f32) {
    if cos_a <= -1.0 || cos_b <= -1.0 {
        return (wa, -1.0);
    }
    let (theta_a, theta_b) = (cos_a.clamp(-1.0, 1.0).acos(), cos_b.clamp(-1.0, 1.0).acos());
    let theta_d = angle_between(wa, wb);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (wa, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (wb, cos_b);
    }
    // The merged cone spans from a's far edge to b's far edge; rotate a's axis toward b.
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (wa, -1.0);
    }
    let axis = wa.cross(wb);
    if axis.length_squared() < 1e-20 {
        return (wa, -1.0);
    }
    let w = Quat::from_axis_angle(axis.normalize(), theta_o - theta_a) * wa;
    (w.normalize(), theta_o.cos())
}

/// Union of two light bounds; bounds without power are skipped (pbrt-v4 `Union(LightBounds, ...)`).
pub fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
    if !(a.phi > 0.0) {
        return *b;
    }
    if !(b.phi > 0.0) {
        return *a;
    }
    let (w, cos_theta_o) = cone_union(a.w, a.cos_theta_o, b.w, b.cos_theta_o);
    LightBounds {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
        phi: a.phi + b.phi,
        w,
        cos_theta_o,
        cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
        two_sided: a.two_sided || b.two_sided,
    }
}

/// Conty & Kulla's orientation measure M_Omega: the cosine-weighted solid angle of a cone of
/// normals (half-angle theta_o) widened by the emission spread theta_e (their eq. 1; pbrt-v4
/// `EvaluateCost`). 4 pi for lights that emit everywhere.
pub fn orientation_measure(cos_theta_o: f32, cos_theta_e: f32) -> f32 {
    if cos_theta_o <= -1.0 {
        return 4.0 * PI;
    }
    let theta_o = cos_theta_o.clamp(-1.0, 1.0).acos();
    let theta_e = cos_theta_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = safe_sqrt(1.0 - cos_theta_o * cos_theta_o);
    2.0 * PI * (1.0 - cos_theta_o)
        + PI / 2.0 * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + cos_theta_o)
}

/// Surface area of the bounds' box, m^2.
#[inline]
pub fn surface_area(b: &LightBounds) -> f32 {
    let d = (b.max - b.min).max(Vec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

/// A cluster's cost: power x orientation measure x box surface area (the SAOH of Conty & Kulla
/// without the split-axis factor). 0 for bounds without power.
pub fn cluster_cost(b: &LightBounds) -> f32 {
    cluster_cost_with(b, orientation_measure(b.cos_theta_o, b.cos_theta_e))
}

/// [`cluster_cost`] given the bounds' orientation measure.
#[inline]
pub fn cluster_cost_with(b: &LightBounds, orientation: f32) -> f32 {
    if !(b.phi > 0.0) {
        return 0.0;
    }
    b.phi * orientation * surface_area(b)
}

/// A cluster's bounds in the form the importance reads, with what can be precomputed (the box's
/// radius, the sine of the normal-cone angle): 56 bytes, so a tree node with it fits 64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterQuery {
    pub(super) min: Vec3,
    pub(super) max: Vec3,
    pub(super) w: Vec3,
    pub(super) phi: f32,
    /// Radius of the box's bounding sphere; its sign bit is the two-sided flag (so the flag
    /// takes no bytes of its own).
    pub(super) signed_radius: f32,
    pub(super) cos_theta_o: f32,
    pub(super) sin_theta_o: f32,
    pub(super) cos_theta_e: f32,
}

impl From<&LightBounds> for ClusterQuery {
    fn from(b: &LightBounds) -> Self {
        let radius = 0.5 * (b.max - b.min).length();
        Self {
            min: b.min,
            max: b.max,
            w: b.w,
            phi: if b.phi > 0.0 { b.phi } else { 0.0 },
            signed_radius: if b.two_sided { -radius } else { radius },
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o),
            cos_theta_e: b.cos_theta_e,
        }
    }
}

impl ClusterQuery {
    /// The bounds this was made from (power clamped at 0).
    pub fn bounds(&self) -> LightBounds {
        LightBounds {
            min: self.min,
            max: self.max,
            phi: self.phi,
            w: self.w,
            cos_theta_o: self.cos_theta_o,
            cos_theta_e: self.cos_theta_e,
            two_sided: self.two_sided(),
        }
    }
    #[inline]
    pub(super) fn two_sided(&self) -> bool {
        self.signed_radius.is_sign_negative()
    }
}

/// How much light the cluster `b` can send to a point `p` with normal `n` (zero for no normal);
/// see [`ClusterQuery::importance`].
#[inline]
pub fn importance(b: &LightBounds, p: Vec3, n: Vec3) -> f32 {
    ClusterQuery::from(b).importance(p, n)
}

impl ClusterQuery {
    /// How much light the cluster can send to a point `p` with normal `n` (zero for no normal):
    /// power over squared distance, times the cosine of the smallest angle between emission and
    /// the direction to `p`, times the cosine at the receiver, both taken conservatively over the
    /// box (Conty & Kulla 2018, section 4.3; pbrt-v4 `LightBounds::Importance`). Unnormalised:
    /// only ratios between siblings matter. 0 when `p` lies outside every emission cone.
    ///
    /// Two changes from pbrt-v4, both measured on the scaling scene (`kelvin bench lights`):
    /// - The squared distance to the centre is clamped below at radius x gap, the geometric mean
    ///   of the box's radius and its distance from `p` (at least radius / 8): a cluster next to
    ///   or around `p` is not weighed as if its power sat at its centre. pbrt clamps at the
    ///   half-diagonal's length, which is not scale-free; this is, and does as well.
    /// - The receiver cosine is also bounded by the box's extent along `n` over its distance
    ///   from `p`, much tighter than the bounding-sphere cone for wide, flat clusters seen at
    ///   grazing angles.
    #[inline(always)]
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        if self.phi == 0.0 {
            return 0.0;
        }
        let radius = self.signed_radius.abs();
        let to_p = p - 0.5 * (self.min + self.max);
        let dist2 = to_p.length_squared();
        let gap = (self.min - p).max(p - self.max).max(Vec3::ZERO).length();
        let d2 = (dist2.sqrt() * gap).max(radius * radius / 64.0).max(MIN_DISTANCE_SQUARED);
        let inv_dist = if dist2 > 0.0 { dist2.sqrt().recip() } else { 0.0 };
        let wi = to_p * inv_dist;

        // Angle subtended by the box's bounding sphere from p: all directions when p is inside.
        let (sin_b, cos_b) = if dist2 <= radius * radius {
            (0.0, -1.0)
        } else {
            let sin_b = radius * inv_dist;
            (sin_b, safe_sqrt(1.0 - sin_b * sin_b))
        };

        // theta' = max(0, theta_w - theta_o - theta_b): the smallest angle between an emission
        // direction of the cluster and the direction toward p.
        let cos_p = if self.cos_theta_o <= -1.0 {
            1.0
        } else {
            let mut cos_w = self.w.dot(wi);
            if self.two_sided() {
                cos_w = cos_w.abs();
            }
            let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
            let cos_x = cos_sub_clamped(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
            let sin_x = sin_sub_clamped(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
            cos_sub_clamped(sin_x, cos_x, sin_b, cos_b)
        };
        // Strict, so a hard-edged spot (theta_e = 0, cos_theta_e = 1) still counts inside its cone.
        if cos_p < self.cos_theta_e {
            return 0.0;
        }
        // Emission toward p: Conty & Kulla's cos theta' for Lambertian spreads (theta_e = pi/2);
        // for narrower spreads (spot falloff bands) a smoothstep from 1 at theta' = 0 to 0 at
        // theta_e, the spot's own profile, rather than a cosine still near 1 at the beam's edge.
        let emission = if self.cos_theta_e <= 0.0 || cos_p >= 1.0 {
            cos_p
        } else {
            let t = (cos_p - self.cos_theta_e) / (1.0 - self.cos_theta_e);
            t * t * (3.0 - 2.0 * t)
        };
        let mut value = self.phi * emission / d2;

        // Receiver cosine, two-sided (transmission), conservative over the box.
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            let cone_bound = cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
            // The box's largest offset along n from the plane through p, over its distance.
            let (lo, hi) = ((self.min - p) * n, (self.max - p) * n);
            let offset = lo.max(hi).element_sum().max(-lo.min(hi).element_sum());
            let plane_bound = if offset >= gap { 1.0 } else { offset / gap };
            let bound = cone_bound.min(plane_bound);
            value *= bound;
        }
        value.clamp(0.0, MAX_IMPORTANCE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(p: Vec3, phi: f32) -> LightBounds {
        LightBounds { min: p, max: p, phi, w: Vec3::Z, cos_theta_o: -1.0, cos_theta_e: 0.0, two_sided: false }
    }

    fn spot(p: Vec3, w: Vec3, cos_o: f32) -> LightBounds {
        LightBounds { min: p, max: p, phi: 1.0, w, cos_theta_o: cos_o, cos_theta_e: 1.0, two_sided: false }
    }

    #[test]
    fn cone_union_contains_both_cones() {
        let dirs = [Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0).normalize(), Vec3::new(0.3, -0.2, 0.9).normalize()];
        for &a in &dirs {
            for &b in &dirs {
                for (ca, cb) in [(0.9, 0.95), (0.5, 0.99), (0.0, 0.7)] {
                    let (w, c) = cone_union(a, ca, b, cb);
                    let angle = |v: Vec3, cv: f32| angle_between(w, v) + f32::acos(cv);
                    assert!(angle(a, ca) <= c.acos() + 1e-4, "a {a} b {b}");
                    assert!(angle(b, cb) <= c.acos() + 1e-4, "a {a} b {b}");
                }
            }
        }
        // Opposite axes have no unique merged axis: the whole sphere, conservatively.
        assert_eq!(cone_union(Vec3::X, 0.9, Vec3::NEG_X, 0.9).1, -1.0);
        let (w, c) = cone_union(Vec3::X, 1.0, Vec3::Y, 1.0);
        assert!((w - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6 && (c - 0.5f32.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn union_skips_empty_bounds_and_adds_power() {
        let a = point(Vec3::ONE, 2.0);
        assert_eq!(union(&a, &EMPTY_BOUNDS), a);
        assert_eq!(union(&EMPTY_BOUNDS, &a), a);
        let u = union(&a, &point(-Vec3::ONE, 3.0));
        assert_eq!((u.min, u.max, u.phi), (-Vec3::ONE, Vec3::ONE, 5.0));
    }

    #[test]
    fn orientation_measure_of_full_sphere_and_hemisphere() {
        // theta_o = pi: 4 pi. theta_o = 0, theta_e = pi/2 (a Lambertian emitter): pi.
        assert!((orientation_measure(-1.0, 0.0) - 4.0 * PI).abs() < 1e-5);
        assert!((orientation_measure(1.0, 0.0) - PI).abs() < 1e-5);
    }

    #[test]
    fn importance_of_a_point_light_is_power_over_distance_squared() {
        let b = point(Vec3::new(0.0, 2.0, 0.0), 8.0);
        let v = importance(&b, Vec3::ZERO, Vec3::ZERO);
        assert!((v - 2.0).abs() < 1e-6);
        // With a receiver normal at 60 degrees to the light.
        let n = Vec3::new(3f32.sqrt() / 2.0, 0.5, 0.0);
        assert!((importance(&b, Vec3::ZERO, n) - 1.0).abs() < 1e-5);
        // On the light: large and finite.
        assert!(importance(&b, b.min, Vec3::ZERO).is_finite());
    }

    #[test]
    fn importance_is_zero_outside_a_spot_cone() {
        let s = spot(Vec3::ZERO, Vec3::NEG_Y, 0.9);
        assert!(importance(&s, Vec3::new(0.0, -3.0, 0.0), Vec3::ZERO) > 0.0);
        assert_eq!(importance(&s, Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO), 0.0);
        assert_eq!(importance(&EMPTY_BOUNDS, Vec3::ONE, Vec3::ZERO), 0.0);
    }
}
