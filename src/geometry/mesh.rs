//! `Mesh`: an indexed triangle mesh in local space (from glTF or built in code).

use bevy_ecs::component::Component;
use glam::{Vec2, Vec3};

use super::GeometryError;
use super::triangle::is_degenerate;

/// Indexed triangles in the entity's local space. Counter-clockwise winding is the front face
/// (glTF). Built through [`Mesh::new`], which checks every invariant below, so the scene BVH
/// never meets a NaN vertex or an out-of-range index.
///
/// Invariants: positions are finite; `indices.len()` is a multiple of 3 and every index is below
/// `positions.len()`; normals and uvs, when present, have one finite entry per position.
/// Degenerate triangles (repeated or collinear vertices) are allowed: the BVH skips them and
/// lists them in its build report (see [`Mesh::degenerate_triangles`]).
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    indices: Vec<u32>,
}

impl Mesh {
    /// A mesh from vertex positions (metres, local space) and triangle indices.
    pub fn new(positions: Vec<Vec3>, indices: Vec<u32>) -> Result<Self, GeometryError> {
        if let Some((index, value)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(GeometryError::NonFiniteVertex { index, value: *value });
        }
        if !indices.len().is_multiple_of(3) {
            return Err(GeometryError::IndexCountNotTriangles { count: indices.len() });
        }
        if let Some((i, &index)) = indices.iter().enumerate().find(|&(_, &i)| i as usize >= positions.len()) {
            return Err(GeometryError::IndexOutOfRange { triangle: i / 3, index, vertex_count: positions.len() });
        }
        Ok(Self { positions, normals: None, uvs: None, indices })
    }

    /// A mesh from a list of triangles (three vertices each, no sharing).
    pub fn from_triangles(triangles: &[[Vec3; 3]]) -> Result<Self, GeometryError> {
        let positions: Vec<Vec3> = triangles.iter().flatten().copied().collect();
        Self::new(positions, (0..triangles.len() as u32 * 3).collect())
    }

    /// Adds per-vertex shading normals (need not be unit length; zero ones fall back to the
    /// geometric normal at hit time).
    pub fn with_normals(mut self, normals: Vec<Vec3>) -> Result<Self, GeometryError> {
        self.check_attribute_len("normals", normals.len())?;
        if let Some((index, _)) = normals.iter().enumerate().find(|(_, n)| !n.is_finite()) {
            return Err(GeometryError::NonFiniteAttribute { attribute: "normals", index });
        }
        self.normals = Some(normals);
        Ok(self)
    }

    /// Adds per-vertex texture coordinates.
    pub fn with_uvs(mut self, uvs: Vec<Vec2>) -> Result<Self, GeometryError> {
        self.check_attribute_len("uvs", uvs.len())?;
        if let Some((index, _)) = uvs.iter().enumerate().find(|(_, uv)| !uv.is_finite()) {
            return Err(GeometryError::NonFiniteAttribute { attribute: "uvs", index });
        }
        self.uvs = Some(uvs);
        Ok(self)
    }

    fn check_attribute_len(&self, attribute: &'static str, len: usize) -> Result<(), GeometryError> {
        if len == self.positions.len() {
            Ok(())
        } else {
            Err(GeometryError::AttributeLength { attribute, len, expected: self.positions.len() })
        }
    }

    /// Vertex positions, local space.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Per-vertex normals, if any.
    pub fn normals(&self) -> Option<&[Vec3]> {
        self.normals.as_deref()
    }

    /// Per-vertex texture coordinates, if any.
    pub fn uvs(&self) -> Option<&[Vec2]> {
        self.uvs.as_deref()
    }

    /// Triangle indices, three per triangle.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Number of triangles, degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Vertex indices of triangle `i`. Panics if `i >= triangle_count()`.
    pub fn triangle_indices(&self, i: usize) -> [u32; 3] {
        [self.indices[3 * i], self.indices[3 * i + 1], self.indices[3 * i + 2]]
    }

