//! Hit records: what a triangle's hits share ([`TriangleAttributes`]), the part that varies over
//! the triangle (`surface_at`, written once for one hit and for a lane of hits), and the closest
//! hits of a packet as lane columns ([`HitLanes`]).

use glam::{Vec2, Vec3};

use super::bvh::{GeometryId, SceneBvh};
use super::mesh::Mesh;
use super::ray::triangle_point_error;
use super::visibility::Hit;
use crate::lanes::{F32x16, Mask16, Real, U32x16, Vec3x16, Vector};

/// A triangle's data that its hits share: world vertices and unit normal, the mesh's vertex
/// normals in world space (not unit; zero where the mesh has none) and uvs (the unit triangle
/// (0, 0), (1, 0), (0, 1) where it has none, so that a hit's uv is its barycentrics (b1, b2)),
/// and its ids.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriangleAttributes {
    v: [Vec3; 3],
    ng: Vec3,
    normals: [Vec3; 3],
    uvs: [Vec2; 3],
    id: GeometryId,
    material: u32,
    instance: u32,
}

/// The uvs of a mesh without texture coordinates: a hit's uv is then (b1, b2).
const BARYCENTRIC_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

/// A hit's point, its error bound, its shading normal and its uv on a triangle with vertices `v`,
/// unit normal `ng`, vertex normals `n` and uvs `uv`, at barycentrics `b`. The shading normal is
/// the vertex normals' interpolation made unit (interpolating world-space normals is transforming
/// the interpolated object-space one: the normal map is linear), or `ng` where that has no
/// direction (zero normals: the mesh has none). For one hit (`Vec3`) or a lane of hits.
#[inline(always)]
fn surface_at<V: Vector>(
    v: &[V; 3],
    ng: V,
    n: &[V; 3],
    uv: &[[V::Real; 2]; 3],
    b: [V::Real; 3],
) -> (V, V, V, [V::Real; 2]) {
    let p = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
    let interpolated = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
    // As glam's `normalize_or_zero`, with `ng` for zero.
    let rcp = V::Real::splat(1.0) / interpolated.length();
    let unit = rcp.is_finite() & rcp.gt(V::Real::splat(0.0));
    let ns = V::select(unit, interpolated * rcp, ng);
    let along = |a: usize| uv[0][a] * b[0] + uv[1][a] * b[1] + uv[2][a] * b[2];
    (p, triangle_point_error(v, b), ns, [along(0), along(1)])
}

impl TriangleAttributes {
    /// The hit record at parameter `t` and barycentrics `b`.
    #[inline(always)]
    pub(super) fn hit(&self, t: f32, b: [f32; 3]) -> Hit {
        let uv = self.uvs.map(|t| [t.x, t.y]);
        let (p, p_error, ns, [u, v]) = surface_at(&self.v, self.ng, &self.normals, &uv, b);
        let (id, material, instance) = (self.id, self.material, self.instance);
        Hit { t, p, p_error, ng: self.ng, ns, uv: Vec2::new(u, v), id, material, instance }
    }
}

impl SceneBvh {
    /// What every hit on the triangle in leaf slot `slot` (input primitive `prim`) shares.
    #[inline(always)]
    pub(super) fn triangle_attributes(&self, prim: u32, slot: usize) -> TriangleAttributes {
        let (instance, id, material) = self.id_of(prim);
        let v = self.leaf[slot].v;
        let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or(Vec3::Z);
        let (mut normals, mut uvs) = ([Vec3::ZERO; 3], BARYCENTRIC_UVS);
        if let Some(mesh) = self.mesh_of(instance) {
            let idx = mesh.triangle_indices(id.primitive as usize).map(|k| k as usize);
            if let Some(n) = mesh.normals() {
                let transform = self.instances[instance as usize].transform;
                normals = idx.map(|k| transform.transform_normal(n[k]));
            }
            if let Some(t) = mesh.uvs() {
                uvs = idx.map(|k| t[k]);
            }
        }
        TriangleAttributes { v, ng, normals, uvs, id, material, instance }
    }
}

/// The point of triangle `t` of a world-space mesh at barycentrics `b` as a hit there has it: the
/// point, its error bound, the unit geometric normal and the shading normal (as `surface_at`, not
/// yet turned to the geometric normal's side). For points that start paths on a surface (bakes).
pub(crate) fn mesh_point(mesh: &Mesh, t: usize, b: [f32; 3]) -> (Vec3, Vec3, Vec3, Vec3) {
    let v = mesh.triangle(t);
    let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or(Vec3::Z);
    let normals = mesh.normals().map_or([Vec3::ZERO; 3], |n| mesh.triangle_indices(t).map(|k| n[k as usize]));
    let uv = BARYCENTRIC_UVS.map(|t| [t.x, t.y]);
    let (p, p_error, ns, _) = surface_at(&v, ng, &normals, &uv, b);
    (p, p_error, ng, ns)
}

