//! Building the light BVH top-down with binned SAOH splits (Conty & Kulla 2018, section 4.2;
//! pbrt-v4 `BVHLightSampler::buildBVH`): 12 buckets per axis over the lights' centroids, cost =
//! power x orientation measure x surface area of each side, scaled by the split axis's aspect
//! factor so long thin boxes are split across.
//!
//! **Layout.** Nodes are 64 bytes and siblings sit side by side, so the two importances of a
//! traversal step read two adjacent cache lines. Children always follow their parent (an
//! interior node reserves its children's pair before building below them), which lets a refit
//! recompute nodes in decreasing index order.

use glam::Vec3;

use super::importance::{ClusterQuery, EMPTY_BOUNDS, cluster_cost, union};
use crate::light::{LightBounds, LightId, LightKind};

/// pbrt-v4's bucket count.
const BUCKETS: usize = 12;
/// Ranges at least this long build their two halves in parallel.
const PARALLEL_MIN: usize = 8 * 1024;

/// A light to place in the tree.
#[derive(Clone, Copy, Debug)]
pub(super) struct BuildItem {
    pub bounds: LightBounds,
    pub centroid: Vec3,
    pub id: LightId,
}

/// A tree node: its cluster's bounds and either its children or its light.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub(super) struct Node {
    pub query: ClusterQuery,
    /// Interior: the first of its two adjacent children. Leaf: the light's row.
    pub index: u32,
    /// Leaf: the light's kind. None for interior nodes.
    pub kind: Option<LightKind>,
}

impl Node {
    fn leaf(item: &BuildItem) -> Self {
        Self { query: ClusterQuery::from(&item.bounds), index: item.id.row, kind: Some(item.id.kind) }
    }
    /// The node's light, for a leaf.
    #[inline]
    pub fn light(&self) -> Option<LightId> {
        self.kind.map(|kind| LightId { kind, row: self.index })
    }
}

/// The nodes of a tree over `items` (reordered in place), root first; empty for no items.
pub(super) fn build_tree(items: &mut [BuildItem]) -> Vec<Node> {
    if items.is_empty() {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(2 * items.len() - 1);
    let placeholder = Node { query: ClusterQuery::from(&EMPTY_BOUNDS), index: 0, kind: None };
    out.push(placeholder);
    let (root, _) = build_below(items, &mut out, 0);
    out[0] = root;
    out
}

/// Appends every node below the subtree over `items` to `out` (whose first element has global
/// index `base`) and returns the subtree's root node and bounds, for the caller to place. A
/// subtree over k lights has 2k - 2 nodes below its root, so the right child's descendants'
/// position is known before the left ones are built, which lets the halves build in parallel.
fn build_below(items: &mut [BuildItem], out: &mut Vec<Node>, base: u32) -> (Node, LightBounds) {
    if let [item] = items {
        return (Node::leaf(item), item.bounds);
    }
    let mid = partition(items);
    let pair = out.len();
    let first_child = base + pair as u32;
    let placeholder = Node { query: ClusterQuery::from(&EMPTY_BOUNDS), index: 0, kind: None };
    out.extend([placeholder; 2]);
    let (left, right) = items.split_at_mut(mid);
    let right_base = first_child + 2 + 2 * (left.len() as u32 - 1);
    let ((ln, lb), (rn, rb)) = if left.len() + right.len() >= PARALLEL_MIN {
        let mut right_nodes = Vec::with_capacity(2 * right.len() - 2);
        let (l, r) = rayon::join(|| build_below(left, out, base), || build_below(right, &mut right_nodes, right_base));
        out.extend(right_nodes);
        (l, r)
    } else {
        let l = build_below(left, out, base);
        debug_assert_eq!(base + out.len() as u32, right_base);
        (l, build_below(right, out, base))
    };
    out[pair] = ln;
    out[pair + 1] = rn;
    let bounds = union(&lb, &rb);
    (Node { query: ClusterQuery::from(&bounds), index: first_child, kind: None }, bounds)
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
