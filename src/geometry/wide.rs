//! The traversal tree of a [`SceneBvh`]: obvhs's binary tree collapsed to 8 children per node,
//! with exact f32 child boxes in structure-of-arrays form (one slab test covers all 8), and leaves
//! of up to [`LEAF_PRIMS`] primitives whose triangles sit in lane blocks (one watertight test
//! covers the block; see [`triangle_block_hits`]).
//!
//! The node test is pbrt-v4's conservative slab test (section 6.8.2): each slab parameter carries
//! at most 3 roundings, so stretching the far end by 1 + 2 gamma(3) never culls a box that the
//! exact ray meets. Triangle lanes run the same operations as the scalar test, so they decide
//! exactly as it does; lanes where an edge function rounds to zero take the scalar test itself
//! (its f64 recomputation). A query therefore returns what testing every primitive returns.

use std::mem::MaybeUninit;

use glam::{Vec3, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

use super::ray::{Ray, gamma};
use super::ray_stats;
use super::triangle::{PERMUTED, any_edge_zero, decide, edges, sheared_xy};

pub(crate) mod packet;

/// Children per node.
pub(crate) const WIDTH: usize = 8;
/// Largest number of primitives in a leaf (the lanes of one [`PrimBlock`]).
pub(crate) const LEAF_PRIMS: usize = 4;
/// `child` of a slot with nothing in it.
const EMPTY: u32 = u32::MAX;
/// Set in `child` for a leaf: the rest is its block index.
const LEAF: u32 = 1 << 31;
/// Lane `slot` of a block with no primitive.
pub(crate) const NO_SLOT: u32 = u32::MAX;
/// Cap on |1/d| so that zero direction components give huge but finite slab parameters
/// (never inf * 0 = NaN): 2^100, valid for scene coordinates below 2^20.
const MAX_INV_DIR: f32 = 1.267_650_6e30;
/// Entries of the traversal stack; deeper trees fall back to testing every primitive.
const STACK: usize = 512;

/// Up to 8 children: their boxes (lower and upper corners, axis by axis) and what each is.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    lo: [[f32; WIDTH]; 3],
    hi: [[f32; WIDTH]; 3],
    /// A node index, `LEAF | block`, or `EMPTY` (whose box is empty, so no ray meets it).
    child: [u32; WIDTH],
}

impl WideNode {
    const EMPTY: Self =
        Self { lo: [[f32::INFINITY; WIDTH]; 3], hi: [[f32::NEG_INFINITY; WIDTH]; 3], child: [EMPTY; WIDTH] };

    fn set_box(&mut self, c: usize, b: &Aabb) {
        for a in 0..3 {
            (self.lo[a][c], self.hi[a][c]) = (b.min[a], b.max[a]);
        }
    }

    fn child_box(&self, c: usize) -> Aabb {
        obvhs_box(
            Vec3::new(self.lo[0][c], self.lo[1][c], self.lo[2][c]),
            Vec3::new(self.hi[0][c], self.hi[1][c], self.hi[2][c]),
        )
    }
}

/// A leaf's primitives, one per lane: each lane's leaf slot, and the triangles' vertices axis by
/// axis (lanes that hold a shape or nothing keep zero vertices and are masked out).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct PrimBlock {
    /// `v[vertex][axis][lane]`.
    v: [[[f32; LEAF_PRIMS]; 3]; 3],
    /// The `SceneBvh::leaf` slot of each lane, or `NO_SLOT`.
    pub(crate) slot: [u32; LEAF_PRIMS],
    /// Lanes holding a triangle, and lanes holding an analytic shape.
    pub(crate) triangles: u8,
    pub(crate) shapes: u8,
}

