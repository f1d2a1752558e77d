//! Which triangles bound a solid: closed, consistently wound surfaces, whose inside lies behind
//! their faces (counter-clockwise front) whatever their material says about shading the back.
//! Bakes drop samples that start inside one (`bake`'s leak test): a double-sided box still has an
//! inside, while an open double-sided quad (a lamp, a single wall) has none.

use std::collections::HashMap;

use glam::Vec3;

use super::SceneBvh;
use super::shapes::Shape;

/// Per triangle of `triangles` (world-space corners; None for a triangle to leave out): whether it
/// lies in a closed surface. Corners are joined where their positions are bit for bit equal (a
/// mesh splits its vertices at hard edges and uv seams; the same point through the same transform
/// gives the same bits). A surface is a set of triangles connected through shared edges; it is
/// closed when each of its edges is shared by exactly two triangles that run it in opposite
/// directions (every edge of a consistently wound, watertight mesh). A surface with a hole, a
/// flipped triangle, or an edge shared three ways is open.
pub fn closed_triangles(triangles: &[Option<[Vec3; 3]>]) -> Vec<bool> {
    let mut vertex_of: HashMap<[u32; 3], u32> = HashMap::new();
    let mut weld = |p: Vec3| {
        // +0.0 and -0.0 are one point.
        let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
        let next = vertex_of.len() as u32;
        *vertex_of.entry(key).or_insert(next)
    };
    // Per undirected edge (low, high vertex): the triangles on it, and whether each runs it low to high.
    let mut edges: HashMap<(u32, u32), Vec<(u32, bool)>> = HashMap::new();
    let mut open = vec![false; triangles.len()];
    for (t, tri) in triangles.iter().enumerate() {
        let Some(tri) = tri else {
            open[t] = true;
            continue;
        };
        let v = tri.map(&mut weld);
        if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
            open[t] = true;
            continue;
        }
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push((t as u32, a < b));
        }
    }
    let mut sets = DisjointSets::new(triangles.len());
    for on_edge in edges.values() {
        for &(t, _) in &on_edge[1..] {
            sets.union(on_edge[0].0, t);
        }
        let paired = on_edge.len() == 2 && on_edge[0].1 != on_edge[1].1;
        if !paired {
            open[on_edge[0].0 as usize] = true;
        }
    }
    // A surface is open if any of its triangles is.
    let mut open_root = vec![false; triangles.len()];
    for (t, &o) in open.iter().enumerate() {
        if o {
            open_root[sets.find(t as u32) as usize] = true;
        }
    }
    (0..triangles.len() as u32).map(|t| triangles[t as usize].is_some() && !open_root[sets.find(t) as usize]).collect()
}

/// Union-find over triangle indices (path halving, union by size).
struct DisjointSets {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        Self { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let up = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = up;
            x = up;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

/// Which primitives of a [`SceneBvh`]'s instances bound a solid: the triangles of closed surfaces
/// ([`closed_triangles`], over the instances of one group taken together) and spheres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClosedSurfaces {
    /// Per instance, per triangle (one entry for a shape).
    closed: Vec<Vec<bool>>,
    /// [`CONTACT`] times the diagonal of the scene's bounds, m.
    contact: f32,
}

/// Two surfaces nearer than this share of the scene's diagonal touch: a box exported standing on a
/// floor has its bottom a few float steps above or below the floor, where rays cannot tell which
/// side they start on. Well above those steps (2^-23 of the coordinates), well below any gap a
/// texel could see through.
pub const CONTACT: f32 = 1e-5;

impl ClosedSurfaces {
    /// The closed primitives of `bvh`. Instances with the same `group` key are welded together
    /// (the primitives of one glTF mesh, spawned as an entity each, may close a solid only
    /// together); instances of different groups never join, so two solids that touch stay closed.
    pub fn of(bvh: &SceneBvh, group: impl Fn(u32) -> u64) -> Self {
        let n = bvh.instance_count() as u32;
        let mut closed: Vec<Vec<bool>> = vec![Vec::new(); n as usize];
        let mut groups: HashMap<u64, Vec<u32>> = HashMap::new();
        for i in 0..n {
            if let Some(shape) = bvh.placed_shape(i) {
                closed[i as usize] = vec![matches!(shape.shape, Shape::Sphere(_))];
            } else if bvh.mesh_of(i).is_some() {
                groups.entry(group(i)).or_default().push(i);
            }
        }
        for members in groups.values() {
            let mut triangles = Vec::new();
            for &i in members {
                let count = bvh.mesh_of(i).map_or(0, |m| m.triangle_count() as u32);
                triangles.extend((0..count).map(|t| bvh.world_triangle(i, t)));
            }
            let mut flags = closed_triangles(&triangles).into_iter();
            for &i in members {
                let count = bvh.mesh_of(i).map_or(0, |m| m.triangle_count());
                closed[i as usize] = flags.by_ref().take(count).collect();
            }
        }
        let contact = bvh.world_bounds().map_or(0.0, |(lo, hi)| CONTACT * (hi - lo).length());
        Self { closed, contact }
    }

