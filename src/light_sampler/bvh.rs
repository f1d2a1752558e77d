//! `BvhSampler`: lights chosen by walking a light BVH from the root, at each node picking a child
//! in proportion to its importance at the shading point (Conty Estevez & Kulla 2018; pbrt-v4
//! `BVHLightSampler`, section 12.6.3). Lights at infinity (no bounds) are chosen outside the tree,
//! uniformly, with probability n_inf / (n_inf + 1) as pbrt does.
//!
//! **Weights.** Leaves carry the light's luminous power (lm, what [`super::PowerSampler`] uses,
//! so the photometric image is what is weighed), rescaled to that of an isotropic emitter of
//! the same peak intensity (see `leaf_bounds`): the orientation cones already confine a light's
//! importance to where it shines.
//!
//! **Following changes.** Lights that move or change power in place are refitted: their leaves
//! are recomputed, then each parent whose child's bounds changed, in decreasing index order
//! (children always follow their parent, so every child is final before its parent); a light
//! that moves inside its cluster's box stops the climb early.
//! The cost ratio (the geometric mean of each node's SAOH cost over its cost at the last build,
//! kept up to date during the refit) tells how far the topology has drifted from a good one;
//! past [`LIGHT_TREE_REBUILD_RATIO`] the tree is rebuilt.
//! Adding or removing lights rebuilds: the table swap-removes rows, so leaves would need
//! re-pointing and new lights a place in the tree, and in the ECS lights appear and disappear
//! far less often than they move (a rebuild of 10k lights takes a few ms; see the bench).

use glam::Vec3;

use super::bvh_build::{BuildItem, Node, build_tree};
use super::importance::{ClusterQuery, cluster_cost_with, orientation_measure, union};
use super::wide::{WideTree, choose_lane, lane_probability};
use crate::light::{LightBounds, LightId, LightKind, LightSampleContext, LightTable};
use crate::prefetch::prefetch;

/// Rebuild after refits once [`BvhSampler::cost_ratio`] passes this: up to here the variance stays
/// near a fresh tree's (`light_tree_quality` in tests/light_sampler.rs), and rebuilds stay rare.
pub const LIGHT_TREE_REBUILD_RATIO: f32 = 1.5;

/// How many changed lights ahead a refit prefetches leaf nodes.
const PREFETCH_DISTANCE: usize = 8;

/// `parent` of the root.
const NO_PARENT: u32 = u32::MAX;
/// `leaf_of` entry of a row that is not in the sampler.
const ABSENT: u32 = u32::MAX;
/// `leaf_of` entry of a light chosen outside the tree.
const AT_INFINITY: u32 = u32::MAX - 1;
/// Floor of the orientation measure (sr) in leaf weights: a beam narrower than ~0.5 degrees
/// weighs as one of that width rather than without bound.
const MIN_ORIENTATION_MEASURE: f32 = 1e-4;
/// The largest f32 below 1, so remapped sample values stay in [0, 1).
pub(super) const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// What the last [`BvhSampler::update`] did.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum BvhUpdate {
    /// Nothing changed.
    #[default]
    UpToDate,
    /// Refitted `nodes` nodes; the cost ratio is now `cost_ratio`.
    Refit {
        /// Number of nodes whose bounds were recomputed.
        nodes: usize,
        /// [`BvhSampler::cost_ratio`] after the refit.
        cost_ratio: f32,
    },
    /// Built from scratch.
    Rebuilt,
}

/// Per-node bookkeeping for refits.
#[derive(Clone, Copy, Debug)]
struct NodeMeta {
    /// The parent, [`NO_PARENT`] for the root.
    parent: u32,
    /// The first child (interior nodes): a copy of `Node::index`.
    first_child: u32,
    /// The node's slot in the wide tree, or `wide::NONE`.
    slot: u32,
    /// Orientation measure of the node's cone, reused while the cone does not change.
    orientation: f32,
    /// The node's cluster cost right after the last build.
    built_cost: f32,
    /// ln(cost now / `built_cost`): how much refits have degraded the node (0 for nodes built
    /// without cost).
    growth: f32,
}

impl NodeMeta {
    fn growth_of(&self, cost: f32) -> f32 {
        if self.built_cost > 0.0 { (cost.max(1e-6 * self.built_cost) / self.built_cost).ln() } else { 0.0 }
    }
}

