//! The hit test of flat shapes (disks, rectangles): the plane z = 0 in object space, first in
//! f32 and, where its answer is not sure, in f64.

use glam::{DAffine3, Vec3};

use super::{PlacedShape, gamma};

/// A flat shape's maps rounded to f32, for the f32 hit test: the rows of to_object's linear part
/// (which turn directions into object space) and their absolute values (for the bound on row
/// z); and the part of to_world that maps object-space (x, y, 0): columns x and y of the linear
/// part, the translation, and their absolute values (for point error bounds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct FlatMap {
    rows: [[f32; 3]; 3],
    abs_row_z: [f32; 3],
    x: Vec3,
    y: Vec3,
    t: Vec3,
    abs_x: Vec3,
    abs_y: Vec3,
    abs_t: Vec3,
}

impl FlatMap {
    pub(super) fn new(to_world: &DAffine3, to_object: &DAffine3) -> Self {
        let m = &to_object.matrix3;
        let rows = [0, 1, 2].map(|i| [m.x_axis[i] as f32, m.y_axis[i] as f32, m.z_axis[i] as f32]);
        let (x, y, t) =
            (to_world.matrix3.x_axis.as_vec3(), to_world.matrix3.y_axis.as_vec3(), to_world.translation.as_vec3());
        Self { rows, abs_row_z: rows[2].map(f32::abs), x, y, t, abs_x: x.abs(), abs_y: y.abs(), abs_t: t.abs() }
    }
}

impl PlacedShape {
    /// [`Self::local_hit`] of a flat shape: whether the ray o + t d meets it in (0, t_max], at t
    /// and object-space (x, y, 0). The f32 test answers unless t lies within its error bound of 0
    /// or t_max ([`flat_hit_f32_from_rows`]); then the f64 test does. The plane test needs only
    /// row z, and most shadow rays fail it (they leave the plane), so rows x and y wait for it.
    #[inline(always)]
    pub(super) fn flat_hit(&self, o: [f64; 3], d: [f64; 3], t_max: f32) -> (bool, f32, f32, f32) {
        let d32 = d.map(|c| c as f32);
        let (oz, dz) = (self.object_point_row(2, o) as f32, self.object_dir_row32(2, d32));
        let dz_error = dz_error_bound(self.abs_object_row_z32(), d32);
        let (sure, _) = plane_t_f32(oz, dz, dz_error, t_max);
        if sure {
            let rows = [0, 1].map(|i| (self.object_point_row(i, o) as f32, self.object_dir_row32(i, d32)));
            let rows = [rows[0], rows[1], (oz, dz)];
            let (_, hit, t, x, y) =
                flat_hit_f32_from_rows(rows, dz_error, t_max, |x, y| self.shape.flat_contains32(x, y));
            return (hit, t, x, y);
        }
        let (oz, dz) = self.object_row(2, o, d);
        if !plane_t(oz, dz, t_max).0 {
            return (false, 0.0, 0.0, 0.0);
        }
        let rows = [self.object_row(0, o, d), self.object_row(1, o, d), (oz, dz)];
        let (hit, t, x, y) = flat_hit_from_rows(rows, t_max, |x, y| self.shape.flat_contains(x, y));
        (hit, t, x as f32, y as f32)
    }

    /// Row `i` of direction `d` in object space, in f32.
    #[inline(always)]
    fn object_dir_row32(&self, i: usize, d: [f32; 3]) -> f32 {
        dot_row32(self.flat_map.rows[i], d)
    }

    /// |row z| of to_object's linear part in f32.
    #[inline(always)]
    fn abs_object_row_z32(&self) -> [f32; 3] {
        self.flat_map.abs_row_z
    }

    /// Row `i` of the ray o + t d in object space: origin and direction components, the f64
    /// sums that `transform_point3` and `transform_vector3` form.
    #[inline(always)]
    fn object_row(&self, i: usize, o: [f64; 3], d: [f64; 3]) -> (f64, f64) {
        (self.object_point_row(i, o), self.object_dir_row(i, d))
    }

    /// The origin half of [`Self::object_row`].
    #[inline(always)]
    fn object_point_row(&self, i: usize, o: [f64; 3]) -> f64 {
        dot_row(self.object_matrix_row(i), o) + self.to_object.translation[i]
    }

    /// The direction half of [`Self::object_row`].
    #[inline(always)]
    fn object_dir_row(&self, i: usize, d: [f64; 3]) -> f64 {
        dot_row(self.object_matrix_row(i), d)
    }

