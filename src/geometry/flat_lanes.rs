//! Ray queries of [`LANES`] rays at once for scenes of a few flat shapes (a ground rectangle, a
//! disk light): the answers of [`SceneBvh::closest_hit`] and [`SceneBvh::occluded_from`] bit for
//! bit, from the same operations in the same order (`PlacedShape::flat_hit`: the f32 test, the
//! f64 test where the f32 answer is not sure, and `PlacedShape::flat_world_coordinate`) run as
//! lane loops, which compile to vector code inside `lanes::widest`. Other scenes answer one ray
//! at a time.

use glam::{Vec2, Vec3};

use super::bvh::{GeometryId, NO_SHAPE, SceneBvh};
use super::ray::{Lanes3, Ray};
use super::shapes::{
    PlacedShape, Shape, dot_row, dot_row32, dz_error_bound, flat_hit_f32_from_rows, flat_hit_from_rows,
};
use super::visibility::{FEW_PRIMITIVES, Hit};
use crate::lanes::LANES;

/// [`LANES`] rays as lane columns, widened to f64 (origins' object-space rows are formed in f64,
/// and directions' too where the f32 test is not sure).
/// Lanes never set hold invalid rays (zero direction), which hit nothing.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct RayLanes {
    o: [[f64; LANES]; 3],
    d: [[f64; LANES]; 3],
    t_max: [f32; LANES],
    /// [`Ray::is_valid`] per lane.
    valid: [bool; LANES],
}

impl Default for RayLanes {
    fn default() -> Self {
        Self { o: [[0.0; LANES]; 3], d: [[0.0; LANES]; 3], t_max: [0.0; LANES], valid: [false; LANES] }
    }
}

impl RayLanes {
    /// The rays as lanes.
    #[inline(always)]
    pub fn from_rays(rays: &[Ray; LANES]) -> Self {
        let mut r = Self::default();
        for (l, ray) in rays.iter().enumerate() {
            r.set(l, ray);
        }
        r
    }

    /// Rays from lane columns of origins and directions, all with the same `t_max`.
    #[inline(always)]
    pub fn from_columns([origin, dir]: &[Lanes3; 2], t_max: f32) -> Self {
        let mut valid = [false; LANES];
        for (l, valid) in valid.iter_mut().enumerate() {
            let origin_finite = origin[0][l].is_finite() & origin[1][l].is_finite() & origin[2][l].is_finite();
            *valid = origin_finite & dir_valid(dir, l) & (t_max > 0.0);
        }
        // Built whole, not over `default()`: t_max written lane by lane came out as two half
        // stores, and the full-width load of it in `closest_hits_lanes` stalled on them.
        let widen = |c: &Lanes3| c.map(|row| row.map(f64::from));
        Self { o: widen(origin), d: widen(dir), t_max: [t_max; LANES], valid }
    }

    /// Puts `ray` in lane `l`, reading its fields one by one (copying whole `Ray`s between
    /// arrays stalls on store-to-load forwarding).
    #[inline(always)]
    pub fn set(&mut self, l: usize, ray: &Ray) {
        for a in 0..3 {
            (self.o[a][l], self.d[a][l]) = (ray.origin[a] as f64, ray.dir[a] as f64);
        }
        (self.t_max[l], self.valid[l]) = (ray.t_max, ray.is_valid());
    }

    /// The rays as f32 columns (exact: the f64 values came from f32); invalid lanes get
    /// t_max = 0, which keeps them invalid.
    #[inline(always)]
    fn f32_columns(&self) -> (Lanes3, Lanes3, [f32; LANES]) {
        let (mut origin, mut dir, mut t_max) = ([[0f32; LANES]; 3], [[0f32; LANES]; 3], self.t_max);
        for a in 0..3 {
            for l in 0..LANES {
                (origin[a][l], dir[a][l]) = (self.o[a][l] as f32, self.d[a][l] as f32);
            }
        }
        for l in 0..LANES {
            t_max[l] = if self.valid[l] { t_max[l] } else { 0.0 };
        }
        (origin, dir, t_max)
    }

    #[inline(always)]
    fn origin(&self, l: usize) -> [f64; 3] {
        [self.o[0][l], self.o[1][l], self.o[2][l]]
    }
}

/// The direction half of [`Ray::is_valid`] for lane `l`: finite and not zero. `&` and `|`, not
/// `&&` and `||`, so that lane loops stay free of branches.
#[inline(always)]
fn dir_valid(dir: &Lanes3, l: usize) -> bool {
    let (x, y, z) = (dir[0][l], dir[1][l], dir[2][l]);
    x.is_finite() & y.is_finite() & z.is_finite() & ((x != 0.0) | (y != 0.0) | (z != 0.0))
}

