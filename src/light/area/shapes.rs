//! World-space shapes of area lights and their solid-angle sampling (pbrt-v4 sections 6.2 and 6.5).
//!
//! Every shape has one sampling strategy per reference point, chosen the same way by `sample` and
//! by `hit` (which gives the density of a direction), so the two always agree:
//! - sphere: uniform sampling of the cone it subtends, or uniform area sampling when the point is
//!   on, inside or within [`SPHERE_NEAR_MARGIN`] of the surface (the cone is a hemisphere there);
//! - disk: uniform area sampling (concentric map), converted to solid angle;
//! - rectangle / triangle: uniform solid-angle sampling (Urena et al. 2013 / Arvo 1995) while the
//!   subtended solid angle is within [`MIN_SPHERICAL_SAMPLE_AREA`, `MAX_SPHERICAL_SAMPLE_AREA`],
//!   area sampling outside that band, where spherical sampling loses precision.
//!
//! Geometry that cancels (distances to nearby surfaces, cone angles of tiny spheres) is done in
//! f64; only results are rounded to f32. This is the reference; `fast.rs` is the f32 path that
//! `sample_li` takes, tested against it.

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};

use crate::sampling::{
    Frame, sample_spherical_rectangle, sample_spherical_triangle, sample_uniform_disk_concentric,
    sample_uniform_sphere, sample_uniform_triangle, spherical_rectangle_solid_angle, triangle_solid_angle,
};

/// Below this solid angle (sr) spherical rectangle / triangle sampling is imprecise; area sampling
/// is used (pbrt-v4 `MinSphericalSampleArea`).
pub const MIN_SPHERICAL_SAMPLE_AREA: f32 = 3e-4;
/// Above this solid angle (sr, close to 2 pi) spherical sampling is unstable too (pbrt-v4
/// `MaxSphericalSampleArea`).
pub const MAX_SPHERICAL_SAMPLE_AREA: f32 = 6.22;
/// A reference point with d^2 <= r^2 (1 + margin) from a sphere's centre samples its area rather
/// than its cone (the cone is nearly a hemisphere and its axis ill-defined there).
pub const SPHERE_NEAR_MARGIN: f64 = 1e-4;

/// An area light's shape in world space (metres). Normals are unit; one-sided lights emit on the
/// normal's side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// Normal points outward. uv: spherical coordinates around world +Y, u = azimuth / 2 pi
    /// (from +X toward -Z), v = polar angle / pi (0 at the +Y pole).
    Sphere {
        /// Centre, metres.
        center: Vec3,
        /// Radius in metres.
        radius: f32,
    },
    /// uv: polar, u = azimuth / 2 pi in `Frame::from_z(normal)`, v = 1 - rho / radius.
    Disk {
        /// Centre, metres.
        center: Vec3,
        /// Unit normal, the emitting side of a one-sided light.
        normal: Vec3,
        /// Radius in metres.
        radius: f32,
    },
    /// The parallelogram corner + s ex + t ey, s, t in [0, 1], with ex orthogonal to ey;
    /// normal = normalize(ex x ey); uv = (s, t).
    Rectangle {
        /// The corner at uv (0, 0), metres.
        corner: Vec3,
        /// First edge from `corner` (s direction), metres; its length is the side length.
        ex: Vec3,
        /// Second edge from `corner` (t direction), metres, orthogonal to `ex`.
        ey: Vec3,
    },
    /// Counter-clockwise vertices (normal = normalize((p1 - p0) x (p2 - p0))) with their uvs.
    Triangle {
        /// Vertices, metres, counter-clockwise seen from the emitting side.
        p: [Vec3; 3],
        /// Texture coordinates of the vertices, interpolated barycentrically.
        uv: [Vec2; 3],
    },
}

/// How a shape is sampled from a given reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SamplingStrategy {
    /// Uniform in the cone a sphere subtends.
    Cone,
    /// Uniform over the surface, converted to solid angle.
    Area,
    /// Uniform over the solid angle of a rectangle.
    SphericalRectangle,
    /// Uniform over the solid angle of a triangle.
    SphericalTriangle,
}

