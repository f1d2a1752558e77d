//! The f32 kernel of triangle sampling from a point: the same maps as [`super::spherical`]'s f64
//! reference (Arvo 1995 in its half-angle form, Van Oosterom-Strackee areas), with the rounding
//! error of every step bounded, so that a caller can tell where f32 is accurate enough and use
//! the f64 reference elsewhere. No libm: atan and sin/cos are polynomials with tested error.
//!
//! Every quantity is taken from the vertices relative to the point, r_i = v_i - p, and the edges
//! e1 = v1 - v0, e2 = v2 - v0, e12 = v2 - v1 (each one f32 rounding of exact differences), never
//! from differences of normalised directions, which lose digits for small triangles:
//! - r0 . N (N = e1 x e2, accurate from the caller) gives the distance to the plane;
//! - r0 x e1 = r0 x r1, r0 x e2 = r0 x r2 and r1 x e12 = r1 x r2 give the arcs' sines, the angle at
//!   v0 and the barycentrics of any direction (b_i is proportional to w . (r_{i+1} x r_{i+2})).
//!
//! Written once over [`Real`]: `f32` for one point, `F32x16` for a lane each. Branches are masks:
//! [`TriangleView::new`] does not hold where a bound says f32 loses more than [`MAX_REL_ERROR`]:
//! the point within ~1.4 degrees of the plane as seen from the farthest vertex (r . N cancels),
//! or (for sampling, [`TriangleView::spherical`]) an arc or Arvo's sine denominator so
//! ill-conditioned that the map would move by more than ~1e-5 of the triangle's size.

use std::f32::consts::PI;

use crate::lanes::math::{ATAN_REL_ERROR, atan2_pos, sin_cos_0_pi};
use crate::lanes::{Real, Real3, Vector};

/// Largest relative error of the distance to the plane (and so of solid angles and area-sampling
/// densities) that the f32 kernel accepts: 2e-5, well under the 1e-4 at which a sample's density
/// and `pdf_li` are tested to agree.
pub const MAX_REL_ERROR: f32 = 2e-5;

/// Largest condition number (relative error out per relative error in) of the spherical map's
/// arcs and of Arvo's denominator sin(alpha - A'/2): ~100 * 6 eps ~ 1e-4 of the triangle's size.
const MAX_CONDITION: f32 = 100.0;

const EPS: f32 = f32::EPSILON;

/// Where a direction goes relative to the triangle, as far as f32 rounding can tell, per value:
/// at most one of `inside` and `outside` holds; neither means within rounding of an edge (or of
/// the plane), where the f64 reference decides.
#[derive(Clone, Copy, Debug)]
pub struct EdgeTest<F: Real> {
    /// It meets the triangle in front of the point, clear of every edge...
    pub inside: F::Mask,
    /// ...with these barycentrics.
    pub b: [F; 3],
    /// It surely misses.
    pub outside: F::Mask,
}

/// A triangle seen from a point in f32, with its solid angle and an error bound; what both area
/// and solid-angle sampling need from the point. `F` is `f32` (one point) or `F32x16` (a lane
/// each).
#[derive(Clone, Copy, Debug)]
pub struct TriangleView<F: Real3> {
    r0: F::Vector,
    r1: F::Vector,
    l: [F; 3],
    /// r1 x r2, r2 x r0, r0 x r1 (barycentric numerators' normals).
    n_bc: F::Vector,
    n_ac: F::Vector,
    n_ab: F::Vector,
    /// |r| |e| of each of those crosses: w . n may have the wrong sign below 16 eps |r| |e|
    /// (3x the bound on its rounding error).
    scale: [F; 3],
    /// sign of r0 . N: +1 when the point is on the side N points to.
    side: F,
    /// Cosines between the vertex directions (a.b, a.c).
    cos_ab: F,
    cos_ac: F,
    /// |r0 . N|, and Van Oosterom-Strackee's atan2 arguments on unit vectors.
    det_abs: F,
    det: F,
    denom: F,
    /// Solid angle (sr) and a bound on its absolute error.
    pub solid_angle: F,
    /// Bound on the absolute error of `solid_angle`, sr.
    pub solid_angle_error: F,
    /// |N| = twice the triangle's area.
    cross_len: F,
}

