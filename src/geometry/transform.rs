//! `Transform`: where an entity sits in the world (glTF's TRS, right-handed, +Y up, metres).

use bevy_ecs::component::Component;
use glam::{Affine3A, Mat3, Quat, Vec3};

/// Translation, rotation and scale, applied as scale, then rotation, then translation.
/// Defaults to the identity.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Position in metres.
    pub translation: Vec3,
    /// Orientation; must be normalised.
    pub rotation: Quat,
    /// Per-axis scale; lights ignore it except area-light shapes.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// No translation, rotation or scale.
    pub const IDENTITY: Self = Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE };

    /// A pure translation.
    pub const fn from_translation(translation: Vec3) -> Self {
        Self { translation, rotation: Quat::IDENTITY, scale: Vec3::ONE }
    }

    /// From an affine matrix (e.g. a glTF node's world matrix).
    pub fn from_affine(m: Affine3A) -> Self {
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        Self { translation, rotation, scale }
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
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// The local -Z axis in world space (the forward direction of spot, distant and projection
    /// lights and of cameras, as glTF defines it).
    pub fn forward(&self) -> Vec3 {
        self.rotation * Vec3::NEG_Z
    }

    /// A point from local to world space.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.translation + self.rotation * (self.scale * p)
    }

    /// A direction from local to world space (scaled, not normalised).
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * (self.scale * v)
    }

    /// A world-space direction in this transform's local frame, ignoring scale (for lights,
    /// whose emission profiles live in the rotated frame).
    pub fn to_local_direction(&self, v: Vec3) -> Vec3 {
        self.rotation.inverse() * v
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
