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
//! [`TriangleView::new`] refuses (None) where a bound says f32 loses more than [`MAX_REL_ERROR`]:
//! the point within ~1.4 degrees of the plane as seen from the farthest vertex (r . N cancels),
//! or (for sampling, [`TriangleView::spherical`]) an arc or Arvo's sine denominator so
//! ill-conditioned that the map would move by more than ~1e-5 of the triangle's size.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3};

/// Largest relative error of the distance to the plane (and so of solid angles and area-sampling
/// densities) that the f32 kernel accepts: 2e-5, well under the 1e-4 at which a sample's density
/// and `pdf_li` are tested to agree.
pub const MAX_REL_ERROR: f32 = 2e-5;

/// Largest condition number (relative error out per relative error in) of the spherical map's
/// arcs and of Arvo's denominator sin(alpha - A'/2): ~100 * 6 eps ~ 1e-4 of the triangle's size.
const MAX_CONDITION: f32 = 100.0;

/// Relative error bound of [`atan2_pos`] (Cephes `atanf`: 1.9e-7, plus the range reduction).
const ATAN_REL_ERROR: f32 = 4e-7;

const EPS: f32 = f32::EPSILON;

/// atan2(y, x) for y >= 0, in [0, pi]: octant reduction and the Cephes `atanf` polynomial
/// (Moshier 1989), relative error < 4e-7 (tested against f64).
#[inline]
pub fn atan2_pos(y: f32, x: f32) -> f32 {
    let ax = x.abs();
    let (num, den) = if y <= ax { (y, ax) } else { (ax, y) };
    let z = if den > 0.0 { num / den } else { 0.0 };
    // atan on [0, 1]: around 1 through atan(z) = pi/4 + atan((z - 1) / (z + 1)).
    let (base, z) = if z > 0.414_213_57 { (FRAC_PI_4, (z - 1.0) / (z + 1.0)) } else { (0.0, z) };
    let z2 = z * z;
    let poly = (((8.053_744_5e-2 * z2 - 1.387_768_6e-1) * z2 + 1.997_771_1e-1) * z2 - 3.333_295e-1) * z2 * z + z;
    let r = base + poly;
    let r = if y <= ax { r } else { FRAC_PI_2 - r };
    if x < 0.0 { PI - r } else { r }
}

/// (sin x, cos x) for x in [0, pi]: Taylor polynomials of x/2 (terms to x^11 and x^12, whose
/// remainders at pi/2 are 6e-8 and 7e-9) and the double-angle formulas, which keep sin's
/// relative accuracy near 0. Errors < 3e-7, absolute, and relative for sin on [0, pi/2]
/// (tested); near pi, x itself carries more.
#[inline]
pub fn sin_cos_0_pi(x: f32) -> (f32, f32) {
    let h = 0.5 * x;
    let h2 = h * h;
    let s = h * (1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0 * (1.0 - h2 / 72.0 * (1.0 - h2 / 110.0)))));
    let c = 1.0
        - h2 / 2.0 * (1.0 - h2 / 12.0 * (1.0 - h2 / 30.0 * (1.0 - h2 / 56.0 * (1.0 - h2 / 90.0 * (1.0 - h2 / 132.0)))));
    // cos x from whichever of sin, cos (x/2) is under 1/sqrt 2, halving its error.
    (2.0 * s * c, if h < FRAC_PI_4 { 1.0 - 2.0 * s * s } else { 2.0 * c * c - 1.0 })
}

/// Where a direction goes relative to the triangle, as far as f32 rounding can tell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeTest {
    /// It meets the triangle in front of the point, with these barycentrics, clear of every edge.
    Inside([f32; 3]),
    /// It surely misses.
    Outside,
    /// Within rounding of an edge (or of the plane): the f64 reference decides.
    Unsure,
}

