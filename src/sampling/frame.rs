//! `Frame`: a right-handed orthonormal basis, to carry z-up local directions to world space and back.

use glam::Vec3;

/// An orthonormal basis with `x × y = z`. Local coordinates of a vector are its dot products
/// with the three axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Unit axis of local x.
    pub x: Vec3,
    /// Unit axis of local y.
    pub y: Vec3,
    /// Unit axis of local z, the "up" of local directions (a normal, say).
    pub z: Vec3,
}

impl Default for Frame {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Frame {
    /// The world axes.
    pub const IDENTITY: Self = Self { x: Vec3::X, y: Vec3::Y, z: Vec3::Z };

    /// A frame whose z axis is `n`, by the branchless construction of Duff et al. 2017 ("Building
    /// an Orthonormal Basis, Revisited", JCGT 6(1)): continuous except across n.z = 0's sign flip,
    /// and exact for n = ±z. `n` must be normalised.
    pub fn from_z(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { x, y, z: n }
    }

    /// A frame from two orthonormal axes x and y; z = x × y.
    pub fn from_xy(x: Vec3, y: Vec3) -> Self {
        Self { x, y, z: x.cross(y) }
    }

    /// A frame from two orthonormal axes x and z; y = z × x.
    pub fn from_xz(x: Vec3, z: Vec3) -> Self {
        Self { x, y: z.cross(x), z }
    }

    /// World vector `v` in this frame's coordinates.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// Local vector `v` in world coordinates.
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crate::sampling::warp::sample_uniform_sphere;

    fn assert_orthonormal_right_handed(f: &Frame) {
        for (a, b) in [(f.x, f.y), (f.y, f.z), (f.z, f.x)] {
            assert!(a.dot(b).abs() < 1e-6, "{f:?}");
        }
        for a in [f.x, f.y, f.z] {
            assert!((a.length() - 1.0).abs() < 1e-6, "{f:?}");
        }
        assert!((f.x.cross(f.y) - f.z).length() < 1e-6, "{f:?}");
    }

    #[test]
    fn from_z_is_orthonormal_and_right_handed_for_random_and_axis_normals() {
        let mut rng = SplitMix64::new(7);
        let mut normals: Vec<Vec3> = (0..10_000).map(|_| sample_uniform_sphere(rng.vec2())).collect();
        normals.extend([Vec3::Z, Vec3::NEG_Z, Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 0.0, -0.0)]);
        normals.push(Vec3::new(1e-4, 0.0, -1.0).normalize());
        for n in normals {
            let f = Frame::from_z(n);
            assert_orthonormal_right_handed(&f);
            assert_eq!(f.z, n);
        }
    }

    #[test]
    fn to_local_and_from_local_round_trip() {
        let f = Frame::from_z(Vec3::new(0.3, -0.5, 0.8).normalize());
        let v = Vec3::new(1.5, -2.0, 0.25);
        assert!((f.from_local(f.to_local(v)) - v).length() < 1e-5);
        assert!((f.to_local(f.z) - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn from_xy_and_from_xz_complete_the_basis() {
        assert_orthonormal_right_handed(&Frame::from_xy(Vec3::Y, Vec3::Z));
        assert_orthonormal_right_handed(&Frame::from_xz(Vec3::Y, Vec3::X));
    }
}
