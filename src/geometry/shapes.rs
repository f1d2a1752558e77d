//! Analytic shapes for area lights and occluders: `Sphere`, `Disk`, `Rectangle`.
//!
//! Each is a component sized in its local frame and placed by the entity's `Transform`. Flat
//! shapes lie in the local XY plane with their front (emitting) side toward local +Z and ignore
//! `scale.z`; a sphere needs a uniform scale (an ellipsoid has no closed-form uniform sampling).
//!
//! Intersection and sampling run in f64 in object space: the hit (or sample) is re-projected
//! exactly onto the surface, mapped to world space in f64 and rounded once to f32, which gives the
//! small error bound documented in `ray.rs` ([`f64_point_error`]).
//!
//! Area lights should sample a [`PlacedShape`] (made once per change with [`PlacedShape::new`],
//! or read back with `SceneBvh::placed_shape`): it carries the same f64 maps the BVH traces, so
//! samples lie on the traced surface and [`SurfacePoint::spawn_ray_to`] never self-intersects.

use bevy_ecs::component::Component;
use glam::{DAffine3, DMat3, DVec3, Vec2, Vec3};
use std::f64::consts::{PI, TAU};

use super::GeometryError;
use super::ray::{Ray, SurfacePoint, f64_point_error, gamma};
use super::transform::Transform;
use flat::FlatMap;

mod flat;

/// A sphere centred on the entity's origin. Poles on local +-Y.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Radius in metres (before scale); must be positive.
    pub radius: f32,
}

/// A disk (or annulus) in the local XY plane, centred on the origin, front side toward +Z.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Outer radius in metres (before scale); must be positive.
    pub radius: f32,
    /// Inner radius in metres, 0 for a full disk; must be below `radius`.
    pub inner_radius: f32,
}

/// A rectangle in the local XY plane, centred on the origin, front side toward +Z.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Rectangle {
    /// Half the side lengths along local X and Y, in metres (before scale); must be positive.
    pub half_size: Vec2,
}

/// The closed set of analytic shapes; one `match` per operation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A sphere centred on the origin.
    Sphere(Sphere),
    /// A disk or annulus in the local XY plane.
    Disk(Disk),
    /// A rectangle in the local XY plane.
    Rectangle(Rectangle),
}

/// A shape fixed in world space, with the f64 maps the BVH and light sampling share.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedShape {
    /// The shape, sized in its local frame.
    pub shape: Shape,
    pub(super) to_world: DAffine3,
    pub(super) to_object: DAffine3,
    /// |to_world's linear part| and |its translation|, for point error bounds.
    pub(super) abs_linear: DMat3,
    pub(super) abs_translation: DVec3,
    /// The inverse transpose of to_world's linear part, which maps normals.
    normal_matrix: DMat3,
    /// Flat shapes: their world normal (the front, +Z), the same for every point.
    pub(super) flat_normal: Option<Vec3>,
    /// The maps of the f32 flat-shape hit test, rounded to f32.
    flat_map: FlatMap,
}

/// A ray-shape hit in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Hit point, its error bound and the outward / front (+Z) unit normal.
    pub point: SurfacePoint,
    /// Surface parameters in [0, 1]^2 (sphere: longitude, latitude from +Y; disk: angle, radial
    /// from the rim as pbrt; rectangle: local x, y).
    pub uv: Vec2,
}

impl Sphere {
    /// World-space surface area, m^2 (uniform scale expected).
    pub fn area(&self, transform: &Transform) -> f32 {
        Shape::Sphere(*self).area(transform)
    }
}

impl Disk {
    /// A full disk.
    pub const fn new(radius: f32) -> Self {
        Self { radius, inner_radius: 0.0 }
    }

    /// World-space surface area, m^2.
    pub fn area(&self, transform: &Transform) -> f32 {
        Shape::Disk(*self).area(transform)
    }
}

impl Rectangle {
    /// A rectangle of full side lengths `size` (metres).
    pub fn from_size(size: Vec2) -> Self {
        Self { half_size: 0.5 * size }
    }

    /// World-space surface area, m^2.
    pub fn area(&self, transform: &Transform) -> f32 {
        Shape::Rectangle(*self).area(transform)
    }
}

impl From<Sphere> for Shape {
    fn from(s: Sphere) -> Self {
        Shape::Sphere(s)
    }
}
impl From<Disk> for Shape {
    fn from(d: Disk) -> Self {
        Shape::Disk(d)
    }
}
impl From<Rectangle> for Shape {
    fn from(r: Rectangle) -> Self {
        Shape::Rectangle(r)
    }
}