/// The flat-shape hit test (`PlacedShape::local_hit`) of every lane over (0, t_max[l]]: hit
/// flags, t, object-space x and y.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops on purpose (as `occluded_lanes`)
fn flat_hits(shape: &PlacedShape, r: &RayLanes, t_max: &[f32; LANES]) -> FlatHits {
    // One step per loop over all lanes, so that LLVM vectorises across lanes.
    let (mut o_row, mut d) = ([[0.0f64; LANES]; 3], [[0.0f32; LANES]; 3]);
    for i in 0..3 {
        for l in 0..LANES {
            (o_row[i][l], d[i][l]) = (shape.object_point_row(i, r.origin(l)), r.d[i][l] as f32);
        }
    }
    let mut hits = flat_hits_f32(shape, t_max, &o_row, &d);
    // Invalid lanes (zero directions, unset lanes of a partial block) count as no hit anyway.
    for l in 0..LANES {
        hits.sure[l] |= !r.valid[l];
    }
    hits.settle(|| flat_hits_of_rows(shape, t_max, &o_row, &dir_rows(shape, &r.d)));
    hits
}

/// The f64 object-space rows of directions `d` (for the f64 test).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops on purpose (as `occluded_lanes`)
fn dir_rows(shape: &PlacedShape, d: &Rows) -> Rows {
    let mut d_row = [[0.0f64; LANES]; 3];
    for (i, row) in d_row.iter_mut().enumerate() {
        // The matrix row is read once per row, not per lane: read per lane, the loop stayed scalar.
        let m = shape.object_matrix_row(i);
        for l in 0..LANES {
            row[l] = dot_row(m, [d[0][l], d[1][l], d[2][l]]);
        }
    }
    d_row
}