/// The collapsed tree. Node 0 is the root; parents come before their children.
#[derive(Clone, Debug, Default)]
pub(crate) struct WideBvh {
    nodes: Vec<WideNode>,
    blocks: Vec<PrimBlock>,
    /// Per node: its parent and its slot there (the root's parent is itself).
    parent: Vec<(u32, u8)>,
    /// Per block: the node and slot that hold it.
    block_parent: Vec<(u32, u8)>,
    /// Per leaf slot: the block that holds it.
    block_of_slot: Vec<u32>,
    /// Refit scratch: nodes whose box in their parent must be recomputed.
    dirty: Vec<bool>,
    /// Sum of the half areas of every child box, kept up to date by refits.
    area_sum: f64,
}

/// obvhs's box of kelvin's corners, passed as plain floats: obvhs may be built with another glam
/// than kelvin (an app's own resolution picks the newest glam each allows), so no glam type
/// crosses between them.
pub(crate) fn obvhs_box(lo: Vec3, hi: Vec3) -> Aabb {
    Aabb::new(lo.to_array().into(), hi.to_array().into())
}

/// kelvin's corners of obvhs's box (see [`obvhs_box`]).
pub(crate) fn box_corners(b: &Aabb) -> (Vec3, Vec3) {
    (Vec3::from_array(b.min.to_array()), Vec3::from_array(b.max.to_array()))
}

fn half_area(b: &Aabb) -> f64 {
    let d = b.max - b.min;
    f64::from(d.x * d.y + d.y * d.z + d.z * d.x)
}

/// What the tree needs to know of each primitive: its box, and for triangles their vertices.
pub(crate) trait LeafSource {
    fn leaf_count(&self) -> usize;
    /// World-space vertices of the triangle in leaf slot `slot`, or None for a shape.
    fn triangle(&self, slot: usize) -> Option<[Vec3; 3]>;
    fn bounds(&self, slot: usize) -> Aabb;
}

impl WideBvh {
    /// Collapses `bvh2` (whose leaves hold primitive `i` as leaf slot `slot_of_prim[i]`).
    pub(crate) fn from_bvh2(bvh2: &Bvh2, slot_of_prim: &[u32], leaves: &impl LeafSource) -> Self {
        let mut tree = Self { block_of_slot: vec![u32::MAX; leaves.leaf_count()], ..Self::default() };
        if leaves.leaf_count() == 0 || bvh2.nodes.is_empty() {
            return tree;
        }
        // Shapes are tested one at a time, so a leaf holds more than one primitive only if they are
        // all triangles (whose lanes cost one test).
        let (counts, shapes) = subtree_counts(bvh2, |p| leaves.triangle(slot_of_prim[p as usize] as usize).is_none());
        let is_leaf = |n: usize| {
            bvh2.nodes[n].is_leaf() || counts[n] <= 1 || (counts[n] as usize <= LEAF_PRIMS && shapes[n] == 0)
        };
        tree.nodes.push(WideNode::EMPTY);
        tree.parent.push((0, 0));
        // Work list of (BVH2 node, wide node to fill).
        let mut work = vec![(0usize, 0usize)];
        while let Some((n2, wide)) = work.pop() {
            let children = if is_leaf(n2) { vec![n2] } else { widen(bvh2, &is_leaf, n2) };
            for (c, &child) in children.iter().enumerate() {
                tree.nodes[wide].set_box(c, bvh2.nodes[child].aabb());
                if is_leaf(child) {
                    let mut slots = Vec::with_capacity(LEAF_PRIMS);
                    collect_prims(bvh2, child, &mut |p| slots.push(slot_of_prim[p as usize]));
                    tree.add_leaf(wide, c, &slots, leaves);
                } else {
                    let id = tree.add_node(wide, c);
                    work.push((child, id));
                }
            }
        }
        tree.dirty = vec![false; tree.nodes.len()];
        tree.area_sum = tree
            .nodes
            .iter()
            .flat_map(|n| (0..WIDTH).filter(|&c| n.child[c] != EMPTY).map(|c| half_area(&n.child_box(c))))
            .sum();
        tree
    }

    /// A new empty node as child `c` of node `parent`; its index.
    fn add_node(&mut self, parent: usize, c: usize) -> usize {
        let id = self.nodes.len();
        self.nodes.push(WideNode::EMPTY);
        self.parent.push((parent as u32, c as u8));
        self.nodes[parent].child[c] = id as u32;
        id
    }

