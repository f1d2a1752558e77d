//! Packet traversal: [`LANES`] rays walk the wide tree together, one lane per ray. A node's child
//! boxes are tested against every ray of the packet, and a leaf's triangles one at a time against
//! every ray that reached the leaf, so coherent rays (a pixel's camera samples, a point's shadow
//! rays toward one light) share each node and triangle fetch. Where the rays part ways and at most
//! [`SINGLE_RAY_LANES`] of them reach a subtree, each walks it alone (8 child boxes per node for
//! one ray instead of 8 x 16 lanes for a few live ones): the hybrid that keeps incoherent packets
//! as fast as single rays.
//!
//! Answers are the single-ray traversal's, bit for bit: the slab test is the same conservative
//! one, per lane; triangle lanes run the operations of `ShearedRay::intersect` (lanes where an
//! edge function rounds to zero take that scalar test itself); and the closest hit is the least
//! (t, input primitive) pair, which does not depend on the order leaves are visited in.

use std::mem::MaybeUninit;

use super::{EMPTY, LEAF, PrimBlock, STACK, WIDTH, WideBvh, capped_inv};
use crate::geometry::ray::gamma;
use crate::geometry::triangle::{EARLY_REJECT_SLACK, PERMUTED, shear_lanes, t_error_bound};
use crate::lanes::{F32x16, LANES, Mask16, Vec3x16};

/// Lane columns: `[axis][lane]`.
pub(crate) type Columns = Vec3x16;

/// A packet's rays in the form the traversal and the triangle test read: origins, capped
/// reciprocal directions, and the watertight test's axis choice and shear per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayPacket {
    pub(crate) origin: Columns,
    inv_dir: Columns,
    /// Bit l of `by_kz[k]`: lane l's largest direction component is axis k (`ShearedRay::kz`).
    by_kz: [u32; 3],
    /// (Sx, Sy, Sz) of `ShearedRay::new`, in the lane's permuted axes.
    shear: Columns,
    /// Lanes that hold a valid ray ([`crate::geometry::Ray::is_valid`]).
    pub(crate) valid: u32,
}

impl RayPacket {
    /// The packet of rays `origin + t dir`, t in (0, t_max[l]]; lanes past `n` are left out.
    #[inline(always)]
    pub(crate) fn new(origin: &Columns, dir: &Columns, t_max: &[f32; LANES], n: usize) -> Self {
        let mut inv_dir = Vec3x16::ZERO;
        let mut valid = 0u32;
        for l in 0..LANES {
            let d = [dir[0][l], dir[1][l], dir[2][l]];
            let o = [origin[0][l], origin[1][l], origin[2][l]];
            let finite = d.iter().chain(&o).all(|v| v.is_finite());
            let ok = finite && d != [0.0; 3] && t_max[l] > 0.0 && l < n;
            valid |= u32::from(ok) << l;
            for a in 0..3 {
                inv_dir[a][l] = capped_inv(d[a]);
            }
        }
        let (x_largest, y_largest, [sx, sy, sz]) = shear_lanes([dir[0], dir[1], dir[2]]);
        let (x_largest, y_largest) = (x_largest.bits(), y_largest.bits());
        let by_kz = [x_largest, y_largest, !(x_largest | y_largest)];
        let shear = Vec3x16 { x: sx, y: sy, z: sz };
        Self { origin: *origin, inv_dir, by_kz, shear, valid }
    }
}

/// The least of `v` (none is NaN), as a tree of lane-wise steps: a running minimum would be a
/// chain of 16 dependent scalar compares.
#[inline(always)]
fn nearest(mut v: [f32; LANES]) -> f32 {
    let mut width = LANES / 2;
    while width > 0 {
        for l in 0..width {
            v[l] = if v[l + width] < v[l] { v[l + width] } else { v[l] };
        }
        width /= 2;
    }
    v[0]
}

/// Triangle hits of a packet against one triangle: lanes hit over (delta_t, t_max[l]], their t
/// and barycentrics, and the lanes whose edge functions rounded to zero (for the scalar test).
pub(crate) struct TriangleLanes {
    pub(crate) hit: u32,
    pub(crate) exact: u32,
    pub(crate) t: [f32; LANES],
    pub(crate) b: Columns,
}

