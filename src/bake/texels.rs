//! Which texels of a lightmap a mesh covers, and where in them to sample. Each UV1 triangle is
//! rasterised conservatively: every texel it overlaps with positive area gets the pieces of the
//! triangle inside the texel (the triangle clipped to the texel's square, as a fan of triangles in
//! the triangle's barycentric coordinates). A texel's samples are spread uniformly over its pieces
//! by area, so no sample lies outside a triangle and a texel half covered is sampled on its
//! covered half only.

use glam::{DVec2, Vec2, Vec3};

use crate::geometry::{GeometryId, Mesh, mesh_point};
use crate::render::surface_paths::StartPoint;
use crate::sampling::sample_uniform_triangle;

/// Clipped pieces smaller than this (in texels squared) are rounding, not coverage: a triangle
/// edge that runs along a texel's border.
const MIN_PIECE_AREA: f64 = 1e-9;

/// One mesh primitive of a lightmap: its world-space mesh, its TEXCOORD_1, and its entity.
pub(super) struct Surface {
    /// The spawned `Mesh` (world space; triangles in the file's order).
    pub(super) mesh: Mesh,
    /// One uv per vertex of `mesh`.
    pub(super) uvs1: Vec<Vec2>,
    /// `Entity::index_u32` of the mesh's entity, as the scene BVH reports it.
    pub(super) entity_index: u32,
    /// Diffuse albedo (linear sRGB): what an engine multiplies the texel by (Bevy's
    /// `diffuse_color`, the base colour and its texture's mean, times 1 - metallic).
    pub(super) albedo: Vec3,
}

/// The world area (m^2) of `surfaces`' triangles and the area their uv1 triangles cover (a share
/// of [0, 1]^2; overlapping charts count twice).
pub(super) fn areas(surfaces: &[Surface]) -> (f64, f64) {
    let (mut world, mut uv) = (0.0, 0.0);
    for s in surfaces {
        for t in 0..s.mesh.triangle_count() {
            let [a, b, c] = s.mesh.triangle(t).map(|p| p.as_dvec3());
            world += 0.5 * (b - a).cross(c - a).length();
            let [a, b, c] = s.mesh.triangle_indices(t).map(|i| s.uvs1[i as usize].as_dvec2());
            uv += 0.5 * (b - a).perp_dot(c - a).abs();
        }
    }
    (world, uv)
}

/// A triangle of one texel's covered part: corners as barycentrics (b1, b2) of the mesh triangle.
#[derive(Clone, Copy, Debug)]
struct Piece {
    surface: u32,
    triangle: u32,
    corners: [Vec2; 3],
    /// Area in texels squared.
    area: f32,
}

/// The texels a lightmap's surfaces cover and the pieces of triangles inside each.
#[derive(Default)]
pub(super) struct Coverage {
    /// Covered texels (row-major index, row 0 at v = 0), ascending.
    pub(super) texels: Vec<u32>,
    /// Texel k's pieces are `pieces[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    pieces: Vec<Piece>,
    /// Triangles with a corner outside [0, 1]^2 in uv (their part outside is not baked).
    pub(super) outside: usize,
    /// Triangles of zero area in uv or in the world (nothing to sample).
    pub(super) degenerate: usize,
}

impl Coverage {
    /// Rasterises every triangle of `surfaces` into a `size` x `size` lightmap.
    pub(super) fn of(surfaces: &[Surface], size: u32) -> Self {
        let mut coverage = Self::default();
        let mut found: Vec<(u32, Piece)> = Vec::new();
        let n = size as f64;
        for (s, surface) in surfaces.iter().enumerate() {
            for t in 0..surface.mesh.triangle_count() {
                let corners = surface.mesh.triangle_indices(t).map(|i| surface.uvs1[i as usize]);
                if corners.iter().any(|c| c.cmplt(Vec2::ZERO).any() || c.cmpgt(Vec2::ONE).any()) {
                    coverage.outside += 1;
                }
                let uv = corners.map(|c| c.as_dvec2() * n);
                let Some(to_barycentric) = Barycentric::new(uv).filter(|_| !surface.mesh.is_degenerate(t)) else {
                    coverage.degenerate += 1;
                    continue;
                };
                let lo = uv[0].min(uv[1]).min(uv[2]).floor().max(DVec2::ZERO);
                let hi = uv[0].max(uv[1]).max(uv[2]).ceil().min(DVec2::splat(n));
                for y in lo.y as u32..hi.y as u32 {
                    for x in lo.x as u32..hi.x as u32 {
                        let polygon = clip_to_texel(&uv, x as f64, y as f64);
                        for k in 1..polygon.len().saturating_sub(1) {
                            let piece = [polygon[0], polygon[k], polygon[k + 1]];
                            let area = 0.5 * (piece[1] - piece[0]).perp_dot(piece[2] - piece[0]).abs();
                            if area > MIN_PIECE_AREA {
                                let corners = piece.map(|p| to_barycentric.at(p));
                                let piece = Piece { surface: s as u32, triangle: t as u32, corners, area: area as f32 };
                                found.push((y * size + x, piece));
                            }
                        }
                    }
                }
            }
        }
        // Stable: a texel's pieces stay in the order of the mesh's triangles.
        found.sort_by_key(|(texel, _)| *texel);
        for (texel, piece) in found {
            if coverage.texels.last() != Some(&texel) {
                coverage.texels.push(texel);
                coverage.starts.push(coverage.pieces.len() as u32);
            }
            coverage.pieces.push(piece);
        }
        coverage.starts.push(coverage.pieces.len() as u32);
        coverage
    }