    /// Distance (m) within which a point touches a closed surface ([`CONTACT`]): a point that
    /// close to a solid's face, on either side, is in contact with it (under a box on a floor).
    pub fn contact_distance(&self) -> f32 {
        self.contact
    }

    /// Whether primitive `primitive` of instance `instance` bounds a solid (false for unknown ids).
    pub fn contains(&self, instance: u32, primitive: u32) -> bool {
        self.closed.get(instance as usize).and_then(|c| c.get(primitive as usize)).copied().unwrap_or(false)
    }

    /// Number of primitives that bound a solid.
    pub fn count(&self) -> usize {
        self.closed.iter().flatten().filter(|c| **c).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 12 triangles of the box [lo, hi], fronts out (`inward`: in), each face with its own corners.
    fn cube(lo: Vec3, hi: Vec3, inward: bool) -> Vec<Option<[Vec3; 3]>> {
        let mut out = Vec::new();
        for face in 0..6 {
            let (a, positive) = (face / 2, face % 2 == 1);
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let corner = |sb: bool, sc: bool| {
                let mut p = Vec3::ZERO;
                p[a] = if positive { hi[a] } else { lo[a] };
                p[b] = if sb { hi[b] } else { lo[b] };
                p[c] = if sc { hi[c] } else { lo[c] };
                p
            };
            let q = [corner(false, false), corner(true, false), corner(true, true), corner(false, true)];
            // q[0], q[1], q[2] wind to +e_a.
            let mut tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
            if positive == inward {
                tris.iter_mut().for_each(|t| t.swap(1, 2));
            }
            out.extend(tris.map(Some));
        }
        out
    }

    #[test]
    fn a_box_is_closed_either_way_round() {
        for inward in [false, true] {
            assert!(closed_triangles(&cube(Vec3::ZERO, Vec3::ONE, inward)).iter().all(|c| *c), "inward {inward}");
        }
    }

    #[test]
    fn a_box_with_a_hole_or_a_flipped_face_is_open() {
        let mut holed = cube(Vec3::ZERO, Vec3::ONE, false);
        holed.truncate(10);
        assert!(closed_triangles(&holed).iter().all(|c| !*c));
        let mut flipped = cube(Vec3::ZERO, Vec3::ONE, false);
        for t in flipped[4..6].iter_mut().flatten() {
            t.swap(1, 2);
        }
        assert!(closed_triangles(&flipped).iter().all(|c| !*c));
        let mut degenerate = cube(Vec3::ZERO, Vec3::ONE, false);
        degenerate[3] = None;
        assert!(closed_triangles(&degenerate).iter().all(|c| !*c));
    }

    /// A box and a quad in one list: the box's surface is closed, the quad's open.
    #[test]
    fn surfaces_are_judged_apart() {
        let mut tris = cube(Vec3::ZERO, Vec3::ONE, false);
        let (a, b, c, d) =
            (Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 1.0), Vec3::Z * 2.0);
        tris.extend([Some([a, b, c]), Some([a, c, d])]);
        let closed = closed_triangles(&tris);
        assert!(closed[..12].iter().all(|c| *c) && closed[12..].iter().all(|c| !*c), "{closed:?}");
    }

    /// Two boxes sharing a face in one list: the shared edges are met four times, so neither is closed.
    #[test]
    fn an_edge_shared_by_four_triangles_is_open() {
        let mut tris = cube(Vec3::ZERO, Vec3::ONE, false);
        tris.extend(cube(Vec3::X, Vec3::new(2.0, 1.0, 1.0), false));
        assert!(closed_triangles(&tris).iter().all(|c| !*c));
    }
}
