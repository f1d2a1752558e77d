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
use crate::lanes::{Real3, Vector};
use crate::sampling::sample_uniform_triangle_of;
use crate::sampling::spherical_f32::{MAX_REL_ERROR, TriangleView};

/// What the f32 path made of a sample or a hit: a result, or a case for the f64 reference.
enum Fast {
    Done(Option<ShapeSample>),
    Reference,
}

/// The triangle's strategy from `view` as the reference's `choose` picks it from its f64 solid
/// angle (`spherical`: true for solid-angle sampling), and where that is `known`: not where the
/// f32 bound straddles a band edge.
#[inline(always)]
fn spherical_strategy<F: Real3>(view: &TriangleView<F>) -> (F::Mask, F::Mask) {
    let (lo, hi) = (view.solid_angle - view.solid_angle_error, view.solid_angle + view.solid_angle_error);
    let spherical = lo.gt(F::splat(BAND_LO)) & hi.lt(F::splat(BAND_HI));
    let area = hi.lt(F::splat(MIN_SPHERICAL_SAMPLE_AREA * (1.0 - f32::EPSILON)))
        | lo.gt(F::splat(MAX_SPHERICAL_SAMPLE_AREA * (1.0 + f32::EPSILON)));
    (spherical, spherical | area)
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

/// A triangle light's sample from the f32 kernel, per value (one, or a lane each): where
/// `reference` holds, the f64 reference must decide; elsewhere a sample where `ok` holds (unit
/// `wi` toward point `p`, at barycentrics `b`, density `pdf`) and none where it does not.
#[derive(Clone, Copy, Debug)]
pub struct TriangleSample<F: Real3> {
    /// Unit direction toward `p`.
    pub wi: F::Vector,
    /// The sampled point on the triangle.
    pub p: F::Vector,
    /// Its barycentrics.
    pub b: [F; 3],
    /// Solid-angle density of `wi`, 1/sr.
    pub pdf: F,
    /// A finite sample (where `reference` does not hold).
    pub ok: F::Mask,
    /// Where only the f64 reference can decide.
    pub reference: F::Mask,
}

/// The f32 sampling of triangle `v` (unit `normal`, `area` > 0) from `p_ref` at `u`: the
/// reference's strategy (solid angle or area), computed in f32 where the error bounds allow.
/// Both strategies are computed and the one that applies is selected, so that it runs as one
/// lane kernel; [`AreaShape::sample_fast_with`] runs it at one value.
#[inline(always)]
pub fn sample_triangle<F: Real3>(
    v: [F::Vector; 3],
    normal: F::Vector,
    area: F,
    p_ref: F::Vector,
    u: [F; 2],
) -> TriangleSample<F> {
    let zero = F::splat(0.0);
    let (view, viewed) = TriangleView::<F>::new(v, normal * (area * 2.0), p_ref);
    let (spherical, known) = spherical_strategy(&view);
    let interpolate = |b: [F; 3]| v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
    // Solid angle: its density is 1 / solid angle, only where that is as accurate as the distance.
    let (tri, mapped) = view.spherical();
    let accurate = view.solid_angle_error.le(view.solid_angle * MAX_REL_ERROR);
    let wi_s = tri.sample(u);
    // Near an edge (not inside) the reference nudges the rounded direction in.
    let hit_s = view.edge_test(wi_s);
    let (p_s, pdf_s) = (interpolate(hit_s.b), F::splat(1.0) / view.solid_angle);
    // Area: t^2 / (|cos| A) with t to the plane along the rounded direction, as the reference.
    let b_a = sample_uniform_triangle_of(u[0], u[1]);
    let p_a = interpolate(b_a);
    let wi_a = (p_a - p_ref).normalize_or_zero();
    let hit_a = view.edge_test(wi_a);
    let t = view.distance_along(wi_a, normal);
    let pdf_a = t * t / (normal.dot(wi_a).abs() * area);
    let pick = |s: F, a: F| F::select(spherical, s, a);
    let (wi, p) = (F::Vector::select(spherical, wi_s, wi_a), F::Vector::select(spherical, p_s, p_a));
    let (b, pdf) = ([0, 1, 2].map(|i| pick(hit_s.b[i], b_a[i])), pick(pdf_s, pdf_a));
    let fast_s = spherical & mapped & accurate & hit_s.inside;
    let fast_a = !spherical & hit_a.inside;
    let reference = !(viewed & known & (fast_s | fast_a));
    // As `finite_sample`.
    let finite = pdf.is_finite() & pdf.gt(zero) & wi.is_finite() & wi.dot(wi).gt(zero) & p.is_finite();
    TriangleSample { wi, p, b, pdf, ok: finite & !reference, reference }
}

#[inline]
fn triangle(v: [Vec3; 3], uv: [Vec2; 3], normal: Vec3, area: f32, p_ref: Vec3, u: Vec2) -> Fast {
    let s = sample_triangle::<f32>(v, normal, area, p_ref, [u.x, u.y]);
    if s.reference {
        return Fast::Reference;
    }
    let uv = s.b[0] * uv[0] + s.b[1] * uv[1] + s.b[2] * uv[2];
    Fast::Done(s.ok.then_some(ShapeSample { point: SurfacePoint { p: s.p, n: normal, uv }, wi: s.wi, pdf: s.pdf }))
}

#[inline]
fn triangle_hit(v: [Vec3; 3], uv: [Vec2; 3], normal: Vec3, area: f32, p_ref: Vec3, wi: Vec3) -> Fast {
    let w = wi.normalize_or_zero();
    if w == Vec3::ZERO {
        return Fast::Done(None); // as the reference, which refuses a zero direction
    }
    let (view, viewed) = TriangleView::<f32>::new(v, normal * (area * 2.0), p_ref);
    if !viewed {
        return Fast::Reference;
    }
    // A sure miss needs no strategy: the exact ray misses too (outside an edge or behind).
    let hit = view.edge_test(w);
    if hit.outside {
        return Fast::Done(None);
    }
    let (spherical, known) = spherical_strategy(&view);
    if !hit.inside || !known {
        return Fast::Reference;
    }
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
    let b = hit.b;
    let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
    let uv = b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2];
    Fast::Done(finite_sample(SurfacePoint { p, n: normal, uv }, w, pdf))
}