    /// Per covered texel (as `texels`): the world area (m^2) of the surfaces inside it, and their
    /// area-weighted mean albedo.
    pub(super) fn areas(&self, surfaces: &[Surface], size: u32) -> Vec<(f32, Vec3)> {
        let n = size as f64;
        // World m^2 per texel^2 of each triangle, by surface and triangle.
        let scale: Vec<Vec<f64>> = surfaces
            .iter()
            .map(|s| {
                (0..s.mesh.triangle_count())
                    .map(|t| {
                        let [a, b, c] = s.mesh.triangle(t).map(|p| p.as_dvec3());
                        let [d, e, f] = s.mesh.triangle_indices(t).map(|i| s.uvs1[i as usize].as_dvec2() * n);
                        let uv = (e - d).perp_dot(f - d).abs();
                        if uv > 0.0 { (b - a).cross(c - a).length() / uv } else { 0.0 }
                    })
                    .collect()
            })
            .collect();
        (0..self.texels.len())
            .map(|k| {
                let (mut area, mut albedo) = (0.0f64, Vec3::ZERO);
                for p in &self.pieces[self.starts[k] as usize..self.starts[k + 1] as usize] {
                    let a = p.area as f64 * scale[p.surface as usize][p.triangle as usize];
                    (area, albedo) = (area + a, albedo + a as f32 * surfaces[p.surface as usize].albedo);
                }
                (area as f32, if area > 0.0 { albedo / area as f32 } else { Vec3::ZERO })
            })
            .collect()
    }

    /// The point of covered texel `k` that `u` (three uniform numbers) picks, uniform over the
    /// texel's covered area, as a path's start: its pixel and sample keys are `pixel`, `sample`.
    pub(super) fn point(&self, surfaces: &[Surface], k: usize, u: [f32; 3], pixel: u32, sample: u32) -> StartPoint {
        let pieces = &self.pieces[self.starts[k] as usize..self.starts[k + 1] as usize];
        let total: f32 = pieces.iter().map(|p| p.area).sum();
        let mut target = u[0] * total;
        // Rounding can leave `target` past the last piece's share: the last piece takes it.
        let piece = pieces.iter().find(|p| {
            target -= p.area;
            target < 0.0
        });
        let piece = piece.unwrap_or(&pieces[pieces.len() - 1]);
        let w = sample_uniform_triangle(Vec2::new(u[1], u[2]));
        let b12 = w[0] * piece.corners[0] + w[1] * piece.corners[1] + w[2] * piece.corners[2];
        let b12 = b12.clamp(Vec2::ZERO, Vec2::ONE);
        let b = [(1.0 - b12.x - b12.y).max(0.0), b12.x, b12.y];
        let surface = &surfaces[piece.surface as usize];
        let t = piece.triangle as usize;
        let (p, p_error, ng, ns) = mesh_point(&surface.mesh, t, b);
        // As the camera pass does: a vertex normal against the winding turns over, not flat.
        let ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
        let geometry = GeometryId { entity_index: surface.entity_index, primitive: piece.triangle };
        StartPoint { p, p_error, ng, ns, geometry, pixel, sample }
    }
}

/// The affine map from a uv triangle's plane to its barycentrics (b1, b2).
struct Barycentric {
    origin: DVec2,
    /// Rows of the inverse of the matrix [e1 e2].
    inverse: [DVec2; 2],
}