impl<F: Real3> TriangleView<F> {
    /// The triangle `v` seen from `p`, given `cross` = (v1 - v0) x (v2 - v0) to f32 precision
    /// (the caller's f64 value rounded), and where it holds: not where the distance to the plane
    /// would carry a relative error above [`MAX_REL_ERROR`] (the point in or near the plane) or
    /// anything is not finite.
    #[inline(always)]
    pub fn new(v: [F::Vector; 3], cross: F::Vector, p: F::Vector) -> (Self, F::Mask) {
        let one = F::splat(1.0);
        let (r0, r1, r2) = (v[0] - p, v[1] - p, v[2] - p);
        let (e1, e2, e12) = (v[1] - v[0], v[2] - v[0], v[2] - v[1]);
        let l = [r0.length(), r1.length(), r2.length()];
        let l_max = l[0].max(l[1]).max(l[2]);
        let cross_len = cross.length();
        let det = r0.dot(cross);
        // r0 . N: 3 eps |r0| |N| (roundings of r0, N and the dot); the farthest vertex bounds the
        // density's error too (its cosine is det / (|N| l)).
        let near = l_max * (4.0 * EPS) * cross_len;
        let mut ok = near.le(det.abs() * MAX_REL_ERROR) & (l[0] * l[1] * l[2]).is_finite();
        let inv = [one / l[0], one / l[1], one / l[2]];
        let cos_ab = r0.dot(r1) * inv[0] * inv[1];
        let cos_ac = r0.dot(r2) * inv[0] * inv[2];
        let cos_bc = r1.dot(r2) * inv[1] * inv[2];
        // Van Oosterom-Strackee on unit vectors: tan(A / 2) = |det'| / (1 + cos_ab + cos_ac + cos_bc).
        let det_u = det.abs() * inv[0] * inv[1] * inv[2];
        let denom = cos_ab + 1.0 + cos_ac + cos_bc;
        let solid_angle = atan2_pos(det_u, denom) * 2.0;
        // dA = 2 (denom d(det') - det' d(denom)) / (det'^2 + denom^2), with d(det') <= 8 eps det'
        // (the distance bound plus the three 1 / l) and d(denom) <= 8 eps (three cosines).
        let d_det = (near / det.abs() + 4.0 * EPS) * det_u;
        let d_denom = 8.0 * EPS;
        let solid_angle_error = (denom.abs() * d_det + det_u * d_denom) * 2.0 / (det_u * det_u + denom * denom)
            + solid_angle * ATAN_REL_ERROR;
        let (n_ab, n_ac, n_bc) = (r0.cross(e1), r0.cross(e2), r1.cross(e12));
        let scale = [l[1] * e12.length(), l[0] * e2.length(), l[0] * e1.length()];
        ok = ok & solid_angle.is_finite() & solid_angle_error.is_finite();
        let side = F::select(det.lt(F::splat(0.0)), F::splat(-1.0), one);
        let view = Self {
            r0,
            r1,
            l,
            n_bc,
            n_ac,
            n_ab,
            scale,
            side,
            cos_ab,
            cos_ac,
            det_abs: det.abs(),
            det: det_u,
            denom,
            solid_angle,
            solid_angle_error,
            cross_len,
        };
        (view, ok)
    }

    /// Where the ray along unit `w` goes: inside (with its barycentrics) only with a margin that
    /// f32 rounding cannot cross, so that the exact ray (and the f64 reference's test) hits the
    /// triangle too, in front of the point and not grazing; outside only where some edge's
    /// numerator is negative by more than its rounding error, so the exact ray misses (outside
    /// that edge, or behind the point).
    #[inline(always)]
    pub fn edge_test(&self, w: F::Vector) -> EdgeTest<F> {
        let x = [w.dot(self.n_bc) * self.side, -w.dot(self.n_ac) * self.side, w.dot(self.n_ab) * self.side];
        let margin = [self.scale[0] * (16.0 * EPS), self.scale[1] * (16.0 * EPS), self.scale[2] * (16.0 * EPS)];
        let outside = x[0].lt(-margin[0]) | x[1].lt(-margin[1]) | x[2].lt(-margin[2]);
        let sum = x[0] + x[1] + x[2];
        // w . N = sum: its cosine with the plane must dwarf an f32 normal's error too.
        let clear = x[0].ge(margin[0]) & x[1].ge(margin[1]) & x[2].ge(margin[2]);
        let inside = clear & sum.ge(self.cross_len * (4.0 * EPS)) & !outside;
        EdgeTest { inside, b: [x[0] / sum, x[1] / sum, x[2] / sum], outside }
    }

    /// Distance along `w` to the plane (for densities t^2 / (|cos| A)).
    #[inline(always)]
    pub fn distance_along(&self, w: F::Vector, normal: F::Vector) -> F {
        self.r0.dot(normal) / w.dot(normal)
    }