    /// Row `i` of the world-to-object matrix.
    #[inline(always)]
    fn object_matrix_row(&self, i: usize) -> [f64; 3] {
        let m = &self.to_object.matrix3;
        [m.x_axis[i], m.y_axis[i], m.z_axis[i]]
    }

    /// World coordinate `a` of the object-space point (x, y, 0) of a flat shape, and its error
    /// bound, in f32. The point (x, y, 0) lies on the shape
    /// exactly, so the bound covers the f32 sums (pbrt-v4's gamma(3) for a transformed point)
    /// and the rounding of the f64 map to f32 (one more unit roundoff): gamma(5) leaves room for
    /// the rounding of the bound itself.
    #[inline(always)]
    pub(super) fn flat_world_coordinate(&self, a: usize, x: f32, y: f32) -> (f32, f32) {
        let m = &self.flat_map;
        let p = m.x[a] * x + m.y[a] * y + m.t[a];
        let terms = m.abs_x[a] * x.abs() + m.abs_y[a] * y.abs() + m.abs_t[a];
        (p, gamma(5) * terms + f32::MIN_POSITIVE)
    }
}

/// The sum the object rows form from matrix row `m` (before the translation, for points).
#[inline(always)]
fn dot_row(m: [f64; 3], d: [f64; 3]) -> f64 {
    m[0] * d[0] + m[1] * d[1] + m[2] * d[2]
}

/// [`dot_row`] in f32: row `i` of a direction in object space, from row `i` of to_object's
/// linear part in f32 (`FlatMap::rows`).
#[inline(always)]
fn dot_row32(m: [f32; 3], d: [f32; 3]) -> f32 {
    m[0] * d[0] + m[1] * d[1] + m[2] * d[2]
}

/// A bound on the error of direction `d`'s z row in f32 ([`dot_row32`]) against the f64 row,
/// from |row z| of to_object's linear part (`PlacedShape::abs_object_row_z32`): the f32 sum's
/// gamma(3) and the rounding of the matrix (one unit roundoff), with room for the rounding of
/// the bound itself (gamma(6) in all).
#[inline(always)]
fn dz_error_bound(abs_row_z: [f32; 3], d: [f32; 3]) -> f32 {
    gamma(6) * (abs_row_z[0] * d[0].abs() + abs_row_z[1] * d[1].abs() + abs_row_z[2] * d[2].abs())
}

/// The rest of [`PlacedShape::flat_hit`] from the object-space ray's rows (origin, direction)
/// for x, y and z, with the shape's containment test.
#[inline(always)]
fn flat_hit_from_rows(
    [(ox, dx), (oy, dy), (oz, dz)]: [(f64, f64); 3],
    t_max: f32,
    contains: impl Fn(f64, f64) -> bool,
) -> (bool, f32, f64, f64) {
    let (ahead, t, t32) = plane_t(oz, dz, t_max);
    let (x, y) = (ox + t * dx, oy + t * dy);
    (ahead & contains(x, y), t32, x, y)
}

/// Where a ray with object-space z row (oz, dz) meets the plane z = 0: whether in (0, t_max]
/// (tested on t rounded to f32, so that every caller agrees), t and t as f32.
#[inline(always)]
fn plane_t(oz: f64, dz: f64, t_max: f32) -> (bool, f64, f32) {
    // dz = 0 (parallel to the plane) makes t infinite or NaN, which the tests reject.
    let t = -oz / dz;
    let t32 = t as f32;
    ((dz != 0.0) & (t > 0.0) & (t32 > 0.0) & (t32 <= t_max), t, t32)
}

/// The f32 form of [`flat_hit_from_rows`]: rows (origin, direction) in f32, where the origin rows
/// are the f64 ones rounded and `dz_error` bounds the z direction row's error. Returns whether the
/// answer is sure ([`plane_t_f32`]), then the hit, t, x and y. A sure answer's plane test is the
/// f64 test's; the containment test runs on the f32 x and y.
#[inline(always)]
fn flat_hit_f32_from_rows(
    [(ox, dx), (oy, dy), (oz, dz)]: [(f32, f32); 3],
    dz_error: f32,
    t_max: f32,
    contains: impl Fn(f32, f32) -> bool,
) -> (bool, bool, f32, f32, f32) {
    let (sure, t) = plane_t_f32(oz, dz, dz_error, t_max);
    let (x, y) = (ox + t * dx, oy + t * dy);
    (sure, sure & (t > 0.0) & (t <= t_max) & contains(x, y), t, x, y)
}