/// A light BVH over the table's bounded lights plus a list of lights at infinity.
#[derive(Clone, Debug, Default)]
pub struct BvhSampler {
    /// Root first; siblings adjacent; children after their parent.
    pub(super) nodes: Vec<Node>,
    /// Per node, what a refit needs besides the bounds, together so it costs one cache line.
    meta: Vec<NodeMeta>,
    /// What sampling walks: the tree collapsed into nodes of four SIMD lanes.
    pub(super) wide: WideTree,
    pub(super) infinite: Vec<LightId>,
    /// Per kind, per row: the leaf node, [`AT_INFINITY`] or [`ABSENT`].
    leaf_of: [Vec<u32>; LightKind::COUNT],
    /// Sum of `NodeMeta::growth` over all nodes (f64: refits add and subtract into it), and the
    /// number of nodes with a cost at build.
    growth_sum: f64,
    costed_nodes: usize,
    /// The table's generation and light count this sampler reflects.
    generation: u64,
    light_count: usize,
    /// Refit scratch: one bit per node, set while the node waits to be recomputed (all clear
    /// between refits).
    dirty: Vec<u64>,
    /// What the last update did.
    pub last_update: BvhUpdate,
    /// Overrides [`LIGHT_TREE_REBUILD_RATIO`] (to study or tune it).
    pub rebuild_ratio: Option<f32>,
}

/// A light's bounds as the tree weighs them, or None for a light at infinity. The weight is the
/// light's luminous power scaled to that of an isotropic emitter with the same peak intensity,
/// 4 pi Phi_v / M_Omega (per emitting side): the orientation cones already keep a light's
/// importance to where it shines, so inside its beam a narrow spot must weigh as much as a point
/// light of the same intensity, not as little as its small power (pbrt-v4 gives spot bounds the
/// power 4 pi I_max for this reason). M_Omega is Conty & Kulla's orientation measure, exactly
/// Phi / I_max for isotropic points (4 pi), Lambertian surfaces (pi) and uniform cones. A
/// light with non-finite bounds gets no weight: it is never chosen.
///
/// `orientation` is the bounds' orientation measure when the caller knows it (a refit whose
/// light kept its cone); returns the bounds and their orientation measure.
fn leaf_bounds(table: &LightTable, id: LightId, known: Option<(f32, f32, f32)>) -> Option<(LightBounds, f32)> {
    let mut b = table.bounds(id)?;
    let orientation = match known {
        Some((cos_o, cos_e, m)) if cos_o == b.cos_theta_o && cos_e == b.cos_theta_e => m,
        _ => orientation_measure(b.cos_theta_o, b.cos_theta_e),
    };
    let sides = if b.two_sided { 2.0 } else { 1.0 };
    let spread = orientation.max(MIN_ORIENTATION_MEASURE) * sides;
    b.phi = table.luminous_power(id) * (4.0 * std::f32::consts::PI / spread);
    let finite = b.min.is_finite() && b.max.is_finite() && b.w.is_finite() && b.phi.is_finite();
    if !finite || b.cos_theta_o.is_nan() || b.cos_theta_e.is_nan() {
        b = LightBounds { min: Vec3::ZERO, max: Vec3::ZERO, phi: 0.0, ..super::importance::EMPTY_BOUNDS };
    }
    Some((b, orientation))
}

impl BvhSampler {
    /// A tree over the lights of `table`.
    pub fn build(table: &LightTable) -> Self {
        let mut s = Self::default();
        s.rebuild(table);
        s
    }

