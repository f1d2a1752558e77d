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
//! **Following changes.** Lights that move or change power in place are refitted: only their
//! leaves and those leaves' ancestors are recomputed (children always follow their parent, so
//! recomputing the dirty ancestors in decreasing index order sees every child before its parent).
//! The tree's cost (the sum of every node's SAOH cluster cost over the root's, kept up to date
//! during the refit) tells how far the topology has drifted from a good one; past
//! [`LIGHT_TREE_REBUILD_RATIO`] times its value after the last build, the tree is rebuilt.
//! Adding or removing lights rebuilds: the table swap-removes rows, so leaves would need
//! re-pointing and new lights a place in the tree, and in the ECS lights appear and disappear
//! far less often than they move (a rebuild of 10k lights takes a few ms; see the bench).

use glam::Vec3;

use super::bvh_build::{BuildItem, Node, build_tree};
use super::importance::{ClusterQuery, cluster_cost, orientation_measure, union};
use crate::light::{LightBounds, LightId, LightSampleContext, LightTable};

/// Rebuild after refits once the tree cost has grown by this factor since the last build.
/// Measured on the scaling scene (10k lights random-walking; `light_tree_quality` in
/// tests/light_sampler.rs): at a cost ratio of 1.25 the BVH estimator's variance is ~10% above
/// a fresh tree's, at 1.5 ~20-25%, and it keeps growing with the ratio; a rebuild costs as
/// much as ~50-100 refits of 1% of the lights, so a 10% loss is the point to pay for one.
pub const LIGHT_TREE_REBUILD_RATIO: f32 = 1.25;

/// Number of [`LightKind`]s (rows of `leaf_of`).
const KINDS: usize = 8;
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
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// What the last [`BvhSampler::update`] did.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum BvhUpdate {
    /// Nothing changed.
    #[default]
    UpToDate,
    /// Refitted `nodes` nodes; the cost ratio is now `cost_ratio`.
    Refit { nodes: usize, cost_ratio: f32 },
    /// Built from scratch.
    Rebuilt,
}

/// A light BVH over the table's bounded lights plus a list of lights at infinity.
#[derive(Clone, Debug, Default)]
pub struct BvhSampler {
    /// Root first; siblings adjacent; children after their parent.
    nodes: Vec<Node>,
    /// Per node: its parent ([`NO_PARENT`] for the root) and its cluster cost.
    parent: Vec<u32>,
    cost: Vec<f32>,
    infinite: Vec<LightId>,
    /// Per kind, per row: the leaf node, [`AT_INFINITY`] or [`ABSENT`].
    leaf_of: [Vec<u32>; KINDS],
    /// Sum of `cost` over all nodes (f64: refits add and subtract into it).
    cost_sum: f64,
    /// Normalised cost right after the last build.
    built_cost: f64,
    /// The table's generation and light count this sampler reflects.
    generation: u64,
    light_count: usize,
    /// Scratch for refits: a per-node stamp and the dirty list.
    stamp: Vec<u32>,
    current_stamp: u32,
    dirty: Vec<u32>,
    /// What the last update did.
    pub last_update: BvhUpdate,
}

