//! Solid-angle sampling of planar triangles and rectangles seen from a point: directions uniform
//! over the spherical polygon they subtend, with pdf 1 / solid angle, and the inverse maps.
//!
//! All of it runs in f64: a triangle of 1e-8 sr has interior angles summing to pi + 1e-8, which an
//! f32 cannot tell from pi, and even f64 loses half its digits in Arvo's published formulas at that
//! size. Areas come from the Van Oosterom-Strackee formula, and the triangle sampler solves for its
//! intermediate vertex with a half-angle tangent, so both stay accurate from ~1e-12 sr to ~2 pi sr.

use std::f64::consts::TAU;

use glam::{DVec2, DVec3, Vec2, Vec3};

/// Below this solid angle (sr) the rectangle sampler maps the unit square bilinearly onto the
/// rectangle: there, the angle-sum form of Ureña et al. has lost more digits (relative error
/// ~1e-15 / Omega) than the planar map's distortion costs (~sqrt(Omega)); both are ~1e-5.
const RECT_PLANAR_BELOW_SR: f64 = 1e-10;

/// Solid angle subtended from the origin by the triangle (r1, r2, r3), vectors of any length.
/// Van Oosterom & Strackee 1983: tan(Omega / 2) = |r1 . (r2 × r3)| / D with
/// D = |r1||r2||r3| + (r1.r2)|r3| + (r1.r3)|r2| + (r2.r3)|r1|. The triple product is taken over
/// edges (r2 - r1, r3 - r1), which keeps its digits for tiny triangles; atan2 keeps them for
/// triangles near a hemisphere.
fn solid_angle_f64(r1: DVec3, r2: DVec3, r3: DVec3) -> f64 {
    let (l1, l2, l3) = (r1.length(), r2.length(), r3.length());
    let det = r1.dot((r2 - r1).cross(r3 - r1)).abs();
    let denom = l1 * l2 * l3 + r1.dot(r2) * l3 + r1.dot(r3) * l2 + r2.dot(r3) * l1;
    let omega = 2.0 * det.atan2(denom);
    if omega.is_finite() { omega } else { 0.0 }
}

/// Area (sr) of the spherical triangle with vertices `a`, `b`, `c` on the unit sphere (they need not
/// be normalised: the area is that of the cone they span). Van Oosterom & Strackee 1983, in f64:
/// accurate for tiny triangles and for ones near a hemisphere (2 pi).
pub fn spherical_triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    solid_angle_f64(a.as_dvec3(), b.as_dvec3(), c.as_dvec3()) as f32
}

/// Solid angle (sr) subtended by the planar triangle `v` seen from `p`; 0 if `p` is in its plane.
pub fn triangle_solid_angle(v: [Vec3; 3], p: Vec3) -> f32 {
    let r = rel(v, p);
    solid_angle_f64(r[0], r[1], r[2]) as f32
}

fn rel(v: [Vec3; 3], p: Vec3) -> [DVec3; 3] {
    let p = p.as_dvec3();
    v.map(|q| q.as_dvec3() - p)
}

/// A spherical triangle (unit vertices a, b, c) with what Arvo's sampler needs precomputed.
struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    /// Interior angle at `a`.
    alpha: f64,
    /// tan of half the arc a-b, and of half the arc a-c.
    tan_half_ab: f64,
    tan_half_ac: f64,
    /// Unit tangent at `a` toward `c` along their great circle.
    toward_c: DVec3,
    /// Area in sr.
    area: f64,
}

impl SphericalTriangle {
    /// None when a vertex coincides with the viewpoint, two directions are parallel or opposite, or
    /// the viewpoint lies in the triangle's plane.
    fn new(r: [DVec3; 3]) -> Option<Self> {
        let area = solid_angle_f64(r[0], r[1], r[2]);
        let [a, b, c] = r.map(|v| v.normalize_or_zero());
        let (n_ab, n_ac) = (a.cross(b), a.cross(c));
        let toward_c = n_ac.cross(a).normalize_or_zero();
        let alpha = n_ab.cross(n_ac).length().atan2(n_ab.dot(n_ac));
        // tan(arc / 2) = |chord difference| / |chord sum| for unit vectors.
        let tan_half_ab = (a - b).length() / (a + b).length();
        let tan_half_ac = (a - c).length() / (a + c).length();
        let ok = area > 0.0
            && alpha > 0.0
            && tan_half_ab > 0.0
            && tan_half_ab.is_finite()
            && tan_half_ac.is_finite()
            && toward_c != DVec3::ZERO
            && b.cross(c) != DVec3::ZERO;
        ok.then_some(Self { a, b, c, alpha, tan_half_ab, tan_half_ac, toward_c, area })
    }