impl Barycentric {
    /// None for a triangle of (almost) zero area.
    fn new(uv: [DVec2; 3]) -> Option<Self> {
        let (e1, e2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = e1.perp_dot(e2);
        (det.abs() > MIN_PIECE_AREA)
            .then(|| Self { origin: uv[0], inverse: [DVec2::new(e2.y, -e2.x) / det, DVec2::new(-e1.y, e1.x) / det] })
    }

    fn at(&self, p: DVec2) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(self.inverse[0].dot(d) as f32, self.inverse[1].dot(d) as f32)
    }
}

/// Triangle `tri` clipped to the texel square [x, x + 1] x [y, y + 1] (Sutherland-Hodgman):
/// a convex polygon, empty where they do not overlap.
fn clip_to_texel(tri: &[DVec2; 3], x: f64, y: f64) -> Vec<DVec2> {
    let mut polygon = tri.to_vec();
    // Each edge of the square as (axis, bound, keep the side below the bound).
    for (axis, bound, below) in [(0, x, false), (0, x + 1.0, true), (1, y, false), (1, y + 1.0, true)] {
        let inside = |p: DVec2| if below { p[axis] <= bound } else { p[axis] >= bound };
        let input = std::mem::take(&mut polygon);
        for (i, &a) in input.iter().enumerate() {
            let b = input[(i + 1) % input.len()];
            if inside(a) {
                polygon.push(a);
            }
            if inside(a) != inside(b) {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                polygon.push(a + (b - a) * t);
            }
        }
        if polygon.is_empty() {
            break;
        }
    }
    polygon
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_surface(uv: [Vec2; 4]) -> Surface {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, -1.0), Vec3::NEG_Z];
        let mesh = Mesh::new(positions, vec![0, 1, 2, 0, 2, 3]).unwrap();
        Surface { mesh, uvs1: uv.to_vec(), entity_index: 0, albedo: Vec3::ONE }
    }

    /// The pieces of every texel add up to the uv area of the triangles: coverage is exact, and
    /// conservative (every texel a triangle overlaps is in, none more).
    #[test]
    fn pieces_tile_the_triangles_exactly() {
        let uv = [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.15), Vec2::new(0.8, 0.7), Vec2::new(0.2, 0.95)];
        let surfaces = [quad_surface(uv)];
        let size = 13;
        let c = Coverage::of(&surfaces, size);
        let total: f64 = c.pieces.iter().map(|p| p.area as f64).sum();
        let uv_area = |a: Vec2, b: Vec2, c: Vec2| 0.5 * (b - a).perp_dot(c - a).abs() as f64;
        let expected = (uv_area(uv[0], uv[1], uv[2]) + uv_area(uv[0], uv[2], uv[3])) * (size * size) as f64;
        assert!((total - expected).abs() < 1e-4 * expected, "{total} vs {expected}");
        // A texel fully inside the quad is one whole texel of area; the corner texels are partial.
        let centre = 6 * size + 6;
        let k = c.texels.iter().position(|&t| t == centre).unwrap();
        let area: f32 = c.pieces[c.starts[k] as usize..c.starts[k + 1] as usize].iter().map(|p| p.area).sum();
        assert!((area - 1.0).abs() < 1e-5, "{area}");
        assert!(!c.texels.contains(&0), "texel (0, 0) lies outside the quad");
        assert_eq!((c.outside, c.degenerate), (0, 0));
    }

    /// Sample points lie on the mesh and inside their texel's covered part, with the triangle's
    /// normal.
    #[test]
    fn points_lie_in_their_texel_on_the_surface() {
        let uv = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
        let surfaces = [quad_surface(uv)];
        let size = 4;
        let c = Coverage::of(&surfaces, size);
        assert_eq!(c.texels.len(), 16);
        let mut rng = crate::rng::SplitMix64::new(1);
        for (k, &texel) in c.texels.iter().enumerate() {
            for _ in 0..50 {
                let s = c.point(&surfaces, k, [rng.f32(), rng.f32(), rng.f32()], 0, 0);
                // The quad maps uv (u, v) to (u, 0, -v).
                let (tx, ty) = ((s.p.x * size as f32).floor() as u32, (-s.p.z * size as f32).floor() as u32);
                assert_eq!(ty.min(size - 1) * size + tx.min(size - 1), texel, "{:?}", s.p);
                assert!(s.p.y.abs() < 1e-6 && s.ng.abs_diff_eq(Vec3::Y, 1e-6) && s.ns == s.ng);
            }
        }
    }
}