    /// Makes child `c` of `node` the leaf of `slots`: one block, or (for a binary leaf of more
    /// primitives than a block holds) a node over blocks of them.
    fn add_leaf(&mut self, node: usize, c: usize, slots: &[u32], leaves: &impl LeafSource) {
        if slots.len() <= LEAF_PRIMS {
            for &s in slots {
                self.block_of_slot[s as usize] = self.blocks.len() as u32;
            }
            self.nodes[node].child[c] = LEAF | self.blocks.len() as u32;
            self.block_parent.push((node as u32, c as u8));
            self.blocks.push(make_block(slots, leaves));
            return;
        }
        let id = self.add_node(node, c);
        for (k, group) in slots.chunks(slots.len().div_ceil(WIDTH).max(LEAF_PRIMS)).enumerate() {
            let bounds = group.iter().fold(Aabb::empty(), |b, &s| b.union(&leaves.bounds(s as usize)));
            self.nodes[id].set_box(k, &bounds);
            self.add_leaf(id, k, group, leaves);
        }
    }

    /// Rewrites the blocks holding leaf slots `slots` from `leaves` (after their primitives
    /// moved) and the boxes above them, keeping the topology; every other box stays as it is.
    /// Returns the sum of the child boxes' half areas (the tree's SAH-style cost).
    pub(crate) fn refit(&mut self, slots: impl IntoIterator<Item = u32>, leaves: &impl LeafSource) -> f64 {
        let mut blocks: Vec<u32> = slots.into_iter().map(|s| self.block_of_slot[s as usize]).collect();
        blocks.sort_unstable();
        blocks.dedup();
        let mut dirty_nodes = Vec::new();
        for b in blocks {
            let block = &mut self.blocks[b as usize];
            let n_slots = block.slot.iter().take_while(|&&s| s != NO_SLOT).count();
            let slots = block.slot;
            *block = make_block(&slots[..n_slots], leaves);
            let bounds = slots[..n_slots].iter().fold(Aabb::empty(), |acc, &s| acc.union(&leaves.bounds(s as usize)));
            let (node, c) = self.block_parent[b as usize];
            self.set_child_box(node as usize, c as usize, &bounds);
            let mut n = node;
            while n != 0 && !std::mem::replace(&mut self.dirty[n as usize], true) {
                dirty_nodes.push(n);
                n = self.parent[n as usize].0;
            }
        }
        // Children come after their parents, so the highest index first sees every child first.
        dirty_nodes.sort_unstable_by(|a, b| b.cmp(a));
        for n in dirty_nodes {
            self.dirty[n as usize] = false;
            let node = &self.nodes[n as usize];
            let bounds =
                (0..WIDTH).filter(|&c| node.child[c] != EMPTY).fold(Aabb::empty(), |b, c| b.union(&node.child_box(c)));
            let (parent, c) = self.parent[n as usize];
            self.set_child_box(parent as usize, c as usize, &bounds);
        }
        self.area_sum
    }

    /// Sets the box of child `c` of `node`, keeping `area_sum` in step.
    fn set_child_box(&mut self, node: usize, c: usize, bounds: &Aabb) {
        self.area_sum += half_area(bounds) - half_area(&self.nodes[node].child_box(c));
        self.nodes[node].set_box(c, bounds);
    }

    /// The box around everything in the tree, or None when it is empty.
    pub(crate) fn bounds(&self) -> Option<Aabb> {
        let root = self.nodes.first()?;
        Some((0..WIDTH).filter(|&c| root.child[c] != EMPTY).fold(Aabb::empty(), |b, c| b.union(&root.child_box(c))))
    }

    /// Sum of the half areas of every child box (the tree's SAH-style cost).
    pub(crate) fn cost(&self) -> f64 {
        self.area_sum
    }