/// The f32 test of [`flat_hits`] (`PlacedShape::flat_hit`'s first step) for rays whose origins'
/// object-space rows are `o_row` (f64) and whose world directions are `d`. Each shape kind gets
/// its own loop, so that no `match` stops it vectorising.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops on purpose (as `occluded_lanes`)
fn flat_hits_f32(shape: &PlacedShape, t_max: &[f32; LANES], o_row: &Rows, d: &[[f32; LANES]; 3]) -> FlatHits {
    let (mut o32, mut d_row, mut dz_error) = ([[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3], [0.0f32; LANES]);
    for (o32, o_row) in o32.iter_mut().zip(o_row) {
        for l in 0..LANES {
            o32[l] = o_row[l] as f32;
        }
    }
    for (i, row) in d_row.iter_mut().enumerate() {
        // The matrix row is read once per row, not per lane (read per lane, loops stayed scalar).
        let m = shape.object_matrix_row32(i);
        for l in 0..LANES {
            row[l] = dot_row32(m, [d[0][l], d[1][l], d[2][l]]);
        }
    }
    let a = shape.abs_object_row_z32();
    for l in 0..LANES {
        dz_error[l] = dz_error_bound(a, [d[0][l], d[1][l], d[2][l]]);
    }
    #[inline(always)]
    fn each(
        t_max: &[f32; LANES],
        o: &[[f32; LANES]; 3],
        d: &[[f32; LANES]; 3],
        dz_error: &[f32; LANES],
        contains: impl Fn(f32, f32) -> bool,
    ) -> FlatHits {
        let mut out = FlatHits::default();
        for l in 0..LANES {
            let rows = [(o[0][l], d[0][l]), (o[1][l], d[1][l]), (o[2][l], d[2][l])];
            (out.sure[l], out.hit[l], out.t[l], out.x[l], out.y[l]) =
                flat_hit_f32_from_rows(rows, dz_error[l], t_max[l], &contains);
        }
        out
    }
    match shape.shape {
        Shape::Rectangle(rect) => {
            each(t_max, &o32, &d_row, &dz_error, |x, y| Shape::Rectangle(rect).flat_contains32(x, y))
        }
        Shape::Disk(disk) => each(t_max, &o32, &d_row, &dz_error, |x, y| Shape::Disk(disk).flat_contains32(x, y)),
        Shape::Sphere(_) => FlatHits::default(),
    }
}

/// The f64 test of [`flat_hits`] for the rays whose object-space rows `i` are `o_row[i]` (origins)
/// and `d_row[i]` (directions), x and y rounded to f32 (as `PlacedShape::flat_hit`). Every answer
/// is sure.
#[inline(always)]
fn flat_hits_of_rows(shape: &PlacedShape, t_max: &[f32; LANES], o_row: &Rows, d_row: &Rows) -> FlatHits {
    #[inline(always)]
    fn each(t_max: &[f32; LANES], o_row: &Rows, d_row: &Rows, contains: impl Fn(f64, f64) -> bool) -> FlatHits {
        let mut out = FlatHits { sure: [true; LANES], ..FlatHits::default() };
        for l in 0..LANES {
            let rows = [(o_row[0][l], d_row[0][l]), (o_row[1][l], d_row[1][l]), (o_row[2][l], d_row[2][l])];
            let (hit, t, x, y) = flat_hit_from_rows(rows, t_max[l], &contains);
            (out.hit[l], out.t[l], out.x[l], out.y[l]) = (hit, t, x as f32, y as f32);
        }
        out
    }
    match shape.shape {
        Shape::Rectangle(rect) => each(t_max, o_row, d_row, |x, y| Shape::Rectangle(rect).flat_contains(x, y)),
        Shape::Disk(disk) => each(t_max, o_row, d_row, |x, y| Shape::Disk(disk).flat_contains(x, y)),
        Shape::Sphere(_) => FlatHits::default(),
    }
}

/// Object-space rows of `LANES` rays, one array of lanes per axis.
type Rows = [[f64; LANES]; 3];

/// What [`flat_hits`] finds per lane: whether the f32 test was sure, whether the ray hits, t, and
/// the object-space x and y. 64-byte aligned, as `RayLanes` is (a tuple of these arrays had them
/// straddle cache lines).
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct FlatHits {
    x: [f32; LANES],
    y: [f32; LANES],
    t: [f32; LANES],
    hit: [bool; LANES],
    sure: [bool; LANES],
}

impl FlatHits {
    /// Takes the answers of `exact` (the f64 test) for the lanes whose f32 answer is not sure;
    /// `exact` runs only if there are any.
    #[inline(always)]
    fn settle(&mut self, exact: impl FnOnce() -> FlatHits) {
        // A fold without early exit, so that it stays in lanes.
        if self.sure.iter().fold(true, |all, &s| all & s) {
            return;
        }
        let e = exact();
        for l in 0..LANES {
            if !self.sure[l] {
                (self.hit[l], self.t[l], self.x[l], self.y[l], self.sure[l]) = (e.hit[l], e.t[l], e.x[l], e.y[l], true);
            }
        }
    }
}

/// [`Shape::flat_uv`] of every lane, one loop per shape kind (as [`flat_hits`]).
#[inline(always)]
fn flat_uvs(shape: &Shape, x: &[f32; LANES], y: &[f32; LANES]) -> [[f32; LANES]; 2] {
    #[inline(always)]
    fn each(x: &[f32; LANES], y: &[f32; LANES], uv: impl Fn(f32, f32) -> Vec2) -> [[f32; LANES]; 2] {
        let mut out = [[0.0; LANES]; 2];
        for l in 0..LANES {
            (out[0][l], out[1][l]) = uv(x[l], y[l]).into();
        }
        out
    }
    match *shape {
        Shape::Rectangle(rect) => each(x, y, |x, y| Shape::Rectangle(rect).flat_uv(x, y)),
        Shape::Disk(disk) => each(x, y, |x, y| Shape::Disk(disk).flat_uv(x, y)),
        Shape::Sphere(_) => [[0.0; LANES]; 2],
    }
}

/// The closest hits of `LANES` rays that all hit the same flat primitive, as lane columns.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct FlatHitBlock {
    pub t: [f32; LANES],
    pub p: [[f32; LANES]; 3],
    pub p_error: [[f32; LANES]; 3],
    pub uv: [[f32; LANES]; 2],
    /// The shape's normal: the geometric and the shading normal of every lane.
    pub n: Vec3,
    pub id: GeometryId,
    pub material: u32,
    pub instance: u32,
}

impl FlatHitBlock {
    /// Lane `l` as a [`Hit`].
    #[inline(always)]
    pub fn hit(&self, l: usize) -> Hit {
        let v = |c: &[[f32; LANES]; 3]| Vec3::new(c[0][l], c[1][l], c[2][l]);
        let (t, n, uv) = (self.t[l], self.n, Vec2::new(self.uv[0][l], self.uv[1][l]));
        Hit {
            t,
            p: v(&self.p),
            p_error: v(&self.p_error),
            ng: n,
            ns: n,
            uv,
            id: self.id,
            material: self.material,
            instance: self.instance,
        }
    }
}