/// A light's bounds as the tree weighs them, or None for a light at infinity. The weight is the
/// light's luminous power scaled to that of an isotropic emitter with the same peak intensity,
/// 4 pi Phi_v / M_Omega (per emitting side): the orientation cones already keep a light's
/// importance to where it shines, so inside its beam a narrow spot must weigh as much as a point
/// light of the same intensity, not as little as its small power (pbrt-v4 gives spot bounds the
/// power 4 pi I_max for this reason). M_Omega is Conty & Kulla's orientation measure, exactly
/// Phi / I_max for isotropic points (4 pi), Lambertian surfaces (pi) and uniform cones. A
/// light with non-finite bounds gets no weight: it is never chosen.
fn leaf_bounds(table: &LightTable, id: LightId) -> Option<LightBounds> {
    let mut b = table.bounds(id)?;
    let sides = if b.two_sided { 2.0 } else { 1.0 };
    let spread = orientation_measure(b.cos_theta_o, b.cos_theta_e).max(MIN_ORIENTATION_MEASURE) * sides;
    b.phi = table.luminous_power(id) * (4.0 * std::f32::consts::PI / spread);
    let finite = b.min.is_finite() && b.max.is_finite() && b.w.is_finite() && b.phi.is_finite();
    if !finite || b.cos_theta_o.is_nan() || b.cos_theta_e.is_nan() {
        b = LightBounds { min: Vec3::ZERO, max: Vec3::ZERO, phi: 0.0, ..super::importance::EMPTY_BOUNDS };
    }
    Some(b)
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
            let rows = &mut self.leaf_of[id.kind as usize];
            if rows.len() <= id.row as usize {
                rows.resize(id.row as usize + 1, ABSENT);
            }
            match leaf_bounds(table, id) {
                Some(bounds) => items.push(BuildItem { bounds, centroid: 0.5 * (bounds.min + bounds.max), id }),
                None => {
                    rows[id.row as usize] = AT_INFINITY;
                    self.infinite.push(id);
                }
            }
        }
        self.nodes = build_tree(&mut items);
        self.parent.clear();
        self.parent.resize(self.nodes.len(), NO_PARENT);
        self.cost.clear();
        self.cost_sum = 0.0;
        for (i, node) in self.nodes.iter().enumerate() {
            let cost = cluster_cost(&node.query.bounds());
            self.cost.push(cost);
            self.cost_sum += cost as f64;
            match node.light() {
                Some(id) => self.leaf_of[id.kind as usize][id.row as usize] = i as u32,
                None => {
                    let c = node.index as usize;
                    (self.parent[c], self.parent[c + 1]) = (i as u32, i as u32);
                }
            }
        }
        self.built_cost = self.normalized_cost();
        self.stamp.clear();
        self.stamp.resize(self.nodes.len(), 0);
        self.current_stamp = 0;
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
        if cost_ratio > LIGHT_TREE_REBUILD_RATIO {
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
        self.current_stamp = self.current_stamp.wrapping_add(1);
        if self.current_stamp == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.current_stamp = 1;
        }
        let stamp = self.current_stamp;
        self.dirty.clear();
        for &id in changed {
            let leaf = *self.leaf_of.get(id.kind as usize)?.get(id.row as usize)?;
            let bounds = leaf_bounds(table, id);
            match (leaf, bounds) {
                (AT_INFINITY, None) => continue,
                (AT_INFINITY | ABSENT, _) | (_, None) => return None,
                (leaf, Some(b)) => {
                    self.set_bounds(leaf as usize, b);
                    let mut n = self.parent[leaf as usize];
                    while n != NO_PARENT && self.stamp[n as usize] != stamp {
                        self.stamp[n as usize] = stamp;
                        self.dirty.push(n);
                        n = self.parent[n as usize];
                    }
                }
            }
        }
        // Children have larger indices than their parent: highest first sees children first.
        self.dirty.sort_unstable_by(|a, b| b.cmp(a));
        for k in 0..self.dirty.len() {
            let n = self.dirty[k] as usize;
            let c = self.nodes[n].index as usize;
            let b = union(&self.nodes[c].query.bounds(), &self.nodes[c + 1].query.bounds());
            self.set_bounds(n, b);
        }
        Some(self.dirty.len() + changed.len())
    }

    fn set_bounds(&mut self, n: usize, bounds: LightBounds) {
        let cost = cluster_cost(&bounds);
        self.cost_sum += cost as f64 - self.cost[n] as f64;
        self.cost[n] = cost;
        self.nodes[n].query = ClusterQuery::from(&bounds);
    }

    fn normalized_cost(&self) -> f64 {
        match self.cost.first() {
            Some(&root) if root > 0.0 => self.cost_sum / root as f64,
            _ => 1.0,
        }
    }

    /// The tree's cost (sum of node costs over the root's) relative to its value after the last
    /// build: 1 after a build, growing as refits let boxes and cones overlap.
    pub fn cost_ratio(&self) -> f32 {
        if self.built_cost > 0.0 { (self.normalized_cost() / self.built_cost) as f32 } else { 1.0 }
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
            depth[i] = depth[self.parent[i] as usize] + 1;
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
    fn infinite_probability(&self) -> f32 {
        let n = self.infinite.len() as f32;
        if self.nodes.is_empty() { if n > 0.0 { 1.0 } else { 0.0 } } else { n / (n + 1.0) }
    }

    /// A light and the probability of choosing it at `ctx`, or None when no light can reach it.
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
            return (root.query.importance(ctx.p, ctx.n) > 0.0).then_some((id, pmf));
        }
        let mut c = root.index as usize;
        loop {
            let w0 = self.nodes[c].query.importance(ctx.p, ctx.n);
            let w1 = self.nodes[c + 1].query.importance(ctx.p, ctx.n);
            if w0 == 0.0 && w1 == 0.0 {
                return None;
            }
            let p0 = w0 / (w0 + w1);
            let chosen = if u < p0 {
                (u, pmf) = ((u / p0).min(ONE_MINUS_EPSILON), pmf * p0);
                c
            } else {
                let p1 = 1.0 - p0;
                (u, pmf) = (((u - p0) / p1).min(ONE_MINUS_EPSILON), pmf * p1);
                c + 1
            };
            let node = &self.nodes[chosen];
            if let Some(id) = node.light() {
                return Some((id, pmf));
            }
            c = node.index as usize;
        }
    }

    /// Probability that `sample` returns `light` at `ctx`: the product of the child choices on
    /// the path from the root to its leaf (0 for a light not in this sampler).
    pub fn pmf(&self, ctx: &LightSampleContext, light: LightId) -> f32 {
        let leaf = self.leaf_of.get(light.kind as usize).and_then(|r| r.get(light.row as usize)).copied();
        let leaf = match leaf {
            None | Some(ABSENT) => return 0.0,
            Some(AT_INFINITY) => return self.infinite_probability() / self.infinite.len() as f32,
            Some(leaf) => leaf as usize,
        };
        let mut pmf = 1.0 - self.infinite_probability();
        if leaf == 0 {
            return if self.nodes[0].query.importance(ctx.p, ctx.n) > 0.0 { pmf } else { 0.0 };
        }
        let mut child = leaf;
        while child != 0 {
            // Sibling pairs start at odd indices (the root is 0 and pairs are allocated whole).
            let first = if child % 2 == 1 { child } else { child - 1 };
            let w0 = self.nodes[first].query.importance(ctx.p, ctx.n);
            let w1 = self.nodes[first + 1].query.importance(ctx.p, ctx.n);
            if w0 == 0.0 && w1 == 0.0 {
                return 0.0;
            }
            let p0 = w0 / (w0 + w1);
            pmf *= if child == first { p0 } else { 1.0 - p0 };
            child = self.parent[child] as usize;
        }
        pmf
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
            let reachable = root.query.importance(ctx.p, ctx.n) > 0.0;
            f(id, if reachable { 1.0 - p_inf } else { 0.0 });
            return;
        }
        let mut stack = vec![(root.index as usize, 1.0 - p_inf)];
        while let Some((c, pmf)) = stack.pop() {
            let w0 = self.nodes[c].query.importance(ctx.p, ctx.n);
            let w1 = self.nodes[c + 1].query.importance(ctx.p, ctx.n);
            let (q0, q1) = if w0 == 0.0 && w1 == 0.0 {
                (0.0, 0.0)
            } else {
                let p0 = w0 / (w0 + w1);
                (pmf * p0, pmf * (1.0 - p0))
            };
            for (child, q) in [(c + 1, q1), (c, q0)] {
                match self.nodes[child].light() {
                    Some(id) => f(id, q),
                    None => stack.push((self.nodes[child].index as usize, q)),
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