impl Shape {
    /// Short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Sphere(_) => "sphere",
            Shape::Disk(_) => "disk",
            Shape::Rectangle(_) => "rectangle",
        }
    }

    /// Checks the size parameters: positive, finite, inner radius below the outer one.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let ok = match *self {
            Shape::Sphere(s) => s.radius > 0.0 && s.radius.is_finite(),
            Shape::Disk(d) => {
                d.radius > 0.0 && d.radius.is_finite() && d.inner_radius >= 0.0 && d.inner_radius < d.radius
            }
            Shape::Rectangle(r) => r.half_size.cmpgt(Vec2::ZERO).all() && r.half_size.is_finite(),
        };
        if ok { Ok(()) } else { Err(GeometryError::InvalidShape { shape: *self }) }
    }

    /// World-space surface area in m^2 (flat shapes scale by |sx sy|, spheres by sx^2).
    pub fn area(&self, transform: &Transform) -> f32 {
        let s = transform.scale.abs();
        match *self {
            Shape::Sphere(sp) => 4.0 * std::f32::consts::PI * (sp.radius * s.x).powi(2),
            Shape::Disk(d) => std::f32::consts::PI * (d.radius.powi(2) - d.inner_radius.powi(2)) * s.x * s.y,
            Shape::Rectangle(r) => 4.0 * r.half_size.x * r.half_size.y * s.x * s.y,
        }
    }

    /// Density of [`PlacedShape::sample_area`] per unit world area: 1 / area.
    pub fn area_pdf(&self, transform: &Transform) -> f32 {
        1.0 / self.area(transform)
    }

    fn is_flat(&self) -> bool {
        !matches!(self, Shape::Sphere(_))
    }

    /// Object-space bounding box.
    fn local_bounds(&self) -> (DVec3, DVec3) {
        let h = match *self {
            Shape::Sphere(s) => DVec3::splat(s.radius as f64),
            Shape::Disk(d) => DVec3::new(d.radius as f64, d.radius as f64, 0.0),
            Shape::Rectangle(r) => DVec3::new(r.half_size.x as f64, r.half_size.y as f64, 0.0),
        };
        (-h, h)
    }

    /// Whether the object-space point (x, y, 0) lies on a flat shape.
    #[inline(always)]
    pub(crate) fn flat_contains(&self, x: f64, y: f64) -> bool {
        match *self {
            Shape::Disk(disk) => {
                let rho2 = x * x + y * y;
                let (r, ri) = (disk.radius as f64, disk.inner_radius as f64);
                rho2 <= r * r && rho2 >= ri * ri
            }
            Shape::Rectangle(rect) => x.abs() <= rect.half_size.x as f64 && y.abs() <= rect.half_size.y as f64,
            Shape::Sphere(_) => false,
        }
    }

    /// [`Self::flat_contains`] in f32, for the f32 hit test.
    #[inline(always)]
    pub(crate) fn flat_contains32(&self, x: f32, y: f32) -> bool {
        match *self {
            Shape::Disk(disk) => {
                let rho2 = x * x + y * y;
                rho2 <= disk.radius * disk.radius && rho2 >= disk.inner_radius * disk.inner_radius
            }
            Shape::Rectangle(rect) => x.abs() <= rect.half_size.x && y.abs() <= rect.half_size.y,
            Shape::Sphere(_) => false,
        }
    }

    /// The uv of object-space point (x, y, 0) on a flat shape (see [`ShapeHit::uv`]).
    #[inline(always)]
    pub(crate) fn flat_uv(&self, x: f32, y: f32) -> Vec2 {
        match *self {
            Shape::Disk(d) => {
                let rho = (x * x + y * y).sqrt();
                let phi = y.atan2(x).rem_euclid(std::f32::consts::TAU);
                Vec2::new(phi / std::f32::consts::TAU, (d.radius - rho) / (d.radius - d.inner_radius))
            }
            Shape::Rectangle(rect) => {
                // Reciprocals: divisions per hit are the slow step.
                let inv = rect.half_size.recip();
                Vec2::new(0.5 * (x * inv.x + 1.0), 0.5 * (y * inv.y + 1.0))
            }
            Shape::Sphere(_) => Vec2::ZERO,
        }
    }

    /// The surface point nearest `p` (object space), its outward / +Z normal and its uv.
    fn project(&self, p: DVec3) -> (DVec3, DVec3, Vec2) {
        match *self {
            Shape::Sphere(s) => {
                let r = s.radius as f64;
                let n = p.try_normalize().unwrap_or(DVec3::Y);
                let phi = (-n.z).atan2(n.x).rem_euclid(TAU);
                let theta = n.y.clamp(-1.0, 1.0).acos();
                (n * r, n, Vec2::new((phi / TAU) as f32, (theta / PI) as f32))
            }
            Shape::Disk(_) | Shape::Rectangle(_) => {
                (DVec3::new(p.x, p.y, 0.0), DVec3::Z, self.flat_uv(p.x as f32, p.y as f32))
            }
        }
    }

    /// A uniformly distributed object-space point for `u` in [0, 1)^2 (pbrt-v4 section 6.2-6.5).
    fn sample_local(&self, u: Vec2) -> DVec3 {
        let (u0, u1) = (u.x as f64, u.y as f64);
        match *self {
            Shape::Sphere(s) => {
                let y = 1.0 - 2.0 * u0;
                let rxz = (1.0 - y * y).max(0.0).sqrt();
                let phi = TAU * u1;
                s.radius as f64 * DVec3::new(rxz * phi.cos(), y, -rxz * phi.sin())
            }
            Shape::Disk(d) => {
                // Area-uniform radius on the annulus: rho^2 uniform in [ri^2, r^2].
                let (r, ri) = (d.radius as f64, d.inner_radius as f64);
                let rho = (ri * ri + u0 * (r * r - ri * ri)).sqrt();
                let phi = TAU * u1;
                DVec3::new(rho * phi.cos(), rho * phi.sin(), 0.0)
            }
            Shape::Rectangle(rect) => {
                let h = rect.half_size.as_dvec2();
                DVec3::new((2.0 * u0 - 1.0) * h.x, (2.0 * u1 - 1.0) * h.y, 0.0)
            }
        }
    }
}