    /// Arvo 1995 ("Stratified Sampling of Spherical Triangles"): u.x picks the sub-triangle
    /// (a, b, c') of area u.x * A, with c' on arc a-c; u.y picks the point on arc b-c' so the
    /// density is uniform. Arvo's cos(arc a-c') cancels catastrophically for small triangles, so we
    /// solve for t = tan(arc a-c' / 2) instead, from the area of a triangle with two sides and the
    /// included angle: tan(E/2) = t k sin(alpha) / (1 + t k cos(alpha)), k = tan(arc a-b / 2),
    /// which gives t = sin(E/2) / (k sin(alpha - E/2)). Since E < 2 alpha for any spherical
    /// triangle, t is finite and >= 0.
    fn sample(&self, u: DVec2) -> DVec3 {
        let half = 0.5 * u.x * self.area;
        let denom = self.tan_half_ab * (self.alpha - half).sin();
        let t = if denom > 0.0 { (half.sin() / denom).min(self.tan_half_ac) } else { self.tan_half_ac };
        let t2 = t * t;
        let c_p = self.a * ((1.0 - t2) / (1.0 + t2)) + self.toward_c * (2.0 * t / (1.0 + t2));
        // Along b -> c': 1 - cos(theta) = u.y (1 - cos(theta_max)), i.e. sin(theta / 2) =
        // sqrt(u.y) * |c' - b| / 2; the half-angle form keeps its digits for short arcs.
        let s = u.y.max(0.0).sqrt() * 0.5 * (c_p - self.b).length();
        let cos_theta = 1.0 - 2.0 * s * s;
        let sin_theta = 2.0 * s * (1.0 - s * s).max(0.0).sqrt();
        let tangent = (c_p - self.b * c_p.dot(self.b)).normalize_or_zero();
        (self.b * cos_theta + tangent * sin_theta).normalize()
    }

    /// The sample point that [`Self::sample`] maps to unit direction `w` (Arvo's inversion: c' is
    /// where the great circle through b and w meets arc a-c).
    fn invert(&self, w: DVec3) -> Option<Vec2> {
        let bw = self.b.cross(w);
        if bw == DVec3::ZERO {
            return (w.dot(self.b) > 0.0).then_some(Vec2::ZERO); // w = b: every u.x maps there
        }
        let mut c_p = bw.cross(self.a.cross(self.c)).normalize_or_zero();
        if c_p == DVec3::ZERO {
            return None;
        }
        if c_p.dot(self.a + self.c) < 0.0 {
            c_p = -c_p; // the intersection on the arc, not its antipode
        }
        let u0 = solid_angle_f64(self.a, self.b, c_p) / self.area;
        let u1 = (w - self.b).length_squared() / (c_p - self.b).length_squared();
        Some(Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32))
    }
}

/// Samples a direction from `p` uniformly over the solid angle of the triangle `v` and returns the
/// barycentrics `[b0, b1, b2]` (weights of `v[0]`, `v[1]`, `v[2]`) of the point it hits, with the
/// pdf per steradian, 1 / solid angle (Arvo 1995; pbrt-v4 §6.5.4, made robust as above).
///
/// Corners of the unit square land where pbrt-v4's bilinear pre-warp expects them: u.y = 0 gives
/// `v[1]`, u = (0, 1) gives `v[0]`, u = (1, 1) gives `v[2]`; so weights
/// `[cos1, cos1, cos0, cos2]` for [`crate::sampling::sample_bilinear`] approximate cos(theta).
///
/// None when the triangle is degenerate as seen from `p`: `p` in its plane or on a vertex, or
/// collinear vertices. Callers that want to handle tiny or nearly-hemispherical triangles
/// differently can test [`triangle_solid_angle`] first; this function itself is accurate for
/// both.
pub fn sample_spherical_triangle(v: [Vec3; 3], p: Vec3, u: Vec2) -> Option<([f32; 3], f32)> {
    let tri = SphericalTriangle::new(rel(v, p))?;
    let w = tri.sample(u.as_dvec2());
    let b = barycentrics_along_ray(v, p, w)?;
    let pdf = (1.0 / tri.area) as f32;
    pdf.is_finite().then_some((b, pdf))
}