/// A point on a shape's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position, world space, metres.
    pub p: Vec3,
    /// Unit geometric normal (the shape's orientation, not flipped toward anyone).
    pub n: Vec3,
    /// Texture coordinate in the shape's parameterisation (see [`AreaShape`]).
    pub uv: Vec2,
}

/// A direction toward a shape, the visible surface point along it and the solid-angle density
/// (1/sr) of the shape's sampling strategy for that direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeSample {
    /// The visible surface point along `wi`.
    pub point: SurfacePoint,
    /// Unit direction from the reference point toward `point`.
    pub wi: Vec3,
    /// Solid-angle density of `wi` under the shape's sampling strategy, 1/sr.
    pub pdf: f32,
}

impl AreaShape {
    /// Surface area, m^2 (0 for degenerate shapes).
    pub fn area(&self) -> f32 {
        let a = match *self {
            Self::Sphere { radius, .. } => 4.0 * PI * (radius as f64).powi(2),
            Self::Disk { radius, .. } => PI * (radius as f64).powi(2),
            Self::Rectangle { ex, ey, .. } => ex.as_dvec3().cross(ey.as_dvec3()).length(),
            Self::Triangle { p, .. } => 0.5 * triangle_cross(&p).length(),
        };
        if a.is_finite() { a as f32 } else { 0.0 }
    }