    /// Local-space vertices of triangle `i`. Panics if `i >= triangle_count()`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangle_indices(i).map(|k| self.positions[k as usize])
    }

    /// Triangles with zero area in local space (repeated indices or collinear vertices).
    pub fn degenerate_triangles(&self) -> Vec<u32> {
        (0..self.triangle_count()).filter(|&i| self.is_degenerate(i)).map(|i| i as u32).collect()
    }

    /// Whether triangle `i` has zero area in local space.
    pub fn is_degenerate(&self, i: usize) -> bool {
        let [a, b, c] = self.triangle_indices(i);
        a == b || b == c || a == c || is_degenerate(&self.triangle(i))
    }

    /// dp/du and dp/dv of triangle `i` in the mesh's space, from its vertices and uvs (pbrt-v4's
    /// triangle shading frame); None without uvs or for uvs of zero area.
    pub fn uv_derivatives(&self, i: usize) -> Option<(Vec3, Vec3)> {
        let uvs = self.uvs()?;
        let [a, b, c] = self.triangle_indices(i).map(|k| k as usize);
        let (p, uv) = (self.positions(), [uvs[a], uvs[b], uvs[c]]);
        let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
        let (dp02, dp12) = (p[a] - p[c], p[b] - p[c]);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        if !(det.abs() > 1e-12) {
            return None;
        }
        let dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
        let dpdv = (dp12 * duv02.x - dp02 * duv12.x) / det;
        (dpdu.is_finite() && dpdv.is_finite()).then_some((dpdu, dpdv))
    }

    /// A UV sphere of `radius` around the origin, poles on local +-Y, with outward normals and
    /// (longitude, latitude) uvs in [0, 1]. `segments >= 3` around, `rings >= 2` from pole to
    /// pole; smaller values are raised to these. Triangles at the poles are not degenerate.
    pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Self {
        let (segments, rings) = (segments.max(3), rings.max(2));
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                let dir = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
                positions.push(radius * dir);
                uvs.push(Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
            }
        }
        let normals = positions.iter().map(|p| p.normalize_or_zero()).collect();
        let row = segments + 1;
        let mut indices = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, r * row + s + 1);
                let (c, d) = (a + row, b + row);
                if r != 0 {
                    indices.extend([a, c, b]);
                }
                if r != rings - 1 {
                    indices.extend([b, c, d]);
                }
            }
        }
        Self { positions, normals: Some(normals), uvs: Some(uvs), indices }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_input_with_where() {
        let nan = Vec3::new(0.0, f32::NAN, 0.0);
        assert!(matches!(
            Mesh::new(vec![Vec3::ZERO, nan, Vec3::X], vec![0, 1, 2]),
            Err(GeometryError::NonFiniteVertex { index: 1, .. })
        ));
        assert!(matches!(
            Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2, 2, 1, 7]),
            Err(GeometryError::IndexOutOfRange { triangle: 1, index: 7, vertex_count: 3 })
        ));
        assert!(matches!(
            Mesh::new(vec![Vec3::ZERO; 3], vec![0, 1]),
            Err(GeometryError::IndexCountNotTriangles { count: 2 })
        ));
        let m = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).unwrap();
        assert!(matches!(m.clone().with_normals(vec![Vec3::Z]), Err(GeometryError::AttributeLength { .. })));
        assert!(matches!(
            m.with_uvs(vec![Vec2::ZERO, Vec2::NAN, Vec2::ONE]),
            Err(GeometryError::NonFiniteAttribute { attribute: "uvs", index: 1 })
        ));
    }

    #[test]
    fn finds_degenerate_triangles() {
        let m = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, 2.0 * Vec3::X], vec![0, 1, 2, 0, 0, 1, 0, 1, 3]).unwrap();
        assert_eq!(m.degenerate_triangles(), vec![1, 2]);
    }

    #[test]
    fn uv_sphere_is_closed_and_outward() {
        let m = Mesh::uv_sphere(2.0, 16, 8);
        assert!(m.degenerate_triangles().is_empty());
        // Closed and outward: the signed volume equals that of the inscribed polyhedron (> 0).
        let vol: f32 = (0..m.triangle_count())
            .map(|i| {
                let [a, b, c] = m.triangle(i);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let sphere = 4.0 / 3.0 * std::f32::consts::PI * 8.0;
        assert!(vol > 0.9 * sphere && vol < sphere, "volume {vol}");
    }
}