    /// Visits the blocks whose leaf boxes `ray` may meet over [0, t_max], skipping boxes beyond
    /// the current `t_max` (which `visit` may lower). `visit` returns true to stop. With `NEAREST`
    /// (closest hits), each node's children are visited nearest box first; without (any hit),
    /// a node's leaves are visited as soon as the node is, before any child node, since any
    /// blocker ends the query. Returns false if the tree was too deep for the stack (the caller
    /// then tests every primitive).
    #[inline(always)]
    pub(crate) fn traverse<const NEAREST: bool>(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        visit: impl FnMut(&PrimBlock, &mut f32) -> bool,
    ) -> bool {
        self.traverse_from::<NEAREST>(0, ray, t_max, visit)
    }

    /// [`Self::traverse`] of the subtree at stack entry `root` (a node index, or a block with
    /// `LEAF` set): packets hand a subtree to it once few of their rays are left there.
    #[inline(always)]
    pub(crate) fn traverse_from<const NEAREST: bool>(
        &self,
        root: u32,
        ray: &Ray,
        t_max: &mut f32,
        mut visit: impl FnMut(&PrimBlock, &mut f32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let inv_dir = ray.dir.to_array().map(capped_inv);
        let origin = ray.origin.to_array();
        let neg = inv_dir.map(|i| i < 0.0);
        let far_pad = 1.0 + 2.0 * gamma(3);
        // Left uninitialised: zeroing 4 KB per ray cost more than the traversal of a small scene.
        let mut stack = [const { MaybeUninit::<(u32, f32)>::uninit() }; STACK];
        let mut sp = 0;
        // The entry being visited: a node goes on with its nearest child directly, so a ray that
        // meets one child of a node does not go through the stack.
        let mut entry = root;
        loop {
            if entry & LEAF != 0 {
                let block = &self.blocks[(entry & !LEAF) as usize];
                ray_stats::block(block.triangles);
                if visit(block, t_max) {
                    return true;
                }
            } else {
                let node = &self.nodes[entry as usize];
                ray_stats::node();
                let mut t_near = [0f32; WIDTH];
                let mut t_far = [0f32; WIDTH];
                for c in 0..WIDTH {
                    t_near[c] = 0.0;
                    t_far[c] = *t_max;
                }
                for a in 0..3 {
                    // Which corner the ray enters the slab at.
                    let (lo, hi) = if neg[a] { (&node.hi[a], &node.lo[a]) } else { (&node.lo[a], &node.hi[a]) };
                    for c in 0..WIDTH {
                        // Plain compares, not f32::max / min (whose NaN rules cost extra steps): no
                        // slab parameter is NaN, since |1/d| is capped and finite boxes have finite
                        // corners, and an empty child's infinite corners meet a nonzero 1/d.
                        let (t0, t1) = ((lo[c] - origin[a]) * inv_dir[a], (hi[c] - origin[a]) * inv_dir[a]);
                        t_near[c] = if t0 > t_near[c] { t0 } else { t_near[c] };
                        t_far[c] = if t1 < t_far[c] { t1 } else { t_far[c] };
                    }
                }
                let mut mask = 0u32;
                for c in 0..WIDTH {
                    mask |= u32::from(t_near[c] <= t_far[c] * far_pad) << c;
                }
                if sp + WIDTH > STACK {
                    return false;
                }
                if mask.count_ones() > 1 {
                    self.prefetch_children(node, mask);
                }
                if !NEAREST {
                    let mut leaves = mask & leaf_mask(node);
                    mask &= !leaves;
                    while leaves != 0 {
                        let c = leaves.trailing_zeros() as usize;
                        leaves &= leaves - 1;
                        let block = &self.blocks[(node.child[c] & !LEAF) as usize];
                        ray_stats::block(block.triangles);
                        if visit(block, t_max) {
                            return true;
                        }
                    }
                    if mask != 0 {
                        entry = node.child[mask.trailing_zeros() as usize];
                        mask &= mask - 1;
                        while mask != 0 {
                            let c = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            stack[sp].write((node.child[c], t_near[c]));
                            sp += 1;
                        }
                        continue;
                    }
                } else if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        entry = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    // Push the hit children farthest first, then go on with the nearest.
                    let first = sp;
                    while mask != 0 {
                        let c = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let item = (node.child[c], t_near[c]);
                        let mut k = sp;
                        // SAFETY: entries `first..sp` were written in this loop.
                        while k > first && unsafe { stack[k - 1].assume_init_ref() }.1 < item.1 {
                            stack[k] = stack[k - 1];
                            k -= 1;
                        }
                        stack[k].write(item);
                        sp += 1;
                    }
                    sp -= 1;
                    // SAFETY: written just above.
                    entry = unsafe { stack[sp].assume_init_read() }.0;
                    continue;
                }
            }
            // The next entry from the stack that may still hold something nearer than `t_max`.
            loop {
                if sp == 0 {
                    return true;
                }
                sp -= 1;
                // SAFETY: entries below `sp` are written.
                let (next, near) = unsafe { stack[sp].assume_init_read() };
                if near > *t_max * far_pad {
                    continue;
                }
                entry = next;
                break;
            }
        }
    }
}