/// The unit-square sample that [`sample_spherical_triangle`] maps to direction `w` (need not be
/// normalised) from `p`; None for degenerate triangles or a zero `w`.
pub fn invert_spherical_triangle_sample(v: [Vec3; 3], p: Vec3, w: Vec3) -> Option<Vec2> {
    let tri = SphericalTriangle::new(rel(v, p))?;
    let w = w.as_dvec3().normalize_or_zero();
    if w == DVec3::ZERO {
        return None;
    }
    tri.invert(w)
}

/// Barycentrics of where the ray p + t w meets the plane of `v` (Möller-Trumbore in f64),
/// clamped onto the triangle to absorb rounding.
fn barycentrics_along_ray(v: [Vec3; 3], p: Vec3, w: DVec3) -> Option<[f32; 3]> {
    let [b1, b2] = raw_barycentrics(v, p, w)?;
    let (mut b1, mut b2) = (b1.clamp(0.0, 1.0), b2.clamp(0.0, 1.0));
    if b1 + b2 > 1.0 {
        let s = b1 + b2;
        (b1, b2) = (b1 / s, b2 / s);
    }
    Some([(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32])
}

fn raw_barycentrics(v: [Vec3; 3], p: Vec3, w: DVec3) -> Option<[f64; 2]> {
    let [v0, v1, v2] = v.map(|q| q.as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 || !divisor.is_finite() {
        return None; // w parallel to the plane: only for triangles covering a whole hemisphere
    }
    let s = p.as_dvec3() - v0;
    Some([s.dot(s1) / divisor, w.dot(s.cross(e1)) / divisor])
}

/// A rectangle seen from a point, in the local frame of Ureña et al. 2013 ("An Area-Preserving
/// Parametrization for Spherical Rectangles"): x along `ex`, y along `ey`, z the normal flipped
/// so the rectangle lies at z = z0 < 0.
struct SphericalRectangle {
    p_ref: DVec3,
    corner: DVec3,
    ex: DVec3,
    ey: DVec3,
    axes: [DVec3; 3],
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    /// Normal z components of the planes through the bottom (y0) and top (y1) edges.
    b0: f64,
    b1: f64,
    /// 2 pi minus the interior angles at the two x0 corners.
    k: f64,
    /// Solid angle from the interior-angle sum (what the parametrization is consistent with).
    angle_sum: f64,
    /// Solid angle from Van Oosterom-Strackee (accurate; gives the pdf).
    solid_angle: f64,
}

impl SphericalRectangle {
    /// None if an edge is zero, the edges are not perpendicular (|cos| > 1e-3), or `p_ref` lies in
    /// the rectangle's plane.
    fn new(p_ref: Vec3, corner: Vec3, ex: Vec3, ey: Vec3) -> Option<Self> {
        let (p_ref, corner, ex, ey) = (p_ref.as_dvec3(), corner.as_dvec3(), ex.as_dvec3(), ey.as_dvec3());
        let (exl, eyl) = (ex.length(), ey.length());
        if !(exl > 0.0 && eyl > 0.0 && (exl * eyl).is_finite()) || ex.dot(ey).abs() > 1e-3 * exl * eyl {
            return None;
        }
        let x_axis = ex / exl;
        let y_axis = (ey - x_axis * ey.dot(x_axis)).normalize();
        let mut z_axis = x_axis.cross(y_axis);
        let d = corner - p_ref;
        let (x0, y0, mut z0) = (d.dot(x_axis), d.dot(y_axis), d.dot(z_axis));
        if z0 > 0.0 {
            z_axis = -z_axis;
            z0 = -z0;
        }
        if z0 == 0.0 || z0.is_nan() {
            return None; // the viewpoint is in the rectangle's plane
        }
        let (x1, y1, z) = (x0 + exl, y0 + eyl, -z0);
        // Interior angles at the four corners, as atan2 of the edge planes' normals (Ureña et al.
        // give acos(-n_i . n_j), which loses digits for angles near 0 or pi).
        let r = |x: f64, y: f64| (x * x + y * y + z * z).sqrt();
        let g0 = (z * r(x1, y0)).atan2(y0 * x1);
        let g1 = (z * r(x1, y1)).atan2(-x1 * y1);
        let g2 = (z * r(x0, y1)).atan2(x0 * y1);
        let g3 = (z * r(x0, y0)).atan2(-x0 * y0);
        let [v00, v10, v11, v01] = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| DVec3::new(x, y, z0));
        let solid_angle = solid_angle_f64(v00, v10, v11) + solid_angle_f64(v00, v11, v01);
        if !(solid_angle > 0.0 && solid_angle.is_finite()) {
            return None;
        }
        Some(Self {
            p_ref,
            corner,
            ex,
            ey,
            axes: [x_axis, y_axis, z_axis],
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: -y0 / (z * z + y0 * y0).sqrt(),
            b1: y1 / (z * z + y1 * y1).sqrt(),
            k: TAU - g2 - g3,
            angle_sum: g0 + g1 + g2 + g3 - TAU,
            solid_angle,
        })
    }

    fn planar(&self) -> bool {
        !(self.angle_sum > RECT_PLANAR_BELOW_SR && self.solid_angle > RECT_PLANAR_BELOW_SR)
    }

    /// h(y) = y / sqrt(dd^2 + y^2), the quantity uniform along a vertical line at distance dd.
    fn h(dd2: f64, y: f64) -> f64 {
        y / (dd2 + y * y).sqrt()
    }

    fn sample(&self, u: DVec2) -> DVec3 {
        let (u0, u1) = (u.x, u.y);
        if self.planar() {
            return self.corner + self.ex * u0 + self.ey * u1;
        }
        // x: the sub-rectangle [x0, xu] has solid angle u0 * S (Ureña et al. §3, eqs. 9-11).
        let au = u0 * self.angle_sum + self.k;
        let (sin_au, cos_au) = au.sin_cos();
        let fu = (cos_au * self.b0 - self.b1) / sin_au;
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt()).copysign(fu).clamp(-1.0 + 1e-15, 1.0 - 1e-15);
        let xu = (-cu * self.z0 / (1.0 - cu * cu).sqrt()).clamp(self.x0, self.x1);
        // y: uniform in h along the line x = xu.
        let dd2 = xu * xu + self.z0 * self.z0;
        let (h0, h1) = (Self::h(dd2, self.y0), Self::h(dd2, self.y1));
        let hv = h0 + u1 * (h1 - h0);
        let one_minus_hv2 = (1.0 - hv) * (1.0 + hv);
        let yv = if one_minus_hv2 > 0.0 { hv * dd2.sqrt() / one_minus_hv2.sqrt() } else { self.y1 };
        let [xa, ya, za] = self.axes;
        self.p_ref + xa * xu + ya * yv.clamp(self.y0, self.y1) + za * self.z0
    }

    fn invert(&self, q: DVec3) -> Vec2 {
        if self.planar() {
            let d = q - self.corner;
            let s = d.dot(self.ex) / self.ex.length_squared();
            let t = d.dot(self.ey) / self.ey.length_squared();
            return Vec2::new(s.clamp(0.0, 1.0) as f32, t.clamp(0.0, 1.0) as f32);
        }
        let d = q - self.p_ref;
        let xu = d.dot(self.axes[0]).clamp(self.x0, self.x1);
        let yv = d.dot(self.axes[1]).clamp(self.y0, self.y1);
        let z = -self.z0;
        let r = |x: f64, y: f64| (x * x + y * y + z * z).sqrt();
        // The interior angles at the sub-rectangle's new corners (xu, y0), (xu, y1) sum to au.
        let au = (z * r(xu, self.y0)).atan2(self.y0 * xu) + (z * r(xu, self.y1)).atan2(-xu * self.y1);
        let u0 = (au - self.k) / self.angle_sum;
        let dd2 = xu * xu + z * z;
        let (h0, h1) = (Self::h(dd2, self.y0), Self::h(dd2, self.y1));
        let u1 = (Self::h(dd2, yv) - h0) / (h1 - h0);
        Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32)
    }
}

