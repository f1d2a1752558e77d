//! The f32 paths of [`AreaShape::sample`] and [`AreaShape::hit`]: the same strategies and maps,
//! computed in f32 where error bounds show it is accurate (see `sampling::spherical_f32`), and
//! the f64 reference everywhere else, decided per reference point and, at edges, per direction.
//!
//! It keeps `sample`'s guarantee without re-intersecting: a direction is returned only if its
//! f32 barycentrics clear every edge by more than their rounding error, so the exact ray (and
//! `hit`, in f64) meets the shape too; and only where the f32 solid angle's error bound leaves
//! no doubt about which strategy `hit` picks, so `hit` gives the same density (to the bound,
//! under `MAX_REL_ERROR` = 2e-5 relative). `hit_fast` decides the strategy from the same
//! [`TriangleView`], so for a sampled direction both give the same density (bit for bit where
//! both stay in f32).

use glam::{Vec2, Vec3};

use super::shapes::{
    AreaShape, MAX_SPHERICAL_SAMPLE_AREA, MIN_SPHERICAL_SAMPLE_AREA, ShapeSample, SurfacePoint, finite_sample,
};
use crate::sampling::sample_uniform_triangle;
use crate::sampling::spherical_f32::{EdgeTest, MAX_REL_ERROR, TriangleView};

/// What the f32 path made of a sample or a hit: a result, or a case for the f64 reference.
enum Fast {
    Done(Option<ShapeSample>),
    Reference,
}

/// The triangle's strategy from `view` as the reference's `choose` picks it from its f64 solid
/// angle (true: spherical), or None where the f32 bound straddles a band edge.
#[inline]
fn spherical_strategy(view: &TriangleView) -> Option<bool> {
    let (lo, hi) = (view.solid_angle - view.solid_angle_error, view.solid_angle + view.solid_angle_error);
    if lo > BAND_LO && hi < BAND_HI {
        Some(true)
    } else if hi < MIN_SPHERICAL_SAMPLE_AREA * (1.0 - f32::EPSILON)
        || lo > MAX_SPHERICAL_SAMPLE_AREA * (1.0 + f32::EPSILON)
    {
        Some(false)
    } else {
        None // too close to a band edge to know `hit`'s choice
    }
}

impl AreaShape {
    /// [`AreaShape::sample`] through the f32 kernels: the same strategy, density and (to ~1e-5
    /// of the shape's size) the same direction for the same `u`, with the same guarantee that
    /// `wi` hits the shape and [`AreaShape::hit`] gives it the same density (to 2e-5 relative).
    pub fn sample_fast(&self, p_ref: Vec3, u: Vec2) -> Option<ShapeSample> {
        self.sample_fast_with(self.plane_normal().unwrap_or(Vec3::ZERO), self.area(), p_ref, u)
    }

    /// [`Self::sample_fast`] with the shape's [`AreaShape::plane_normal`] (zero for none) and
    /// [`AreaShape::area`] computed once by the caller.
    #[inline]
    pub fn sample_fast_with(&self, normal: Vec3, area: f32, p_ref: Vec3, u: Vec2) -> Option<ShapeSample> {
        let fast = match *self {
            Self::Triangle { p, uv } if area > 0.0 && normal != Vec3::ZERO && p_ref.is_finite() => {
                triangle(p, uv, normal, area, p_ref, u)
            }
            Self::Sphere { .. } | Self::Disk { .. } | Self::Rectangle { .. } | Self::Triangle { .. } => Fast::Reference,
        };
        match fast {
            Fast::Done(s) => s,
            Fast::Reference => self.sample(p_ref, u),
        }
    }

    /// [`AreaShape::hit`] through the f32 kernels: the same hit or miss, the same density (to
    /// 2e-5 relative) and the surface point to f32 rounding; the f64 reference where the error
    /// bounds cannot tell (the point near the plane, the solid angle near a band edge, the
    /// direction within rounding of an edge).
    pub fn hit_fast(&self, p_ref: Vec3, wi: Vec3) -> Option<ShapeSample> {
        self.hit_fast_with(self.plane_normal().unwrap_or(Vec3::ZERO), self.area(), p_ref, wi)
    }