impl WideBvh {
    /// Asks the cache for the children of `node` in `mask`, so that their fetches overlap rather
    /// than follow one another as the walk reaches each: an incoherent ray's time goes mostly to
    /// waiting for nodes and blocks.
    #[inline(always)]
    fn prefetch_children(&self, node: &WideNode, mut mask: u32) {
        while mask != 0 {
            let c = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let child = node.child[c];
            if child & LEAF != 0 {
                prefetch(self.blocks.as_ptr().wrapping_add((child & !LEAF) as usize));
            } else {
                prefetch(self.nodes.as_ptr().wrapping_add(child as usize));
            }
        }
    }
}

/// Prefetches every cache line of the `T` at `p` (a hint: `p` need not be valid).
#[inline(always)]
fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    for line in (0..size_of::<T>()).step_by(64) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch never faults and reads nothing into the program.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>().wrapping_add(line)) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// 1 / d, capped at [`MAX_INV_DIR`] in magnitude (the slab test's reciprocal direction).
#[inline(always)]
pub(crate) fn capped_inv(d: f32) -> f32 {
    let i = 1.0 / d;
    if i.is_finite() && i.abs() <= MAX_INV_DIR { i } else { MAX_INV_DIR.copysign(d) }
}

/// Bit `c` set for each child `c` of `node` that is a leaf.
#[inline(always)]
fn leaf_mask(node: &WideNode) -> u32 {
    let mut mask = 0;
    for c in 0..WIDTH {
        mask |= u32::from(node.child[c] != EMPTY && node.child[c] & LEAF != 0) << c;
    }
    mask
}

/// The lanes of `block` whose triangle `ray` (as `sheared`) hits over (delta_t, t_max], with their
/// t and barycentrics: bit `l` of the mask for lane `l`. The watertight test's own steps
/// (`triangle::decide`) over the block's 4 lanes at once, branch-free; lanes where an edge function
/// is exactly zero are reported in the second mask, for the scalar test to decide.
#[inline(always)]
pub(crate) fn triangle_block_hits(
    block: &PrimBlock,
    sheared: &super::triangle::ShearedRay,
    t_max: f32,
) -> (u8, u8, [f32; LEAF_PRIMS], [[f32; LEAF_PRIMS]; 3]) {
    let (origin, kz, s) = sheared.parts();
    // Axis order after the permutation that makes the ray's dominant axis z.
    let [ax, ay, az] = PERMUTED[usize::from(kz)];
    let o = origin.to_array();
    let shear = [Vec4::splat(s.x), Vec4::splat(s.y)];
    let p = [0, 1, 2].map(|vertex| {
        let axis = |a: usize| Vec4::from_array(block.v[vertex][a]) - Vec4::splat(o[a]);
        sheared_xy([axis(ax), axis(ay), axis(az)], shear)
    });
    let e = edges(&p);
    let exact = any_edge_zero(e).bitmask() as u8 & block.triangles;
    let (hit, t, b) = decide(&p, e, Vec4::splat(s.z), Vec4::splat(t_max));
    let hit = hit.bitmask() as u8 & block.triangles & !exact;
    (hit, exact, t.to_array(), b.map(|b| b.to_array()))
}

