//! `Transform`: where an entity sits in the world (glTF's TRS, right-handed, +Y up, metres).

use bevy_ecs::component::Component;
use glam::{Affine3A, DVec3, Mat3, Quat, Vec3};

/// Translation, rotation, scale and shear, applied as shear, then scale, then rotation, then
/// translation: any affine map (`from_affine` keeps all of it). Defaults to the identity.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Position in metres.
    pub translation: Vec3,
    /// Orientation; must be normalised.
    pub rotation: Quat,
    /// Per-axis scale; lights ignore it except area-light shapes.
    pub scale: Vec3,
    /// The shear applied first, as the unit upper-triangular matrix [[1, x, y], [0, 1, z],
    /// [0, 0, 1]]: x' = x + shear.x y + shear.y z, y' = y + shear.z z. Zero for a plain TRS
    /// transform. Meshes follow it; lights ignore it (as scale), and analytic shapes refuse it.
    pub shear: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// No translation, rotation or scale.
    pub const IDENTITY: Self =
        Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE, shear: Vec3::ZERO };

    /// A pure translation.
    pub const fn from_translation(translation: Vec3) -> Self {
        Self { translation, ..Self::IDENTITY }
    }

    /// From an affine matrix (e.g. a glTF node's world matrix), exactly: its linear part as
    /// rotation x scale x shear (a QR factorisation, Gram-Schmidt on the columns in f64), so a
    /// rotated node with non-uniform scale keeps its shear. A mirror makes `scale.z` negative; a
    /// singular matrix gives a zero scale and no shear along the lost axes.
    pub fn from_affine(m: Affine3A) -> Self {
        let c = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis].map(|v| v.as_dvec3());
        let unit = |v: DVec3, fallback: DVec3| if v.length() > 0.0 { v.normalize() } else { fallback };
        let s0 = c[0].length();
        let q0 = unit(c[0], DVec3::X);
        let u01 = q0.dot(c[1]);
        let r1 = c[1] - u01 * q0;
        let s1 = r1.length();
        let q1 = unit(r1, q0.any_orthonormal_vector());
        let (u02, u12) = (q0.dot(c[2]), q1.dot(c[2]));
        let r2 = c[2] - u02 * q0 - u12 * q1;
        let mut s2 = r2.length();
        let q2 = q0.cross(q1);
        if q2.dot(r2) < 0.0 {
            s2 = -s2;
        }
        let ratio = |u: f64, s: f64| if s != 0.0 { (u / s) as f32 } else { 0.0 };
        Self {
            translation: m.translation.into(),
            rotation: Quat::from_mat3(&Mat3::from_cols(q0.as_vec3(), q1.as_vec3(), q2.as_vec3())).normalize(),
            scale: DVec3::new(s0, s1, s2).as_vec3(),
            shear: Vec3::new(ratio(u01, s0), ratio(u02, s0), ratio(u12, s1)),
        }
    }

    /// The shear as a matrix (see [`Transform::shear`]).
    fn shear_matrix(&self) -> Mat3 {
        let h = self.shear;
        Mat3::from_cols(Vec3::X, Vec3::new(h.x, 1.0, 0.0), Vec3::new(h.y, h.z, 1.0))
    }

    /// Whether the transform shears (beyond f32 rounding of a plain TRS matrix).
    pub fn is_sheared(&self) -> bool {
        self.shear.abs().max_element() > 1e-5
    }

    /// This transform with its local -Z axis (glTF's light and camera forward) turned to `dir`.
    /// `dir` need not be normalised; a zero `dir` leaves the rotation unchanged.
    pub fn looking_to(mut self, dir: Vec3, up: Vec3) -> Self {
        let f = dir.normalize_or_zero();
        if f == Vec3::ZERO {
            return self;
        }
        let up = if f.cross(up).length_squared() < 1e-12 { f.any_orthonormal_vector() } else { up };
        let right = f.cross(up).normalize();
        let new_up = right.cross(f);
        self.rotation = Quat::from_mat3(&Mat3::from_cols(right, new_up, -f));
        self
    }

    /// The affine matrix of this transform.
    pub fn to_affine(&self) -> Affine3A {
        let linear = Mat3::from_quat(self.rotation) * Mat3::from_diagonal(self.scale) * self.shear_matrix();
        Affine3A::from_mat3_translation(linear, self.translation)
    }

    /// The local -Z axis in world space, normalised: the forward direction of spot, distant,
    /// projection and goniometric lights and of cameras. As glTF, Bevy's
    /// `GlobalTransform::forward()` and three.js define it, this is the whole matrix applied to
    /// -Z, so a mirror or a shear of a parent node turns it as it turns the node's geometry.
    pub fn forward(&self) -> Vec3 {
        self.aim() * Vec3::NEG_Z
    }

    /// The rotation that aims lights and cameras: its -Z is [`Self::forward`] and its +Y the
    /// matrix's +Y made orthogonal to that (a camera's up, a profile's zero azimuth plane's
    /// neighbour). Unlike `rotation` (the QR factor that places meshes, into which a mirror folds
    /// as a negative `scale.z`), it never flips the forward axis. A matrix that loses the Z axis
    /// keeps `rotation`.
    pub fn aim(&self) -> Quat {
        let m = self.to_affine().matrix3;
        let Some(back) = Vec3::from(m.z_axis).try_normalize() else { return self.rotation };
        let up = Vec3::from(m.y_axis);
        let up = (up - back * back.dot(up)).try_normalize().unwrap_or_else(|| back.any_orthonormal_vector());
        Quat::from_mat3(&Mat3::from_cols(up.cross(back), up, back)).normalize()
    }

    /// A point from local to world space.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.translation + self.transform_vector(p)
    }

    /// A direction from local to world space (scaled, not normalised).
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * (self.scale * (self.shear_matrix() * v))
    }

    /// A surface normal from local to world space (by the inverse transpose; not normalised):
    /// rotation (n / scale) with the shear's inverse transpose applied first.
    pub fn transform_normal(&self, n: Vec3) -> Vec3 {
        let h = self.shear;
        let unsheared = Vec3::new(n.x, n.y - h.x * n.x, n.z - h.z * n.y + (h.x * h.z - h.y) * n.x);
        self.rotation * (unsheared / self.scale)
    }

    /// A world-space direction in the frame of [`Self::aim`] (for lights, whose emission
    /// profiles live in that frame).
    pub fn to_local_direction(&self, v: Vec3) -> Vec3 {
        self.aim().inverse() * v
    }
}

/// Where the light system reads an entity's placement from: kelvin's own [`Transform`] (the
/// bevy_ecs entry, `LightingPlugin::build`), or with the `bevy` feature Bevy's `GlobalTransform`
/// (the `bevy_app::Plugin`). Its systems are generic over this one type, so an entity keeps one
/// transform, whichever app it lives in.
pub trait Placement: Component {
    /// The world-space transform of the entity.
    fn placement(&self) -> Transform;
}

impl Placement for Transform {
    #[inline]
    fn placement(&self) -> Transform {
        *self
    }
}

#[cfg(feature = "bevy")]
impl Placement for bevy_transform::components::GlobalTransform {
    fn placement(&self) -> Transform {
        // Bevy's glam is another version than kelvin's: pass the matrix as plain floats.
        Transform::from_affine(Affine3A::from_cols_array(&self.affine().to_cols_array()))
    }
}
