//! Building the light BVH top-down with binned SAOH splits (Conty & Kulla 2018, section 4.2;
//! pbrt-v4 `BVHLightSampler::buildBVH`): 12 buckets per axis over the lights' centroids, cost =
//! power x orientation measure x surface area of each side, scaled by the split axis's aspect
//! factor so long thin boxes are split across. Nodes come out in depth-first order: an interior
//! node's first child is the next node, so every child follows its parent.

use glam::Vec3;

use super::importance::{EMPTY_BOUNDS, cluster_cost, union};
use crate::light::{LightBounds, LightId};

/// pbrt-v4's bucket count.
const BUCKETS: usize = 12;
/// Ranges at least this long build their two halves in parallel.
const PARALLEL_MIN: usize = 8 * 1024;
/// `Node::parent` of the root.
pub(super) const NO_PARENT: u32 = u32::MAX;

/// A light to place in the tree.
#[derive(Clone, Copy, Debug)]
pub(super) struct BuildItem {
    pub bounds: LightBounds,
    pub centroid: Vec3,
    pub id: LightId,
}

/// A tree node. Interior nodes have exactly two children.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    /// Bounds of every light below (empty, `phi = 0`, if none has power).
    pub bounds: LightBounds,
    /// Interior: the second child (the first is the next node). Leaf: the light's row.
    pub index: u32,
    /// The parent node, or [`NO_PARENT`].
    pub parent: u32,
    /// Leaf: the light's kind. None for interior nodes.
    pub kind: Option<crate::light::LightKind>,
    /// `cluster_cost(bounds)`, kept for the running tree cost.
    pub cost: f32,
}

impl Node {
    #[inline]
    pub fn light(&self) -> Option<LightId> {
        self.kind.map(|kind| LightId { kind, row: self.index })
    }
}

/// The nodes of a tree over `items` (reordered in place); empty for no items.
pub(super) fn build_tree(items: &mut [BuildItem]) -> Vec<Node> {
    if items.is_empty() {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(2 * items.len() - 1);
    build_range(items, &mut out, 0, NO_PARENT);
    out
}

/// Appends the subtree over `items` to `out`, whose first node has global index `base`, and
/// returns its bounds. A binary tree over k leaves has 2k - 1 nodes, so the right subtree's
/// index is known before the left one is built, which lets the halves build in parallel.
fn build_range(items: &mut [BuildItem], out: &mut Vec<Node>, base: u32, parent: u32) -> LightBounds {
    let me = base + out.len() as u32;
    if let [item] = items {
        let id = item.id;
        out.push(Node { bounds: item.bounds, index: id.row, parent, kind: Some(id.kind), cost: 0.0 });
        return item.bounds;
    }
    let mid = partition(items);
    let slot = out.len();
    out.push(Node { bounds: EMPTY_BOUNDS, index: 0, parent, kind: None, cost: 0.0 });
    let (left, right) = items.split_at_mut(mid);
    let right_first = me + 2 * left.len() as u32;
    let (lb, rb) = if left.len() + right.len() >= PARALLEL_MIN {
        let mut right_nodes = Vec::with_capacity(2 * right.len() - 1);
        let (lb, rb) =
            rayon::join(|| build_range(left, out, base, me), || build_range(right, &mut right_nodes, right_first, me));
        out.extend(right_nodes);
        (lb, rb)
    } else {
        let lb = build_range(left, out, base, me);
        debug_assert_eq!(base + out.len() as u32, right_first);
        (lb, build_range(right, out, base, me))
    };
    let bounds = union(&lb, &rb);
    out[slot].bounds = bounds;
    out[slot].index = right_first;
    bounds
}

#[inline]
fn bucket_of(c: f32, lo: f32, extent: f32) -> usize {
    (((c - lo) / extent * BUCKETS as f32) as usize).min(BUCKETS - 1)
}

/// Reorders `items` into two non-empty halves and returns the split index: the cheapest bucket
/// boundary, ties going to the more balanced split; the median of the widest centroid axis when
/// every centroid coincides along every axis.
fn partition(items: &mut [BuildItem]) -> usize {
    let n = items.len();
    if n == 2 {
        return 1;
    }
    let mut bounds = EMPTY_BOUNDS;
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for it in items.iter() {
        bounds = union(&bounds, &it.bounds);
        lo = lo.min(it.centroid);
        hi = hi.max(it.centroid);
    }
    let diag = (bounds.max - bounds.min).max(Vec3::ZERO);
    // (cost, imbalance, axis, first bucket of the right side)
    let mut best: Option<(f32, usize, usize, usize)> = None;
    for axis in 0..3 {
        let extent = hi[axis] - lo[axis];
        if !(extent > 0.0) {
            continue;
        }
        let mut buckets = [(EMPTY_BOUNDS, 0usize); BUCKETS];
        for it in items.iter() {
            let b = &mut buckets[bucket_of(it.centroid[axis], lo[axis], extent)];
            b.0 = union(&b.0, &it.bounds);
            b.1 += 1;
        }
        // Conty & Kulla's K_r: favour splitting the box across its long side.
        let kr = if diag[axis] > 0.0 { diag.max_element() / diag[axis] } else { 1.0 };
        let mut right_cost = [0.0f32; BUCKETS];
        let mut acc = EMPTY_BOUNDS;
        for i in (1..BUCKETS).rev() {
            acc = union(&acc, &buckets[i].0);
            right_cost[i] = cluster_cost(&acc);
        }
        let (mut left, mut left_count) = (EMPTY_BOUNDS, 0);
        for split in 1..BUCKETS {
            left = union(&left, &buckets[split - 1].0);
            left_count += buckets[split - 1].1;
            if left_count == 0 || left_count == n {
                continue;
            }
            let cost = kr * (cluster_cost(&left) + right_cost[split]);
            let imbalance = left_count.abs_diff(n - left_count);
            let better = match best {
                None => true,
                Some((c, imb, ..)) => cost < c * (1.0 - 1e-6) || (cost <= c * (1.0 + 1e-6) && imbalance < imb),
            };
            if better {
                best = Some((cost, imbalance, axis, split));
            }
        }
    }
    match best {
        Some((_, _, axis, split)) => {
            let extent = hi[axis] - lo[axis];
            let mut mid = 0;
            for i in 0..n {
                if bucket_of(items[i].centroid[axis], lo[axis], extent) < split {
                    items.swap(i, mid);
                    mid += 1;
                }
            }
            mid
        }
        None => {
            let axis = (hi - lo).max_position();
            let mid = n / 2;
            items.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            mid
        }
    }
}