/// A triangle seen from a point in f32, with its solid angle and an error bound; what both area
/// and solid-angle sampling need from the point.
#[derive(Clone, Copy, Debug)]
pub struct TriangleView {
    r0: Vec3,
    r1: Vec3,
    l: [f32; 3],
    /// r1 x r2, r2 x r0, r0 x r1 (barycentric numerators' normals).
    n_bc: Vec3,
    n_ac: Vec3,
    n_ab: Vec3,
    /// |r| |e| of each of those crosses: w . n may have the wrong sign below 16 eps |r| |e|
    /// (3x the bound on its rounding error).
    scale: [f32; 3],
    /// sign of r0 . N: +1 when the point is on the side N points to.
    side: f32,
    /// Cosines between the vertex directions (a.b, a.c).
    cos_ab: f32,
    cos_ac: f32,
    /// |r0 . N|, and Van Oosterom-Strackee's atan2 arguments on unit vectors.
    det_abs: f32,
    det: f32,
    denom: f32,
    /// Solid angle (sr) and a bound on its absolute error.
    pub solid_angle: f32,
    /// Bound on the absolute error of `solid_angle`, sr.
    pub solid_angle_error: f32,
    /// |N| = twice the triangle's area.
    cross_len: f32,
}

impl TriangleView {
    /// The triangle `v` seen from `p`, given `cross` = (v1 - v0) x (v2 - v0) to f32 precision
    /// (the caller's f64 value rounded); None where the distance to the plane would carry a
    /// relative error above [`MAX_REL_ERROR`] (the point in or near the plane) or anything is not
    /// finite.
    #[inline]
    pub fn new(v: [Vec3; 3], cross: Vec3, p: Vec3) -> Option<Self> {
        let (r0, r1, r2) = (v[0] - p, v[1] - p, v[2] - p);
        let (e1, e2, e12) = (v[1] - v[0], v[2] - v[0], v[2] - v[1]);
        let l = [r0.length(), r1.length(), r2.length()];
        let l_max = l[0].max(l[1]).max(l[2]);
        let cross_len = cross.length();
        let det = r0.dot(cross);
        // r0 . N: 3 eps |r0| |N| (roundings of r0, N and the dot); the farthest vertex bounds the
        // density's error too (its cosine is det / (|N| l)).
        if !(4.0 * EPS * l_max * cross_len <= MAX_REL_ERROR * det.abs()) || !(l[0] * l[1] * l[2]).is_finite() {
            return None;
        }
        let inv = [1.0 / l[0], 1.0 / l[1], 1.0 / l[2]];
        let cos_ab = r0.dot(r1) * inv[0] * inv[1];
        let cos_ac = r0.dot(r2) * inv[0] * inv[2];
        let cos_bc = r1.dot(r2) * inv[1] * inv[2];
        // Van Oosterom-Strackee on unit vectors: tan(A / 2) = |det'| / (1 + cos_ab + cos_ac + cos_bc).
        let det_u = det.abs() * inv[0] * inv[1] * inv[2];
        let denom = 1.0 + cos_ab + cos_ac + cos_bc;
        let solid_angle = 2.0 * atan2_pos(det_u, denom);
        // dA = 2 (denom d(det') - det' d(denom)) / (det'^2 + denom^2), with d(det') <= 8 eps det'
        // (the distance bound plus the three 1 / l) and d(denom) <= 8 eps (three cosines).
        let d_det = (4.0 * EPS * l_max * cross_len / det.abs() + 4.0 * EPS) * det_u;
        let d_denom = 8.0 * EPS;
        let solid_angle_error = 2.0 * (denom.abs() * d_det + det_u * d_denom) / (det_u * det_u + denom * denom)
            + ATAN_REL_ERROR * solid_angle;
        let (n_ab, n_ac, n_bc) = (r0.cross(e1), r0.cross(e2), r1.cross(e12));
        let scale = [l[1] * e12.length(), l[0] * e2.length(), l[0] * e1.length()];
        let ok = solid_angle.is_finite() && solid_angle_error.is_finite();
        ok.then_some(Self {
            r0,
            r1,
            l,
            n_bc,
            n_ac,
            n_ab,
            scale,
            side: det.signum(),
            cos_ab,
            cos_ac,
            det_abs: det.abs(),
            det: det_u,
            denom,
            solid_angle,
            solid_angle_error,
            cross_len,
        })
    }