    /// Bounding box (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Self::Sphere { center, radius } => (center - Vec3::splat(radius), center + Vec3::splat(radius)),
            Self::Disk { center, normal, radius } => {
                // Extent of a disk along axis i: r sqrt(1 - n_i^2).
                let e = radius * (Vec3::ONE - normal * normal).max(Vec3::ZERO).sqrt();
                (center - e, center + e)
            }
            Self::Rectangle { corner, ex, ey } => {
                let c = [corner, corner + ex, corner + ey, corner + ex + ey];
                (c.iter().fold(c[0], |a, &b| a.min(b)), c.iter().fold(c[0], |a, &b| a.max(b)))
            }
            Self::Triangle { p, .. } => (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])),
        }
    }

    /// The unit normal of a planar shape; None for spheres and degenerate shapes.
    pub fn plane_normal(&self) -> Option<Vec3> {
        let n = match *self {
            Self::Sphere { .. } => return None,
            Self::Disk { normal, .. } => normal.as_dvec3(),
            Self::Rectangle { ex, ey, .. } => ex.as_dvec3().cross(ey.as_dvec3()),
            Self::Triangle { p, .. } => triangle_cross(&p),
        };
        let n = n.normalize_or_zero().as_vec3();
        (n != Vec3::ZERO && n.is_finite()).then_some(n)
    }

    /// A point uniformly distributed over the surface (density 1 / area).
    pub fn sample_area(&self, u: Vec2) -> Option<SurfacePoint> {
        if !(self.area() > 0.0) {
            return None;
        }
        Some(match *self {
            Self::Sphere { center, radius } => {
                let n = sample_uniform_sphere(u);
                SurfacePoint { p: center + radius * n, n, uv: sphere_uv(n.as_dvec3()) }
            }
            Self::Disk { center, normal, radius } => {
                let d = sample_uniform_disk_concentric(u) * radius;
                let p = center + Frame::from_z(normal).from_local(d.extend(0.0));
                SurfacePoint { p, n: normal, uv: disk_uv(normal, radius, (p - center).as_dvec3()) }
            }
            Self::Rectangle { corner, ex, ey } => {
                SurfacePoint { p: corner + u.x * ex + u.y * ey, n: self.plane_normal()?, uv: u }
            }
            Self::Triangle { p, uv } => {
                let b = sample_uniform_triangle(u);
                let point = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
                SurfacePoint { p: point, n: self.plane_normal()?, uv: b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2] }
            }
        })
    }

    /// The strategy `sample` and `hit` use from `p_ref`, with the solid angle for spherical ones.
    fn choose(&self, p_ref: Vec3) -> (SamplingStrategy, f32) {
        match *self {
            Self::Sphere { center, radius } => {
                let d2 = (center.as_dvec3() - p_ref.as_dvec3()).length_squared();
                let r2 = (radius as f64).powi(2);
                let s =
                    if d2 <= r2 * (1.0 + SPHERE_NEAR_MARGIN) { SamplingStrategy::Area } else { SamplingStrategy::Cone };
                (s, 0.0)
            }
            Self::Disk { .. } => (SamplingStrategy::Area, 0.0),
            Self::Rectangle { corner, ex, ey } => {
                let omega = spherical_rectangle_solid_angle(p_ref, corner, ex, ey);
                if in_spherical_band(omega) {
                    (SamplingStrategy::SphericalRectangle, omega)
                } else {
                    (SamplingStrategy::Area, 0.0)
                }
            }
            Self::Triangle { p, .. } => {
                let omega = triangle_solid_angle(p, p_ref);
                if in_spherical_band(omega) {
                    (SamplingStrategy::SphericalTriangle, omega)
                } else {
                    (SamplingStrategy::Area, 0.0)
                }
            }
        }
    }

    /// The strategy used from reference point `p_ref`.
    pub fn strategy(&self, p_ref: Vec3) -> SamplingStrategy {
        self.choose(p_ref).0
    }

    /// A point of a planar shape's plane (the one `hit` intersects).
    fn plane_point(&self) -> Vec3 {
        match *self {
            Self::Sphere { center, .. } | Self::Disk { center, .. } => center,
            Self::Rectangle { corner, .. } => corner,
            Self::Triangle { p, .. } => p[0],
        }
    }

    /// Centre of the shape (a direction toward it from outside points inside the shape).
    fn centroid(&self) -> Vec3 {
        match *self {
            Self::Sphere { center, .. } | Self::Disk { center, .. } => center,
            Self::Rectangle { corner, ex, ey } => corner + 0.5 * (ex + ey),
            Self::Triangle { p, .. } => (p[0] + p[1] + p[2]) / 3.0,
        }
    }

    /// A direction from `p_ref` toward the shape with its solid-angle density; None for
    /// degenerate shapes and where the density is 0 or not finite (`p_ref` in a planar shape's
    /// plane). For a sphere sampled by area, the point returned is the first one along `wi` (a
    /// sample on the far side is replaced by the near surface in front of it) and the density
    /// sums over both points.
    ///
    /// The f32 `wi` always hits the shape, so [`AreaShape::hit`] gives it the same density: the
    /// rare sample whose rounded direction falls just outside an edge is pulled a few ulps toward
    /// the shape's centre.
    pub fn sample(&self, p_ref: Vec3, u: Vec2) -> Option<ShapeSample> {
        if !(self.area() > 0.0) || !p_ref.is_finite() {
            return None;
        }
        let (strategy, omega) = self.choose(p_ref);
        let s = self.sample_with(p_ref, u, strategy)?;
        if self.hit_with(p_ref, s.wi, strategy, omega).is_some() {
            return Some(s);
        }
        let toward = (self.centroid().as_dvec3() - p_ref.as_dvec3()).normalize_or_zero();
        let mut eps = 1e-6;
        while eps < 0.5 {
            let w = s.wi.as_dvec3().lerp(toward, eps).normalize_or_zero().as_vec3();
            if let Some(h) = self.hit_with(p_ref, w, strategy, omega) {
                // `h.wi` is `w` renormalised in f64, which may round an ulp off the one checked.
                return Some(ShapeSample { wi: w, ..h });
            }
            eps *= 4.0;
        }
        None
    }

    /// One sample of `strategy`, with its density computed from the sampling side.
    fn sample_with(&self, p_ref: Vec3, u: Vec2, strategy: SamplingStrategy) -> Option<ShapeSample> {
        let dir = |p: Vec3| (p.as_dvec3() - p_ref.as_dvec3()).normalize_or_zero().as_vec3();
        match (*self, strategy) {
            (Self::Sphere { center, radius }, SamplingStrategy::Cone) => sample_sphere_cone(center, radius, p_ref, u),
            (Self::Sphere { .. }, _) => {
                let wi = dir(self.sample_area(u)?.p);
                self.hit_with(p_ref, wi, strategy, 0.0)
            }
            (Self::Rectangle { corner, ex, ey }, SamplingStrategy::SphericalRectangle) => {
                let (p, pdf) = sample_spherical_rectangle(p_ref, corner, ex, ey, u)?;
                let uv = rectangle_uv(ex, ey, (p - corner).as_dvec3());
                finite_sample(SurfacePoint { p, n: self.plane_normal()?, uv }, dir(p), pdf)
            }
            (Self::Triangle { p: v, uv }, SamplingStrategy::SphericalTriangle) => {
                let (b, pdf) = sample_spherical_triangle(v, p_ref, u)?;
                let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
                let uv = b[0] * uv[0] + b[1] * uv[1] + b[2] * uv[2];
                finite_sample(SurfacePoint { p, n: self.plane_normal()?, uv }, dir(p), pdf)
            }
            _ => {
                let on = self.sample_area(u)?;
                let wi = dir(on.p);
                // Density t^2 / (|cos| A) of the direction as rounded to f32 (near grazing it
                // differs from the unrounded one by ~1e-7 / |cos|), with t to the plane `hit`
                // uses: on.p is off that plane by f32 rounding, which grazing rays amplify.
                let (o, w, n) = (p_ref.as_dvec3(), wi.as_dvec3().normalize_or_zero(), on.n.as_dvec3());
                let t = n.dot(self.plane_point().as_dvec3() - o) / n.dot(w);
                finite_sample(on, wi, area_pdf(t, w, on.n, self.area() as f64) as f32)
            }
        }
    }

    /// Where the ray from `p_ref` along `wi` meets the shape, with the density `sample` gives that
    /// direction; None on a miss.
    pub fn hit(&self, p_ref: Vec3, wi: Vec3) -> Option<ShapeSample> {
        let (strategy, omega) = self.choose(p_ref);
        self.hit_with(p_ref, wi, strategy, omega)
    }

    fn hit_with(&self, p_ref: Vec3, wi: Vec3, strategy: SamplingStrategy, omega: f32) -> Option<ShapeSample> {
        let area = self.area() as f64;
        let w = wi.as_dvec3().normalize_or_zero();
        if !(area > 0.0) || w == DVec3::ZERO || !w.is_finite() || !p_ref.is_finite() {
            return None;
        }
        let o = p_ref.as_dvec3();
        let (point, pdf) = match *self {
            Self::Sphere { center, radius } => return hit_sphere(center, radius, o, w, strategy, area),
            Self::Disk { center, normal, radius } => {
                let (t, q) = hit_plane(o, w, center.as_dvec3(), normal.as_dvec3())?;
                let rel = q - center.as_dvec3();
                if rel.length() > radius as f64 {
                    return None;
                }
                (
                    SurfacePoint { p: q.as_vec3(), n: normal, uv: disk_uv(normal, radius, rel) },
                    area_pdf(t, w, normal, area),
                )
            }
            Self::Rectangle { corner, ex, ey } => {
                let n = self.plane_normal()?;
                let (t, q) = hit_plane(o, w, corner.as_dvec3(), n.as_dvec3())?;
                let rel = q - corner.as_dvec3();
                for e in [ex.as_dvec3(), ey.as_dvec3()] {
                    if !(0.0..=e.length_squared()).contains(&rel.dot(e)) {
                        return None;
                    }
                }
                let uv = rectangle_uv(ex, ey, rel);
                let pdf = if strategy == SamplingStrategy::Area { area_pdf(t, w, n, area) } else { 1.0 / omega as f64 };
                (SurfacePoint { p: q.as_vec3(), n, uv }, pdf)
            }
            Self::Triangle { p, uv } => {
                let n = self.plane_normal()?;
                let (t, q) = hit_plane(o, w, p[0].as_dvec3(), n.as_dvec3())?;
                let b = triangle_barycentrics(&p, q, n.as_dvec3())?;
                let uv = b[0] as f32 * uv[0] + b[1] as f32 * uv[1] + b[2] as f32 * uv[2];
                let pdf = if strategy == SamplingStrategy::Area { area_pdf(t, w, n, area) } else { 1.0 / omega as f64 };
                (SurfacePoint { p: q.as_vec3(), n, uv }, pdf)
            }
        };
        finite_sample(point, w.as_vec3(), pdf as f32)
    }
}