/// The block of the leaf slots `slots` (at most [`LEAF_PRIMS`]).
fn make_block(slots: &[u32], leaves: &impl LeafSource) -> PrimBlock {
    debug_assert!(slots.len() <= LEAF_PRIMS);
    let mut block = PrimBlock { v: [[[0.0; LEAF_PRIMS]; 3]; 3], slot: [NO_SLOT; LEAF_PRIMS], triangles: 0, shapes: 0 };
    for (l, &slot) in slots.iter().enumerate() {
        block.slot[l] = slot;
        match leaves.triangle(slot as usize) {
            Some(v) => {
                block.triangles |= 1 << l;
                for (vertex, p) in v.iter().enumerate() {
                    for a in 0..3 {
                        block.v[vertex][a][l] = p[a];
                    }
                }
            }
            None => block.shapes |= 1 << l,
        }
    }
    block
}

/// Per BVH2 node, its number of primitives and of those the shapes (`is_shape` of an input
/// primitive), by a walk from the root (obvhs's builders do not all place children after parents).
fn subtree_counts(bvh2: &Bvh2, is_shape: impl Fn(u32) -> bool) -> (Vec<u32>, Vec<u32>) {
    let mut counts = vec![0u32; bvh2.nodes.len()];
    let mut shapes = vec![0u32; bvh2.nodes.len()];
    // Post-order without recursion: a node is summed when it is met the second time.
    let mut stack = vec![(0usize, false)];
    while let Some((n, children_done)) = stack.pop() {
        let node = &bvh2.nodes[n];
        if node.is_leaf() {
            let first = node.first_index as usize;
            let prims = &bvh2.primitive_indices[first..first + node.prim_count as usize];
            counts[n] = node.prim_count;
            shapes[n] = prims.iter().filter(|&&p| is_shape(p)).count() as u32;
        } else if children_done {
            let c = node.first_index as usize;
            (counts[n], shapes[n]) = (counts[c] + counts[c + 1], shapes[c] + shapes[c + 1]);
        } else {
            stack.extend([(n, true), (node.first_index as usize, false), (node.first_index as usize + 1, false)]);
        }
    }
    (counts, shapes)
}

/// Up to [`WIDTH`] BVH2 nodes under `n` that cover it: its two children, then repeatedly the
/// largest-area child that is not to be a leaf (`is_leaf`), opened into its two children.
fn widen(bvh2: &Bvh2, is_leaf: &impl Fn(usize) -> bool, n: usize) -> Vec<usize> {
    let first = bvh2.nodes[n].first_index as usize;
    let mut children = vec![first, first + 1];
    while children.len() < WIDTH {
        let open = children
            .iter()
            .enumerate()
            .filter(|&(_, &c)| !is_leaf(c))
            .max_by(|a, b| bvh2.nodes[*a.1].aabb().half_area().total_cmp(&bvh2.nodes[*b.1].aabb().half_area()));
        let Some((i, &c)) = open else { break };
        let grand = bvh2.nodes[c].first_index as usize;
        children[i] = grand;
        children.push(grand + 1);
    }
    children
}

/// Calls `f` with every primitive (input index) under BVH2 node `n`.
fn collect_prims(bvh2: &Bvh2, n: usize, f: &mut impl FnMut(u32)) {
    let node = &bvh2.nodes[n];
    if node.is_leaf() {
        let first = node.first_index as usize;
        for &p in &bvh2.primitive_indices[first..first + node.prim_count as usize] {
            f(p);
        }
    } else {
        collect_prims(bvh2, node.first_index as usize, f);
        collect_prims(bvh2, node.first_index as usize + 1, f);
    }
}

#[cfg(test)]
mod tests;