/// Samples a point on the rectangle `corner + s ex + t ey` (s, t in [0, 1]; `ex` ⟂ `ey`) so that
/// its direction from `p_ref` is uniform over the rectangle's solid angle; returns the point and the
/// pdf per steradian, 1 / solid angle (Ureña, Fajardo, King 2013, in f64, with interior angles by
/// atan2). The unit square's corners map to the rectangle's corners, so `u` may be pre-warped by
/// [`crate::sampling::sample_bilinear`] toward cos(theta) at the corners, as pbrt-v4 does.
///
/// None if an edge has zero length, the edges are not perpendicular (|cos| > 1e-3), or `p_ref`
/// lies in the rectangle's plane. Below 1e-10 sr the map degrades gracefully to a bilinear one
/// (relative distortion ~1e-5), keeping the exact pdf.
pub fn sample_spherical_rectangle(p_ref: Vec3, corner: Vec3, ex: Vec3, ey: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    let rect = SphericalRectangle::new(p_ref, corner, ex, ey)?;
    let q = rect.sample(u.as_dvec2());
    Some((q.as_vec3(), (1.0 / rect.solid_angle) as f32))
}

/// The unit-square sample that [`sample_spherical_rectangle`] maps to `p_rect` (a point on the
/// rectangle; off-rectangle points are clamped onto it). None for the same degenerate inputs.
pub fn invert_spherical_rectangle_sample(p_ref: Vec3, corner: Vec3, ex: Vec3, ey: Vec3, p_rect: Vec3) -> Option<Vec2> {
    let rect = SphericalRectangle::new(p_ref, corner, ex, ey)?;
    Some(rect.invert(p_rect.as_dvec3()))
}