fn in_spherical_band(omega: f32) -> bool {
    (MIN_SPHERICAL_SAMPLE_AREA..=MAX_SPHERICAL_SAMPLE_AREA).contains(&omega)
}

/// Keeps a sample only if its density and direction are usable.
pub(super) fn finite_sample(point: SurfacePoint, wi: Vec3, pdf: f32) -> Option<ShapeSample> {
    let ok = pdf.is_finite() && pdf > 0.0 && wi.is_finite() && wi != Vec3::ZERO && point.p.is_finite();
    ok.then_some(ShapeSample { point, wi, pdf })
}

/// (p1 - p0) x (p2 - p0) in f64.
fn triangle_cross(p: &[Vec3; 3]) -> DVec3 {
    let [a, b, c] = p.map(|v| v.as_dvec3());
    (b - a).cross(c - a)
}

/// Solid-angle density of area sampling: t^2 / (|cos| A) (pbrt-v4 eq. 6.8's Jacobian).
fn area_pdf(t: f64, w: DVec3, n: Vec3, area: f64) -> f64 {
    t * t / (n.as_dvec3().dot(w).abs() * area)
}

/// Distance and point where the ray meets a plane, for t > 0.
fn hit_plane(o: DVec3, w: DVec3, q: DVec3, n: DVec3) -> Option<(f64, DVec3)> {
    let denom = n.dot(w);
    let t = n.dot(q - o) / denom;
    (t > 0.0 && t.is_finite()).then(|| (t, o + t * w))
}