    /// Barycentrics of where the ray along unit `w` meets the triangle, if it does with a margin
    /// that f32 rounding cannot cross: then the exact ray (and the f64 reference's test) hits it
    /// too, in front of the point and not grazing. None near an edge, outside, or behind.
    #[inline]
    pub fn barycentrics(&self, w: Vec3) -> Option<[f32; 3]> {
        match self.edge_test(w) {
            EdgeTest::Inside(b) => Some(b),
            EdgeTest::Outside | EdgeTest::Unsure => None,
        }
    }

    /// [`Self::barycentrics`], telling apart a sure miss: some edge's numerator negative by more
    /// than its rounding error, so the exact ray misses (outside that edge, or behind the point).
    #[inline]
    pub fn edge_test(&self, w: Vec3) -> EdgeTest {
        let x = [w.dot(self.n_bc), -w.dot(self.n_ac), w.dot(self.n_ab)].map(|x| x * self.side);
        let margin = self.scale.map(|s| 16.0 * EPS * s);
        if (0..3).any(|i| x[i] < -margin[i]) {
            return EdgeTest::Outside;
        }
        let sum = x[0] + x[1] + x[2];
        // w . N = sum: its cosine with the plane must dwarf an f32 normal's error too.
        let inside = (0..3).all(|i| x[i] >= margin[i]) && sum >= 4.0 * EPS * self.cross_len;
        if inside { EdgeTest::Inside(x.map(|x| x / sum)) } else { EdgeTest::Unsure }
    }

    /// Distance along `w` to the plane (for densities t^2 / (|cos| A)).
    #[inline]
    pub fn distance_along(&self, w: Vec3, normal: Vec3) -> f32 {
        self.r0.dot(normal) / w.dot(normal)
    }

    /// The solid-angle sampler of this view, None where its map is too ill-conditioned for f32
    /// (an arc from v0 seen nearly end-on, or Arvo's denominator near 0: triangles close to a
    /// hemisphere); the f64 reference takes those.
    #[inline]
    pub fn spherical(&self) -> Option<SphericalTriangleF32> {
        let (n_ab_len, n_ac_len) = (self.n_ab.length(), self.n_ac.length());
        let l = self.l;
        // sin(arc) = |r x e| / (l l'): relative error ~ eps l |e| / |r x e| (that is, 1 / sin of
        // the angle between r0 and the edge).
        let sin_ab = n_ab_len / (l[0] * l[1]);
        let sin_ac = n_ac_len / (l[0] * l[2]);
        let (cond_ab, cond_ac) = (self.scale[2] / n_ab_len, self.scale[1] / n_ac_len);
        // tan(arc / 2) without cancellation on either side of a quarter circle.
        let tan_half = |s: f32, c: f32| if c >= 0.0 { s / (1.0 + c) } else { (1.0 - c) / s };
        let tan_half_ab = tan_half(sin_ab, self.cos_ab);
        let tan_half_ac = tan_half(sin_ac, self.cos_ac);
        // (r0 x r1) x (r0 x r2) = r0 det: the angle at a.
        let inv_nn = 1.0 / (n_ab_len * n_ac_len);
        let sin_alpha = self.det_abs * inv_nn * l[0];
        let cos_alpha = self.n_ab.dot(self.n_ac) * inv_nn;
        // sin(alpha - h) over h in [0, A/2] is smallest at an end (sin is concave on [0, pi]);
        // its rounding error is eps (sin alpha + sin h).
        let hyp = (self.det * self.det + self.denom * self.denom).sqrt();
        let (sin_half_a, cos_half_a) = (self.det / hyp, self.denom / hyp);
        let den_end = sin_alpha * cos_half_a - cos_alpha * sin_half_a;
        let sin_h_max = if cos_half_a < 0.0 { 1.0 } else { sin_half_a };
        let cond_den = (sin_alpha + sin_h_max) / den_end.min(sin_alpha);
        let toward_c = self.n_ac.cross(self.r0).normalize_or_zero();
        let ok = cond_ab <= MAX_CONDITION
            && cond_ac <= MAX_CONDITION
            && den_end > 0.0
            && cond_den <= MAX_CONDITION
            && tan_half_ab > 0.0
            && tan_half_ac.is_finite()
            && toward_c != Vec3::ZERO;
        ok.then(|| SphericalTriangleF32 {
            a: self.r0 * (1.0 / l[0]),
            b: self.r1 * (1.0 / l[1]),
            toward_c,
            sin_alpha,
            cos_alpha,
            tan_half_ab,
            tan_half_ac,
            area: self.solid_angle,
        })
    }
}