/// Where [`SceneBvh::closest_hits_lanes`] hands its hits. Any `FnMut(lane, hit)` is one.
pub trait HitSink {
    /// The closest hit of lane `l` (None: the ray hit nothing).
    fn hit(&mut self, l: usize, hit: Option<Hit>);
    /// Every lane hit the same flat primitive. By default, its lanes one by one.
    #[inline(always)]
    fn block(&mut self, hits: &FlatHitBlock) {
        for l in 0..LANES {
            self.hit(l, Some(hits.hit(l)));
        }
    }
}

impl<F: FnMut(usize, Option<Hit>)> HitSink for F {
    #[inline(always)]
    fn hit(&mut self, l: usize, hit: Option<Hit>) {
        self(l, hit)
    }
}

/// The leaf slot of no primitive.
const NO_SLOT: usize = usize::MAX;

impl SceneBvh {
    /// Whether [`Self::closest_hits_lanes`] and [`Self::occluded_lanes`] run in lanes: the scene
    /// has one to `FEW_PRIMITIVES` primitives, all flat shapes. Otherwise they answer one ray at
    /// a time, and callers holding single rays may as well ask for them directly.
    #[inline(always)]
    pub fn few_flat_shapes(&self) -> bool {
        let flat = |s: u32| s != NO_SHAPE && !matches!(self.shapes[s as usize].shape, Shape::Sphere(_));
        !self.leaf.is_empty() && self.leaf.len() <= FEW_PRIMITIVES && self.leaf.iter().all(|p| flat(p.shape))
    }

    /// [`Self::closest_hit`] of the `LANES` rays `r`, bit for bit, handed to `out` in place (a
    /// returned array of hits would be copied once more): lane by lane, or as one block when
    /// every lane hit the same flat primitive.
    #[inline(always)]
    pub fn closest_hits_lanes(&self, r: &RayLanes, out: &mut impl HitSink) {
        if !self.few_flat_shapes() {
            let (origin, dir, t_max) = r.f32_columns();
            return self.closest_hits_packet(&origin, &dir, &t_max, LANES, out);
        }
        // As `closest_hit_each`: primitives in input order; a later one wins only when nearer.
        let (mut best_t, mut best_slot) = (r.t_max, [NO_SLOT; LANES]);
        let (mut best_x, mut best_y) = ([0.0f32; LANES], [0.0f32; LANES]);
        for prim in 0..self.leaf.len() as u32 {
            let slot = self.slot_of(prim);
            let hits = flat_hits(&self.shapes[self.leaf[slot].shape as usize], r, &best_t);
            for l in 0..LANES {
                let (hit, t, x, y) = (hits.hit[l], hits.t[l], hits.x[l], hits.y[l]);
                let first = best_slot[l] == NO_SLOT;
                if r.valid[l] & hit & (first | (t < best_t[l])) {
                    (best_t[l], best_slot[l], best_x[l], best_y[l]) = (t, slot, x, y);
                }
            }
        }
        if best_slot[0] != NO_SLOT && best_slot.iter().all(|&s| s == best_slot[0]) {
            out.block(&self.flat_hit_block(best_slot[0], &best_t, &best_x, &best_y));
            return;
        }
        for l in (0..LANES).filter(|&l| best_slot[l] == NO_SLOT) {
            out.hit(l, None);
        }
        // Hit records, one primitive's lanes at a time.
        for slot in 0..self.leaf.len() {
            if !best_slot.contains(&slot) {
                continue;
            }
            let block = self.flat_hit_block(slot, &best_t, &best_x, &best_y);
            for l in (0..LANES).filter(|&l| best_slot[l] == slot) {
                out.hit(l, Some(block.hit(l)));
            }
        }
    }