/// Barycentrics of `q` (in the triangle's plane) if it lies inside.
fn triangle_barycentrics(p: &[Vec3; 3], q: DVec3, n: DVec3) -> Option<[f64; 3]> {
    let v = p.map(|v| v.as_dvec3());
    let twice_area = (v[1] - v[0]).cross(v[2] - v[0]).dot(n);
    let mut b = [0.0; 3];
    for k in 0..3 {
        // Edge opposite vertex k, from v[k+1] to v[k+2].
        let (a, c) = (v[(k + 1) % 3], v[(k + 2) % 3]);
        b[k] = (c - a).cross(q - a).dot(n) / twice_area;
        if b[k] < 0.0 {
            return None;
        }
    }
    Some(b)
}

fn rectangle_uv(ex: Vec3, ey: Vec3, rel: DVec3) -> Vec2 {
    let (ex, ey) = (ex.as_dvec3(), ey.as_dvec3());
    Vec2::new((rel.dot(ex) / ex.length_squared()) as f32, (rel.dot(ey) / ey.length_squared()) as f32)
}

fn sphere_uv(n: DVec3) -> Vec2 {
    let phi = (-n.z).atan2(n.x).rem_euclid(2.0 * PI);
    Vec2::new((phi / (2.0 * PI)) as f32, (n.y.clamp(-1.0, 1.0).acos() / PI) as f32)
}

fn disk_uv(normal: Vec3, radius: f32, rel: DVec3) -> Vec2 {
    let f = Frame::from_z(normal);
    let (x, y) = (rel.dot(f.x.as_dvec3()), rel.dot(f.y.as_dvec3()));
    let phi = y.atan2(x).rem_euclid(2.0 * PI);
    Vec2::new((phi / (2.0 * PI)) as f32, (1.0 - x.hypot(y) / radius as f64) as f32)
}