    /// Builds from scratch.
    pub fn rebuild(&mut self, table: &LightTable) {
        self.infinite.clear();
        self.leaf_of.iter_mut().for_each(Vec::clear);
        let mut items = Vec::with_capacity(table.len());
        for id in table.ids() {
            let rows = &mut self.leaf_of[id.kind.index()];
            if rows.len() <= id.row as usize {
                rows.resize(id.row as usize + 1, ABSENT);
            }
            match leaf_bounds(table, id, None).map(|(b, _)| b) {
                Some(bounds) => items.push(BuildItem { bounds, centroid: 0.5 * (bounds.min + bounds.max), id }),
                None => {
                    rows[id.row as usize] = AT_INFINITY;
                    self.infinite.push(id);
                }
            }
        }
        self.nodes = build_tree(&mut items);
        self.wide = WideTree::build(&self.nodes);
        self.meta.clear();
        (self.growth_sum, self.costed_nodes) = (0.0, 0);
        for (i, node) in self.nodes.iter().enumerate() {
            let b = node.query.bounds();
            let orientation = orientation_measure(b.cos_theta_o, b.cos_theta_e);
            let cost = cluster_cost_with(&b, orientation);
            self.costed_nodes += (cost > 0.0) as usize;
            let first_child = if node.kind.is_none() { node.index } else { NO_PARENT };
            let slot = self.wide.slot_of[i];
            self.meta.push(NodeMeta {
                parent: NO_PARENT,
                first_child,
                slot,
                orientation,
                built_cost: cost,
                growth: 0.0,
            });
            if let Some(id) = node.light() {
                self.leaf_of[id.kind.index()][id.row as usize] = i as u32;
            }
        }
        for i in 0..self.nodes.len() {
            let c = self.meta[i].first_child;
            if c != NO_PARENT {
                self.meta[c as usize].parent = i as u32;
                self.meta[c as usize + 1].parent = i as u32;
            }
        }
        self.dirty.clear();
        self.dirty.resize(self.nodes.len().div_ceil(64), 0);
        self.generation = table.generation;
        self.light_count = table.len();
        self.last_update = BvhUpdate::Rebuilt;
    }