/// The lanes of `mask` tested against triangle `k` of `block` (which must hold one), the
/// operations of `ShearedRay::intersect` lane by lane.
#[inline(always)]
pub(crate) fn triangle_lanes(
    block: &PrimBlock,
    k: usize,
    rays: &RayPacket,
    mask: u32,
    t_max: &[f32; LANES],
) -> TriangleLanes {
    let mut out = TriangleLanes { hit: 0, exact: 0, t: [0.0; LANES], b: Vec3x16::ZERO };
    for (kz, &lanes) in rays.by_kz.iter().enumerate() {
        if lanes & mask != 0 {
            triangle_lanes_kz(block, k, rays, lanes & mask, t_max, PERMUTED[kz], &mut out);
        }
    }
    out
}

/// [`triangle_lanes`] for lanes that share the axis permutation `[ax, ay, az]`: the steps of
/// `triangle::decide`, fused lane by lane so that LLVM vectorises them across the 16 rays. (Calling
/// `decide` over `F32x16` kept every intermediate as 16 lanes and spilled them; calling it per lane
/// was not vectorised: 1.2x and 2.4x the instructions per ray, cachegrind.) The packet tests hold
/// both to the same bits.
#[inline(always)]
fn triangle_lanes_kz(
    block: &PrimBlock,
    k: usize,
    rays: &RayPacket,
    mask: u32,
    t_max: &[f32; LANES],
    [ax, ay, az]: [usize; 3],
    out: &mut TriangleLanes,
) {
    let (o, s) = (&rays.origin, &rays.shear);
    // p[vertex][axis][lane], translated, permuted and sheared.
    let mut p = [Vec3x16::ZERO; 3];
    for (vertex, pv) in p.iter_mut().enumerate() {
        let v = [block.v[vertex][ax][k], block.v[vertex][ay][k], block.v[vertex][az][k]];
        for l in 0..LANES {
            let z = v[2] - o[az][l];
            pv[0][l] = (v[0] - o[ax][l]) + s[0][l] * z;
            pv[1][l] = (v[1] - o[ay][l]) + s[1][l] * z;
            pv[2][l] = z;
        }
    }
    let (mut hit, mut exact) = (0u32, 0u32);
    for l in 0..LANES {
        let e0 = p[1][0][l] * p[2][1][l] - p[1][1][l] * p[2][0][l];
        let e1 = p[2][0][l] * p[0][1][l] - p[2][1][l] * p[0][0][l];
        let e2 = p[0][0][l] * p[1][1][l] - p[0][1][l] * p[1][0][l];
        let zero = (e0 == 0.0) | (e1 == 0.0) | (e2 == 0.0);
        let mixed = ((e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0)) & ((e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0));
        let det = e0 + e1 + e2;
        let (z0, z1, z2) = (p[0][2][l] * s[2][l], p[1][2][l] * s[2][l], p[2][2][l] * s[2][l]);
        let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
        let t_reject = t_max[l] * EARLY_REJECT_SLACK;
        let behind_or_far = if det < 0.0 {
            (t_scaled >= 0.0) | (t_scaled < t_reject * det)
        } else {
            (t_scaled <= 0.0) | (t_scaled > t_reject * det)
        };
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        let max_x = p[0][0][l].abs().max(p[1][0][l].abs()).max(p[2][0][l].abs());
        let max_y = p[0][1][l].abs().max(p[1][1][l].abs()).max(p[2][1][l].abs());
        let max_z = z0.abs().max(z1.abs()).max(z2.abs());
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        // A NaN t fails `t <= t_max` below, as in the scalar test.
        let too_close = t <= t_error_bound([max_x, max_y, max_z], max_e, inv_det);
        let miss = mixed | (det == 0.0) | behind_or_far | !(t <= t_max[l]) | too_close;
        exact |= u32::from(zero) << l;
        hit |= u32::from(!zero & !miss) << l;
        // Lanes outside `mask` keep what another permutation's pass wrote.
        let mine = (mask >> l) & 1 != 0;
        out.t[l] = if mine { t } else { out.t[l] };
        for (a, e) in [e0, e1, e2].into_iter().enumerate() {
            out.b[a][l] = if mine { e * inv_det } else { out.b[a][l] };
        }
    }
    out.exact |= exact & mask;
    out.hit |= hit & mask;
}

/// Most live lanes at a stack entry for which the packet hands the subtree to single rays.
const SINGLE_RAY_LANES: u32 = 2;

#[cfg(test)]
thread_local! {
    /// Tests raise it (to `LANES`: every subtree handed over) to check the single-ray side alone.
    pub(crate) static SINGLE_RAY_LANES_FOR_TESTS: std::cell::Cell<u32> = const { std::cell::Cell::new(SINGLE_RAY_LANES) };
}