/// Where an f32 ray row z (oz, dz) meets the plane z = 0, and whether that t lies clear of 0 and
/// of t_max (so that the f64 t, rounded to f32, falls on the same side of both). With |dz| >
/// 4 dz_error, t is within |t| (8u + 3 dz_error / |dz|) of the f64 t: oz's rounding, the
/// reciprocal and the product (u each), and dz's error. The margin doubles the unit roundoffs
/// for its own rounding.
#[inline(always)]
fn plane_t_f32(oz: f32, dz: f32, dz_error: f32, t_max: f32) -> (bool, f32) {
    const U: f32 = crate::geometry::ray::F32_UNIT_ROUNDOFF;
    let r = 1.0 / dz;
    let t = -oz * r;
    let margin = t.abs() * (16.0 * U + 4.0 * dz_error * r.abs());
    let apart = ((t > margin) & (t + margin <= t_max)) | (t < -margin) | (t - margin > t_max);
    (apart & (dz.abs() > 4.0 * dz_error), t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Rectangle, Transform};
    use glam::{Quat, Vec2};

    fn placed(shape: impl Into<super::super::Shape>, t: Transform) -> PlacedShape {
        PlacedShape::new(shape.into(), &t).unwrap()
    }

    /// The f32 plane test answers as the f64 test does wherever the answer matters: segments that
    /// end on the shape (t_max at the hit, one f32 step either side, and short by
    /// SHADOW_EPSILON), and grazing rays. Unsure cases go to the f64 test, and some must.
    #[test]
    fn f32_plane_test_decides_as_the_f64_test() {
        let rotation = Quat::from_rotation_x(0.3) * Quat::from_rotation_z(0.2);
        let transform = Transform {
            translation: Vec3::new(3.0, -2.0, 7.0),
            rotation,
            scale: Vec3::new(2.0, 3.0, 1.0),
            shear: glam::Vec3::ZERO,
        };
        // Large, so that the rays here meet it far from its edges (where the f32 and f64
        // containment tests may differ).
        let shape = placed(Rectangle::from_size(Vec2::splat(2e4)), transform);
        let near = |u: f32, half_width: f32| 0.5 + half_width * (u - 0.5) / 1e4;
        let mut rng = crate::rng::SplitMix64::new(7);
        let (mut unsure, mut unsure_clear_of_t_max) = (0, 0);
        for i in 0..4000 {
            let mut u = || rng.f32();
            let target = shape.sample_area(Vec2::new(near(u(), 10.0), near(u(), 10.0))).p;
            let o = if i % 2 == 0 {
                Vec3::new(20.0 * u() - 10.0, 20.0 * u() - 10.0, 20.0 * u() - 10.0)
            } else {
                // Grazing: from a point on the plane's extension, lifted by a hair.
                let n = shape.flat_normal.unwrap();
                let far = shape.sample_area(Vec2::new(near(u(), 100.0), near(u(), 100.0))).p;
                target + (far - target) * (1.0 + 10.0 * u()) + n * (1e-4 * u())
            };
            let (o64, d) = (o.as_dvec3().to_array(), (target - o).as_dvec3().to_array());
            let (oz, dz) = shape.object_row(2, o64, d);
            let t = (-oz / dz) as f32;
            for t_max in [t, t.next_down(), t.next_up(), 1.0 - crate::geometry::SHADOW_EPSILON, 1.0, f32::INFINITY] {
                let rows = [shape.object_row(0, o64, d), shape.object_row(1, o64, d), (oz, dz)];
                let f64_answer = flat_hit_from_rows(rows, t_max, |x, y| shape.shape.flat_contains(x, y)).0;
                let d32 = d.map(|c| c as f32);
                let (dz32, dz_error) =
                    (shape.object_dir_row32(2, d32), dz_error_bound(shape.abs_object_row_z32(), d32));
                let sure = plane_t_f32(oz as f32, dz32, dz_error, t_max).0;
                unsure += !sure as usize;
                let clear = i % 2 == 0 && (t_max == f32::INFINITY || t_max == 1.0 - crate::geometry::SHADOW_EPSILON);
                unsure_clear_of_t_max += (clear && !sure) as usize;
                assert_eq!(shape.flat_hit(o64, d, t_max).0, f64_answer, "ray {o} -> {target}, t_max {t_max}");
            }
        }
        // The f64 test ran, but hardly ever for random rays with t_max far from t (4000 cases).
        assert!(unsure > 1000 && unsure_clear_of_t_max < 40, "{unsure} unsure, {unsure_clear_of_t_max} of them clear");
    }
}