/// Orthonormal x, y for a unit z in f64 (Duff et al. 2017, as `Frame::from_z`).
fn basis(z: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(z.z);
    let a = -1.0 / (sign + z.z);
    let b = z.x * z.y * a;
    (DVec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x), DVec3::new(b, sign + z.y * z.y * a, -z.y))
}

/// The cone a sphere subtends from outside: sin^2 and 1 - cos of its half-angle, exact for tiny
/// spheres (1 - cos = sin^2 / (1 + cos) replaces pbrt-v4's Taylor branch for sin^2 < 6.85e-4).
fn sphere_cone(center: Vec3, radius: f32, o: DVec3) -> (f64, f64, DVec3) {
    let dc = center.as_dvec3() - o;
    let d2 = dc.length_squared();
    let r2 = (radius as f64).powi(2);
    let sin2_max = r2 / d2;
    let cos_max = ((d2 - r2) / d2).max(0.0).sqrt();
    (sin2_max, sin2_max / (1.0 + cos_max), dc)
}

/// Uniform cone sampling of a sphere from outside (pbrt-v4 `Sphere::Sample(ctx, u)`): the
/// direction's angle theta gives the point's angle alpha at the centre in closed form, so no ray
/// is intersected.
fn sample_sphere_cone(center: Vec3, radius: f32, p_ref: Vec3, u: Vec2) -> Option<ShapeSample> {
    let (sin2_max, one_minus_cos_max, dc) = sphere_cone(center, radius, p_ref.as_dvec3());
    let one_minus_cos = u.x as f64 * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin2_theta = one_minus_cos * (2.0 - one_minus_cos);
    let cos_alpha = sin2_theta / sin2_max.sqrt() + cos_theta * (1.0 - sin2_theta / sin2_max).max(0.0).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y as f64;
    let z = dc.normalize();
    let (x, y) = basis(z);
    let n = -(sin_alpha * phi.cos() * x + sin_alpha * phi.sin() * y + cos_alpha * z);
    let to_point = dc + radius as f64 * n;
    let p = p_ref.as_dvec3() + to_point;
    let point = SurfacePoint { p: p.as_vec3(), n: n.as_vec3(), uv: sphere_uv(n) };
    finite_sample(point, to_point.normalize().as_vec3(), (1.0 / (2.0 * PI * one_minus_cos_max)) as f32)
}

/// Ray-sphere intersection with the density of the strategy in use.
fn hit_sphere(
    center: Vec3,
    radius: f32,
    o: DVec3,
    w: DVec3,
    strategy: SamplingStrategy,
    area: f64,
) -> Option<ShapeSample> {
    let (c, r) = (center.as_dvec3(), radius as f64);
    let oc = o - c;
    let b = oc.dot(w);
    // r^2 - (distance from the centre to the line)^2, accurate for grazing rays.
    let perp = oc - b * w;
    let disc = r * r - perp.length_squared();
    if disc < 0.0 {
        return None;
    }
    // Stable roots of t^2 + 2 b t + (|oc|^2 - r^2): q and c0 / q.
    let c0 = oc.length_squared() - r * r;
    let q = -b - disc.sqrt().copysign(b);
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (q.min(c0 / q), q.max(c0 / q)) };
    let roots = [t0, t1];
    let t_first = *roots.iter().find(|&&t| t > 0.0)?;
    let n_at = |t: f64| (oc + t * w) / r;
    let n = n_at(t_first);
    let pdf = match strategy {
        SamplingStrategy::Cone => {
            let (_, one_minus_cos_max, _) = sphere_cone(center, radius, o);
            1.0 / (2.0 * PI * one_minus_cos_max)
        }
        // Area sampling: every point on the ray contributes t^2 / (|cos| A).
        _ => roots.iter().filter(|&&t| t > 0.0).map(|&t| t * t / (n_at(t).dot(w).abs() * area)).sum(),
    };
    let point = SurfacePoint { p: (o + t_first * w).as_vec3(), n: n.normalize().as_vec3(), uv: sphere_uv(n) };
    finite_sample(point, w.as_vec3(), pdf as f32)
}