impl PlacedShape {
    /// Places `shape` with `transform`, checking both. Flat shapes ignore `scale.z`; spheres need
    /// |sx| = |sy| = |sz| (to 1e-4 relative).
    pub fn new(shape: Shape, transform: &Transform) -> Result<Self, GeometryError> {
        shape.validate()?;
        let mut scale = transform.scale.as_dvec3();
        if shape.is_flat() {
            scale.z = 1.0;
        }
        let s = scale.abs();
        let uniform = (s.x - s.y).abs() <= 1e-4 * s.x && (s.x - s.z).abs() <= 1e-4 * s.x;
        if !shape.is_flat() && !uniform {
            return Err(GeometryError::NonUniformSphereScale { scale: transform.scale });
        }
        // A flat shape lies at local z = 0, where only the xy shear acts.
        let shear = if shape.is_flat() { transform.shear.x.abs() } else { transform.shear.abs().max_element() };
        if shear > 1e-5 {
            return Err(GeometryError::ShearedShape { shape, shear: transform.shear });
        }
        let to_world = DAffine3::from_scale_rotation_translation(
            scale,
            transform.rotation.as_dquat().normalize(),
            transform.translation.as_dvec3(),
        );
        let invertible = s.min_element() > 0.0 && to_world.is_finite() && to_world.matrix3.determinant() != 0.0;
        if !invertible || !transform.rotation.is_finite() || transform.rotation.length_squared() == 0.0 {
            return Err(GeometryError::InvalidTransform { transform: *transform });
        }
        let to_object = to_world.inverse();
        let normal_matrix = to_object.matrix3.transpose();
        let placed = Self {
            shape,
            to_world,
            to_object,
            abs_linear: to_world.matrix3.abs(),
            abs_translation: to_world.translation.abs(),
            normal_matrix,
            flat_normal: shape.is_flat().then(|| (normal_matrix * DVec3::Z).normalize().as_vec3()),
            flat_map: FlatMap::new(&to_world, &to_object),
        };
        let (lo, hi) = placed.world_bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(GeometryError::InvalidTransform { transform: *transform });
        }
        Ok(placed)
    }

    /// World-space bounds (min, max), rounded outward to f32.
    pub fn world_bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.shape.local_bounds();
        let mut min = DVec3::INFINITY;
        let mut max = DVec3::NEG_INFINITY;
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let w = self.to_world.transform_point3(c);
            min = min.min(w);
            max = max.max(w);
        }
        let down = |x: f64| {
            let f = x as f32;
            if f as f64 > x { f.next_down() } else { f }
        };
        let up = |x: f64| {
            let f = x as f32;
            if (f as f64) < x { f.next_up() } else { f }
        };
        (Vec3::new(down(min.x), down(min.y), down(min.z)), Vec3::new(up(max.x), up(max.y), up(max.z)))
    }

    /// World-space area, m^2.
    pub fn area(&self) -> f32 {
        let m = self.to_world.matrix3;
        match self.shape {
            Shape::Sphere(s) => (4.0 * PI * (s.radius as f64 * m.x_axis.length()).powi(2)) as f32,
            // Flat shapes: the local unit area maps to |x_axis x y_axis|.
            _ => (self.shape.area(&Transform::IDENTITY) as f64 * m.x_axis.cross(m.y_axis).length()) as f32,
        }
    }

    /// Parameter of the nearest hit in (0, t_max], if any (the ray must be valid).
    pub fn intersect_t(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        self.local_hit(ray, t_max).map(|(t, _)| t)
    }

    /// The nearest hit in (0, t_max] with its surface point, error bound, normal and uv.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<ShapeHit> {
        let (t, p) = self.local_hit(ray, t_max)?;
        Some(self.hit_at_local(t, p))
    }

    /// The hit at parameter `t` and object-space point `p` that [`Self::local_hit`] returned.
    pub(crate) fn hit_at_local(&self, t: f32, p: DVec3) -> ShapeHit {
        if let Some(n) = self.flat_normal {
            let (x, y) = (p.x as f32, p.y as f32);
            let (mut p, mut p_error) = (Vec3::ZERO, Vec3::ZERO);
            for a in 0..3 {
                (p[a], p_error[a]) = self.flat_world_coordinate(a, x, y);
            }
            return ShapeHit { t, point: SurfacePoint { p, p_error, n }, uv: self.shape.flat_uv(x, y) };
        }
        let (p_obj, n_obj, uv) = self.shape.project(p);
        ShapeHit { t, point: self.surface_point(p_obj, n_obj), uv }
    }

    /// The nearest hit's `t` in (0, t_max] (tested after rounding to f32, so that every caller
    /// agrees on it exactly) and its object-space point, before re-projection onto the surface.
    #[inline]
    pub(crate) fn local_hit(&self, ray: &Ray, t_max: f32) -> Option<(f32, DVec3)> {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        if let Shape::Sphere(s) = self.shape {
            let (o, d) = (self.to_object.transform_point3(o), self.to_object.transform_vector3(d));
            let t = intersect_sphere_local(s.radius as f64, o, d, t_max)?;
            return Some((t, o + t as f64 * d));
        }
        let (hit, t, x, y) = self.flat_hit(o.to_array(), d.to_array(), t_max);
        hit.then_some((t, DVec3::new(x as f64, y as f64, 0.0)))
    }

    /// A point uniformly distributed over the surface (density 1 / area per m^2), with its error
    /// bound and outward / front normal, for `u` in [0, 1)^2.
    pub fn sample_area(&self, u: Vec2) -> SurfacePoint {
        let (p_obj, n_obj, _) = self.shape.project(self.shape.sample_local(u));
        self.surface_point(p_obj, n_obj)
    }

    fn surface_point(&self, p_obj: DVec3, n_obj: DVec3) -> SurfacePoint {
        let (m, abs_m) = (&self.to_world.matrix3, &self.abs_linear);
        let (p64, terms, n) = match self.flat_normal {
            // Flat shapes' points have z = 0: the z column drops out (`flat_world_coordinate`
            // forms the same sums one axis at a time).
            Some(n) => (
                m.x_axis * p_obj.x + m.y_axis * p_obj.y + self.to_world.translation,
                abs_m.x_axis * p_obj.x.abs() + abs_m.y_axis * p_obj.y.abs() + self.abs_translation,
                n,
            ),
            None => (
                self.to_world.transform_point3(p_obj),
                *abs_m * p_obj.abs() + self.abs_translation,
                (self.normal_matrix * n_obj).normalize().as_vec3(),
            ),
        };
        SurfacePoint { p: p64.as_vec3(), p_error: f64_point_error(p64, terms), n }
    }
}