/// Arvo's sampler in f32 (see `SphericalTriangle::sample` in the f64 reference for the
/// derivation of the half-angle form).
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangleF32 {
    a: Vec3,
    b: Vec3,
    toward_c: Vec3,
    sin_alpha: f32,
    cos_alpha: f32,
    tan_half_ab: f32,
    tan_half_ac: f32,
    area: f32,
}

impl SphericalTriangleF32 {
    /// The unit direction that `u` maps to, as the f64 reference maps it (to ~1e-5 of the
    /// triangle's size where [`TriangleView::spherical`] accepts it).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (sin_h, cos_h) = sin_cos_0_pi((0.5 * u.x * self.area).clamp(0.0, PI));
        // t = tan(arc a-c' / 2) = sin(h) / (k sin(alpha - h)).
        let denom = self.tan_half_ab * (self.sin_alpha * cos_h - self.cos_alpha * sin_h);
        let t = if denom > 0.0 { (sin_h / denom).min(self.tan_half_ac) } else { self.tan_half_ac };
        let t2 = t * t;
        let inv = 1.0 / (1.0 + t2);
        let c_p = self.a * ((1.0 - t2) * inv) + self.toward_c * (2.0 * t * inv);
        let s = u.y.max(0.0).sqrt() * 0.5 * (c_p - self.b).length();
        let cos_theta = 1.0 - 2.0 * s * s;
        let sin_theta = 2.0 * s * (1.0 - s * s).max(0.0).sqrt();
        let tangent = (c_p - self.b * c_p.dot(self.b)).normalize_or_zero();
        (self.b * cos_theta + tangent * sin_theta).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_pos_is_within_its_bound_of_f64() {
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            // Angles over [0, pi], densest near the ends, at radii 1e-20 to 1e20.
            let t = i as f64 / 200_000.0;
            let theta = std::f64::consts::PI * t * t * (3.0 - 2.0 * t);
            let r = 10f64.powf(40.0 * ((i * 7919) % 1000) as f64 / 1000.0 - 20.0);
            let (y, x) = ((r * theta.sin()) as f32, (r * theta.cos()) as f32);
            let exact = (y as f64).atan2(x as f64);
            if exact > 0.0 {
                worst = worst.max((atan2_pos(y, x) as f64 - exact).abs() / exact);
            }
        }
        assert!(worst < ATAN_REL_ERROR as f64, "{worst}");
    }

    #[test]
    fn sin_cos_0_pi_is_within_3e_7_of_f64() {
        for i in 0..=100_000 {
            let x = (PI * i as f32 / 100_000.0).min(PI);
            let (s, c) = sin_cos_0_pi(x);
            let (se, ce) = (x as f64).sin_cos();
            let sin_tol = if x <= std::f32::consts::FRAC_PI_2 { 3e-7 * se } else { 3e-7 };
            assert!((s as f64 - se).abs() <= sin_tol, "sin {x}");
            assert!((c as f64 - ce).abs() <= 3e-7, "cos {x}");
        }
        // Tiny arguments keep sin's relative accuracy.
        for x in [1e-30f32, 1e-10, 1e-5, 3e-3] {
            assert!(((sin_cos_0_pi(x).0 as f64) / (x as f64).sin() - 1.0).abs() < 3e-7);
        }
    }
}