    /// Brings the tree up to date with `table`: refits the leaves of lights changed in place
    /// (`table.changed_rows`) and their ancestors; rebuilds when lights were added or removed,
    /// when the change log does not cover every change since the last update, or when the refit
    /// pushed the cost ratio past [`LIGHT_TREE_REBUILD_RATIO`]. Returns what it did.
    pub fn update(&mut self, table: &LightTable) -> &'static str {
        if self.generation == table.generation {
            self.last_update = BvhUpdate::UpToDate;
            return "up to date";
        }
        if table.rows_reordered || table.len() != self.light_count {
            self.rebuild(table);
            return "lights added or removed: tree rebuilt";
        }
        if table.changes_since > self.generation {
            self.rebuild(table);
            return "changes cleared before this sampler saw them: tree rebuilt";
        }
        let Some(nodes) = self.refit(table, &table.changed_rows) else {
            self.rebuild(table);
            return "a light entered or left the tree: tree rebuilt";
        };
        self.generation = table.generation;
        let cost_ratio = self.cost_ratio();
        if cost_ratio > self.rebuild_ratio.unwrap_or(LIGHT_TREE_REBUILD_RATIO) {
            self.rebuild(table);
            return "refits degraded the tree past the cost ratio: tree rebuilt";
        }
        self.last_update = BvhUpdate::Refit { nodes, cost_ratio };
        "lights moved or changed power: tree refit"
    }

    /// Recomputes the leaves of `changed` lights from `table` and every ancestor of those leaves.
    /// Returns the number of nodes recomputed, or None (changing nothing further) if a light
    /// would have to enter or leave the tree.
    fn refit(&mut self, table: &LightTable, changed: &[LightId]) -> Option<usize> {
        // Large trees outgrow the caches and a refit waits on memory, so each step prefetches the
        // table rows and nodes of a later one.
        let mut recomputed = 0;
        for (k, &id) in changed.iter().enumerate() {
            if let Some(&a) = changed.get(k + PREFETCH_DISTANCE) {
                table.prefetch_bounds(a);
                if let Some(&ahead) = self.leaf_at(a) {
                    prefetch(&self.nodes, ahead as usize);
                    prefetch(&self.meta, ahead as usize);
                }
            }
            let leaf = *self.leaf_at(id)?;
            let known = self
                .nodes
                .get(leaf as usize)
                .map(|n| (n.query.cos_theta_o, n.query.cos_theta_e, self.meta[leaf as usize].orientation));
            match (leaf, leaf_bounds(table, id, known)) {
                (AT_INFINITY, None) => continue,
                (AT_INFINITY | ABSENT, _) | (_, None) => return None,
                (leaf, Some((b, orientation))) => {
                    recomputed += 1;
                    if self.set_bounds(leaf as usize, b, orientation) {
                        self.mark_parent(leaf as usize);
                    }
                }
            }
        }
        // Children have larger indices than their parent, so taking the highest dirty node first
        // sees every child before its parent; a parent is marked only if a child's bounds changed.
        let mut next = self.next_dirty_below(self.nodes.len());
        while let Some(n) = next {
            self.dirty[n / 64] &= !(1 << (n % 64));
            next = self.next_dirty_below(n);
            // Two stages ahead: the next node's record now, its children once that has arrived.
            if let Some(n1) = next {
                let c1 = self.meta[n1].first_child as usize;
                prefetch(&self.nodes, c1);
                prefetch(&self.nodes, n1);
                self.wide.prefetch_slot(self.meta[n1].slot);
                if let Some(n2) = self.next_dirty_below(n1) {
                    prefetch(&self.meta, n2);
                }
            }
            let c = self.meta[n].first_child as usize;
            let b = union(&self.nodes[c].query.bounds(), &self.nodes[c + 1].query.bounds());
            let q = &self.nodes[n].query;
            let orientation = if (q.cos_theta_o, q.cos_theta_e) == (b.cos_theta_o, b.cos_theta_e) {
                self.meta[n].orientation
            } else {
                orientation_measure(b.cos_theta_o, b.cos_theta_e)
            };
            recomputed += 1;
            if self.set_bounds(n, b, orientation)
                && let Some(p) = self.mark_parent(n)
                && next.is_none_or(|x| p > x)
            {
                // The parent lies between this node and the next one found above: it goes first.
                next = Some(p);
            }
        }
        debug_assert!(self.dirty.iter().all(|&w| w == 0), "a dirty node was skipped");
        Some(recomputed)
    }

    /// The leaf entry of light `id` (a node, [`AT_INFINITY`] or [`ABSENT`]).
    #[inline]
    fn leaf_at(&self, id: LightId) -> Option<&u32> {
        self.leaf_of.get(id.kind.index())?.get(id.row as usize)
    }

    /// The highest dirty node below `n`.
    #[inline]
    fn next_dirty_below(&self, n: usize) -> Option<usize> {
        if n == 0 {
            return None;
        }
        let (mut word, bit) = ((n - 1) / 64, (n - 1) % 64);
        let mut bits = self.dirty[word] & (u64::MAX >> (63 - bit));
        loop {
            if bits != 0 {
                return Some(64 * word + 63 - bits.leading_zeros() as usize);
            }
            if word == 0 {
                return None;
            }
            word -= 1;
            bits = self.dirty[word];
        }
    }

    /// Marks node `n`'s parent dirty and returns it (None for the root).
    #[inline]
    fn mark_parent(&mut self, n: usize) -> Option<usize> {
        let p = self.meta[n].parent;
        (p != NO_PARENT).then(|| {
            self.dirty[p as usize / 64] |= 1 << (p % 64);
            p as usize
        })
    }

    /// Sets node `n`'s bounds (with their orientation measure); returns whether they changed.
    fn set_bounds(&mut self, n: usize, bounds: LightBounds, orientation: f32) -> bool {
        let query = ClusterQuery::from(&bounds);
        if query == self.nodes[n].query {
            return false;
        }
        let cost = cluster_cost_with(&bounds, orientation);
        let meta = &mut self.meta[n];
        let growth = meta.growth_of(cost);
        self.growth_sum += growth as f64 - meta.growth as f64;
        (meta.growth, meta.orientation) = (growth, orientation);
        let slot = meta.slot;
        self.nodes[n].query = query;
        self.wide.set_slot(slot, &query);
        true
    }

    /// How much refits have degraded the tree: the geometric mean, over the nodes, of each
    /// node's SAOH cost now over its cost right after the last build. 1 after a build, growing
    /// as moving lights stretch the boxes and cones. (A sum of costs over the root's, as the
    /// geometry BVH uses, is dominated by the few top nodes, whose bounds barely move, and
    /// missed the variance's growth; see `light_tree_quality`.)
    pub fn cost_ratio(&self) -> f32 {
        if self.costed_nodes > 0 { (self.growth_sum / self.costed_nodes as f64).exp() as f32 } else { 1.0 }
    }

    /// Number of tree nodes (2 n - 1 for n bounded lights).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth of the deepest leaf (the root alone has depth 0).
    pub fn depth(&self) -> usize {
        let mut depth = vec![0u32; self.nodes.len()];
        let mut max = 0;
        for i in 1..self.nodes.len() {
            depth[i] = depth[self.meta[i].parent as usize] + 1;
            max = max.max(depth[i]);
        }
        max as usize
    }

    /// True if both trees have the same shape and the same light in every leaf.
    pub fn same_topology(&self, other: &Self) -> bool {
        self.nodes.len() == other.nodes.len()
            && self.nodes.iter().zip(&other.nodes).all(|(a, b)| (a.index, a.kind) == (b.index, b.kind))
    }

    /// Probability of choosing a light at infinity (all of them together).
    #[inline]
    pub(super) fn infinite_probability(&self) -> f32 {
        let n = self.infinite.len() as f32;
        if self.nodes.is_empty() { if n > 0.0 { 1.0 } else { 0.0 } } else { n / (n + 1.0) }
    }

    /// A light and the probability of choosing it at `ctx` (clusters ranked with its shading
    /// normal, as the BSDF weighs light; two-sided, so no light that reaches the point gets pmf 0),
    /// or None when no light can reach it.
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(LightId, f32)> {
        let p_inf = self.infinite_probability();
        if u < p_inf {
            let n = self.infinite.len();
            let i = ((u / p_inf * n as f32) as usize).min(n - 1);
            return Some((self.infinite[i], p_inf / n as f32));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).min(ONE_MINUS_EPSILON);
        let mut pmf = 1.0 - p_inf;
        let root = &self.nodes[0];
        if let Some(id) = root.light() {
            return (root.query.importance(ctx.p, ctx.ns) > 0.0).then_some((id, pmf));
        }
        let mut w = 0;
        loop {
            let node = &self.wide.nodes[w];
            let (lane, p, remapped) = choose_lane(node.importance(ctx.p, ctx.ns), u)?;
            (pmf, u) = (pmf * p, remapped);
            match node.light(lane) {
                Some(id) => return Some((id, pmf)),
                None => w = node.child[lane] as usize,
            }
        }
    }

    /// Probability that `sample` returns `light` at `ctx`: the product of the child choices on
    /// the path from the root to its leaf (0 for a light not in this sampler).
    pub fn pmf(&self, ctx: &LightSampleContext, light: LightId) -> f32 {
        let leaf = self.leaf_of.get(light.kind.index()).and_then(|r| r.get(light.row as usize)).copied();
        let leaf = match leaf {
            None | Some(ABSENT) => return 0.0,
            Some(AT_INFINITY) => return self.infinite_probability() / self.infinite.len() as f32,
            Some(leaf) => leaf as usize,
        };
        let mut pmf = 1.0 - self.infinite_probability();
        if leaf == 0 {
            return if self.nodes[0].query.importance(ctx.p, ctx.ns) > 0.0 { pmf } else { 0.0 };
        }
        let slot = self.wide.slot_of[leaf] as usize;
        let (mut w, mut lane) = (slot / 4, slot % 4);
        loop {
            pmf *= lane_probability(self.wide.nodes[w].importance(ctx.p, ctx.ns), lane);
            match self.wide.parent_slot(w) {
                Some(up) => (w, lane) = up,
                None => return pmf,
            }
        }
    }
}