    /// The solid-angle sampler of this view, and where it holds: not where its map is too
    /// ill-conditioned for f32 (an arc from v0 seen nearly end-on, or Arvo's denominator near 0:
    /// triangles close to a hemisphere); the f64 reference takes those.
    #[inline(always)]
    pub fn spherical(&self) -> (SphericalTriangleF32<F>, F::Mask) {
        let (zero, one) = (F::splat(0.0), F::splat(1.0));
        let (n_ab_len, n_ac_len) = (self.n_ab.length(), self.n_ac.length());
        let l = self.l;
        // sin(arc) = |r x e| / (l l'): relative error ~ eps l |e| / |r x e| (that is, 1 / sin of
        // the angle between r0 and the edge).
        let sin_ab = n_ab_len / (l[0] * l[1]);
        let sin_ac = n_ac_len / (l[0] * l[2]);
        let (cond_ab, cond_ac) = (self.scale[2] / n_ab_len, self.scale[1] / n_ac_len);
        // tan(arc / 2) without cancellation on either side of a quarter circle.
        let tan_half = |s: F, c: F| F::select(c.ge(zero), s / (c + 1.0), (one - c) / s);
        let tan_half_ab = tan_half(sin_ab, self.cos_ab);
        let tan_half_ac = tan_half(sin_ac, self.cos_ac);
        // (r0 x r1) x (r0 x r2) = r0 det: the angle at a.
        let inv_nn = one / (n_ab_len * n_ac_len);
        let sin_alpha = self.det_abs * inv_nn * l[0];
        let cos_alpha = self.n_ab.dot(self.n_ac) * inv_nn;
        // sin(alpha - h) over h in [0, A/2] is smallest at an end (sin is concave on [0, pi]);
        // its rounding error is eps (sin alpha + sin h).
        let hyp = (self.det * self.det + self.denom * self.denom).sqrt();
        let (sin_half_a, cos_half_a) = (self.det / hyp, self.denom / hyp);
        let den_end = sin_alpha * cos_half_a - cos_alpha * sin_half_a;
        let sin_h_max = F::select(cos_half_a.lt(zero), one, sin_half_a);
        let cond_den = (sin_alpha + sin_h_max) / den_end.min(sin_alpha);
        let toward_c = self.n_ac.cross(self.r0).normalize_or_zero();
        let limit = F::splat(MAX_CONDITION);
        let ok = cond_ab.le(limit)
            & cond_ac.le(limit)
            & den_end.gt(zero)
            & cond_den.le(limit)
            & tan_half_ab.gt(zero)
            & tan_half_ac.is_finite()
            & toward_c.dot(toward_c).gt(zero);
        let tri = SphericalTriangleF32 {
            a: self.r0 * (one / l[0]),
            b: self.r1 * (one / l[1]),
            toward_c,
            sin_alpha,
            cos_alpha,
            tan_half_ab,
            tan_half_ac,
            area: self.solid_angle,
        };
        (tri, ok)
    }
}

/// Arvo's sampler in f32 (see `SphericalTriangle::sample` in the f64 reference for the
/// derivation of the half-angle form).
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangleF32<F: Real3> {
    a: F::Vector,
    b: F::Vector,
    toward_c: F::Vector,
    sin_alpha: F,
    cos_alpha: F,
    tan_half_ab: F,
    tan_half_ac: F,
    area: F,
}

impl<F: Real3> SphericalTriangleF32<F> {
    /// The unit direction that `u` maps to, as the f64 reference maps it (to ~1e-5 of the
    /// triangle's size where [`TriangleView::spherical`] holds).
    #[inline(always)]
    pub fn sample(&self, u: [F; 2]) -> F::Vector {
        let (zero, one) = (F::splat(0.0), F::splat(1.0));
        let (sin_h, cos_h) = sin_cos_0_pi((u[0] * 0.5 * self.area).max(zero).min(F::splat(PI)));
        // t = tan(arc a-c' / 2) = sin(h) / (k sin(alpha - h)).
        let denom = self.tan_half_ab * (self.sin_alpha * cos_h - self.cos_alpha * sin_h);
        let t = F::select(denom.gt(zero), (sin_h / denom).min(self.tan_half_ac), self.tan_half_ac);
        let t2 = t * t;
        let inv = one / (t2 + 1.0);
        let c_p = self.a * ((one - t2) * inv) + self.toward_c * (t * 2.0 * inv);
        let s = u[1].max(zero).sqrt() * 0.5 * (c_p - self.b).length();
        let cos_theta = one - s * 2.0 * s;
        let sin_theta = s * 2.0 * (one - s * s).max(zero).sqrt();
        let tangent = (c_p - self.b * c_p.dot(self.b)).normalize_or_zero();
        (self.b * cos_theta + tangent * sin_theta).normalize()
    }
}