    /// [`Self::closest_hits_lanes`] of rays from one `origin` (a pinhole camera's) along `dirs`,
    /// bit for bit. In a scene of one flat shape the origin's object-space rows are formed once
    /// and no `RayLanes` is built; other scenes take `closest_hits_lanes`.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops on purpose (as `occluded_lanes`)
    pub fn closest_hits_from(&self, origin: Vec3, dirs: &Lanes3, t_max: f32, out: &mut impl HitSink) {
        if self.leaf.len() != 1 || !self.few_flat_shapes() {
            let origins = [[origin.x; LANES], [origin.y; LANES], [origin.z; LANES]];
            if !self.few_flat_shapes() {
                return self.closest_hits_packet(&origins, dirs, &[t_max; LANES], LANES, out);
            }
            return self.closest_hits_lanes(&RayLanes::from_columns(&[origins, *dirs], t_max), out);
        }
        let shape = &self.shapes[self.leaf[0].shape as usize];
        let o = origin.as_dvec3().to_array();
        let o_row = [0, 1, 2].map(|i| [shape.object_point_row(i, o); LANES]);
        let mut hits = flat_hits_f32(shape, &[t_max; LANES], &o_row, dirs);
        hits.settle(|| {
            let d_row = dir_rows(shape, &dirs.map(|row| row.map(f64::from)));
            flat_hits_of_rows(shape, &[t_max; LANES], &o_row, &d_row)
        });
        // `Ray::is_valid` of each lane; a fold without early exit, so that it stays in lanes.
        let origin_valid = origin.is_finite() && t_max > 0.0;
        let mut all = true;
        for l in 0..LANES {
            hits.hit[l] &= dir_valid(dirs, l) & origin_valid;
            all &= hits.hit[l];
        }
        let block = self.flat_hit_block(0, &hits.t, &hits.x, &hits.y);
        if all {
            return out.block(&block);
        }
        for l in 0..LANES {
            out.hit(l, hits.hit[l].then(|| block.hit(l)));
        }
    }

    /// The hit records of every lane as hits on leaf `slot` at flat coordinates (x, y).
    #[inline(always)]
    fn flat_hit_block(&self, slot: usize, t: &[f32; LANES], x: &[f32; LANES], y: &[f32; LANES]) -> FlatHitBlock {
        let shape = &self.shapes[self.leaf[slot].shape as usize];
        let (mut p, mut p_error) = ([[0.0f32; LANES]; 3], [[0.0f32; LANES]; 3]);
        for a in 0..3 {
            for l in 0..LANES {
                (p[a][l], p_error[a][l]) = shape.flat_world_coordinate(a, x[l], y[l]);
            }
        }
        let uv = flat_uvs(&shape.shape, x, y);
        let (instance, id, material) = self.id_of(self.prim_of_slot(slot));
        let n = shape.flat_normal.unwrap_or(Vec3::Z);
        FlatHitBlock { t: *t, p, p_error, uv, n, id, material, instance }
    }

    /// [`Self::occluded_from`] of the first `n` of `LANES` rays, leaving from `origins`, bit for
    /// bit (later lanes: false).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops on purpose (see below)
    pub fn occluded_lanes(&self, r: &RayLanes, n: usize, origins: &[GeometryId; LANES]) -> [bool; LANES] {
        let mut out = [false; LANES];
        if !self.few_flat_shapes() {
            let (origin, dir, t_max) = r.f32_columns();
            let blocked = self.occluded_packet(&origin, &dir, &t_max, n, origins);
            for (l, o) in out.iter_mut().enumerate() {
                *o = (blocked >> l) & 1 != 0;
            }
            return out;
        }
        // Plain index loops: iterator adapters may stay out of the wide code.
        let mut origin = [0u64; LANES];
        for l in 0..LANES {
            origin[l] = origins[l].key();
        }
        for slot in 0..self.leaf.len() {
            // Every primitive here is flat, so none blocks rays leaving it (`Self::ignores`).
            let id = self.geometry_of_slot(slot).key();
            let mut others = [false; LANES];
            for l in 0..LANES {
                others[l] = origin[l] != id;
            }
            if !others.contains(&true) {
                continue;
            }
            let hits = flat_hits(&self.shapes[self.leaf[slot].shape as usize], r, &r.t_max);
            for l in 0..LANES {
                out[l] |= hits.hit[l] & others[l];
            }
        }
        for l in 0..LANES {
            out[l] &= r.valid[l] & (l < n);
        }
        out
    }

    /// Whether no primitive can block rays leaving `origins`: the scene is one flat primitive,
    /// and every ray leaves it. Callers may then skip building the rays.
    #[inline(always)]
    pub fn blocks_nothing_from(&self, origins: &[GeometryId]) -> bool {
        let Some(&first) = origins.first() else { return true };
        if self.leaf.len() != 1 || !self.ignores(0, first) {
            return false;
        }
        // A fold without early exit, so that it vectorises over long slices.
        let key = first.key();
        origins.iter().fold(true, |all, o| all & (o.key() == key))
    }
}

#[cfg(test)]
mod tests;