/// [`SINGLE_RAY_LANES`], or a test's value.
#[inline(always)]
fn single_ray_lanes() -> u32 {
    #[cfg(test)]
    return SINGLE_RAY_LANES_FOR_TESTS.with(|c| c.get());
    #[cfg(not(test))]
    SINGLE_RAY_LANES
}

impl WideBvh {
    /// [`WideBvh::traverse`] for a packet: visits each block whose box some lane of `active` may
    /// meet over [0, t_max[l]], with the mask of those lanes; `visit` may lower `t_max` and returns
    /// lanes that are done (any hit found), which leave the packet. With `NEAREST`, each node's
    /// children are visited nearest first (by their nearest lane). Where at most
    /// [`SINGLE_RAY_LANES`] lanes reach a stack entry, `alone(state, entry, lanes, t_max)` takes
    /// the subtree instead (each lane as a single ray, [`WideBvh::traverse_from`]) and returns the
    /// lanes that are done. Both closures get `state`, the per-lane results they share. Returns
    /// false if the tree was too deep for the stack.
    #[inline(always)]
    pub(crate) fn traverse_packet<const NEAREST: bool, S>(
        &self,
        rays: &RayPacket,
        mut active: u32,
        t_max: &mut [f32; LANES],
        state: &mut S,
        mut visit: impl FnMut(&mut S, &PrimBlock, u32, &mut [f32; LANES]) -> u32,
        mut alone: impl FnMut(&mut S, u32, u32, &mut [f32; LANES]) -> u32,
    ) -> bool {
        if self.nodes.is_empty() || active == 0 {
            return true;
        }
        let far_pad = 1.0 + 2.0 * gamma(3);
        let (o, inv) = (&rays.origin, &rays.inv_dir);
        let mut stack = [const { MaybeUninit::<(u32, u32, f32)>::uninit() }; STACK];
        stack[0].write((0, active, 0.0));
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` are written (the root above, children below).
            let (entry, lanes, near) = unsafe { stack[sp].assume_init_read() };
            // Lanes still in the packet whose current t_max the subtree's nearest entry is within
            // (any-hit queries do not lower t_max, so their children were tested against it).
            let within = if NEAREST { (F32x16(*t_max) * far_pad).ge(F32x16::splat(near)).bits() } else { !0 };
            let mask = within & lanes & active;
            if mask == 0 {
                continue;
            }
            if mask.count_ones() <= single_ray_lanes() {
                // Few rays left here: each walks the subtree alone (8 boxes per node for one ray,
                // not 8 x 16 lanes for a few live ones).
                active &= !alone(state, entry, mask, t_max);
                if active == 0 {
                    return true;
                }
                continue;
            }
            if entry & LEAF != 0 {
                active &= !visit(state, &self.blocks[(entry & !LEAF) as usize], mask, t_max);
                if active == 0 {
                    return true;
                }
                continue;
            }
            let node = &self.nodes[entry as usize];
            let in_mask = Mask16::from_bits(mask);
            let (mut child_lanes, mut child_near) = ([0u32; WIDTH], [0.0; WIDTH]);
            for c in 0..WIDTH {
                if node.child[c] == EMPTY {
                    continue;
                }
                let (mut t_near, mut t_far) = (F32x16::ZERO, F32x16(*t_max));
                for a in 0..3 {
                    // The slab's entry and exit are the lesser and greater of its two planes' t:
                    // both finite (capped reciprocals), so no NaN, and the order is the
                    // direction's sign's.
                    let t0 = (F32x16::splat(node.lo[a][c]) - o[a]) * inv[a];
                    let t1 = (F32x16::splat(node.hi[a][c]) - o[a]) * inv[a];
                    t_near = t0.min(t1).max(t_near);
                    t_far = t0.max(t1).min(t_far);
                }
                let meets = t_near.le(t_far * far_pad);
                child_lanes[c] = meets.bits() & mask;
                if NEAREST {
                    child_near[c] = nearest(F32x16::select(meets & in_mask, t_near, F32x16::splat(f32::INFINITY)).0);
                }
            }
            if sp + WIDTH > STACK {
                return false;
            }
            let first = sp;
            for c in 0..WIDTH {
                if child_lanes[c] == 0 {
                    continue;
                }
                let item = (node.child[c], child_lanes[c], child_near[c]);
                let mut k = sp;
                if NEAREST {
                    // Farthest first on the stack, so the nearest is popped first.
                    // SAFETY: entries `first..sp` were written in this loop.
                    while k > first && unsafe { stack[k - 1].assume_init_ref() }.2 < item.2 {
                        stack[k] = stack[k - 1];
                        k -= 1;
                    }
                }
                stack[k].write(item);
                sp += 1;
            }
        }
        true
    }
}