/// The closest hits of up to [`LANES`] rays as lane columns, one per field of [`Hit`]; lane `l`
/// holds a hit where `found` does (see [`HitLanes::hit`]), anything elsewhere.
#[derive(Clone, Copy, Debug)]
pub struct HitLanes {
    /// Lanes whose ray hit something.
    pub found: Mask16,
    /// [`Hit::t`].
    pub t: F32x16,
    /// [`Hit::p`].
    pub p: Vec3x16,
    /// [`Hit::p_error`].
    pub p_error: Vec3x16,
    /// [`Hit::ng`].
    pub ng: Vec3x16,
    /// [`Hit::ns`].
    pub ns: Vec3x16,
    /// [`Hit::uv`], u and v.
    pub uv: [F32x16; 2],
    /// [`Hit::id`]'s `entity_index`.
    pub entity_index: U32x16,
    /// [`Hit::id`]'s `primitive`.
    pub primitive: U32x16,
    /// [`Hit::material`].
    pub material: U32x16,
    /// [`Hit::instance`].
    pub instance: U32x16,
}

impl Default for HitLanes {
    fn default() -> Self {
        let zero = U32x16::splat(0);
        Self {
            found: Mask16::splat(false),
            t: F32x16::ZERO,
            p: Vec3x16::ZERO,
            p_error: Vec3x16::ZERO,
            ng: Vec3x16::ZERO,
            ns: Vec3x16::ZERO,
            uv: [F32x16::ZERO; 2],
            entity_index: zero,
            primitive: zero,
            material: zero,
            instance: zero,
        }
    }
}

impl HitLanes {
    /// Lane `l`'s hit, None where its ray hit nothing.
    pub fn hit(&self, l: usize) -> Option<Hit> {
        self.found.test(l).then(|| Hit {
            t: self.t[l],
            p: self.p.lane(l),
            p_error: self.p_error.lane(l),
            ng: self.ng.lane(l),
            ns: self.ns.lane(l),
            uv: Vec2::new(self.uv[0][l], self.uv[1][l]),
            id: GeometryId { entity_index: self.entity_index.0[l], primitive: self.primitive.0[l] },
            material: self.material.0[l],
            instance: self.instance.0[l],
        })
    }

    /// Sets lane `l` to `hit` (None: the ray hit nothing; the other columns keep their values).
    #[inline(always)]
    pub fn set(&mut self, l: usize, hit: Option<Hit>) {
        self.found.0[l] = if hit.is_some() { u32::MAX } else { 0 };
        let Some(h) = hit else { return };
        self.t[l] = h.t;
        self.p.set_lane(l, h.p);
        self.p_error.set_lane(l, h.p_error);
        self.ng.set_lane(l, h.ng);
        self.ns.set_lane(l, h.ns);
        (self.uv[0][l], self.uv[1][l]) = h.uv.into();
        self.set_ids(l, h.id, h.material, h.instance);
    }

    #[inline(always)]
    fn set_ids(&mut self, l: usize, id: GeometryId, material: u32, instance: u32) {
        (self.entity_index.0[l], self.primitive.0[l]) = (id.entity_index, id.primitive);
        (self.material.0[l], self.instance.0[l]) = (material, instance);
    }
}

/// The triangle data of a lane of hits, gathered lane by lane for `surface_at`.
pub(super) struct TriangleLanes {
    v: [Vec3x16; 3],
    ng: Vec3x16,
    n: [Vec3x16; 3],
    uv: [[F32x16; 2]; 3],
}

impl TriangleLanes {
    pub(super) fn new() -> Self {
        Self { v: [Vec3x16::ZERO; 3], ng: Vec3x16::ZERO, n: [Vec3x16::ZERO; 3], uv: [[F32x16::ZERO; 2]; 3] }
    }

    /// Lane `l` hits the triangle of `a` at parameter `t`: its shared data go to the lane
    /// columns (`out`'s for `t` and the ids).
    #[inline(always)]
    pub(super) fn set(&mut self, l: usize, a: &TriangleAttributes, t: f32, out: &mut HitLanes) {
        for k in 0..3 {
            self.v[k].set_lane(l, a.v[k]);
            self.n[k].set_lane(l, a.normals[k]);
            (self.uv[k][0][l], self.uv[k][1][l]) = a.uvs[k].into();
        }
        self.ng.set_lane(l, a.ng);
        out.found.0[l] = u32::MAX;
        out.t[l] = t;
        out.set_ids(l, a.id, a.material, a.instance);
    }

    /// Fills `out`'s point, error, normals and uv columns of every lane from barycentrics `b`;
    /// lanes whose hits are not triangles are then set over.
    #[inline(always)]
    pub(super) fn surfaces(&self, b: &Vec3x16, out: &mut HitLanes) {
        let (p, p_error, ns, uv) = surface_at(&self.v, self.ng, &self.n, &self.uv, [b.x, b.y, b.z]);
        (out.p, out.p_error, out.ng, out.ns, out.uv) = (p, p_error, self.ng, ns, uv);
    }
}