/// Solid angle (sr) of the parallelogram `corner + s ex + t ey` seen from `p_ref`, as two Van
/// Oosterom-Strackee triangles in f64; 0 when degenerate.
pub fn spherical_rectangle_solid_angle(p_ref: Vec3, corner: Vec3, ex: Vec3, ey: Vec3) -> f32 {
    let v00 = (corner - p_ref).as_dvec3();
    let (ex, ey) = (ex.as_dvec3(), ey.as_dvec3());
    let omega = solid_angle_f64(v00, v00 + ex, v00 + ex + ey) + solid_angle_f64(v00, v00 + ex + ey, v00 + ey);
    omega as f32
}

/// Internal checks that need the unclamped barycentrics.
#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::rng::SplitMix64;

    fn hits_inside(v: [Vec3; 3], p: Vec3, u: Vec2, tol: f64) -> bool {
        let tri = SphericalTriangle::new(rel(v, p)).unwrap();
        let [b1, b2] = raw_barycentrics(v, p, tri.sample(u.as_dvec2())).unwrap();
        b1 >= -tol && b2 >= -tol && b1 + b2 <= 1.0 + tol
    }

    #[test]
    fn sampled_directions_hit_the_triangle_unclamped() {
        let cases: [([Vec3; 3], Vec3); 3] = [
            ([Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.5)], Vec3::ZERO),
            // tiny: ~1e-8 sr
            ([Vec3::ZERO, Vec3::new(1.4e-4, 0.0, 0.0), Vec3::new(0.0, 1.4e-4, 0.0)], Vec3::new(0.0, 0.0, 1.0)),
            // near 2 pi: the viewpoint hovers just above the centroid
            (
                [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)],
                Vec3::new(0.0, 1e-3, -0.33),
            ),
        ];
        let mut rng = SplitMix64::new(3);
        for (v, p) in cases {
            for _ in 0..20_000 {
                assert!(hits_inside(v, p, rng.vec2(), 1e-6), "{v:?} from {p:?}");
            }
        }
    }

    /// |dw/du0 × dw/du1| by f64 central differences with step `h`.
    fn direction_jacobian(f: impl Fn(DVec2) -> DVec3, u: DVec2, h: f64) -> f64 {
        let du = (f(u + DVec2::X * h) - f(u - DVec2::X * h)) / (2.0 * h);
        let dv = (f(u + DVec2::Y * h) - f(u - DVec2::Y * h)) / (2.0 * h);
        du.cross(dv).length()
    }

    #[test]
    fn f64_maps_have_constant_jacobian_near_2pi_and_tiny() {
        // Steps: small where the near-2pi maps curve sharply near the viewpoint's foot; larger for
        // tiny polygons, whose directions move by only ~1e-4 over the square and whose f64 maps
        // jitter by ~1e-8 of their width (the rectangle's angle sum at 1e-8 sr), below f32 output.
        let tri_cases = [
            (
                [Vec3::new(-1.0, -0.6, 0.0), Vec3::new(1.0, -0.6, 0.0), Vec3::new(0.0, 1.0, 0.0)],
                Vec3::new(0.0, 0.0, 1e-3),
                1e-6,
            ),
            (
                [Vec3::ZERO, Vec3::new(1.4e-4, 0.0, 0.0), Vec3::new(0.3e-4, 1.4e-4, 0.0)],
                Vec3::new(0.5e-4, 0.3e-4, 1.0),
                1e-4,
            ),
        ];
        let mut rng = SplitMix64::new(17);
        for (v, p, h) in tri_cases {
            let tri = SphericalTriangle::new(rel(v, p)).unwrap();
            for _ in 0..2000 {
                let u = DVec2::new(rng.f64(), rng.f64()) * 0.9 + 0.05;
                let j = direction_jacobian(|u| tri.sample(u), u, h);
                assert!((j / tri.area - 1.0).abs() < 1e-5, "{v:?} at {u}: {j} vs {}", tri.area);
            }
        }
        let rect_cases = [
            (Vec3::new(0.1, 0.2, 1e-3), Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0, 1e-6),
            (Vec3::new(0.3e-4, -0.2e-4, 1.0), Vec3::ZERO, Vec3::X * 1e-4, Vec3::Y * 1e-4, 1e-2),
        ];
        for (p, corner, ex, ey, h) in rect_cases {
            let rect = SphericalRectangle::new(p, corner, ex, ey).unwrap();
            for _ in 0..2000 {
                let u = DVec2::new(rng.f64(), rng.f64()) * 0.9 + 0.05;
                let j = direction_jacobian(|u| (rect.sample(u) - rect.p_ref).normalize(), u, h);
                assert!((j / rect.solid_angle - 1.0).abs() < 1e-5, "rect at {u}: {j} vs {}", rect.solid_angle);
            }
        }
    }

    #[test]
    fn triangle_arcs_end_where_arvo_says() {
        // u = (1, 1) must reach vertex c, u.y = 0 vertex b, u.x = 0 the arc b-a.
        let v = [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.5)];
        let tri = SphericalTriangle::new(rel(v, Vec3::ZERO)).unwrap();
        assert!((tri.sample(DVec2::ONE) - tri.c).length() < 1e-12);
        assert!((tri.sample(DVec2::new(0.4, 0.0)) - tri.b).length() < 1e-12);
        assert!((tri.sample(DVec2::new(0.0, 1.0)) - tri.a).length() < 1e-12);
    }

    #[test]
    fn rectangle_corners_map_to_unit_square_corners() {
        let (p, corner, ex, ey) = (Vec3::new(0.2, 0.3, 1.0), Vec3::ZERO, Vec3::X, Vec3::Y * 2.0);
        for (u, expect) in
            [(Vec2::ZERO, corner), (Vec2::X, corner + ex), (Vec2::Y, corner + ey), (Vec2::ONE, corner + ex + ey)]
        {
            let (q, _) = sample_spherical_rectangle(p, corner, ex, ey, u).unwrap();
            assert!((q - expect).length() < 1e-5, "{u} -> {q}, expected {expect}");
        }
    }

    #[test]
    fn degenerate_inputs_give_none() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(sample_spherical_triangle(v, Vec3::new(0.2, 0.2, 0.0), Vec2::splat(0.5)).is_none());
        assert!(sample_spherical_triangle(v, Vec3::ZERO, Vec2::splat(0.5)).is_none());
        assert!(sample_spherical_triangle([Vec3::ZERO, Vec3::X, Vec3::X * 2.0], Vec3::Z, Vec2::ZERO).is_none());
        assert!(
            sample_spherical_rectangle(Vec3::new(0.5, 0.5, 0.0), Vec3::ZERO, Vec3::X, Vec3::Y, Vec2::ZERO).is_none()
        );
        assert!(sample_spherical_rectangle(Vec3::Z, Vec3::ZERO, Vec3::X, Vec3::X + Vec3::Y, Vec2::ZERO).is_none());
        assert!(sample_spherical_rectangle(Vec3::Z, Vec3::ZERO, Vec3::ZERO, Vec3::Y, Vec2::ZERO).is_none());
        assert_eq!(spherical_triangle_area(Vec3::X, Vec3::X, Vec3::Y), 0.0);
    }

    #[test]
    fn octant_area_is_half_pi() {
        let area = spherical_triangle_area(Vec3::X, Vec3::Y, Vec3::Z);
        assert!((area - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
        let sa = spherical_rectangle_solid_angle(Vec3::ZERO, Vec3::new(-1.0, -1.0, 1.0), Vec3::X * 2.0, Vec3::Y * 2.0);
        assert!((sa as f64 - 4.0 * PI / 6.0).abs() < 1e-6, "cube face: {sa}");
    }
}