    /// [`Self::hit_fast`] with [`AreaShape::plane_normal`] (zero for none) and
    /// [`AreaShape::area`] computed once by the caller.
    #[inline]
    pub fn hit_fast_with(&self, normal: Vec3, area: f32, p_ref: Vec3, wi: Vec3) -> Option<ShapeSample> {
        let fast = match *self {
            Self::Triangle { p, uv } if area > 0.0 && normal != Vec3::ZERO && p_ref.is_finite() && wi.is_finite() => {
                triangle_hit(p, uv, normal, area, p_ref, wi)
            }
            Self::Sphere { .. } | Self::Disk { .. } | Self::Rectangle { .. } | Self::Triangle { .. } => Fast::Reference,
        };
        match fast {
            Fast::Done(s) => s,
            Fast::Reference => self.hit(p_ref, wi),
        }
    }
}

/// Bounds of the spherical band in which `hit`'s rounded f64 solid angle may fall (one f32 ulp).
const BAND_LO: f32 = MIN_SPHERICAL_SAMPLE_AREA * (1.0 + f32::EPSILON);
const BAND_HI: f32 = MAX_SPHERICAL_SAMPLE_AREA * (1.0 - f32::EPSILON);

#[inline]
fn triangle(v: [Vec3; 3], uv: [Vec2; 3], normal: Vec3, area: f32, p_ref: Vec3, u: Vec2) -> Fast {
    let Some(view) = TriangleView::new(v, normal * (2.0 * area), p_ref) else {
        return Fast::Reference;
    };
    let Some(spherical) = spherical_strategy(&view) else {
        return Fast::Reference;
    };
    let interpolate = |b: [f32; 3]| {
        let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
        (p, b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2])
    };
    let (wi, p, uv, pdf) = if spherical {
        // Its density is 1 / solid angle: only where that is as accurate as the distance.
        let Some(tri) = view.spherical().filter(|_| view.solid_angle_error <= MAX_REL_ERROR * view.solid_angle) else {
            return Fast::Reference;
        };
        let wi = tri.sample(u);
        let Some(b) = view.barycentrics(wi) else {
            return Fast::Reference; // near an edge: the reference nudges the rounded direction in
        };
        let (p, uv) = interpolate(b);
        (wi, p, uv, 1.0 / view.solid_angle)
    } else {
        let (p, uv) = interpolate(sample_uniform_triangle(u));
        let wi = (p - p_ref).normalize_or_zero();
        if view.barycentrics(wi).is_none() {
            return Fast::Reference;
        }
        // t^2 / (|cos| A) with t to the plane along the rounded direction, as the reference.
        let t = view.distance_along(wi, normal);
        (wi, p, uv, t * t / (normal.dot(wi).abs() * area))
    };
    Fast::Done(finite_sample(SurfacePoint { p, n: normal, uv }, wi, pdf))
}

#[inline]
fn triangle_hit(v: [Vec3; 3], uv: [Vec2; 3], normal: Vec3, area: f32, p_ref: Vec3, wi: Vec3) -> Fast {
    let w = wi.normalize_or_zero();
    if w == Vec3::ZERO {
        return Fast::Done(None); // as the reference, which refuses a zero direction
    }
    let Some(view) = TriangleView::new(v, normal * (2.0 * area), p_ref) else {
        return Fast::Reference;
    };
    // A sure miss needs no strategy: the exact ray misses too (outside an edge or behind).
    let b = match view.edge_test(w) {
        EdgeTest::Inside(b) => b,
        EdgeTest::Outside => return Fast::Done(None),
        EdgeTest::Unsure => return Fast::Reference,
    };
    let Some(spherical) = spherical_strategy(&view) else {
        return Fast::Reference;
    };
    let pdf = if spherical {
        // 1 / solid angle, as `sample_fast` gives it, where that is as accurate as the distance.
        if view.solid_angle_error > MAX_REL_ERROR * view.solid_angle {
            return Fast::Reference;
        }
        1.0 / view.solid_angle
    } else {
        let t = view.distance_along(w, normal);
        t * t / (normal.dot(w).abs() * area)
    };
    let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
    let uv = b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2];
    Fast::Done(finite_sample(SurfacePoint { p, n: normal, uv }, w, pdf))
}