/// Smallest `t` in (0, t_max] where the object-space ray `o + t d` meets a sphere of radius `r`
/// at the origin. The acceptance test is on `t` rounded to f32 so that every caller agrees on it.
fn intersect_sphere_local(r: f64, o: DVec3, d: DVec3, t_max: f32) -> Option<f32> {
    let accept = |t: f64| {
        let t32 = t as f32;
        (t > 0.0 && t32 > 0.0 && t32 <= t_max).then_some(t32)
    };
    let a = d.length_squared();
    let b = o.dot(d); // half of the usual b
    let c = o.length_squared() - r * r;
    // Discriminant via the closest approach to the centre (Hearn and Baker, as pbrt-v4 6.2.2):
    // stable for rays that graze the sphere.
    let l = (o - (b / a) * d).length();
    let disc = (r - l) * (r + l);
    if disc < 0.0 {
        return None;
    }
    let q = -b - b.signum() * (a * disc).sqrt();
    if q == 0.0 {
        return None;
    }
    let (t0, t1) = (q / a, c / q);
    let (t0, t1) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    accept(t0).or_else(|| accept(t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn placed(shape: impl Into<Shape>, t: Transform) -> PlacedShape {
        PlacedShape::new(shape.into(), &t).unwrap()
    }

    #[test]
    fn sphere_hit_from_outside_and_inside() {
        let s = placed(Sphere { radius: 2.0 }, Transform::from_translation(Vec3::new(0.0, 0.0, -10.0)));
        let hit = s.intersect(&Ray::new(Vec3::ZERO, Vec3::NEG_Z), f32::INFINITY).unwrap();
        assert!((hit.t - 8.0).abs() < 1e-5 && hit.point.n.abs_diff_eq(Vec3::Z, 1e-6));
        let inside = s.intersect(&Ray::new(Vec3::new(0.0, 0.0, -10.0), Vec3::X), f32::INFINITY).unwrap();
        assert!((inside.t - 2.0).abs() < 1e-6);
        assert!(s.intersect_t(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY).is_none());
    }

    #[test]
    fn annulus_hole_and_rim() {
        let d = placed(Disk { radius: 1.0, inner_radius: 0.5 }, Transform::IDENTITY);
        let down = |x: f32| d.intersect_t(&Ray::new(Vec3::new(x, 0.0, 1.0), Vec3::NEG_Z), f32::INFINITY);
        assert!(down(0.25).is_none() && down(0.75).is_some() && down(1.01).is_none());
    }

    #[test]
    fn areas_follow_scale() {
        let t =
            Transform { scale: Vec3::new(2.0, 3.0, 0.0), rotation: Quat::from_rotation_x(0.7), ..Default::default() };
        let r = placed(Rectangle::from_size(Vec2::new(1.0, 2.0)), t);
        assert!(
            (r.area() - 12.0).abs() < 1e-5 && (Rectangle::from_size(Vec2::new(1.0, 2.0)).area(&t) - 12.0).abs() < 1e-5
        );
        let s = placed(Sphere { radius: 1.0 }, Transform { scale: Vec3::splat(2.0), ..Default::default() });
        assert!((s.area() - 16.0 * std::f32::consts::PI).abs() < 1e-4);
    }

    #[test]
    fn samples_lie_on_the_surface_within_their_bound() {
        let t = Transform {
            translation: Vec3::new(1e5, -3e3, 20.0),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.4),
            scale: Vec3::new(1.5, 0.5, 1.0),
            shear: glam::Vec3::ZERO,
        };
        for shape in
            [Shape::Disk(Disk { radius: 2.0, inner_radius: 0.5 }), Shape::Rectangle(Rectangle::from_size(Vec2::ONE))]
        {
            let ps = placed(shape, t);
            for i in 0..50 {
                let u = Vec2::new((i as f32 * 0.618).fract(), (i as f32 * 0.414).fract());
                let sp = ps.sample_area(u);
                // Distance to the plane (exact in f64) stays within the bound along n.
                let plane_d = (sp.p.as_dvec3() - t.translation.as_dvec3()).dot(sp.n.as_dvec3());
                assert!(plane_d.abs() <= sp.n.abs().dot(sp.p_error) as f64 * 1.01, "{shape:?} {plane_d}");
            }
        }
    }

    #[test]
    fn rejects_bad_sizes_and_transforms() {
        assert!(PlacedShape::new(Disk { radius: 1.0, inner_radius: 1.0 }.into(), &Transform::IDENTITY).is_err());
        assert!(PlacedShape::new(Sphere { radius: -1.0 }.into(), &Transform::IDENTITY).is_err());
        let squash = Transform { scale: Vec3::new(1.0, 2.0, 1.0), ..Default::default() };
        assert!(matches!(
            PlacedShape::new(Sphere { radius: 1.0 }.into(), &squash),
            Err(GeometryError::NonUniformSphereScale { .. })
        ));
        let nan = Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
        assert!(matches!(PlacedShape::new(Disk::new(1.0).into(), &nan), Err(GeometryError::InvalidTransform { .. })));
        let huge = Transform { scale: Vec3::splat(1e30), ..Default::default() };
        assert!(matches!(
            PlacedShape::new(Sphere { radius: 1e10 }.into(), &huge),
            Err(GeometryError::InvalidTransform { .. })
        ));
    }
}