impl BvhSampler {
    /// Calls `f` with every light and its pmf at `ctx`, in one pass over the tree (O(nodes),
    /// where calling `pmf` per light costs O(n log n)): for exact variances in reports and tests.
    /// The products are formed top-down, as `sample` forms them.
    pub fn for_each_pmf(&self, ctx: &LightSampleContext, mut f: impl FnMut(LightId, f32)) {
        let p_inf = self.infinite_probability();
        for &id in &self.infinite {
            f(id, p_inf / self.infinite.len() as f32);
        }
        let Some(root) = self.nodes.first() else { return };
        if let Some(id) = root.light() {
            let reachable = root.query.importance(ctx.p, ctx.ns) > 0.0;
            f(id, if reachable { 1.0 - p_inf } else { 0.0 });
            return;
        }
        let mut stack = vec![(0usize, 1.0 - p_inf)];
        while let Some((w, pmf)) = stack.pop() {
            let node = &self.wide.nodes[w];
            let weights = node.importance(ctx.p, ctx.ns);
            for lane in (0..4).rev() {
                let q = pmf * lane_probability(weights, lane);
                match node.light(lane) {
                    Some(id) => f(id, q),
                    None if node.child[lane] != super::wide::NONE => stack.push((node.child[lane] as usize, q)),
                    None => {}
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::LightKind;

    #[test]
    fn empty_sampler_chooses_nothing() {
        let s = BvhSampler::build(&LightTable::default());
        let ctx = LightSampleContext::at(Vec3::ZERO);
        assert_eq!(s.sample(&ctx, 0.5), None);
        assert_eq!(s.pmf(&ctx, LightId { kind: LightKind::Point, row: 0 }), 0.0);
        assert_eq!(s.node_count(), 0);
    }
}
